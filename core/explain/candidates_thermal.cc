// thermal_drift K (docs/explain.md): p_b[K] f(t) (offset) or
// p_b[K] f(t) q_K / 1000 (scale), with f = 1 - exp(-t/tau_s) (settling,
// tau_s by scan + golden section), t / 3600 (rate) or T_sensor - 20 degC
// (um_per_k, one candidate per temperature column).
#include <fmt/format.h>

#include <cmath>

#include "core/explain/candidate.h"
#include "core/explain/distinct_values.h"
#include "core/explain/parameter_report.h"

namespace volmap::explanation {
namespace {

/// The form of a drift along K: a constant offset, or a scale that grows
/// with the K position (per 1000 mm of travel).
struct DriftForm {
  const Observations* obs;
  AxisName k;
  bool scale;
  std::string kind() const { return scale ? "scale" : "offset"; }
  double factor(int i) const { return scale ? obs->position(k, i) / 1000.0 : 1.0; }
};

/// The column p_b[K] factor(q_K) f(row) of a drift of the given form.
template <typename OfRow>
Eigen::MatrixXd drift_column(const Observations& obs, const Eigen::VectorXd& along_k,
                             const DriftForm& form, OfRow f) {
  return one_column(obs, [&](Eigen::Index e) {
    const int i = obs.recording_row[static_cast<std::size_t>(e)];
    return along_k[e] * form.factor(i) * f(i);
  });
}

Candidate settling_candidate(const CandidateContext& c, const DriftForm& form,
                             const Eigen::VectorXd& along_k) {
  const Observations& obs = c.obs;
  const AxisName k = form.k;
  const std::string kind = form.kind();
  Candidate settle{.effect = "thermal_drift",
                   .axis = k,
                   .variant = kind + "/settling",
                   .refine = true,
                   .log_refine = true,
                   .nonlinear = 1};
  for (int j = 0; j <= 16; ++j)
    settle.grid.push_back(c.duration_s / 30.0 * std::pow(150.0, j / 16.0));  // T/30 .. 5 T
  settle.build = [&obs, along_k, form](double tau_s) {
    return drift_column(obs, along_k, form,
                        [&](int i) { return 1.0 - std::exp(-obs.time_s(i) / tau_s); });
  };
  settle.report = [k, kind](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double tau_s,
                            double tau_se, Finding& f) {
    f.parameters = {
        {"kind", kind}, {"amplitude_um", json_number(beta[0])}, {"tau_s", json_number(tau_s)}};
    if (kind == "scale") f.parameters.push_back({"reference_length_mm", 1000});
    f.std_errors = {{"amplitude_um", std::sqrt(cov(0, 0))}, {"tau_s", tau_se}};
    f.explanation = fmt::format(
        "{0} drifts with time, settling to {1:.3g} µm{2} with a time constant of {3:.0f} s: "
        "thermal "
        "growth of the {0} drive (screw or scale expansion) as the machine warms up.",
        axis_letter(k), beta[0], kind == "scale" ? " per 1000 mm of travel" : "", tau_s);
  };
  settle.plot_x = [&obs](int i) { return obs.time_s(i); };
  settle.plot_label = "t_s";
  return settle;
}

/// The steady rate: the settling candidate's plot, linear in time.
Candidate rate_candidate(const Candidate& settle, const DriftForm& form,
                         const Eigen::VectorXd& along_k) {
  const Observations& obs = *form.obs;
  Candidate rate = settle;
  rate.variant = form.kind() + "/rate";
  rate.amplitude_unit = "um_per_h";
  rate.grid.clear();
  rate.nonlinear = 0;
  rate.refine = false;
  rate.build = [&obs, along_k, form](double) {
    // (p_b[K] factor t) / 3600, in this order: the rate is um per hour.
    return one_column(obs, [&](Eigen::Index e) {
      const int i = obs.recording_row[static_cast<std::size_t>(e)];
      return along_k[e] * form.factor(i) * obs.time_s(i) / 3600.0;
    });
  };
  rate.report = [form](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                       Finding& f) {
    f.parameters = {{"kind", form.kind()}, {"rate_um_per_h", json_number(beta[0])}};
    if (form.scale) f.parameters.push_back({"reference_length_mm", 1000});
    f.std_errors = {{"rate_um_per_h", std::sqrt(cov(0, 0))}};
    f.explanation = fmt::format(
        "{0} drifts steadily by {1:.3g} µm per hour{2}: thermal growth that had not settled "
        "during the test.",
        axis_letter(form.k), beta[0], form.scale ? " per 1000 mm of travel" : "");
  };
  return rate;
}

Candidate temperature_candidate(const NamedColumn& tc, const DriftForm& form,
                                const Eigen::VectorXd& along_k) {
  const Observations& obs = *form.obs;
  const AxisName k = form.k;
  const std::string kind = form.kind();
  Candidate temp{.effect = "thermal_drift", .axis = k, .variant = kind + "/" + tc.name};
  temp.amplitude_unit = "um_per_k";
  const std::vector<double>* temperature_c = &tc.values;
  temp.build = [&obs, along_k, form, temperature_c](double) {
    // ISO 1 reference temperature: 20 degC (matters for kind scale).
    return drift_column(obs, along_k, form, [&](int i) {
      return (*temperature_c)[static_cast<std::size_t>(i)] - 20.0;
    });
  };
  const std::string sensor = tc.name.substr(5, tc.name.size() - 7);  // temp_<sensor>_c
  temp.report = [k, kind, sensor](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double,
                                  double, Finding& f) {
    f.parameters = {{"kind", kind},
                    {"um_per_k", json_number(beta[0])},
                    {"sensor", sensor},
                    {"reference_c", 20}};
    if (kind == "scale") f.parameters.push_back({"reference_length_mm", 1000});
    f.std_errors = {{"um_per_k", std::sqrt(cov(0, 0))}};
    f.explanation = fmt::format(
        "{0} moves {1:.3g} µm per kelvin of temp_{2}_c{3}: thermal expansion the rigid-body "
        "model leaves out.",
        axis_letter(k), beta[0], sensor, kind == "scale" ? " per 1000 mm of travel" : "");
  };
  temp.plot_x = [temperature_c](int i) { return (*temperature_c)[static_cast<std::size_t>(i)]; };
  temp.plot_label = tc.name;
  return temp;
}

bool complete(const std::vector<double>& values) {
  bool all_finite = true;
  for (double v : values) all_finite = all_finite && std::isfinite(v);
  return all_finite;
}

}  // namespace

void add_thermal_drift_candidates(const CandidateContext& c, AxisName k, bool k_moves,
                                  const Eigen::VectorXd& along_k, std::vector<Candidate>& out) {
  // Offset always; scale only along an axis the recording moves.
  for (int scale = 0; scale < (k_moves ? 2 : 1); ++scale) {
    const DriftForm form{&c.obs, k, scale != 0};
    if (c.has_time) {
      const Candidate settle = settling_candidate(c, form, along_k);
      out.push_back(settle);
      out.push_back(rate_candidate(settle, form, along_k));
    }
    for (const NamedColumn& tc : c.obs.recordings.temperature_c) {
      if (!varies(tc.values) || !complete(tc.values)) continue;
      out.push_back(temperature_candidate(tc, form, along_k));
    }
  }
}

}  // namespace volmap::explanation
