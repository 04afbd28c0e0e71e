// The linear least squares of `volmap explain` (docs/explain.md), in
// micrometres: every column weighted by sqrt(weight) and normalised to unit
// RMS, a small ridge against rank deficiency, the profile gain of a block of
// columns given the model so far, BIC, and the leave-one-run-out RMS.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <optional>
#include <vector>

#include "core/explain/observations.h"

namespace volmap::explanation {

/// A block of columns: unweighted physical units (um per parameter unit).
struct ColumnBlock {
  Eigen::MatrixXd cols;   ///< n x k, already multiplied by sqrt(weight), unit RMS
  Eigen::VectorXd scale;  ///< physical = normalised / scale (per column)
  bool per_run = false;   ///< setup_shift: each column lives in one run
};

/// Weights and normalises physical columns; zero columns keep scale 1.
ColumnBlock make_column_block(const Observations& obs, Eigen::MatrixXd phys, bool per_run = false);

/// The model so far: baseline plus selected blocks, with its fit.
struct LinearModel {
  Eigen::MatrixXd X;          ///< n x k, weighted, normalised
  Eigen::VectorXd scale;      ///< per column
  std::vector<bool> per_run;  ///< per column
  int nonlinear = 0;          ///< nonlinear parameters, for BIC
  // fit
  Eigen::LDLT<Eigen::MatrixXd> G_ldlt;
  Eigen::VectorXd beta;  ///< normalised
  Eigen::VectorXd r;     ///< weighted residual
  double rss = 0.0;
  int rank = 0;

  Eigen::Index k() const { return X.cols(); }
};

/// The ridge added to the Gram matrix's diagonal (relative to the unit-RMS
/// column scale, times the number of equations).
double ridge_of(const Observations& obs);
/// Fits the model to the observations (beta, residual, rss).
void fit(const Observations& obs, LinearModel& model);
/// Bayesian information criterion of a fit with rss and k parameters.
double bic(const Observations& obs, double rss, int k);
/// Weighted RMS (um) of a weighted residual sum of squares.
double rms_of(const Observations& obs, double rss);
/// Greedy rank: keeps the columns (in order) that are not spanned by the kept
/// ones (Schur complement of the Gram matrix > 1e-8 of the column's square).
std::vector<int> independent_columns(const Eigen::MatrixXd& X);

/// What a candidate block adds to the model on the full data (profile).
struct ProfileGain {
  double rss = 0.0;
  double absorbed_share = 1.0;  ///< largest residual share of a column after the model
  Eigen::VectorXd fitted;       ///< the part of the residual the block explains (weighted)
};
ProfileGain profile(const Observations& obs, const LinearModel& model, const ColumnBlock& b,
                    bool want_fitted = false);

/// The Gram matrix of a block's columns with the fitted model projected
/// out: C^T C - (X^T C)^T G^-1 (X^T C) (kc x kc).
Eigen::MatrixXd projected_gram(const LinearModel& model, const ColumnBlock& b);

/// The columns C (weighted, normalised like the model's) with the fitted
/// model's columns projected out: C - X G^-1 X^T C.
Eigen::MatrixXd projected_out(const LinearModel& model, const Eigen::MatrixXd& C);

/// The model with block b appended (not fitted).
LinearModel with_block(const LinearModel& model, const ColumnBlock& b, int nonlinear);
/// The model without its columns first_col .. first_col + count - 1 and
/// their nonlinear parameters (not fitted).
LinearModel without_block(const LinearModel& model, Eigen::Index first_col, Eigen::Index count,
                          int nonlinear);

/// Leave-one-run-out RMS (um); none with a single run.
std::optional<double> heldout_rms(const Observations& obs, const LinearModel& model);

/// Correlation of two vectors about zero (cosine); 0 when either is zero.
double correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b);

}  // namespace volmap::explanation
