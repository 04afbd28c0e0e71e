// Leave-one-run-out RMS (linear_model.h): each run is predicted by the model
// fitted to the others; a per-run column (setup_shift) of the held-out run is
// estimated on half of its rows and tested on the other half.
#include <algorithm>
#include <cmath>

#include "core/explain/linear_model.h"

namespace volmap::explanation {
namespace {

/// The rows of one run and their normal equations.
struct RunRows {
  Eigen::MatrixXd X;    ///< the model's rows of the run
  Eigen::VectorXd y;    ///< weighted deviations of the run
  Eigen::MatrixXd XtX;  ///< X^T X
  Eigen::VectorXd Xty;  ///< X^T y
};

RunRows rows_of_run(const LinearModel& model, const Eigen::VectorXd& weighted_deviation,
                    const std::vector<int>& eq) {
  const Eigen::Index k = model.k();
  RunRows run;
  Eigen::MatrixXd Xs(static_cast<Eigen::Index>(eq.size()), k);
  Eigen::VectorXd ys(static_cast<Eigen::Index>(eq.size()));
  for (std::size_t e = 0; e < eq.size(); ++e) {
    if (k > 0) Xs.row(static_cast<Eigen::Index>(e)) = model.X.row(eq[e]);
    ys[static_cast<Eigen::Index>(e)] = weighted_deviation[eq[e]];
  }
  run.XtX = Xs.transpose() * Xs;
  run.Xty = Xs.transpose() * ys;
  run.X = std::move(Xs);
  run.y = std::move(ys);
  return run;
}

/// The held-out run's residual after its own per-run columns, each half of
/// its rows predicted by the columns fitted to the other half (two-fold
/// within the run). Unchanged when no per-run column lives in this run.
Eigen::VectorXd without_own_run_columns(const LinearModel& model, const Eigen::MatrixXd& X_run,
                                        const Eigen::VectorXd& res) {
  std::vector<Eigen::Index> own;
  for (Eigen::Index j = 0; j < model.k(); ++j)
    if (model.per_run[static_cast<std::size_t>(j)] && X_run.col(j).squaredNorm() > 0)
      own.push_back(j);
  if (own.empty()) return res;
  const Eigen::Index m_rows = res.size();
  Eigen::MatrixXd P(m_rows, static_cast<Eigen::Index>(own.size()));
  for (std::size_t j = 0; j < own.size(); ++j)
    P.col(static_cast<Eigen::Index>(j)) = X_run.col(own[j]);
  Eigen::VectorXd out = res;
  for (int half = 0; half < 2; ++half) {
    Eigen::MatrixXd Pt = P;
    Eigen::VectorXd rt = res;
    for (Eigen::Index e = 0; e < m_rows; ++e)
      if (e % 2 != half) {
        Pt.row(e).setZero();
        rt[e] = 0;
      }
    Eigen::MatrixXd A = Pt.transpose() * Pt;
    A.diagonal().array() += 1e-9 * (1.0 + A.diagonal().maxCoeff());
    const Eigen::VectorXd gam = A.ldlt().solve(Pt.transpose() * rt);
    for (Eigen::Index e = 0; e < m_rows; ++e)
      if (e % 2 != half) out[e] = res[e] - P.row(e).dot(gam);
  }
  return out;
}

}  // namespace

std::optional<double> heldout_rms(const Observations& obs, const LinearModel& model) {
  if (obs.run_count < 2) return std::nullopt;
  const Eigen::VectorXd yw = obs.deviation_um.cwiseProduct(obs.sqrt_weight);
  const Eigen::Index k = model.k();
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(k);
  std::vector<RunRows> runs;
  for (int r = 0; r < obs.run_count; ++r) {
    runs.push_back(rows_of_run(model, yw, obs.equations_of_run[static_cast<std::size_t>(r)]));
    G += runs.back().XtX;
    b += runs.back().Xty;
  }
  double sse = 0.0, wsum = 0.0;
  for (int r = 0; r < obs.run_count; ++r) {
    const std::size_t rs = static_cast<std::size_t>(r);
    const RunRows& run = runs[rs];
    Eigen::VectorXd res = run.y;
    if (k > 0) {
      Eigen::MatrixXd Gt = G - run.XtX;
      Gt.diagonal().array() += ridge_of(obs);
      const Eigen::VectorXd beta = Gt.ldlt().solve(b - run.Xty);
      res -= run.X * beta;
      res = without_own_run_columns(model, run.X, res);
    }
    sse += res.squaredNorm();
    for (int e : obs.equations_of_run[rs]) wsum += obs.sqrt_weight[e] * obs.sqrt_weight[e];
  }
  return std::sqrt(sse / std::max(wsum, 1e-300));
}

}  // namespace volmap::explanation
