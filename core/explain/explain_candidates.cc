// The candidate physics of `volmap explain`: every effect name of
// shared/spec/explain.md as columns in um per parameter unit (the formulas
// of core/effects.h, which `volmap simulate` injects), with the report of
// its fitted parameters. Table: docs/explain.md.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/explain/explain_internal.h"

namespace volmap::explain_detail {
namespace {

double round_sig(double v, int digits = 6) {
  if (!std::isfinite(v) || v == 0) return v == 0 ? 0.0 : v;
  return std::stod(fmt::format("{:.{}g}", v, digits));
}

nlohmann::json num(double v) {
  if (!std::isfinite(v)) return nullptr;
  return round_sig(v);
}

/// sqrt(g^T cov g) for a function with gradient g.
double delta_se(const Eigen::VectorXd& g, const Eigen::MatrixXd& cov) {
  return std::sqrt(std::max(0.0, g.dot(cov * g)));
}

void amplitude_phase(const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, int i_sin, int i_cos,
                     double& amp, double& amp_se, double& phase_deg) {
  const double a = beta[i_sin], b = beta[i_cos];
  amp = std::hypot(a, b);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(beta.size());
  if (amp > 0) {
    g[i_sin] = a / amp;
    g[i_cos] = b / amp;
  }
  amp_se = delta_se(g, cov);
  phase_deg = std::atan2(b, a) * kRadToDeg;
}

}  // namespace

std::vector<double> unique_sorted(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  v.erase(
      std::unique(v.begin(), v.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }),
      v.end());
  return v;
}

bool varies(const std::vector<double>& v) {
  double lo = INFINITY, hi = -INFINITY;
  for (double x : v)
    if (std::isfinite(x)) {
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  return hi > lo;
}

std::vector<Candidate> make_candidates(const Context& c) {
  const Data& d = c.d;
  const Eigen::Index n = static_cast<Eigen::Index>(d.n);
  std::vector<Candidate> out;
  auto along = [&](AxisName k) {  // p_b[K] per equation
    Eigen::VectorXd v(n);
    for (Eigen::Index e = 0; e < n; ++e) v[e] = d.p_b(static_cast<int>(k), e);
    return v;
  };
  auto has_along = [&](AxisName k) { return along(k).cwiseAbs().maxCoeff() > 1e-9; };

  // Every linear axis of the machine may deflect (the recording need not move it).
  std::vector<AxisName> deflecting;
  for (AxisName a : d.m.axis_order)
    if (!is_rotary(a)) deflecting.push_back(a);
  const auto moves = [&](AxisName a) {
    return std::find(c.linear.begin(), c.linear.end(), a) != c.linear.end();
  };
  for (AxisName k : deflecting) {
    if (!has_along(k)) continue;
    const Eigen::VectorXd pk = along(k);
    // cyclic: period scan over the sampled positions.
    {
      std::vector<double> qs;
      for (std::size_t i = 0; i < d.rec.size(); ++i) qs.push_back(d.q(k, static_cast<int>(i)));
      const std::vector<double> uq = unique_sorted(qs);
      if (uq.size() >= 8) {
        std::vector<double> gaps;
        for (std::size_t i = 1; i < uq.size(); ++i) gaps.push_back(uq[i] - uq[i - 1]);
        std::sort(gaps.begin(), gaps.end());
        const double gap = gaps[gaps.size() / 2];
        const double span = uq.back() - uq.front();
        // At least three periods over the span: a longer 'period' is smooth geometry.
        const double p_min = std::max(2.2 * gap, 1e-3), p_max = span / 3.0;
        if (p_max > 1.5 * p_min) {  // else too few positions per period to scan a period at all
          Candidate cand;
          cand.effect = "cyclic";
          cand.axis = k;
          cand.variant = "";
          cand.nonlinear = 1;
          cand.refine = true;
          const double f_lo = 1.0 / p_max, f_hi = 1.0 / p_min;
          const double df = std::max(1.0 / (4.0 * span), (f_hi - f_lo) / 600.0);
          for (double f = f_lo; f <= f_hi; f += df) cand.grid.push_back(1.0 / f);
          cand.build = [&d, k, pk, n](double period) {
            Eigen::MatrixXd C(n, 2);
            for (Eigen::Index e = 0; e < n; ++e) {
              const double ph = 2 * kPi * d.q(k, d.row[static_cast<std::size_t>(e)]) / period;
              C(e, 0) = pk[e] * std::sin(ph);
              C(e, 1) = pk[e] * std::cos(ph);
            }
            return C;
          };
          cand.report = [k](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double period,
                            double period_se, Finding& f) {
            double amp = 0, amp_se = 0, phase = 0;
            amplitude_phase(beta, cov, 0, 1, amp, amp_se, phase);
            f.parameters = {
                {"period_mm", num(period)}, {"amplitude_um", num(amp)}, {"phase_deg", num(phase)}};
            f.std_errors = {{"period_mm", period_se}, {"amplitude_um", amp_se}};
            f.explanation = fmt::format(
                "{0} deviates periodically along {0} with a period of {1:.4g} mm and an amplitude "
                "of {2:.3g} um: "
                "a screw-pitch or scale/encoder interpolation error, which a smooth polynomial "
                "cannot follow.",
                axis_str(k), period, amp);
          };
          cand.plot_x = [&d, k](int i) { return d.q_user(k, i); };
          cand.plot_label = position_name(k);
          out.push_back(cand);
        }
      }
    }
    // reversal and servo lag: approach direction.
    if (std::find(c.dir_axes.begin(), c.dir_axes.end(), k) != c.dir_axes.end()) {
      Candidate rev;
      rev.effect = "reversal";
      rev.axis = k;
      rev.build = [&d, k, pk, n](double) {
        Eigen::MatrixXd C(n, 1);
        for (Eigen::Index e = 0; e < n; ++e)
          C(e, 0) = pk[e] * 0.5 * d.s(k, d.row[static_cast<std::size_t>(e)]);
        return C;
      };
      rev.report = [k](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                       Finding& f) {
        f.parameters = {{"value_um", num(beta[0])}};
        f.std_errors = {{"value_um", std::sqrt(cov(0, 0))}};
        f.explanation = fmt::format(
            "{0} deviates {1:.3g} um {2} when approached from +{0} than from -{0} (reversal value "
            "B = {3:.3g} um): "
            "lost motion (backlash) in the {0} drive, absent from the rigid-body model.",
            axis_str(k), std::abs(beta[0]), beta[0] >= 0 ? "more" : "less", beta[0]);
      };
      rev.plot_x = [&d, k](int i) { return d.q_user(k, i); };
      rev.plot_label = position_name(k);
      rev.plot_group = [&d, k](int i) { return d.s(k, i); };
      out.push_back(rev);
      if (c.has_feed) {
        Candidate sl;
        sl.effect = "servo_lag";
        sl.axis = k;
        sl.build = [&d, k, pk, n](double) {
          Eigen::MatrixXd C(n, 1);
          for (Eigen::Index e = 0; e < n; ++e) {
            const int i = d.row[static_cast<std::size_t>(e)];
            C(e, 0) = -pk[e] * d.feed(i) / 1000.0 * d.s(k, i);
          }
          return C;
        };
        sl.report = [k](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                        Finding& f) {
          f.parameters = {{"um_per_m_min", num(beta[0])}};
          f.std_errors = {{"um_per_m_min", std::sqrt(cov(0, 0))}};
          f.explanation = fmt::format(
              "{0} lags {1:.3g} um behind the command per m/min of feed, against the direction of "
              "motion: "
              "servo mismatch / following error, which grows with feed and is absent at "
              "standstill.",
              axis_str(k), beta[0]);
        };
        sl.plot_x = [&d, k](int i) { return d.feed(i) * d.s(k, i); };
        sl.plot_label = "feed_mm_min * dir_" + lower_axis(k);
        out.push_back(sl);
      }
    }
    // thermal drift: offset or scale, settling / rate / temperature.
    const int ki = static_cast<int>(k);
    for (int scale = 0; scale < (moves(k) ? 2 : 1); ++scale) {
      auto factor = [&d, k, scale](int i) { return scale ? d.q(k, i) / 1000.0 : 1.0; };
      const std::string kind = scale ? "scale" : "offset";
      if (c.has_time) {
        Candidate settle;
        settle.effect = "thermal_drift";
        settle.axis = k;
        settle.variant = kind + "/settling";
        settle.nonlinear = 1;
        settle.refine = true;
        settle.log_refine = true;
        for (int j = 0; j <= 16; ++j)
          settle.grid.push_back(c.duration_s / 30.0 * std::pow(150.0, j / 16.0));  // T/30 .. 5 T
        settle.build = [&d, pk, n, factor](double tau) {
          Eigen::MatrixXd C(n, 1);
          for (Eigen::Index e = 0; e < n; ++e) {
            const int i = d.row[static_cast<std::size_t>(e)];
            C(e, 0) = pk[e] * factor(i) * (1.0 - std::exp(-d.t(i) / tau));
          }
          return C;
        };
        settle.report = [k, kind](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov,
                                  double tau, double tau_se, Finding& f) {
          f.parameters = {{"kind", kind}, {"amplitude_um", num(beta[0])}, {"tau_s", num(tau)}};
          if (kind == "scale") f.parameters.push_back({"reference_length_mm", 1000});
          f.std_errors = {{"amplitude_um", std::sqrt(cov(0, 0))}, {"tau_s", tau_se}};
          f.explanation = fmt::format(
              "{0} drifts with time, settling to {1:.3g} um{2} with a time constant of {3:.0f} s: "
              "thermal "
              "growth of the {0} drive (screw or scale expansion) as the machine warms up.",
              axis_str(k), beta[0], kind == "scale" ? " per 1000 mm of travel" : "", tau);
        };
        settle.plot_x = [&d](int i) { return d.t(i); };
        settle.plot_label = "t_s";
        out.push_back(settle);

        Candidate rate = settle;
        rate.variant = kind + "/rate";
        rate.grid.clear();
        rate.nonlinear = 0;
        rate.refine = false;
        rate.build = [&d, pk, n, factor](double) {
          Eigen::MatrixXd C(n, 1);
          for (Eigen::Index e = 0; e < n; ++e) {
            const int i = d.row[static_cast<std::size_t>(e)];
            C(e, 0) = pk[e] * factor(i) * d.t(i) / 3600.0;
          }
          return C;
        };
        rate.report = [k, kind](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double,
                                double, Finding& f) {
          f.parameters = {{"kind", kind}, {"rate_um_per_h", num(beta[0])}};
          if (kind == "scale") f.parameters.push_back({"reference_length_mm", 1000});
          f.std_errors = {{"rate_um_per_h", std::sqrt(cov(0, 0))}};
          f.explanation = fmt::format(
              "{0} drifts steadily by {1:.3g} um per hour{2}: thermal growth that had not settled "
              "during the test.",
              axis_str(k), beta[0], kind == "scale" ? " per 1000 mm of travel" : "");
        };
        out.push_back(rate);
      }
      for (const NamedColumn& tc : d.rec.temperature_c) {
        if (!varies(tc.values)) continue;
        bool complete = true;
        for (double v : tc.values) complete = complete && std::isfinite(v);
        if (!complete) continue;
        Candidate temp;
        temp.effect = "thermal_drift";
        temp.axis = k;
        temp.variant = kind + "/" + tc.name;
        const std::vector<double>* values = &tc.values;
        temp.build = [&d, pk, n, factor, values](double) {
          Eigen::MatrixXd C(n, 1);
          for (Eigen::Index e = 0; e < n; ++e) {
            const int i = d.row[static_cast<std::size_t>(e)];
            // ISO 1 reference temperature: 20 degC (matters for kind scale).
            C(e, 0) = pk[e] * factor(i) * ((*values)[static_cast<std::size_t>(i)] - 20.0);
          }
          return C;
        };
        const std::string sensor = tc.name.substr(5, tc.name.size() - 7);
        temp.report = [k, kind, sensor](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov,
                                        double, double, Finding& f) {
          f.parameters = {
              {"kind", kind}, {"um_per_k", num(beta[0])}, {"sensor", sensor}, {"reference_c", 20}};
          if (kind == "scale") f.parameters.push_back({"reference_length_mm", 1000});
          f.std_errors = {{"um_per_k", std::sqrt(cov(0, 0))}};
          f.explanation = fmt::format(
              "{0} moves {1:.3g} um per kelvin of temp_{2}_c{3}: thermal expansion the rigid-body "
              "model leaves out.",
              axis_str(k), beta[0], sensor, kind == "scale" ? " per 1000 mm of travel" : "");
        };
        temp.plot_x = [values](int i) { return (*values)[static_cast<std::size_t>(i)]; };
        temp.plot_label = tc.name;
        out.push_back(temp);
      }
    }
    (void)ki;
    // setup shift: a constant per run along K.
    if (d.runs >= 2) {
      Candidate ss;
      ss.effect = "setup_shift";
      ss.axis = k;
      ss.per_run = true;
      const int runs = d.runs;
      ss.build = [&d, pk, n, runs](double) {
        Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, runs);
        for (Eigen::Index e = 0; e < n; ++e) C(e, d.run[static_cast<std::size_t>(e)]) = pk[e];
        return C;
      };
      ss.report = [k, runs](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                            Finding& f) {
        nlohmann::json per = nlohmann::json::array(), se = nlohmann::json::array();
        double worst = 0;
        for (int r = 0; r < runs; ++r) {
          const double v = beta[r] - beta[0];
          per.push_back(num(v));
          worst = std::max(worst, std::abs(v));
          f.std_errors.push_back({fmt::format("per_run_um/{}", r),
                                  std::sqrt(std::max(0.0, cov(r, r) + cov(0, 0) - 2 * cov(r, 0)))});
        }
        f.parameters = {{"per_run_um", per}, {"relative_to", "first run"}};
        f.explanation = fmt::format(
            "The runs sit at different {0} offsets (up to {1:.3g} um from the first run), constant "
            "within each "
            "run: the set-up (instrument, ball or fixture) moved between runs.",
            axis_str(k), worst);
      };
      ss.plot_x = [&d](int i) {
        return d.rec.has_run() ? static_cast<double>(d.rec.run[static_cast<std::size_t>(i)] + 1)
                               : 1.0;
      };
      ss.plot_label = "run";
      out.push_back(ss);
    }
  }

  // sag: K deflects with the position of another axis J, quadratically.
  std::vector<AxisName> inputs = c.linear;
  inputs.insert(inputs.end(), c.rotary.begin(), c.rotary.end());
  for (AxisName k : deflecting) {
    if (!has_along(k)) continue;
    const Eigen::VectorXd pk = along(k);
    for (AxisName j : inputs) {
      if (j == k) continue;
      std::vector<double> qs;
      for (std::size_t i = 0; i < d.rec.size(); ++i) qs.push_back(d.q_user(j, static_cast<int>(i)));
      const std::vector<double> uq = unique_sorted(qs);
      if (uq.size() < 4) continue;
      const double centre = 0.5 * (uq.front() + uq.back());
      Candidate sag;
      sag.effect = "sag";
      sag.axis = k;
      sag.variant = axis_str(j);
      sag.build = [&d, pk, n, j, centre](double) {
        Eigen::MatrixXd C(n, 2);
        for (Eigen::Index e = 0; e < n; ++e) {
          const double x = d.q_user(j, d.row[static_cast<std::size_t>(e)]) - centre;
          C(e, 0) = pk[e] * x * x;
          C(e, 1) = pk[e] * x;
        }
        return C;
      };
      sag.report = [k, j, centre](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double,
                                  double, Finding& f) {
        const double c2 = beta[0], c1 = beta[1];
        const double origin = c2 != 0 ? centre - c1 / (2 * c2) : centre;
        Eigen::VectorXd g(2);
        g << c1 / (2 * c2 * c2), -1 / (2 * c2);
        f.parameters = {{"input_axis", axis_str(j)},
                        {"coefficient", num(c2)},
                        {"power", 2},
                        {"origin", num(origin)}};
        f.std_errors = {{"coefficient", std::sqrt(cov(0, 0))}, {"origin", delta_se(g, cov)}};
        f.explanation = fmt::format(
            "{0} deflects with the square of the {1} position ({2:.3g} um per {3}^2 about {1} = "
            "{4:.4g}): sag under "
            "gravity or load as {1} moves, which the rigid-body errors of {0} cannot produce.",
            axis_str(k), axis_str(j), c2, is_rotary(j) ? "deg" : "mm", origin);
      };
      sag.plot_x = [&d, j](int i) { return d.q_user(j, i); };
      sag.plot_label = position_name(j);
      out.push_back(sag);
    }
  }

  // rotary axes: wobble and positioning, order 1..4.
  for (AxisName rax : c.rotary) {
    const int own = static_cast<int>(rax) - 3;
    int perp[2] = {-1, -1}, self = -1;
    int np = 0;
    for (int comp = 0; comp < 3; ++comp) {
      const std::string name = component_error_name(static_cast<Component>(comp + 3), rax);
      const auto it = std::find(d.names.begin(), d.names.end(), name);
      const int idx = it == d.names.end() ? -1 : static_cast<int>(it - d.names.begin());
      if (comp == own)
        self = idx;
      else
        perp[np++] = idx;
    }
    // gp is mm per rad; the parameters are urad, the columns um per urad: 1e-3.
    if (perp[0] >= 0 && perp[1] >= 0) {
      Candidate wob;
      wob.effect = "rotary_wobble";
      wob.axis = rax;
      wob.grid = {1, 2, 3, 4};
      wob.nonlinear = 1;
      wob.build = [&d, n, rax, perp](double order) {
        Eigen::MatrixXd C(n, 2);
        for (Eigen::Index e = 0; e < n; ++e) {
          const double th = order * d.q(rax, d.row[static_cast<std::size_t>(e)]);
          const double ga = d.gp(e, perp[0]) * 1e-3, gb = d.gp(e, perp[1]) * 1e-3;
          // EA = a cos - b sin, EB = b cos + a sin  (amplitude (a, b) = A (cos phi, sin phi))
          C(e, 0) = ga * std::cos(th) + gb * std::sin(th);
          C(e, 1) = -ga * std::sin(th) + gb * std::cos(th);
        }
        return C;
      };
      wob.report = [rax](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double order,
                         double, Finding& f) {
        double amp = 0, amp_se = 0, phase = 0;
        amplitude_phase(beta, cov, 0, 1, amp, amp_se, phase);
        f.parameters = {{"order", static_cast<int>(order)},
                        {"amplitude_urad", num(amp)},
                        {"phase_deg", num(phase)}};
        f.std_errors = {{"amplitude_urad", amp_se}};
        f.explanation = fmt::format(
            "The {0} axis tilts by {1:.3g} urad, {2} times per turn: an angle-dependent error "
            "motion "
            "(wobble, ISO 230-7) of the {0} bearing, beyond the constant tilts of the location "
            "errors.",
            axis_str(rax), amp, static_cast<int>(order));
      };
      wob.plot_x = [&d, rax](int i) { return d.q_user(rax, i); };
      wob.plot_label = position_name(rax);
      out.push_back(wob);
    }
    if (self >= 0) {
      Candidate pos;
      pos.effect = "rotary_positioning";
      pos.axis = rax;
      pos.grid = {1, 2, 3, 4};
      pos.nonlinear = 1;
      pos.build = [&d, n, rax, self](double order) {
        Eigen::MatrixXd C(n, 2);
        for (Eigen::Index e = 0; e < n; ++e) {
          const double th = order * d.q(rax, d.row[static_cast<std::size_t>(e)]);
          const double g = d.gp(e, self) * 1e-3;
          C(e, 0) = g * std::sin(th);
          C(e, 1) = g * std::cos(th);
        }
        return C;
      };
      pos.report = [rax](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double order,
                         double, Finding& f) {
        double amp = 0, amp_se = 0, phase = 0;
        amplitude_phase(beta, cov, 0, 1, amp, amp_se, phase);
        f.parameters = {{"order", static_cast<int>(order)},
                        {"amplitude_urad", num(amp)},
                        {"phase_deg", num(phase)}};
        f.std_errors = {{"amplitude_urad", amp_se}};
        f.explanation = fmt::format(
            "The {0} axis mispositions by {1:.3g} urad, {2} times per turn: an angular positioning "
            "error of {0} "
            "(encoder or gear eccentricity) that varies with the angle.",
            axis_str(rax), amp, static_cast<int>(order));
      };
      pos.plot_x = [&d, rax](int i) { return d.q_user(rax, i); };
      pos.plot_label = position_name(rax);
      out.push_back(pos);
    }
  }

  // Fixed baseline: geometric errors it may lack, per linear axis K.
  if (c.opt.baseline) {
    for (AxisName k : c.linear) {
      const AxisLimits& L = d.m.limits[static_cast<std::size_t>(*d.m.index_of(k))];
      const double centre = 0.5 * (L.min + L.max), half = std::max(0.5 * (L.max - L.min), 1e-9);
      for (int comp = 0; comp < 6; ++comp) {
        const std::string name = component_error_name(static_cast<Component>(comp), k);
        const auto it = std::find(d.names.begin(), d.names.end(), name);
        if (it == d.names.end()) continue;
        const int idx = static_cast<int>(it - d.names.begin());
        if (d.gp.col(idx).cwiseAbs().maxCoeff() < 1e-12) continue;
        // Only errors the baseline lacks: the errors file defines the others.
        const AxisErrors* given = c.opt.baseline->errors_of(k);
        if (given && given->present[static_cast<std::size_t>(comp)]) continue;
        const bool angular = comp >= 3;
        const std::string effect =
            angular ? "angular" : (comp == static_cast<int>(k) ? "scale" : "squareness");
        Candidate lin;
        lin.effect = effect;
        lin.axis = k;
        lin.variant = name;
        // The positioning error of K (EKK): scale (linear) and its curvature
        // (s^2, s^3 at the ends of the travel), as a laser calibration gives it.
        const bool positioning = !angular && comp == static_cast<int>(k);
        lin.build = [&d, n, k, idx, angular, positioning, centre, half](double) {
          Eigen::MatrixXd C(n, positioning ? 3 : 1);
          for (Eigen::Index e = 0; e < n; ++e) {
            // error = slope * q / 1000 (um or urad per m); deviation um.
            const double qm = d.q(k, d.row[static_cast<std::size_t>(e)]);
            C(e, 0) = d.gp(e, idx) * (angular ? 1e-3 : 1.0) * qm / 1000.0;
            if (positioning) {
              const double sc = (qm - centre) / half;
              C(e, 1) = d.gp(e, idx) * sc * sc;
              C(e, 2) = d.gp(e, idx) * sc * sc * sc;
            }
          }
          return C;
        };
        const std::string unit = angular ? "urad_per_m" : "um_per_m";
        lin.report = [k, name, unit, effect, positioning](const Eigen::VectorXd& beta,
                                                          const Eigen::MatrixXd& cov, double,
                                                          double, Finding& f) {
          f.parameters = {{"error", name}, {unit, num(beta[0])}};
          f.std_errors = {{unit, std::sqrt(cov(0, 0))}};
          if (positioning) {
            f.parameters.push_back({"quadratic_um", num(beta[1])});
            f.parameters.push_back({"cubic_um", num(beta[2])});
            f.std_errors.push_back({"quadratic_um", std::sqrt(cov(1, 1))});
            f.std_errors.push_back({"cubic_um", std::sqrt(cov(2, 2))});
            f.explanation = fmt::format(
                "The positioning error {} of {} is missing from the baseline: {:.3g} um per m of "
                "travel (scale), "
                "with {:.3g} um quadratic and {:.3g} um cubic curvature at the ends of the travel.",
                name, axis_str(k), beta[0], beta[1], beta[2]);
          } else {
            f.explanation = fmt::format(
                "{} of {} grows linearly along {}: {} {:.3g} {} missing from the baseline.", name,
                axis_str(k), axis_str(k), effect, beta[0], unit);
          }
        };
        lin.plot_x = [&d, k](int i) { return d.q_user(k, i); };
        lin.plot_label = position_name(k);
        out.push_back(lin);
        if (!angular && comp != static_cast<int>(k)) {
          Candidate st;
          st.effect = "straightness";
          st.axis = k;
          st.variant = name;
          st.build = [&d, n, k, idx, centre, half](double) {
            Eigen::MatrixXd C(n, 2);
            for (Eigen::Index e = 0; e < n; ++e) {
              const double s = (d.q(k, d.row[static_cast<std::size_t>(e)]) - centre) / half;
              C(e, 0) = d.gp(e, idx) * s * s;
              C(e, 1) = d.gp(e, idx) * s * s * s;
            }
            return C;
          };
          st.report = [k, name](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double,
                                double, Finding& f) {
            f.parameters = {
                {"error", name}, {"quadratic_um", num(beta[0])}, {"cubic_um", num(beta[1])}};
            f.std_errors = {{"quadratic_um", std::sqrt(cov(0, 0))},
                            {"cubic_um", std::sqrt(cov(1, 1))}};
            f.explanation = fmt::format(
                "{} of {} is curved ({:.3g} um quadratic, {:.3g} um cubic at the ends of "
                "the travel): straightness missing from the baseline.",
                name, axis_str(k), beta[0], beta[1]);
          };
          st.plot_x = [&d, k](int i) { return d.q_user(k, i); };
          st.plot_label = position_name(k);
          out.push_back(st);
        }
      }
    }
    // Angular location errors the baseline lacks (ISO 230-1 squareness of a
    // linear axis, EC0Y; the tilt of a rotary axis's average line, EA0C):
    // constant errors whose effect on the tool varies over the workspace
    // through the levers. Without them a baseline lacking a squareness sent
    // its signature to whatever else could bend to it (sag, wobble).
    for (std::size_t idx = 0; idx < d.names.size(); ++idx) {
      const std::string& name = d.names[idx];
      const std::optional<ErrorName> en = parse_error_name(name);
      if (!en || !en->location || !is_angular(en->component)) continue;
      if (c.opt.baseline->location.count(name)) continue;
      const Eigen::Index col = static_cast<Eigen::Index>(idx);
      if (d.gp.col(col).cwiseAbs().maxCoeff() < 1e-12) continue;
      const AxisName k = en->axis;
      Candidate sq;
      sq.effect = "squareness";
      sq.axis = k;
      sq.variant = name;
      sq.build = [&d, n, col](double) {
        Eigen::MatrixXd C(n, 1);
        for (Eigen::Index e = 0; e < n; ++e) C(e, 0) = d.gp(e, col) * 1e-3;  // urad -> um
        return C;
      };
      sq.report = [k, name](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                            Finding& f) {
        f.parameters = {{"error", name}, {"value_urad", num(beta[0])}};
        f.std_errors = {{"value_urad", std::sqrt(cov(0, 0))}};
        f.explanation = fmt::format(
            "The location error {} ({} axis) is missing from the baseline: {:.3g} urad of "
            "squareness (a tilt of the "
            "axis's line) fits the residuals.",
            name, axis_str(k), beta[0]);
      };
      sq.plot_x = [&d, k](int i) { return d.q_user(k, i); };
      sq.plot_label = position_name(k);
      out.push_back(sq);
    }
  }
  return out;
}

}  // namespace volmap::explain_detail
