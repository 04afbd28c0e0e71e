// Selection (docs/explain.md): forward, one effect per step, the best by
// BIC first; a step must pass the likelihood-ratio test of detection.h at
// the family-wise level kFamilyAlpha (look-elsewhere and the number of
// candidates corrected for) and, when the recording has two runs or more,
// lower the leave-one-run-out RMS. Candidates whose columns
// the current model already spans are not estimable here; candidates that
// explain the same structure as the best one (fitted values correlated
// > 0.98, a BIC within the selection margin) are reported as confounded,
// not as a finding. Then a backward check: every finding must still hold up
// in the final model by the same two tests.
#pragma once

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/explain/candidate.h"
#include "core/explain/candidate_fit.h"
#include "core/explain/detection.h"
#include "core/explain/linear_model.h"

namespace volmap::explanation {

/// An effect the selection took, with its evidence at the step it entered.
struct SelectedEffect {
  FittedCandidate fitted;
  bool confounded = false;  ///< another effect explains the same structure
  /// The same effect on this axis gives the same structure: the finding is
  /// the difference of the two (servo mismatch on a circle).
  std::optional<AxisName> relative_to;
  bool relative_is_sum = false;  ///< the signatures are equal (a sum), not opposite
  double rms_before_um = 0, rms_after_um = 0;
  std::optional<double> heldout_before_um, heldout_after_um;
  double delta_bic = 0;
  Eigen::Index first_col = 0;  ///< its columns in the final model
};

/// The test of one candidate at the last step it was tried (its entry step
/// when it became a finding).
struct CandidateTest {
  const Candidate* cand = nullptr;
  double theta = 0;       ///< its fitted nonlinear parameter
  double chi2 = 0;        ///< likelihood-ratio statistic
  double p_value = 1;     ///< corrected (look-elsewhere and family)
  TestDesign design;      ///< how it was tested
  bool taken = false;     ///< entered the model (finding or confounded)
  bool estimable = true;  ///< false: the model already spans its columns
};

struct Selection {
  LinearModel model;  ///< the final model, fitted
  std::optional<double> heldout_rms_um;
  std::vector<SelectedEffect> chosen;
  std::vector<CandidateTest> tests;  ///< every candidate tried, in candidate order
  double first_family = 1;           ///< candidates tried in the first step
};

/// Runs the forward selection from the fitted baseline, then the backward
/// check. Appends the confounded pairs it finds to `confounded`.
Selection select_effects(const CandidateContext& ctx, const std::vector<Candidate>& cands,
                         LinearModel baseline, std::optional<double> baseline_heldout_rms_um,
                         const std::set<std::string>& design_blocked,
                         std::vector<Confounded>& confounded);

}  // namespace volmap::explanation
