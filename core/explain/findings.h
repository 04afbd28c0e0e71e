// The findings of `volmap explain` from the final model (docs/explain.md):
// each selected effect's parameters with standard errors (covariance
// sigma^2 (X^T X)^-1; a nonlinear parameter's from the curvature of the
// profile RSS), its evidence and its plot.
#pragma once

#include "core/explain/candidate.h"
#include "core/explain/selection.h"

namespace volmap::explanation {

/// Appends the findings of the selection to res.findings; per-run offsets
/// that a drift between runs would explain as well go to res.confounded and
/// res.notes instead.
void report_findings(const CandidateContext& ctx, const Selection& sel, ExplainResult& res);

/// Every candidate tested (detectability.cc): status, statistic and the
/// smallest amplitude the design can reveal (detection.h), against the final
/// model (without the candidate itself when it is in it) and its sigma.
std::vector<CandidateResult> candidate_results(const CandidateContext& ctx, const Selection& sel);

}  // namespace volmap::explanation
