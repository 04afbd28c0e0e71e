// cyclic K: p_b[K] (sin, cos)(2 pi q_K / period_mm), the period by scan and
// refinement (docs/explain.md).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/explain/candidate.h"
#include "core/explain/distinct_values.h"
#include "core/explain/parameter_report.h"

namespace volmap::explanation {

void add_cyclic_candidate(const CandidateContext& c, AxisName k, const Eigen::VectorXd& along_k,
                          std::vector<Candidate>& out) {
  const Observations& obs = c.obs;
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  // Period scan over the sampled positions.
  std::vector<double> positions;
  for (std::size_t i = 0; i < obs.recordings.size(); ++i)
    positions.push_back(obs.position(k, static_cast<int>(i)));
  const std::vector<double> distinct = unique_sorted(positions);
  if (distinct.size() < 8) return;
  std::vector<double> gaps;
  for (std::size_t i = 1; i < distinct.size(); ++i) gaps.push_back(distinct[i] - distinct[i - 1]);
  std::sort(gaps.begin(), gaps.end());
  const double gap = gaps[gaps.size() / 2];
  const double span = distinct.back() - distinct.front();
  // At least three periods over the span: a longer 'period' is smooth geometry.
  const double p_min = std::max(2.2 * gap, 1e-3), p_max = span / 3.0;
  if (!(p_max > 1.5 * p_min)) return;  // too few positions per period to scan a period at all
  Candidate cand{.effect = "cyclic", .axis = k, .variant = "", .refine = true, .nonlinear = 1};
  cand.amplitude = Candidate::Amplitude::kPair;
  const double f_lo = 1.0 / p_max, f_hi = 1.0 / p_min;
  const double df = std::max(1.0 / (4.0 * span), (f_hi - f_lo) / 600.0);
  for (double f = f_lo; f <= f_hi; f += df) cand.grid.push_back(1.0 / f);
  // Look-elsewhere path (detection.h) in closed form: d/df of (sin, cos)(2 pi f q)
  // is 2 pi q times the other column; the part q_mean lies in the span, so the
  // span turns at 2 pi sigma_q per unit of frequency (sigma_q the weighted
  // spread of the positions along the columns): L = 2 pi sigma_q (f_hi - f_lo).
  // tests/explain/detection_test.cc checks it against the walked path.
  double w_sum = 0, q_sum = 0, q2_sum = 0;
  for (Eigen::Index e = 0; e < n; ++e) {
    const double w = along_k[e] * along_k[e] * obs.sqrt_weight[e] * obs.sqrt_weight[e];
    const double q = obs.position(k, obs.recording_row[static_cast<std::size_t>(e)]);
    w_sum += w;
    q_sum += w * q;
    q2_sum += w * q * q;
  }
  const double sigma_q =
      w_sum > 0 ? std::sqrt(std::max(0.0, q2_sum / w_sum - (q_sum / w_sum) * (q_sum / w_sum))) : 0;
  const double scanned = 1.0 / cand.grid.back() - 1.0 / cand.grid.front();
  cand.path_length = [sigma_q, scanned] { return 2 * std::numbers::pi * sigma_q * scanned; };
  cand.build = [&obs, k, along_k, n](double period_mm) {
    Eigen::MatrixXd C(n, 2);
    for (Eigen::Index e = 0; e < n; ++e) {
      const double phase_rad = 2 * std::numbers::pi *
                               obs.position(k, obs.recording_row[static_cast<std::size_t>(e)]) /
                               period_mm;
      C(e, 0) = along_k[e] * std::sin(phase_rad);
      C(e, 1) = along_k[e] * std::cos(phase_rad);
    }
    return C;
  };
  cand.report = [k](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double period_mm,
                    double period_se, Finding& f) {
    double amp = 0, amp_se = 0, phase = 0;
    amplitude_phase(beta, cov, 0, 1, amp, amp_se, phase);
    f.parameters = {{"period_mm", json_number(period_mm)},
                    {"amplitude_um", json_number(amp)},
                    {"phase_deg", json_number(phase)}};
    f.std_errors = {{"period_mm", period_se}, {"amplitude_um", amp_se}};
    f.explanation = fmt::format(
        "{0} deviates periodically along {0} with a period of {1:.4g} mm and an amplitude "
        "of {2:.3g} µm: "
        "a screw-pitch or scale/encoder interpolation error, which a smooth polynomial "
        "cannot follow.",
        axis_letter(k), period_mm, amp);
  };
  plot_against_position(cand, obs, k);
  out.push_back(cand);
}

}  // namespace volmap::explanation
