// Confounding (docs/explain.md): effects a recording cannot tell apart, the
// reason, and the test that would separate them.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "core/explain/candidate.h"
#include "core/explain/candidate_fit.h"

namespace volmap::explanation {

/// The test that separates effects a and b.
std::string remedy_for(const std::string& a, const std::string& b);

/// A recording whose time rises with a linear axis position in every run
/// (one-direction sweeps) confounds thermal drift with scale by design:
/// reported whatever the residuals show. Appends to `confounded`; returns
/// the letters of the axes whose drift and scale are not tried.
std::set<std::string> design_confounding(const CandidateContext& ctx,
                                         std::vector<Confounded>& confounded);

/// f and g explain the same structure (fitted deviations correlated rho).
Confounded same_structure(const Observations& obs, const FittedCandidate& f,
                          const FittedCandidate& g, double rho);

/// Appends c unless the same effects on the same axis are reported already.
void add_confounded_once(std::vector<Confounded>& confounded, const Confounded& c);

/// Per-run offsets that change monotonically in run order, in a recording
/// without a time column: a set-up shift or a drift between runs.
bool monotonic_in_run_order(const nlohmann::json& per_run_um);
Confounded shift_or_drift_between_runs(const std::optional<AxisName>& axis);

}  // namespace volmap::explanation
