// sag K from J (docs/explain.md): p_b[K] (q_J - c)^2, p_b[K] (q_J - c),
// reported as a coefficient and the origin of the parabola.
#include <fmt/format.h>

#include <cmath>

#include "core/explain/candidate.h"
#include "core/explain/distinct_values.h"
#include "core/explain/parameter_report.h"

namespace volmap::explanation {
namespace {

Candidate sag_candidate(const Observations& obs, AxisName k, AxisName j, double centre,
                        const Eigen::VectorXd& along_k) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  Candidate sag{.effect = "sag", .axis = k, .variant = axis_letter(j)};
  sag.amplitude_unit = is_rotary(j) ? "um_per_deg2" : "um_per_mm2";  // the coefficient
  sag.build = [&obs, along_k, n, j, centre](double) {
    Eigen::MatrixXd C(n, 2);
    for (Eigen::Index e = 0; e < n; ++e) {
      const double x =
          obs.reported_position(j, obs.recording_row[static_cast<std::size_t>(e)]) - centre;
      C(e, 0) = along_k[e] * x * x;
      C(e, 1) = along_k[e] * x;
    }
    return C;
  };
  sag.report = [k, j, centre](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double,
                              double, Finding& f) {
    const double c2 = beta[0], c1 = beta[1];
    const double origin = c2 != 0 ? centre - c1 / (2 * c2) : centre;
    Eigen::VectorXd g(2);
    g << c1 / (2 * c2 * c2), -1 / (2 * c2);
    f.parameters = {{"input_axis", axis_letter(j)},
                    {"coefficient", json_number(c2)},
                    {"power", 2},
                    {"origin", json_number(origin)}};
    f.std_errors = {{"coefficient", std::sqrt(cov(0, 0))}, {"origin", delta_se(g, cov)}};
    f.explanation = fmt::format(
        "{0} deflects with the square of the {1} position ({2:.3g} µm per {3}^2 about {1} = "
        "{4:.4g}): sag under "
        "gravity or load as {1} moves, which the rigid-body errors of {0} cannot produce.",
        axis_letter(k), axis_letter(j), c2, is_rotary(j) ? "deg" : "mm", origin);
  };
  plot_against_position(sag, obs, j);
  return sag;
}

}  // namespace

void add_sag_candidates(const CandidateContext& c, AxisName k, const Eigen::VectorXd& along_k,
                        std::vector<Candidate>& out) {
  const Observations& obs = c.obs;
  std::vector<AxisName> inputs = c.linear_axes;
  inputs.insert(inputs.end(), c.rotary_axes.begin(), c.rotary_axes.end());
  for (AxisName j : inputs) {
    if (j == k) continue;
    std::vector<double> positions;
    for (std::size_t i = 0; i < obs.recordings.size(); ++i)
      positions.push_back(obs.reported_position(j, static_cast<int>(i)));
    const std::vector<double> distinct = unique_sorted(positions);
    if (distinct.size() < 4) continue;
    const double centre = 0.5 * (distinct.front() + distinct.back());
    out.push_back(sag_candidate(obs, k, j, centre, along_k));
  }
}

}  // namespace volmap::explanation
