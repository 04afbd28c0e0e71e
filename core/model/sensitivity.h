// Error gains (Hsu Tables I and II, generalised): the first-order change of
// the tool pose, in workpiece coordinates, per unit of each geometric error.
// Position gains: mm per mm (translational errors) or mm per rad (angular);
// orientation gains: rad per rad, zero for translational errors.
#pragma once

#include <string>
#include <vector>

#include "core/model/error_model.h"

namespace volmap {

struct ErrorGain {
  std::string name;    ///< ISO 230-1 name, "EXX", "EC0X"
  bool angular;        ///< unit of the error: rad (true) or mm
  Eigen::Vector3d dP;  ///< dx, dy, dz
  Eigen::Vector3d dQ;  ///< di, dj, dk
};

/// The errors of a machine's model, in table order: for each axis in the
/// machine's chain order (workpiece chain from the base, then tool chain),
/// its six component errors EX.. EC; then the location errors: squareness
/// of the linear axes (EC0X, EB0Z, EA0Z: X to Y, Z to X, Z to Y, ISO 230-1,
/// Y the reference direction) and per rotary axis its two line offsets, two
/// tilts and its zero position (EX0C EY0C EA0C EB0C EC0C for C).
std::vector<std::string> model_error_names(const Machine& m);

/// Gains of every error of model_error_names(m) at axis position u, the
/// location errors in the given meaning.
std::vector<ErrorGain> error_gains(const Machine& m, Formulation f, const AxisVector& u,
                                   LocationConvention convention = LocationConvention::kIso230);

/// The value of every error of model_error_names(m) at u, from an error set
/// (mm or rad; zero where the set has none). Component errors of an axis with
/// bidirectional tables take the mean of both directions.
std::vector<double> error_values(const Machine& m, const ErrorSet& errors, const AxisVector& u,
                                 OutsidePolicy outside);

}  // namespace volmap
