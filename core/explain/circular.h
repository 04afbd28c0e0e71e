// Circular tests (ISO 230-4) in a recording (docs/explain.md, "Circular
// tests"): the runs whose projection readings lie on a circle with the
// radial direction as beam, their circular deviation G and hysteresis H,
// before and after the findings.
#pragma once

#include <vector>

#include "core/explain/observations.h"

namespace volmap::explanation {

/// The circular tests of the recording; before_um and after_um per
/// equation (the recorded deviation less a fixed baseline, and the final
/// residual).
std::vector<CircularTest> circular_tests(const Observations& obs, const Eigen::VectorXd& before_um,
                                         const Eigen::VectorXd& after_um);

}  // namespace volmap::explanation
