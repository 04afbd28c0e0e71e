// With a fixed baseline (docs/explain.md): the geometric errors it lacks.
// Per linear axis K, each component error the errors file does not give:
// scale (the positioning error EKK, linear with s^2, s^3 curvature),
// squareness and straightness (a straightness error: linear, then curved),
// angular; and every angular location error it lacks (squareness).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/explain/candidate.h"
#include "core/explain/parameter_report.h"

namespace volmap::explanation {
namespace {

/// A component error that grows linearly along K: slope in um (or urad)
/// per m; the positioning error also its curvature.
Candidate linear_error_candidate(const Observations& obs, AxisName k, int comp,
                                 const std::string& name, int idx, TravelScale travel) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  const bool angular = comp >= 3;
  const std::string effect =
      angular ? "angular" : (comp == static_cast<int>(k) ? "scale" : "squareness");
  Candidate lin{.effect = effect, .axis = k, .variant = name};
  lin.amplitude_unit = angular ? "urad_per_m" : "um_per_m";
  // The positioning error of K (EKK): scale (linear) and its curvature
  // (s^2, s^3 at the ends of the travel), as a laser calibration gives it.
  const bool positioning = !angular && comp == static_cast<int>(k);
  const double centre = travel.centre_mm, half = travel.half_mm;
  lin.build = [&obs, n, k, idx, angular, positioning, centre, half](double) {
    Eigen::MatrixXd C(n, positioning ? 3 : 1);
    for (Eigen::Index e = 0; e < n; ++e) {
      // error = slope * q / 1000 (um or urad per m); deviation um.
      const double q_mm = obs.position(k, obs.recording_row[static_cast<std::size_t>(e)]);
      C(e, 0) = obs.error_gain(e, idx) * (angular ? 1e-3 : 1.0) * q_mm / 1000.0;
      if (positioning) {
        const double sc = (q_mm - centre) / half;
        C(e, 1) = obs.error_gain(e, idx) * sc * sc;
        C(e, 2) = obs.error_gain(e, idx) * sc * sc * sc;
      }
    }
    return C;
  };
  const std::string unit = angular ? "urad_per_m" : "um_per_m";
  lin.report = [k, name, unit, effect, positioning](const Eigen::VectorXd& beta,
                                                    const Eigen::MatrixXd& cov, double, double,
                                                    Finding& f) {
    f.parameters = {{"error", name}, {unit, json_number(beta[0])}};
    f.std_errors = {{unit, std::sqrt(cov(0, 0))}};
    if (positioning) {
      f.parameters.push_back({"quadratic_um", json_number(beta[1])});
      f.parameters.push_back({"cubic_um", json_number(beta[2])});
      f.std_errors.push_back({"quadratic_um", std::sqrt(cov(1, 1))});
      f.std_errors.push_back({"cubic_um", std::sqrt(cov(2, 2))});
      f.explanation = fmt::format(
          "The positioning error {} of {} is missing from the baseline: {:.3g} µm per m of "
          "travel (scale), "
          "with {:.3g} µm quadratic and {:.3g} µm cubic curvature at the ends of the travel.",
          name, axis_letter(k), beta[0], beta[1], beta[2]);
    } else {
      f.explanation =
          fmt::format("{} of {} grows linearly along {}: {} {:.3g} {} missing from the baseline.",
                      name, axis_letter(k), axis_letter(k), effect, beta[0], unit);
    }
  };
  plot_against_position(lin, obs, k);
  return lin;
}

Candidate straightness_candidate(const Observations& obs, AxisName k, const std::string& name,
                                 int idx, TravelScale travel) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  const double centre = travel.centre_mm, half = travel.half_mm;
  Candidate st{.effect = "straightness", .axis = k, .variant = name};
  st.build = [&obs, n, k, idx, centre, half](double) {
    Eigen::MatrixXd C(n, 2);
    for (Eigen::Index e = 0; e < n; ++e) {
      const double s =
          (obs.position(k, obs.recording_row[static_cast<std::size_t>(e)]) - centre) / half;
      C(e, 0) = obs.error_gain(e, idx) * s * s;
      C(e, 1) = obs.error_gain(e, idx) * s * s * s;
    }
    return C;
  };
  st.report = [k, name](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                        Finding& f) {
    f.parameters = {{"error", name},
                    {"quadratic_um", json_number(beta[0])},
                    {"cubic_um", json_number(beta[1])}};
    f.std_errors = {{"quadratic_um", std::sqrt(cov(0, 0))}, {"cubic_um", std::sqrt(cov(1, 1))}};
    f.explanation = fmt::format(
        "{} of {} is curved ({:.3g} µm quadratic, {:.3g} µm cubic at the ends of "
        "the travel): straightness missing from the baseline.",
        name, axis_letter(k), beta[0], beta[1]);
  };
  plot_against_position(st, obs, k);
  return st;
}

/// A constant angular location error, in urad.
Candidate location_squareness_candidate(const Observations& obs, AxisName k,
                                        const std::string& name, Eigen::Index col) {
  Candidate sq{.effect = "squareness", .axis = k, .variant = name};
  sq.amplitude_unit = "urad";
  sq.build = [&obs, col](double) {
    return one_column(obs,
                      [&](Eigen::Index e) { return obs.error_gain(e, col) * 1e-3; });  // urad -> um
  };
  sq.report = [k, name](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                        Finding& f) {
    report_one_parameter("value_urad", beta, cov, f);
    f.parameters.insert(f.parameters.begin(), {"error", name});
    f.explanation = fmt::format(
        "The location error {} ({} axis) is missing from the baseline: {:.3g} µrad of "
        "squareness (a tilt of the "
        "axis's line) fits the residuals.",
        name, axis_letter(k), beta[0]);
  };
  plot_against_position(sq, obs, k);
  return sq;
}

void add_component_error_candidates(const CandidateContext& c, std::vector<Candidate>& out) {
  const Observations& obs = c.obs;
  for (AxisName k : c.linear_axes) {
    const TravelScale travel = travel_scale(obs.machine, k);
    for (int comp = 0; comp < 6; ++comp) {
      const std::string name = component_error_name(static_cast<Component>(comp), k);
      const auto it = std::find(obs.error_names.begin(), obs.error_names.end(), name);
      if (it == obs.error_names.end()) continue;
      const int idx = static_cast<int>(it - obs.error_names.begin());
      if (obs.error_gain.col(idx).cwiseAbs().maxCoeff() < 1e-12) continue;
      // Only errors the baseline lacks: the errors file defines the others.
      const AxisErrors* given = c.options.baseline->errors_of(k);
      if (given && given->present[static_cast<std::size_t>(comp)]) continue;
      out.push_back(linear_error_candidate(obs, k, comp, name, idx, travel));
      const bool angular = comp >= 3;
      if (!angular && comp != static_cast<int>(k))
        out.push_back(straightness_candidate(obs, k, name, idx, travel));
    }
  }
}

// Angular location errors the baseline lacks (ISO 230-1 squareness of a
// linear axis, EC0Y; the tilt of a rotary axis's average line, EA0C):
// constant errors whose effect on the tool varies over the workspace
// through the levers. Without them a baseline lacking a squareness sent
// its signature to whatever else could bend to it (sag, wobble).
void add_location_error_candidates(const CandidateContext& c, std::vector<Candidate>& out) {
  const Observations& obs = c.obs;
  for (std::size_t idx = 0; idx < obs.error_names.size(); ++idx) {
    const std::string& name = obs.error_names[idx];
    const std::optional<ErrorName> en = parse_error_name(name);
    if (!en || !en->location || !is_angular(en->component)) continue;
    if (c.options.baseline->location.count(name)) continue;
    const Eigen::Index col = static_cast<Eigen::Index>(idx);
    if (obs.error_gain.col(col).cwiseAbs().maxCoeff() < 1e-12) continue;
    out.push_back(location_squareness_candidate(obs, en->axis, name, col));
  }
}

}  // namespace

void add_geometric_candidates(const CandidateContext& c, std::vector<Candidate>& out) {
  if (!c.options.baseline) return;
  add_component_error_candidates(c, out);
  add_location_error_candidates(c, out);
}

}  // namespace volmap::explanation
