// Locate (docs/explain.md): where the baseline residuals have structure,
// against every regressor the recording holds (axis positions, approach
// directions, run, time, feed, temperatures, extra columns).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/explain/explain.h"
#include "core/explain/observations.h"

namespace volmap::explanation {

/// The strongest structures (at most 10, strongest first) of the residuals
/// (um, per equation) against every regressor of the recording.
std::vector<Mismatch> locate_mismatch(const Observations& obs, const Eigen::VectorXd& residual_um);

}  // namespace volmap::explanation
