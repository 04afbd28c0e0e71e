// The fit of one candidate given the model so far (docs/explain.md): its
// nonlinear parameter by scan and golden section on the profile RSS, and the
// BIC of the model with it.
#pragma once

#include <optional>

#include "core/explain/candidate.h"
#include "core/explain/linear_model.h"

namespace volmap::explanation {

struct FittedCandidate {
  const Candidate* cand = nullptr;
  double theta = 0.0;  ///< the nonlinear parameter (0 when there is none)
  ColumnBlock block;
  ProfileGain gain;
  double bic = 0.0;
};

/// Fits a candidate's nonlinear parameter (grid, then golden section) by the
/// profile RSS given the model. With a hint (the parameter of an earlier
/// step) a refined candidate is searched within +-15 % of it instead.
std::optional<FittedCandidate> fit_candidate(const Observations& obs, const LinearModel& model,
                                             const Candidate& c,
                                             std::optional<double> hint = std::nullopt);

}  // namespace volmap::explanation
