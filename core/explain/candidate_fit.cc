// The fit of one candidate (candidate_fit.h).
#include "core/explain/candidate_fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>

#include "core/common/golden_section.h"

namespace volmap::explanation {
namespace {

using Evaluate = std::function<FittedCandidate(double theta)>;

/// Golden-section search of f over [a, b] for `iterations` steps; returns
/// the final bracket (a, b).
std::pair<double, double> golden_section_bracket(double a, double b, int iterations,
                                                 const std::function<double(double)>& f) {
  const GoldenSectionResult r = golden_section(a, b, iterations, f);
  return {r.lo, r.hi};
}

// A later step: the parameter was scanned before; refine around it
// (+-15 %) with the current model.
FittedCandidate fit_around_hint(const Evaluate& eval, double hint) {
  const auto [a, b] = golden_section_bracket(std::log(hint / 1.15), std::log(hint * 1.15), 10,
                                             [&](double x) { return eval(std::exp(x)).gain.rss; });
  FittedCandidate best = eval(std::exp(0.5 * (a + b)));
  FittedCandidate at_hint = eval(hint);
  if (at_hint.gain.rss < best.gain.rss) best = std::move(at_hint);
  return best;
}

/// Coarse periodogram of the current residual over the candidate's periods
/// (2x2 per period, unique positions aggregated): (score, period) per period.
std::vector<std::pair<double, double>> periodogram(const Observations& obs,
                                                   const LinearModel& model, const Candidate& c) {
  std::vector<std::pair<double, double>> score;
  // Aggregate residual and weight per position.
  std::map<double, std::array<double, 2>> agg;
  const AxisName k = *c.axis;
  for (std::size_t e = 0; e < obs.count; ++e) {
    const double pk = obs.direction_base(static_cast<int>(k), static_cast<Eigen::Index>(e)) *
                      obs.sqrt_weight[static_cast<Eigen::Index>(e)];
    auto& a = agg[obs.position(k, obs.recording_row[e])];
    a[0] += pk * model.r[static_cast<Eigen::Index>(e)];
    a[1] += pk * pk;
  }
  for (double period : c.grid) {
    double ss = 0, cc = 0, sc = 0, sr = 0, cr = 0;
    for (const auto& [q, a] : agg) {
      const double ph = 2 * std::numbers::pi * q / period, s = std::sin(ph), co = std::cos(ph);
      ss += a[1] * s * s;
      cc += a[1] * co * co;
      sc += a[1] * s * co;
      sr += a[0] * s;
      cr += a[0] * co;
    }
    const double det = ss * cc - sc * sc;
    const double g = det > 1e-12 * (ss * cc + 1e-300)
                         ? (cc * sr * sr - 2 * sc * sr * cr + ss * cr * cr) / det
                         : 0.0;
    score.push_back({g, period});
  }
  return score;
}

// Coarse periodogram of the current residual, then the full profile at the
// best peaks, each refined between its neighbours in frequency.
std::optional<FittedCandidate> fit_cyclic(const Observations& obs, const LinearModel& model,
                                          const Candidate& c, const Evaluate& eval) {
  const std::vector<std::pair<double, double>> score = periodogram(obs, model, c);
  std::vector<std::size_t> order(score.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return score[a].first != score[b].first ? score[a].first > score[b].first : a < b;
  });
  std::optional<FittedCandidate> best;
  for (std::size_t t = 0; t < std::min<std::size_t>(3, order.size()); ++t) {
    const std::size_t i = order[t];
    FittedCandidate f = eval(c.grid[i]);
    // refine between the neighbours in frequency
    double lo = 1.0 / c.grid[i > 0 ? i - 1 : i],
           hi = 1.0 / c.grid[i + 1 < c.grid.size() ? i + 1 : i];
    if (lo > hi) std::swap(lo, hi);
    const auto [a, b] =
        golden_section_bracket(lo, hi, 18, [&](double x) { return eval(1.0 / x).gain.rss; });
    FittedCandidate r = eval(1.0 / (0.5 * (a + b)));
    if (r.gain.rss > f.gain.rss) r = f;
    if (!best || r.gain.rss < best->gain.rss) best = std::move(r);
  }
  return best;
}

// The grid, then (refine) a golden section between the best point's
// neighbours, in log space for log_refine.
std::optional<FittedCandidate> fit_on_grid(const Candidate& c, const Evaluate& eval) {
  std::optional<FittedCandidate> best;
  std::size_t bi = 0;
  for (std::size_t i = 0; i < c.grid.size(); ++i) {
    FittedCandidate f = eval(c.grid[i]);
    if (!best || f.gain.rss < best->gain.rss) {
      best = std::move(f);
      bi = i;
    }
  }
  if (c.refine && c.grid.size() >= 3) {
    auto tr = [&](double x) { return c.log_refine ? std::log(x) : x; };
    auto inv = [&](double x) { return c.log_refine ? std::exp(x) : x; };
    const auto [a, b] = golden_section_bracket(tr(c.grid[bi > 0 ? bi - 1 : bi]),
                                               tr(c.grid[bi + 1 < c.grid.size() ? bi + 1 : bi]), 14,
                                               [&](double x) { return eval(inv(x)).gain.rss; });
    FittedCandidate r = eval(inv(0.5 * (a + b)));
    if (r.gain.rss < best->gain.rss) best = std::move(r);
  }
  return best;
}

}  // namespace

std::optional<FittedCandidate> fit_candidate(const Observations& obs, const LinearModel& model,
                                             const Candidate& c, std::optional<double> hint) {
  const Evaluate eval = [&](double theta) {
    FittedCandidate f;
    f.cand = &c;
    f.theta = theta;
    f.block = make_column_block(obs, c.build(theta), c.per_run);
    f.gain = profile(obs, model, f.block);
    return f;
  };
  std::optional<FittedCandidate> best;
  if (c.grid.empty()) {
    best = eval(0.0);
  } else if (hint && c.refine) {
    best = fit_around_hint(eval, *hint);
  } else if (c.effect == "cyclic") {
    best = fit_cyclic(obs, model, c, eval);
  } else {
    best = fit_on_grid(c, eval);
  }
  if (!best) return std::nullopt;
  best->bic =
      bic(obs, best->gain.rss,
          static_cast<int>(model.k() + best->block.cols.cols()) + model.nonlinear + c.nonlinear);
  return best;
}

}  // namespace volmap::explanation
