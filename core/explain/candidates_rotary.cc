// Rotary axes (docs/explain.md), order n = 1..4 scanned:
//   rotary_wobble R       tilts perpendicular to R, (cos, sin)(n theta)
//   rotary_positioning R  own angular error, (sin, cos)(n theta)
// error_gain is mm per rad; the parameters are urad, the columns um per
// urad: 1e-3.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/explain/candidate.h"
#include "core/explain/parameter_report.h"

namespace volmap::explanation {
namespace {

/// Order, amplitude and phase of a (sin, cos) pair of order n; returns the amplitude.
double report_order_amplitude(const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double order,
                              Finding& f) {
  double amp = 0, amp_se = 0, phase = 0;
  amplitude_phase(beta, cov, 0, 1, amp, amp_se, phase);
  f.parameters = {{"order", static_cast<int>(order)},
                  {"amplitude_urad", json_number(amp)},
                  {"phase_deg", json_number(phase)}};
  f.std_errors = {{"amplitude_urad", amp_se}};
  return amp;
}

/// Columns (n x 2) of order n of R's angle: set_row(e, n theta_e, row) fills
/// equation e's row.
template <typename SetRow>
Eigen::MatrixXd harmonic_columns(const Observations& obs, AxisName rax, double order,
                                 SetRow set_row) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  Eigen::MatrixXd C(n, 2);
  for (Eigen::Index e = 0; e < n; ++e)
    set_row(e, order * obs.position(rax, obs.recording_row[static_cast<std::size_t>(e)]), C.row(e));
  return C;
}

/// A rotary candidate of order 1..4; explanation_format: its explanation,
/// of the axis ({0}), the amplitude in urad ({1}) and the order ({2}).
Candidate rotary_candidate(const Observations& obs, const std::string& effect, AxisName rax,
                           const char* explanation_format) {
  Candidate cand{.effect = effect, .axis = rax, .grid = {1, 2, 3, 4}, .nonlinear = 1};
  cand.amplitude = Candidate::Amplitude::kPair;
  cand.amplitude_unit = "urad";
  cand.report = [rax, explanation_format](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov,
                                          double order, double, Finding& f) {
    const double amp = report_order_amplitude(beta, cov, order, f);
    f.explanation = fmt::format(fmt::runtime(explanation_format), axis_letter(rax), amp,
                                static_cast<int>(order));
  };
  plot_against_position(cand, obs, rax);
  return cand;
}

Candidate wobble_candidate(const Observations& obs, AxisName rax, const int (&perp)[2]) {
  Candidate wob = rotary_candidate(
      obs, "rotary_wobble", rax,
      "The {0} axis tilts by {1:.3g} µrad, {2} times per turn: an angle-dependent error "
      "motion "
      "(wobble, ISO 230-7) of the {0} bearing, beyond the constant tilts of the location "
      "errors.");
  const int perp_a = perp[0], perp_b = perp[1];
  wob.build = [&obs, rax, perp_a, perp_b](double order) {
    return harmonic_columns(obs, rax, order, [&](Eigen::Index e, double th, auto row) {
      const double ga = obs.error_gain(e, perp_a) * 1e-3, gb = obs.error_gain(e, perp_b) * 1e-3;
      // EA = a cos - b sin, EB = b cos + a sin  (amplitude (a, b) = A (cos phi, sin phi))
      row << ga * std::cos(th) + gb * std::sin(th), -ga * std::sin(th) + gb * std::cos(th);
    });
  };
  return wob;
}

Candidate positioning_candidate(const Observations& obs, AxisName rax, int own_error) {
  Candidate pos = rotary_candidate(
      obs, "rotary_positioning", rax,
      "The {0} axis mispositions by {1:.3g} µrad, {2} times per turn: an angular positioning "
      "error of {0} "
      "(encoder or gear eccentricity) that varies with the angle.");
  pos.build = [&obs, rax, own_error](double order) {
    return harmonic_columns(obs, rax, order, [&](Eigen::Index e, double th, auto row) {
      const double g = obs.error_gain(e, own_error) * 1e-3;
      row << g * std::sin(th), g * std::cos(th);
    });
  };
  return pos;
}

}  // namespace

void add_rotary_candidates(const CandidateContext& c, std::vector<Candidate>& out) {
  const Observations& obs = c.obs;
  for (AxisName rax : c.rotary_axes) {
    // The angular errors of R: its own (positioning) and the two tilts.
    const int own = static_cast<int>(rax) - 3;
    int perp[2] = {-1, -1}, self = -1;
    int np = 0;
    for (int comp = 0; comp < 3; ++comp) {
      const std::string name = component_error_name(static_cast<Component>(comp + 3), rax);
      const auto it = std::find(obs.error_names.begin(), obs.error_names.end(), name);
      const int idx =
          it == obs.error_names.end() ? -1 : static_cast<int>(it - obs.error_names.begin());
      if (comp == own)
        self = idx;
      else
        perp[np++] = idx;
    }
    if (perp[0] >= 0 && perp[1] >= 0) out.push_back(wobble_candidate(obs, rax, perp));
    if (self >= 0) out.push_back(positioning_candidate(obs, rax, self));
  }
}

}  // namespace volmap::explanation
