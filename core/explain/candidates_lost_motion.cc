// Effects of the approach direction (docs/explain.md):
//   reversal K    p_b[K] s_K / 2                  value_um
//   servo_lag K   -p_b[K] (F / 1000) s_K          um_per_m_min
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/explain/candidate.h"
#include "core/explain/parameter_report.h"

namespace volmap::explanation {
namespace {

/// The report of a candidate of one coefficient `name`; explanation_of(value)
/// explains the fitted value.
template <typename ExplanationOf>
auto one_coefficient_report(const char* name, ExplanationOf explanation_of) {
  return [name, explanation_of](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double,
                                double, Finding& f) {
    report_one_parameter(name, beta, cov, f);
    f.explanation = explanation_of(beta[0]);
  };
}

Candidate reversal_candidate(const Observations& obs, AxisName k, const Eigen::VectorXd& along_k) {
  Candidate rev{.effect = "reversal", .axis = k};
  rev.build = [&obs, k, along_k](double) {
    return one_column(obs, [&](Eigen::Index e) {
      return along_k[e] * 0.5 * obs.approach(k, obs.recording_row[static_cast<std::size_t>(e)]);
    });
  };
  rev.report = one_coefficient_report("value_um", [k](double value_um) {
    return fmt::format(
        "{0} deviates {1:.3g} µm {2} when approached from +{0} than from -{0} (reversal value "
        "B = {3:.3g} µm): "
        "lost motion (backlash) in the {0} drive, absent from the rigid-body model.",
        axis_letter(k), std::abs(value_um), value_um >= 0 ? "more" : "less", value_um);
  });
  plot_against_position(rev, obs, k);
  rev.plot_group = [&obs, k](int i) { return obs.approach(k, i); };
  return rev;
}

Candidate servo_lag_candidate(const Observations& obs, AxisName k, const Eigen::VectorXd& along_k) {
  Candidate sl{.effect = "servo_lag", .axis = k};
  sl.amplitude_unit = "um_per_m_min";
  sl.build = [&obs, k, along_k](double) {
    return one_column(obs, [&](Eigen::Index e) {
      const int i = obs.recording_row[static_cast<std::size_t>(e)];
      return -along_k[e] * obs.feed_mm_per_min(i) / 1000.0 * obs.moving(k, i);
    });
  };
  sl.report = one_coefficient_report("um_per_m_min", [k](double um_per_m_min) {
    return fmt::format(
        "{0} lags {1:.3g} µm behind the command per m/min of feed, against the direction of "
        "motion: "
        "servo mismatch / following error, which grows with feed and is absent at "
        "standstill.",
        axis_letter(k), um_per_m_min);
  });
  sl.plot_x = [&obs, k](int i) { return obs.feed_mm_per_min(i) * obs.moving(k, i); };
  sl.plot_label = "feed_mm_min * " + dir_column_name(k);
  return sl;
}

}  // namespace

void add_lost_motion_candidates(const CandidateContext& c, AxisName k,
                                const Eigen::VectorXd& along_k, std::vector<Candidate>& out) {
  if (std::find(c.bidirectional_axes.begin(), c.bidirectional_axes.end(), k) ==
      c.bidirectional_axes.end())
    return;
  out.push_back(reversal_candidate(c.obs, k, along_k));
  if (c.has_feed) out.push_back(servo_lag_candidate(c.obs, k, along_k));
}

}  // namespace volmap::explanation
