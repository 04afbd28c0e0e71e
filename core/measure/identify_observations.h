// The observations of `volmap identify` (docs/identify.md, "Method"): one
// scalar equation per recorded deviation cell (ex_um, ey_um, ez_um, or e_um
// along n), y_i = p_i^T R_rec_w dv(u_i, dir_i; e), and the weighted
// first-order Jacobian J_w = sqrt(W) J of Lei & Hsu (2003), section 3 (least
// squares identification of the link errors). Internal to
// core/measure/identify*.cc.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/measure/identify_columns.h"
#include "core/measure/recordings.h"
#include "core/model/gain_evaluator.h"

namespace volmap::identification {

struct Equation {
  int row = 0;          ///< index into the used rows
  Eigen::Vector3d p_w;  ///< direction in workpiece coordinates
  double y_um = 0.0;
  double sqrt_w = 1.0;
};

/// The rows of the recordings with a deviation to fit (weight > 0 and at
/// least one recorded cell), and their equations grouped by row in row order.
struct Observations {
  std::vector<AxisVector> u;            ///< per used row, internal units
  std::vector<ApproachDirections> dir;  ///< per used row
  std::vector<int> run;                 ///< per used row: run index, -1 without runs
  std::vector<int> line;                ///< per used row: recordings line
  std::vector<Equation> equations;      ///< by row
  bool machine_frame = false;           ///< recorded in the machine frame (R_b_w)
};

/// Reads the observations. Throws InputError when there is nothing to fit.
Observations gather_observations(const Machine& m, const Recordings& rec);

/// Per axis (machine order): whether it moves in the used rows.
std::vector<bool> moved_axes(const Machine& m, const std::vector<AxisVector>& u);

/// J_w = sqrt(W) J, J held at first order: column j holds d(recorded um) /
/// d(parameter unit). Setup offsets live in the recording frame.
Eigen::MatrixXd weighted_jacobian(const Machine& m, GainEvaluator& gains, const Observations& obs,
                                  const std::vector<ParameterColumn>& cols);

}  // namespace volmap::identification
