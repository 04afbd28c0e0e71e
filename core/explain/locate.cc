// Locate: where the baseline residuals have structure, against every
// regressor the recording holds (docs/explain.md, "Locate").
#include "core/explain/locate.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <optional>

#include "core/explain/axis_labels.h"
#include "core/explain/distinct_values.h"

namespace volmap::explanation {
namespace {

constexpr const char* kComponentName[kComponentKinds] = {"ex", "ey", "ez", "e"};

struct Regressor {
  std::string name;
  std::vector<double> value;  ///< per recording row (NaN: not recorded)
  bool categorical = false;
  std::function<std::string(double lo, double hi, double mean_um)> where;
  std::string periodic_unit;  ///< non-empty: also scan the residual for a period along it ("mm")
};

/// Strength of the best sine along x (pairs sorted by x): the share of the
/// variance a (sin, cos) pair of the best period explains, less 2 ln(M) / n
/// for having chosen the best of M periods (the expected maximum under
/// noise). Periods: 2.2 x the median spacing of the targets .. span / 3.
std::optional<Mismatch> periodic_structure(const std::vector<std::pair<double, double>>& points,
                                           double ss_total, const std::string& component,
                                           const Regressor& reg) {
  std::vector<double> xs, sum, cnt;
  for (const auto& [x, r] : points) {
    if (xs.empty() || x - xs.back() > 1e-9) {
      xs.push_back(x);
      sum.push_back(0);
      cnt.push_back(0);
    }
    sum.back() += r;
    cnt.back() += 1;
  }
  if (xs.size() < 16) return std::nullopt;
  std::vector<double> gaps;
  for (std::size_t i = 1; i < xs.size(); ++i) gaps.push_back(xs[i] - xs[i - 1]);
  std::sort(gaps.begin(), gaps.end());
  const double span = xs.back() - xs.front(), p_min = 2.2 * gaps[gaps.size() / 2],
               p_max = span / 3.0;
  if (!(p_max > 1.5 * p_min)) return std::nullopt;
  double m_all = 0;
  for (const auto& p : points) m_all += p.second;
  m_all /= static_cast<double>(points.size());
  const double f_lo = 1.0 / p_max, f_hi = 1.0 / p_min,
               df = std::max(1.0 / (4.0 * span), (f_hi - f_lo) / 600.0);
  double best = 0, best_period = 0, best_amp = 0;
  int count = 0;
  for (double f = f_lo; f <= f_hi; f += df, ++count) {
    double ss = 0, cc = 0, sc = 0, sr = 0, cr = 0;
    for (std::size_t i = 0; i < xs.size(); ++i) {
      const double ph = 2 * std::numbers::pi * f * xs[i], sn = std::sin(ph), cs = std::cos(ph);
      const double r = sum[i] - cnt[i] * m_all;
      ss += cnt[i] * sn * sn;
      cc += cnt[i] * cs * cs;
      sc += cnt[i] * sn * cs;
      sr += r * sn;
      cr += r * cs;
    }
    const double det = ss * cc - sc * sc;
    if (!(det > 1e-12 * ss * cc)) continue;
    const double a = (cc * sr - sc * cr) / det, b = (ss * cr - sc * sr) / det;
    const double gain = a * sr + b * cr;
    if (gain > best) {
      best = gain;
      best_period = 1.0 / f;
      best_amp = std::hypot(a, b);
    }
  }
  const double n = static_cast<double>(points.size());
  const double strength = best / ss_total - 2.0 * std::log(std::max(count, 1)) / n;
  if (strength < 0.05) return std::nullopt;
  return Mismatch{component, reg.name + " (periodic)",
                  fmt::format("a period of {:.4g} {} along {}: amplitude {:.3g} µm", best_period,
                              reg.periodic_unit, reg.name, best_amp),
                  std::min(1.0, strength)};
}

std::vector<Mismatch> locate(const Observations& obs, const Eigen::VectorXd& residual_um,
                             const std::vector<Regressor>& regs) {
  std::vector<Mismatch> out;
  for (int g = 0; g < kComponentKinds; ++g) {
    if (!obs.has_component[g]) continue;
    std::vector<int> equations;
    for (std::size_t e = 0; e < obs.count; ++e)
      if (obs.component[e] == g) equations.push_back(static_cast<int>(e));
    if (equations.size() < 12) continue;
    double mean = 0;
    for (int e : equations) mean += residual_um[e];
    mean /= static_cast<double>(equations.size());
    double ss_component = 0;
    for (int e : equations) ss_component += (residual_um[e] - mean) * (residual_um[e] - mean);
    if (ss_component <= 0) continue;
    for (const Regressor& reg : regs) {
      std::vector<std::pair<double, double>> points;  // (regressor value, residual um)
      for (int e : equations) {
        const double x =
            reg.value[static_cast<std::size_t>(obs.recording_row[static_cast<std::size_t>(e)])];
        if (std::isfinite(x)) points.push_back({x, residual_um[e]});
      }
      if (points.size() < 12) continue;
      std::sort(points.begin(), points.end());
      // Bins: the levels of a categorical regressor, else up to 8 quantile bins.
      std::vector<std::size_t> edges{0};
      if (reg.categorical) {
        for (std::size_t i = 1; i < points.size(); ++i)
          if (points[i].first != points[i - 1].first) edges.push_back(i);
      } else {
        const std::size_t bins = std::min<std::size_t>(8, points.size() / 4);
        for (std::size_t b = 1; b < bins; ++b) {
          std::size_t i = b * points.size() / bins;
          while (i < points.size() && i > 0 && points[i].first == points[i - 1].first) ++i;
          if (i < points.size() && i > edges.back()) edges.push_back(i);
        }
      }
      edges.push_back(points.size());
      const std::size_t n_bins = edges.size() - 1;
      if (n_bins < 2) continue;
      double mean_all = 0;
      for (auto& p : points) mean_all += p.second;
      mean_all /= static_cast<double>(points.size());
      double ss_between_bins = 0, ss_total = 0, best = 0, best_lo = 0, best_hi = 0;
      for (auto& p : points) ss_total += (p.second - mean_all) * (p.second - mean_all);
      for (std::size_t b = 0; b < n_bins; ++b) {
        double s = 0;
        for (std::size_t i = edges[b]; i < edges[b + 1]; ++i) s += points[i].second;
        const double bin_count = static_cast<double>(edges[b + 1] - edges[b]);
        const double bin_mean = s / bin_count;
        ss_between_bins += bin_count * (bin_mean - mean_all) * (bin_mean - mean_all);
        if (std::abs(bin_mean - mean_all) > std::abs(best)) {
          best = bin_mean - mean_all;
          best_lo = points[edges[b]].first;
          best_hi = points[edges[b + 1] - 1].first;
        }
      }
      if (ss_total <= 0) continue;
      if (!reg.periodic_unit.empty())
        if (std::optional<Mismatch> p =
                periodic_structure(points, ss_total, kComponentName[g], reg))
          out.push_back(*p);
      const double n_points = static_cast<double>(points.size());
      const double adjusted_r2 =
          1.0 - ((ss_total - ss_between_bins) / (n_points - static_cast<double>(n_bins))) /
                    (ss_total / (n_points - 1));
      if (adjusted_r2 < 0.05) continue;
      out.push_back({kComponentName[g], reg.name, reg.where(best_lo, best_hi, best),
                     std::min(1.0, adjusted_r2)});
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const Mismatch& a, const Mismatch& b) { return a.strength > b.strength; });
  if (out.size() > 10) out.resize(10);
  return out;
}

std::vector<Regressor> regressors(const Observations& obs) {
  const Recordings& rec = obs.recordings;
  std::vector<Regressor> regs;
  const std::size_t rows = rec.size();
  for (AxisName a : obs.machine.axis_order) {
    if (!rec.has_axis(a)) continue;
    Regressor pos;
    pos.name = position_column_name(a);
    for (std::size_t i = 0; i < rows; ++i)
      pos.value.push_back(obs.reported_position(a, static_cast<int>(i)));
    if (!varies(pos.value)) continue;
    const std::string unit = is_rotary(a) ? "deg" : "mm";
    pos.where = [a, unit](double lo, double hi, double m) {
      return fmt::format(
          "{} {:.4g}..{:.4g} {}: mean residual {:+.3g} µm (the region that departs most)",
          axis_letter(a), lo, hi, unit, m);
    };
    if (!is_rotary(a)) pos.periodic_unit = "mm";
    regs.push_back(pos);
    if (!rec.dir[static_cast<std::size_t>(a)].empty()) {
      Regressor dir;
      dir.name = dir_column_name(a);
      dir.categorical = true;
      bool plus = false, minus = false;
      for (std::size_t i = 0; i < rows; ++i) {
        const int s = rec.dir[static_cast<std::size_t>(a)][i];
        plus = plus || s > 0;
        minus = minus || s < 0;
        dir.value.push_back(s == 0 ? std::nan("") : s);
      }
      if (!(plus && minus)) continue;
      dir.where = [a](double lo, double, double m) {
        return fmt::format("all {} sweeps: approached from {}{}, mean residual {:+.3g} µm",
                           axis_letter(a), lo > 0 ? "+" : "-", axis_letter(a), m);
      };
      regs.push_back(dir);
    }
  }
  if (obs.run_count >= 2) {
    Regressor run;
    run.name = "run";
    run.categorical = true;
    for (std::size_t i = 0; i < rows; ++i)
      run.value.push_back(rec.run[i] >= 0 ? rec.run[i] : std::nan(""));
    run.where = [&rec](double lo, double, double m) {
      const std::size_t r = static_cast<std::size_t>(lo);
      return fmt::format("run {}: mean residual {:+.3g} µm",
                         r < rec.run_names.size() ? rec.run_names[r] : "?", m);
    };
    regs.push_back(run);
  }
  auto continuous = [&](const std::string& name, const std::vector<double>& v,
                        const std::string& unit) {
    if (v.empty() || !varies(v)) return;
    Regressor r;
    r.name = name;
    r.value = v;
    r.where = [name, unit](double lo, double hi, double m) {
      return fmt::format("{} {:.4g}..{:.4g} {}: mean residual {:+.3g} µm", name, lo, hi, unit, m);
    };
    regs.push_back(r);
  };
  continuous("t_s", rec.t_s, "s");
  continuous("feed_mm_min", rec.feed_mm_min, "mm/min");
  for (const NamedColumn& t : rec.temperature_c) continuous(t.name, t.values, "degC");
  for (const ExtraColumn& x : rec.extra) continuous(x.name, x.value, "");
  return regs;
}

}  // namespace

std::vector<Mismatch> locate_mismatch(const Observations& obs, const Eigen::VectorXd& residual_um) {
  return locate(obs, residual_um, regressors(obs));
}

}  // namespace volmap::explanation
