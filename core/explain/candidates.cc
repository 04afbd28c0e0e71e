// Every candidate the recording can support, in a fixed order (the order
// breaks ties in the selection): per deflecting axis cyclic, reversal and
// servo lag, thermal drift, setup shift; then sag; then the rotary axes;
// then, with a fixed baseline, the geometric errors it lacks.
#include <algorithm>
#include <cmath>

#include "core/explain/candidate.h"
#include "core/explain/distinct_values.h"
#include "core/explain/parameter_report.h"

namespace volmap::explanation {

CandidateContext candidate_context(const Observations& obs, const ExplainOptions& options) {
  const Recordings& rec = obs.recordings;
  CandidateContext ctx{obs, options, {}, {}, {}};
  for (AxisName a : obs.machine.axis_order) {
    if (!rec.has_axis(a) || !varies(rec.position[static_cast<std::size_t>(a)])) continue;
    (is_rotary(a) ? ctx.rotary_axes : ctx.linear_axes).push_back(a);
    bool plus = false, minus = false;
    for (std::int8_t s : rec.dir[static_cast<std::size_t>(a)]) {
      plus = plus || s > 0;
      minus = minus || s < 0;
    }
    if (plus && minus && !is_rotary(a)) ctx.bidirectional_axes.push_back(a);
  }
  ctx.has_time =
      !rec.t_s.empty() && varies(rec.t_s) &&
      std::all_of(rec.t_s.begin(), rec.t_s.end(), [](double t) { return std::isfinite(t); });
  if (ctx.has_time) ctx.duration_s = *std::max_element(rec.t_s.begin(), rec.t_s.end());
  ctx.has_feed = !rec.feed_mm_min.empty() && varies(rec.feed_mm_min);
  if (!rec.feed_mm_min.empty() && !ctx.has_feed) {
    // one feed: servo lag is indistinguishable from lost motion
    bool any = false;
    for (double f : rec.feed_mm_min) any = any || (std::isfinite(f) && f > 0);
    ctx.has_feed = any;
  }
  return ctx;
}

void plot_against_position(Candidate& cand, const Observations& obs, AxisName a) {
  cand.plot_x = [&obs, a](int i) { return obs.reported_position(a, i); };
  cand.plot_label = position_column_name(a);
}

void report_one_parameter(const std::string& name, const Eigen::VectorXd& beta,
                          const Eigen::MatrixXd& cov, Finding& f) {
  f.parameters = {{name, json_number(beta[0])}};
  f.std_errors = {{name, std::sqrt(cov(0, 0))}};
}

std::vector<Candidate> make_candidates(const CandidateContext& c) {
  const Observations& obs = c.obs;
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  std::vector<Candidate> out;
  auto along = [&](AxisName k) {  // p_b[K] per equation
    Eigen::VectorXd v(n);
    for (Eigen::Index e = 0; e < n; ++e) v[e] = obs.direction_base(static_cast<int>(k), e);
    return v;
  };
  auto has_along = [&](AxisName k) { return along(k).cwiseAbs().maxCoeff() > 1e-9; };

  // Every linear axis of the machine may deflect (the recording need not move it).
  std::vector<AxisName> deflecting;
  for (AxisName a : obs.machine.axis_order)
    if (!is_rotary(a)) deflecting.push_back(a);
  const auto moves = [&](AxisName a) {
    return std::find(c.linear_axes.begin(), c.linear_axes.end(), a) != c.linear_axes.end();
  };
  for (AxisName k : deflecting) {
    if (!has_along(k)) continue;
    const Eigen::VectorXd along_k = along(k);
    add_cyclic_candidate(c, k, along_k, out);
    add_lost_motion_candidates(c, k, along_k, out);
    add_thermal_drift_candidates(c, k, moves(k), along_k, out);
    add_setup_shift_candidate(c, k, along_k, out);
  }
  // sag: K deflects with the position of another axis J, quadratically.
  for (AxisName k : deflecting) {
    if (!has_along(k)) continue;
    add_sag_candidates(c, k, along(k), out);
  }
  add_rotary_candidates(c, out);
  add_geometric_candidates(c, out);
  return out;
}

}  // namespace volmap::explanation
