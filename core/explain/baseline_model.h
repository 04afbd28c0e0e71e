// The baseline of `volmap explain` (docs/explain.md): a constant per
// recorded component (instrument zero) plus, without a fixed baseline,
// every location error and every component error of the linear axes as a
// polynomial s^1..s^degree (s scaled over the travel), through the
// first-order gains (the linearised model `volmap identify` iterates on).
#pragma once

#include <string>

#include "core/explain/linear_model.h"

namespace volmap::explanation {

/// The baseline's identifiable columns (not fitted) and its description for
/// the report.
LinearModel baseline_model(const Observations& obs, const ExplainOptions& opt,
                           std::string& description);

}  // namespace volmap::explanation
