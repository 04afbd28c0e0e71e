// Effects of the approach direction (docs/explain.md):
//   reversal K            p_b[K] s_K / 2                  value_um
//   reversal K, spike     -p_b[K] s_K exp(-d_K / L)       value_um, length_mm (L scanned)
//   reversal K, lateral   p_b[K] s_J / 2 (J reverses)     value_um, input_axis
//   servo_lag K           -p_b[K] (F / 1000) m_K          um_per_m_min
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

/// The axis sticks at its reversal and catches up along the travel: a
/// spike against the new direction decaying with the distance d_K since the
/// reversal (reversal spikes of a circular test, static friction).
Candidate spike_candidate(const Observations& obs, AxisName k, const Eigen::VectorXd& along_k) {
  Candidate sp{.effect = "reversal",
               .axis = k,
               .variant = "spike",
               .refine = true,
               .log_refine = true,
               .nonlinear = 1};
  // decay lengths from a fraction of the smallest step between readings
  // to a quarter of the travel recorded
  double lo = INFINITY, hi = 0, first = INFINITY, last = -INFINITY;
  for (std::size_t i = 1; i < obs.recordings.size(); ++i) {
    const double step =
        std::abs(obs.position(k, static_cast<int>(i)) - obs.position(k, static_cast<int>(i) - 1));
    if (step > 1e-6) lo = std::min(lo, step);
  }
  for (std::size_t i = 0; i < obs.recordings.size(); ++i) {
    first = std::min(first, obs.position(k, static_cast<int>(i)));
    last = std::max(last, obs.position(k, static_cast<int>(i)));
  }
  hi = 0.25 * (last - first);
  if (!(std::isfinite(lo) && hi > 2 * lo)) return sp;
  lo *= 0.5;
  for (int j = 0; j <= 12; ++j) sp.grid.push_back(lo * std::pow(hi / lo, j / 12.0));
  sp.build = [&obs, k, along_k](double length_mm) {
    return one_column(obs, [&](Eigen::Index e) {
      const int i = obs.recording_row[static_cast<std::size_t>(e)];
      const double d = obs.since_reversal_mm(static_cast<int>(k), i);
      return std::isfinite(d) ? -along_k[e] * obs.approach(k, i) * std::exp(-d / length_mm) : 0.0;
    });
  };
  sp.report = [k](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double length_mm,
                  double length_se, Finding& f) {
    report_one_parameter("value_um", beta, cov, f);
    f.parameters.insert(f.parameters.begin(), {"kind", "spike"});
    f.parameters.push_back({"length_mm", json_number(length_mm)});
    f.std_errors.push_back({"length_mm", length_se});
    f.explanation = fmt::format(
        "{0} stays {1:.3g} µm behind just after each reversal and catches up over about "
        "{2:.3g} mm of travel: a reversal spike (static friction at the turn of the drive, "
        "the spikes at the quadrant points of a circular test).",
        axis_letter(k), beta[0], length_mm);
  };
  sp.plot_x = [&obs, k](int i) {
    const double d = obs.since_reversal_mm(static_cast<int>(k), i);
    return std::isfinite(d) ? d : NAN;
  };
  sp.plot_label = "distance since reversal " + axis_letter(k);
  sp.plot_group = [&obs, k](int i) { return obs.approach(k, i); };
  return sp;
}

/// K shifts when J reverses: play across J's guideway (lateral play).
Candidate lateral_candidate(const Observations& obs, AxisName k, AxisName j,
                            const Eigen::VectorXd& along_k) {
  Candidate lat{.effect = "reversal", .axis = k, .variant = "lateral/" + axis_letter(j)};
  lat.build = [&obs, j, along_k](double) {
    return one_column(obs, [&](Eigen::Index e) {
      return along_k[e] * 0.5 * obs.approach(j, obs.recording_row[static_cast<std::size_t>(e)]);
    });
  };
  lat.report = [k, j](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                      Finding& f) {
    report_one_parameter("value_um", beta, cov, f);
    f.parameters.insert(f.parameters.begin(), {"kind", "lateral"});
    f.parameters.push_back({"input_axis", axis_letter(j)});
    f.explanation = fmt::format(
        "{0} sits {1:.3g} µm further along {0} when {2} is approached from +{2} than from "
        "-{2}: lateral play, {2}'s carriage shifting across its guideway when it reverses.",
        axis_letter(k), beta[0], axis_letter(j));
  };
  plot_against_position(lat, obs, j);
  lat.plot_group = [&obs, j](int i) { return obs.approach(j, i); };
  return lat;
}

}  // namespace

void add_lost_motion_candidates(const CandidateContext& c, AxisName k,
                                const Eigen::VectorXd& along_k, std::vector<Candidate>& out) {
  for (AxisName j : c.bidirectional_axes)
    if (j != k && !is_rotary(j)) out.push_back(lateral_candidate(c.obs, k, j, along_k));
  if (std::find(c.bidirectional_axes.begin(), c.bidirectional_axes.end(), k) ==
      c.bidirectional_axes.end())
    return;
  out.push_back(reversal_candidate(c.obs, k, along_k));
  Candidate spike = spike_candidate(c.obs, k, along_k);
  if (!spike.grid.empty()) out.push_back(std::move(spike));
  if (c.has_feed) out.push_back(servo_lag_candidate(c.obs, k, along_k));
}

}  // namespace volmap::explanation
