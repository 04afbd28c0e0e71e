// Confounding (confounding.h).
#include "core/explain/confounding.h"

#include <fmt/format.h>

#include <cmath>

#include "core/explain/linear_model.h"

namespace volmap::explanation {
namespace {

constexpr double kDesignCorrelation = 0.95;

/// Correlation of time and the position of k within runs (each run about
/// its own means).
double time_position_correlation(const Observations& obs, AxisName k) {
  const std::size_t runs = static_cast<std::size_t>(obs.run_count);
  std::vector<double> time_sum_s(runs, 0), position_sum(runs, 0), count(runs, 0);
  for (std::size_t e = 0; e < obs.count; ++e) {
    const std::size_t r = static_cast<std::size_t>(obs.run[e]);
    time_sum_s[r] += obs.time_s(obs.recording_row[e]);
    position_sum[r] += obs.position(k, obs.recording_row[e]);
    count[r] += 1;
  }
  double s_tq = 0, s_tt = 0, s_qq = 0;
  for (std::size_t e = 0; e < obs.count; ++e) {
    const std::size_t r = static_cast<std::size_t>(obs.run[e]);
    const double dt = obs.time_s(obs.recording_row[e]) - time_sum_s[r] / count[r],
                 dq = obs.position(k, obs.recording_row[e]) - position_sum[r] / count[r];
    s_tq += dt * dq;
    s_tt += dt * dt;
    s_qq += dq * dq;
  }
  return s_tt > 0 && s_qq > 0 ? s_tq / std::sqrt(s_tt * s_qq) : 0.0;
}

}  // namespace

std::string remedy_for(const std::string& a, const std::string& b) {
  auto has = [&](const std::string& x) { return a == x || b == x; };
  if (has("reversal") && has("servo_lag"))
    return "repeat the bidirectional run at a second, very different feed (or with a dwell before "
           "each reading): "
           "servo lag scales with feed, lost motion does not";
  if (has("thermal_drift") && has("setup_shift"))
    return "measure one reference target at the start and at the end of every run (and log the "
           "time of every "
           "reading): a drift moves within a run as well, a set-up shift only between runs";
  if (has("thermal_drift"))
    return "repeat the run in reverse order or add a return sweep, so that time and position no "
           "longer rise together";
  if (has("setup_shift"))
    return "repeat a run without touching the set-up, or measure a reference artefact at the start "
           "of every run";
  if (has("sag"))
    return "measure the deflecting axis at two positions of the other axes, or give the geometric "
           "errors as a "
           "fixed `baseline`";
  return "add test points where the two regressors do not move together (other axis positions, "
         "both directions, "
         "another order of the points)";
}

std::set<std::string> design_confounding(const CandidateContext& ctx,
                                         std::vector<Confounded>& confounded) {
  std::set<std::string> design_blocked;
  if (!ctx.has_time) return design_blocked;
  for (AxisName k : ctx.linear_axes) {
    const double rho = time_position_correlation(ctx.obs, k);
    if (std::abs(rho) > kDesignCorrelation) {
      design_blocked.insert(axis_letter(k));
      Confounded c;
      c.effects = {"thermal_drift", "scale"};
      c.axis = k;
      c.explanation = fmt::format(
          "time and {0} position {1} together in every run (correlation {2:.3f} within runs): a "
          "drift that grows "
          "with time and a scale error that grows with {0} give the same deviations on this "
          "recording",
          axis_letter(k), rho > 0 ? "rise" : "move opposite", rho);
      c.remedy = remedy_for("thermal_drift", "scale");
      confounded.push_back(c);
    }
  }
  return design_blocked;
}

Confounded same_structure(const Observations& obs, const FittedCandidate& f,
                          const FittedCandidate& g, double rho) {
  Confounded c;
  c.effects = {f.cand->effect, g.cand->effect};
  c.axis = f.cand->axis;
  const std::string fa = f.cand->axis ? axis_letter(*f.cand->axis) : "-";
  const std::string ga = g.cand->axis ? axis_letter(*g.cand->axis) : "-";
  c.explanation = fmt::format(
      "{} {} and {} {} explain the same structure on this recording (fitted deviations "
      "correlated {:.3f}, "
      "RMS {:.3g} vs {:.3g} µm): the recording cannot tell them apart",
      f.cand->effect, fa, g.cand->effect, ga, rho, rms_of(obs, f.gain.rss),
      rms_of(obs, g.gain.rss));
  if (f.cand->effect == "reversal" || g.cand->effect == "reversal")
    if (f.cand->effect == "servo_lag" || g.cand->effect == "servo_lag")
      c.explanation +=
          "; the recording has a single feed, so lost motion and lag both flip with "
          "direction";
  c.remedy = remedy_for(f.cand->effect, g.cand->effect);
  return c;
}

void add_confounded_once(std::vector<Confounded>& confounded, const Confounded& c) {
  bool dup = false;
  for (const Confounded& o : confounded)
    dup =
        dup || (o.axis == c.axis && std::set<std::string>(o.effects.begin(), o.effects.end()) ==
                                        std::set<std::string>(c.effects.begin(), c.effects.end()));
  if (!dup) confounded.push_back(c);
}

bool monotonic_in_run_order(const nlohmann::json& per_run_um) {
  bool up = true, down = true;
  for (std::size_t r = 1; r < per_run_um.size(); ++r) {
    up = up && per_run_um[r].get<double>() > per_run_um[r - 1].get<double>();
    down = down && per_run_um[r].get<double>() < per_run_um[r - 1].get<double>();
  }
  return up || down;
}

Confounded shift_or_drift_between_runs(const std::optional<AxisName>& axis) {
  Confounded cf;
  cf.effects = {"setup_shift", "thermal_drift"};
  cf.axis = axis;
  cf.explanation =
      "the per-run offsets grow monotonically with the run number and no t_s column records "
      "when "
      "the runs were made: a set-up that moved and a machine that drifted between runs give "
      "the "
      "same readings";
  cf.remedy = remedy_for("setup_shift", "thermal_drift");
  return cf;
}

}  // namespace volmap::explanation
