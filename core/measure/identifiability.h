// Identifiability of the parameters of `volmap identify` from one recording
// (docs/identify.md, "Method", steps 2 and 3): column scaling J_s = J_w D^-1,
// the singular values of J_s from the eigen-decomposition of J_s^T J_s, and
// for each null vector one parameter fixed at 0 and reported, never
// estimated, with the combination it belongs to, why the recording cannot
// separate it and what measurement would. Internal to
// core/measure/identify*.cc.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/measure/identify.h"
#include "core/measure/identify_columns.h"
#include "core/model/gain_evaluator.h"

namespace volmap::identification {

struct Identifiability {
  Eigen::VectorXd column_scale;  ///< D: the column norms of J_w (1 for a zero column)
  Eigen::MatrixXd normal;        ///< N = J_s^T J_s
  std::vector<bool> fixed;       ///< per column: not identifiable, fixed at 0
  int rank = 0;
  std::vector<double> singular_values;  ///< of J_s, descending
  std::vector<UnidentifiableCombination> unidentifiable;
};

/// Scales the columns of J (J_w on entry, J_s on return: in place, no second
/// copy of a 10^4 x 30 matrix) and analyses it. `moved`: per axis, whether
/// it moves in the recording (moved_axes). `gains` is moved to the
/// positions of a rich design.
Identifiability analyse_identifiability(Eigen::MatrixXd& J, const Machine& m, GainEvaluator& gains,
                                        const std::vector<ParameterColumn>& cols,
                                        const std::vector<bool>& moved, double rank_tolerance);

}  // namespace volmap::identification
