// The linear least squares of explain (linear_model.h).
#include "core/explain/linear_model.h"

#include <algorithm>
#include <cmath>

namespace volmap::explanation {
namespace {

constexpr double kRidge = 1e-9;  ///< relative to the unit-RMS column scale

}  // namespace

ColumnBlock make_column_block(const Observations& obs, Eigen::MatrixXd phys, bool per_run) {
  ColumnBlock b;
  b.per_run = per_run;
  b.scale.resize(phys.cols());
  for (Eigen::Index j = 0; j < phys.cols(); ++j) {
    phys.col(j) = phys.col(j).cwiseProduct(obs.sqrt_weight);
    const double rms = std::sqrt(phys.col(j).squaredNorm() / static_cast<double>(obs.count));
    b.scale[j] = rms > 0 ? 1.0 / rms : 1.0;
    phys.col(j) *= b.scale[j];
  }
  b.cols = std::move(phys);
  return b;
}

double ridge_of(const Observations& obs) { return kRidge * static_cast<double>(obs.count); }

void fit(const Observations& obs, LinearModel& model) {
  const Eigen::VectorXd yw = obs.deviation_um.cwiseProduct(obs.sqrt_weight);
  if (model.k() == 0) {
    model.beta.resize(0);
    model.r = yw;
    model.rss = yw.squaredNorm();
    return;
  }
  Eigen::MatrixXd G = model.X.transpose() * model.X;
  G.diagonal().array() += ridge_of(obs);
  model.G_ldlt.compute(G);
  model.beta = model.G_ldlt.solve(model.X.transpose() * yw);
  model.r = yw - model.X * model.beta;
  model.rss = model.r.squaredNorm();
}

double bic(const Observations& obs, double rss, int k) {
  const double n = static_cast<double>(obs.count);
  return n * std::log(std::max(rss, 1e-300) / n) + k * std::log(n);
}

std::vector<int> independent_columns(const Eigen::MatrixXd& X) {
  const Eigen::MatrixXd G = X.transpose() * X;
  std::vector<int> kept;
  Eigen::MatrixXd L(G.rows(), G.cols());
  L.setZero();
  for (Eigen::Index j = 0; j < G.cols(); ++j) {
    if (G(j, j) <= 0) continue;
    // Cholesky row of j against kept columns.
    Eigen::VectorXd l(static_cast<Eigen::Index>(kept.size()));
    for (std::size_t a = 0; a < kept.size(); ++a) {
      double v = G(kept[a], j);
      for (std::size_t b = 0; b < a; ++b)
        v -= L(kept[a], static_cast<Eigen::Index>(b)) * l[static_cast<Eigen::Index>(b)];
      l[static_cast<Eigen::Index>(a)] = v / L(kept[a], static_cast<Eigen::Index>(a));
    }
    const double dj = G(j, j) - l.squaredNorm();
    if (dj <= 1e-8 * G(j, j)) continue;
    for (std::size_t a = 0; a < kept.size(); ++a)
      L(j, static_cast<Eigen::Index>(a)) = l[static_cast<Eigen::Index>(a)];
    L(j, static_cast<Eigen::Index>(kept.size())) = std::sqrt(dj);
    kept.push_back(static_cast<int>(j));
  }
  return kept;
}

namespace {

/// C^T C and M^T C for a block. A per-run block has one non-zero column per
/// row (its run's): both are sums over the rows, n kc and n k instead of
/// n kc^2 and n k kc (a set-up shift over 249 runs of 100 000 readings).
void block_products(const Eigen::MatrixXd& M, const ColumnBlock& b, Eigen::MatrixXd& CtC,
                    Eigen::MatrixXd& MtC) {
  const Eigen::MatrixXd& C = b.cols;
  if (!b.per_run) {
    CtC = C.transpose() * C;
    if (M.cols() > 0) MtC = M.transpose() * C;
    return;
  }
  CtC = Eigen::MatrixXd::Zero(C.cols(), C.cols());
  MtC = Eigen::MatrixXd::Zero(M.cols(), C.cols());
  for (Eigen::Index e = 0; e < C.rows(); ++e)
    for (Eigen::Index j = 0; j < C.cols(); ++j) {
      const double c = C(e, j);
      if (c == 0) continue;
      CtC(j, j) += c * c;
      if (M.cols() > 0) MtC.col(j) += c * M.row(e).transpose();
    }
}

}  // namespace

Eigen::MatrixXd projected_gram(const LinearModel& model, const ColumnBlock& b) {
  if (!b.per_run) {
    // From the projected columns: the Gram form C^T C - C^T X (G + ridge)^-1
    // X^T C also counts ridge * |coefficients|^2, which is not small for a
    // column the model spans only through large coefficients (a period
    // against a value per target).
    const Eigen::MatrixXd P = projected_out(model, b.cols);
    return P.transpose() * P;
  }
  Eigen::MatrixXd S, XtC;
  block_products(model.X, b, S, XtC);
  if (model.k() > 0) S.noalias() -= XtC.transpose() * model.G_ldlt.solve(XtC);
  return S;
}

ProfileGain profile(const Observations& obs, const LinearModel& model, const ColumnBlock& b,
                    bool want_fitted) {
  // Gram form: S = C^T C - (X^T C)^T G^-1 (X^T C) is the Gram matrix of the
  // columns with the model projected out; C~^T r = C^T r since r is
  // orthogonal to X. Costs n k kc (one product), not a projected copy of C.
  ProfileGain g;
  const Eigen::MatrixXd& C = b.cols;
  Eigen::MatrixXd CtC, XtC, A;
  block_products(model.X, b, CtC, XtC);
  Eigen::MatrixXd S = CtC;
  if (model.k() > 0) {
    A = model.G_ldlt.solve(XtC);
    S.noalias() -= XtC.transpose() * A;
  }
  g.absorbed_share = 0.0;
  for (Eigen::Index j = 0; j < S.rows(); ++j)
    if (CtC(j, j) > 0) g.absorbed_share = std::max(g.absorbed_share, S(j, j) / CtC(j, j));
  S.diagonal().array() += ridge_of(obs);
  const Eigen::VectorXd Ctr = C.transpose() * model.r;
  const Eigen::VectorXd gamma = S.ldlt().solve(Ctr);
  g.rss = model.rss - Ctr.dot(gamma);
  if (want_fitted) {
    g.fitted = C * gamma;
    if (model.k() > 0) g.fitted -= model.X * (A * gamma);
  }
  return g;
}

Eigen::MatrixXd projected_out(const LinearModel& model, const Eigen::MatrixXd& C) {
  if (model.k() == 0) return C;
  return C - model.X * model.G_ldlt.solve(model.X.transpose() * C);
}

LinearModel with_block(const LinearModel& model, const ColumnBlock& b, int nonlinear) {
  LinearModel out;
  out.X.resize(model.X.rows(), model.k() + b.cols.cols());
  if (model.k() > 0) out.X.leftCols(model.k()) = model.X;
  out.X.rightCols(b.cols.cols()) = b.cols;
  out.scale.resize(out.X.cols());
  if (model.k() > 0) out.scale.head(model.k()) = model.scale;
  out.scale.tail(b.cols.cols()) = b.scale;
  out.per_run = model.per_run;
  for (Eigen::Index j = 0; j < b.cols.cols(); ++j) out.per_run.push_back(b.per_run);
  out.nonlinear = model.nonlinear + nonlinear;
  out.rank = model.rank;
  return out;
}

LinearModel without_block(const LinearModel& model, Eigen::Index first_col, Eigen::Index count,
                          int nonlinear) {
  LinearModel out;
  out.X.resize(model.X.rows(), model.k() - count);
  out.scale.resize(model.k() - count);
  Eigen::Index j = 0;
  for (Eigen::Index col = 0; col < model.k(); ++col) {
    if (col >= first_col && col < first_col + count) continue;
    out.X.col(j) = model.X.col(col);
    out.scale[j] = model.scale[col];
    out.per_run.push_back(model.per_run[static_cast<std::size_t>(col)]);
    ++j;
  }
  out.nonlinear = model.nonlinear - nonlinear;
  out.rank = model.rank;
  return out;
}

double rms_of(const Observations& obs, double rss) {
  return std::sqrt(rss / std::max(obs.sqrt_weight.squaredNorm(), 1e-300));
}

double correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const double na = a.norm(), nb = b.norm();
  return na > 0 && nb > 0 ? a.dot(b) / (na * nb) : 0.0;
}

}  // namespace volmap::explanation
