// `volmap explain` (explain.h): locate the mismatch, fit every candidate
// effect, select forward on BIC and held-out runs, report confounding.
// docs/explain.md describes the method; each step has its own file.
#include "core/explain/explain.h"

#include <fmt/format.h>

#include <stdexcept>

#include "core/explain/baseline_model.h"
#include "core/explain/candidate.h"
#include "core/explain/circular.h"
#include "core/explain/confounding.h"
#include "core/explain/findings.h"
#include "core/explain/linear_model.h"
#include "core/explain/locate.h"
#include "core/explain/observations.h"
#include "core/explain/selection.h"

namespace volmap {
namespace {

using namespace explanation;

/// Baseline residuals (um per equation, unweighted) for locate.
Eigen::VectorXd residual_um(const Observations& obs, const LinearModel& model) {
  Eigen::VectorXd r_um(static_cast<Eigen::Index>(obs.count));
  for (Eigen::Index e = 0; e < r_um.size(); ++e)
    r_um[e] = obs.sqrt_weight[e] > 0 ? model.r[e] / obs.sqrt_weight[e] : 0.0;
  return r_um;
}

// Translational location errors of rotary axes (the position of the
// axis line, ISO 230-7) have no effect name in explain.md: when the
// fixed baseline lacks one that the recording sees, say so, since
// findings may stand in for it.
std::string rotary_lines_missing_from_baseline(const Observations& obs, const ErrorSet& baseline) {
  std::string missing;
  for (std::size_t idx = 0; idx < obs.error_names.size(); ++idx) {
    const std::optional<ErrorName> en = parse_error_name(obs.error_names[idx]);
    if (!en || !en->location || is_angular(en->component) || !is_rotary(en->axis)) continue;
    if (baseline.location.count(obs.error_names[idx])) continue;
    if (obs.error_gain.col(static_cast<Eigen::Index>(idx)).cwiseAbs().maxCoeff() < 1e-12) continue;
    missing += (missing.empty() ? "" : ", ") + obs.error_names[idx];
  }
  return missing;
}

/// The test that would reveal an effect this recording's design cannot.
std::string revealing_test(const std::string& effect) {
  if (effect == "reversal")
    return "approach every target from both sides (ISO 230-2 bidirectional run)";
  if (effect == "servo_lag") return "run the test at two feeds or more, in both directions";
  if (effect == "thermal_drift")
    return "return to the same targets over time (a return sweep, repeated runs) or record a "
           "temperature";
  if (effect == "cyclic")
    return "sample the axis at least 2.2 points per period over three periods";
  if (effect == "sag")
    return "record the deflecting axis at several positions of the input axis, against a fixed "
           "baseline (`--baseline`): a fitted baseline's straightness takes up any deflection "
           "that depends on one axis";
  if (effect == "setup_shift") return "repeat the run, keeping the set-up between runs";
  if (effect == "rotary_wobble" || effect == "rotary_positioning")
    return "turn the axis through a full revolution at 8 angles or more";
  return "move the axis over its travel and record the direction the error deflects";
}

/// Candidates tested whose amplitude no design direction can show
/// (||P_perp g|| ~ 0 for the least visible amplitude): said, with the test
/// that would.
void design_blind_notes(ExplainResult& res) {
  for (const CandidateResult& c : res.candidates) {
    if (c.status == "not estimable" || c.detectable) continue;
    res.notes.push_back(fmt::format(
        "{}{}{}: this recording's design cannot reveal it (its amplitude leaves no trace "
        "beyond the model); to test it, {}",
        c.effect, c.axis ? " " + axis_letter(*c.axis) : "",
        c.variant.empty() ? "" : " (" + c.variant + ")", revealing_test(c.effect)));
  }
}

void add_notes(const CandidateContext& ctx, ExplainResult& res) {
  const ExplainOptions& opt = ctx.options;
  if (opt.machine_assumed && !ctx.rotary_axes.empty())
    res.notes.push_back(
        "no `machine`: the rotary axes were taken to turn the workpiece about lines through the "
        "origin along X, Y or Z, so effects of the rotary axes (wobble, positioning, a sag driven "
        "by a rotary angle) were not tried; give the machine that made the recording for them");
  for (const CandidateResult& c : res.candidates)
    if (c.status == "not estimable")
      res.notes.push_back(fmt::format(
          "{}{}{}: not estimable on this recording (the baseline already spans its columns); to "
          "test it, {}",
          c.effect, c.axis ? " " + axis_letter(*c.axis) : "",
          c.variant.empty() ? "" : " (" + c.variant + ")", revealing_test(c.effect)));
  design_blind_notes(res);
  if (opt.baseline) {
    const std::string missing = rotary_lines_missing_from_baseline(ctx.obs, *opt.baseline);
    if (!missing.empty())
      res.notes.push_back(
          "the baseline lacks " + missing +
          " (the position of a rotary axis line), which explain does not fit; findings on rotary "
          "axes may stand in for them: add them to the baseline, or explain without `baseline`");
  }
}

}  // namespace

ExplainResult explain(const Machine& m, const Recordings& rec, const ExplainOptions& opt) {
  if (opt.degree < 0 || opt.degree > 12)
    throw std::invalid_argument("ExplainOptions::degree: expected 0 (automatic) or 1..12");
  ExplainResult res;
  res.recordings_file = rec.file;
  auto stage = [&](const char* what) {
    if (opt.progress) opt.progress(what, 0, 0);
  };
  stage("building the observations");
  const Observations obs = build_observations(m, rec, opt);
  res.observations = obs.count;
  res.runs = static_cast<std::size_t>(obs.run_count);
  const CandidateContext ctx = candidate_context(obs, opt);

  stage("fitting the baseline");
  LinearModel baseline = baseline_model(obs, opt, res.baseline_description);
  fit(obs, baseline);
  res.baseline_rms_um = rms_of(obs, baseline.rss);
  res.baseline_heldout_rms_um = heldout_rms(obs, baseline);
  // Locate: baseline residuals (um) against every regressor.
  res.mismatch = locate_mismatch(obs, residual_um(obs, baseline));

  const std::vector<Candidate> cands = make_candidates(ctx);
  const std::set<std::string> design_blocked = design_confounding(ctx, res.confounded);
  const Selection sel = select_effects(ctx, cands, std::move(baseline), res.baseline_heldout_rms_um,
                                       design_blocked, res.confounded);
  stage("reporting the findings");
  res.final_rms_um = rms_of(obs, sel.model.rss);
  res.final_heldout_rms_um = sel.heldout_rms_um;
  report_findings(ctx, sel, res);
  res.candidates = candidate_results(ctx, sel);
  res.circular_tests = circular_tests(obs, obs.deviation_um, residual_um(obs, sel.model));
  add_notes(ctx, res);
  return res;
}

}  // namespace volmap
