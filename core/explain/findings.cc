// The findings from the final model (findings.h).
#include "core/explain/findings.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/explain/confounding.h"
#include "core/explain/parameter_report.h"

namespace volmap::explanation {
namespace {

/// Coefficients (physical units) and their covariance of one selected block.
struct BlockEstimate {
  Eigen::VectorXd beta;
  Eigen::MatrixXd cov;
};

BlockEstimate block_estimate(const LinearModel& model, const Eigen::MatrixXd& Ginv, double sigma2,
                             const SelectedEffect& s) {
  const Eigen::Index kc = s.fitted.block.cols.cols();
  Eigen::VectorXd beta(kc);
  Eigen::MatrixXd cov(kc, kc);
  for (Eigen::Index a = 0; a < kc; ++a) {
    beta[a] = model.beta[s.first_col + a] * model.scale[s.first_col + a];
    for (Eigen::Index b = 0; b < kc; ++b)
      cov(a, b) = sigma2 * Ginv(s.first_col + a, s.first_col + b) * model.scale[s.first_col + a] *
                  model.scale[s.first_col + b];
  }
  return {beta, cov};
}

// A candidate with a fitted nonlinear parameter (tau_s, period_mm): the
// covariance of the whole fit by Gauss-Newton, the model's columns beside
// the derivative of the candidate's fitted term with respect to theta, so
// that the amplitudes' standard errors carry theta's uncertainty (they are
// correlated: a longer tau trades against a larger amplitude). Returns
// theta's standard error and replaces est.cov; NaN and est unchanged when
// the candidate has no refined parameter or the derivative vanishes.
double with_nonlinear_uncertainty(const Observations& obs, const LinearModel& model, double sigma2,
                                  const SelectedEffect& s, BlockEstimate& est) {
  const Candidate& c = *s.fitted.cand;
  if (!c.refine) return std::nan("");
  const double th = s.fitted.theta, h = std::abs(th) * 1e-4;
  const Eigen::MatrixXd dC = (c.build(th + h) - c.build(th - h)) / (2 * h);
  Eigen::VectorXd d = (dC * est.beta).cwiseProduct(obs.sqrt_weight);
  const double d_rms = std::sqrt(d.squaredNorm() / static_cast<double>(obs.count));
  if (!(d_rms > 0)) return std::nan("");
  d /= d_rms;
  const Eigen::Index k = model.k();
  Eigen::MatrixXd J(model.X.rows(), k + 1);
  J.leftCols(k) = model.X;
  J.col(k) = d;
  Eigen::MatrixXd G = J.transpose() * J;
  G.diagonal().array() += ridge_of(obs);
  const Eigen::MatrixXd Ginv = G.ldlt().solve(Eigen::MatrixXd::Identity(k + 1, k + 1));
  const Eigen::Index kc = s.fitted.block.cols.cols();
  for (Eigen::Index a = 0; a < kc; ++a)
    for (Eigen::Index b = 0; b < kc; ++b)
      est.cov(a, b) = sigma2 * Ginv(s.first_col + a, s.first_col + b) *
                      model.scale[s.first_col + a] * model.scale[s.first_col + b];
  return std::sqrt(sigma2 * Ginv(k, k)) / d_rms;
}

// Plot: partial residual (final residual + this term) before, final residual after.
ExplainPlot partial_residual_plot(const Observations& obs, const LinearModel& model,
                                  const SelectedEffect& s) {
  const Candidate& c = *s.fitted.cand;
  const Eigen::Index kc = s.fitted.block.cols.cols();
  ExplainPlot plot;
  plot.regressor = c.plot_label;
  const Eigen::VectorXd contrib =
      model.X.middleCols(s.first_col, kc) * model.beta.segment(s.first_col, kc);
  const std::size_t stride = std::max<std::size_t>(1, obs.count / 1500);
  for (std::size_t e = 0; e < obs.count; e += stride) {
    const Eigen::Index ei = static_cast<Eigen::Index>(e);
    if (obs.sqrt_weight[ei] <= 0) continue;
    plot.x.push_back(c.plot_x(obs.recording_row[e]));
    plot.after_um.push_back(model.r[ei] / obs.sqrt_weight[ei]);
    plot.before_um.push_back((model.r[ei] + contrib[ei]) / obs.sqrt_weight[ei]);
    if (c.plot_group) plot.group.push_back(c.plot_group(obs.recording_row[e]));
  }
  return plot;
}

// The same effect on two axes with one signature: the finding is this
// axis's value less the other's. For servo lag on a circular test that is
// the servo mismatch, which ballbar software quotes in milliseconds: a lag of
// c um per m/min is a time constant of c / (1000 um/mm * 1000 mm/min / 60 s)
// = 0.06 c ms.
void relative_finding(AxisName other, bool sum, Finding& f) {
  f.parameters.push_back({sum ? "plus_axis" : "relative_to_axis", axis_letter(other)});
  const std::string k = f.axis ? axis_letter(*f.axis) : std::string("-");
  f.explanation += fmt::format(
      " This recording shows only the {2} of {0} and {1} ({3} signatures on both axes): the "
      "value is {0}'s {4} {1}'s.",
      k, axis_letter(other), sum ? "sum" : "difference", sum ? "equal" : "opposite",
      sum ? "plus" : "less");
  if (f.effect != "servo_lag" || sum) return;
  double c = f.parameters.front().second.get<double>();
  double se = 0;
  for (const auto& [name, v] : f.std_errors)
    if (name == "um_per_m_min") se = v;
  // Named on the axis that lags, with a positive lag relative to the other.
  std::string late = k, early = axis_letter(other);
  if (c < 0 && f.axis) {
    std::swap(late, early);
    const AxisName lagging = other;
    f.parameters.front().second = json_number(-c);
    for (auto& [name, v] : f.parameters)
      if (name == "relative_to_axis") v = axis_letter(*f.axis);
    f.axis = lagging;
    c = -c;
  }
  f.parameters.push_back({"mismatch_ms", json_number(0.06 * c)});
  f.std_errors.push_back({"mismatch_ms", 0.06 * se});
  f.explanation = fmt::format(
      "{0} lags {1:.3g} µm per m/min of feed more than {2}: servo mismatch, {0} responds {3:.3g} "
      "ms later than {2}. On a circular test (ISO 230-4) an ellipse along the diagonals that turns "
      "with the direction of travel; the circle shows the difference of the two axes' lags, not "
      "each.",
      late, c, early, 0.06 * c);
}

Finding finding_of(const Observations& obs, const LinearModel& model, const Eigen::MatrixXd& Ginv,
                   double sigma2, const SelectedEffect& s) {
  const Candidate& c = *s.fitted.cand;
  BlockEstimate est = block_estimate(model, Ginv, sigma2, s);
  const double theta_se = with_nonlinear_uncertainty(obs, model, sigma2, s, est);
  Finding f;
  f.effect = c.effect;
  f.axis = c.axis;
  c.report(est.beta, est.cov, s.fitted.theta, theta_se, f);
  f.rms_before_um = s.rms_before_um;
  f.rms_after_um = s.rms_after_um;
  f.heldout_rms_before_um = s.heldout_before_um;
  f.heldout_rms_after_um = s.heldout_after_um;
  f.delta_bic = s.delta_bic;
  f.plot = partial_residual_plot(obs, model, s);
  if (s.relative_to) relative_finding(*s.relative_to, s.relative_is_sum, f);
  return f;
}

// Per-run offsets that change monotonically in run order without a time
// column: confounded, not guessed. The pair is reported, not a finding; the
// per-run offsets stay in the final model (they are real).
void report_shift_or_drift(Finding& f, ExplainResult& res) {
  const nlohmann::json& per = f.parameters.front().second;
  f.explanation +=
      " The offsets change monotonically in run order and the recording has no time column: "
      "a "
      "slow drift between runs would look the same.";
  res.confounded.push_back(shift_or_drift_between_runs(f.axis));
  double largest_um = 0;
  for (const auto& v : per) largest_um = std::max(largest_um, std::abs(v.get<double>()));
  res.notes.push_back(
      fmt::format("per-run offsets of {} are in the final model (largest {:.3g} µm); set-up "
                  "shift or drift, see "
                  "confounded",
                  f.axis ? axis_letter(*f.axis) : std::string("-"), largest_um));
}

}  // namespace

void report_findings(const CandidateContext& ctx, const Selection& sel, ExplainResult& res) {
  const Observations& obs = ctx.obs;
  const LinearModel& model = sel.model;
  // Parameters from the final model; covariance sigma^2 (X^T X)^-1.
  const double sigma2 =
      model.rss / std::max(1.0, static_cast<double>(obs.count) - static_cast<double>(model.k()));
  Eigen::MatrixXd G = model.X.transpose() * model.X;
  G.diagonal().array() += ridge_of(obs);
  const Eigen::MatrixXd Ginv = G.ldlt().solve(Eigen::MatrixXd::Identity(G.rows(), G.cols()));
  for (const SelectedEffect& s : sel.chosen) {
    if (s.confounded) continue;
    Finding f = finding_of(obs, model, Ginv, sigma2, s);
    if (f.effect == "setup_shift" && !ctx.has_time && obs.run_count >= 3 &&
        monotonic_in_run_order(f.parameters.front().second)) {
      report_shift_or_drift(f, res);
      continue;
    }
    res.findings.push_back(std::move(f));
  }
}

}  // namespace volmap::explanation
