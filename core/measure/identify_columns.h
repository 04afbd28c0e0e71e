// The parameter set of `volmap identify` (docs/identify.md, "Parameters"):
// one column of the Jacobian per parameter, in this order: location
// errors, component-curve terms, setup offsets. Internal to
// core/measure/identify*.cc.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/measure/identify.h"
#include "core/model/gain_evaluator.h"

namespace volmap::identification {

/// One parameter column.
struct ParameterColumn {
  IdentifiedParameter p;
  int gain = -1;            ///< GainEvaluator index (location, component)
  double unit_scale = 1.0;  ///< internal units per parameter unit (1e-3 mm/um, 1e-6 rad/urad)
  // component curve basis
  AxisName axis = AxisName::X;
  int axis_index = -1;  ///< AxisVector index
  bool fourier = false;
  int power = 0;  ///< polynomial power, or Fourier order
  bool sine = false;
  double centre = 0.0, half_span = 1.0;  ///< s = (q - centre) / half_span
  // setup offset
  int run = -1, coordinate = 0;
};

/// The basis function of a component column at axis position q (mm, rad):
/// s^power (s = (q - centre) / half_span), or cos / sin(power q).
double curve_basis(const ParameterColumn& c, double q);
/// Its derivative d/dq.
double curve_basis_slope(const ParameterColumn& c, double q);

/// The location columns (opt.parameters, or every location error of the
/// model that `known` does not give) followed by the component-curve columns
/// of opt.components. Throws std::invalid_argument for a name that is not a
/// location error, one held in `known`, and ComponentFitError for a
/// component fit the machine or `known` cannot take.
std::vector<ParameterColumn> physical_columns(const Machine& m, const GainEvaluator& gains,
                                              const ErrorSet& known, const IdentifyOptions& opt);

/// Appends a constant offset (x, y, z, um, recording frame) per run of
/// `row_runs` (run index per used row, -1 without a run column).
void append_setup_offset_columns(std::vector<ParameterColumn>& cols,
                                 const std::vector<int>& row_runs, const Recordings& rec);

/// d(tool-tip deviation, workpiece frame, um) / d(parameter unit) of a
/// location or component column at u; `gains` must be at u.
Eigen::Vector3d physical_gain_w_um(const ParameterColumn& c, const GainEvaluator& gains,
                                   const AxisVector& u);

/// The error set with the parameters at theta (parameter units): `known`
/// plus the location errors, and the component curves tabulated over the
/// travel (a full turn for Fourier curves). Setup offsets are not errors.
ErrorSet errors_at(const Machine& m, const ErrorSet& known,
                   const std::vector<ParameterColumn>& cols,
                   const std::vector<std::string>& gain_names, const Eigen::VectorXd& theta);

}  // namespace volmap::identification
