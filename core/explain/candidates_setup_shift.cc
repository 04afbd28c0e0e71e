// setup_shift K (docs/explain.md): p_b[K] [run == r], a constant per run,
// reported relative to the first run (per_run_um).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/explain/candidate.h"
#include "core/explain/parameter_report.h"

namespace volmap::explanation {

void add_setup_shift_candidate(const CandidateContext& c, AxisName k,
                               const Eigen::VectorXd& along_k, std::vector<Candidate>& out) {
  const Observations& obs = c.obs;
  if (obs.run_count < 2) return;
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  Candidate ss{.effect = "setup_shift", .axis = k, .per_run = true};
  ss.amplitude = Candidate::Amplitude::kEachColumn;
  const int runs = obs.run_count;
  ss.build = [&obs, along_k, n, runs](double) {
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, runs);
    for (Eigen::Index e = 0; e < n; ++e) C(e, obs.run[static_cast<std::size_t>(e)]) = along_k[e];
    return C;
  };
  ss.report = [k, runs](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                        Finding& f) {
    nlohmann::json per_run_um = nlohmann::json::array();
    double largest_um = 0;
    for (int r = 0; r < runs; ++r) {
      const double v = beta[r] - beta[0];
      per_run_um.push_back(json_number(v));
      largest_um = std::max(largest_um, std::abs(v));
      f.std_errors.push_back({fmt::format("per_run_um/{}", r),
                              std::sqrt(std::max(0.0, cov(r, r) + cov(0, 0) - 2 * cov(r, 0)))});
    }
    f.parameters = {{"per_run_um", per_run_um}, {"relative_to", "first run"}};
    f.explanation = fmt::format(
        "The runs sit at different {0} offsets (up to {1:.3g} µm from the first run), constant "
        "within each "
        "run: the set-up (instrument, ball or fixture) moved between runs.",
        axis_letter(k), largest_um);
  };
  ss.plot_x = [&obs](int i) {
    return obs.recordings.has_run()
               ? static_cast<double>(obs.recordings.run[static_cast<std::size_t>(i)] + 1)
               : 1.0;
  };
  ss.plot_label = "run";
  out.push_back(ss);
}

}  // namespace volmap::explanation
