// The statistics of explain's detection (docs/explain.md, "Detection"):
// the test a candidate effect must pass to be a finding, and the smallest
// amplitude the recording's design lets that test see.
//
// A candidate of s linear columns G (and maybe a nonlinear parameter theta:
// period, time constant, order) enters y = X b + G(theta) a + noise. With
// sigma estimated from the model with the candidate (n - k - s degrees of
// freedom) the likelihood-ratio test is the F test on the residual sum of
// squares it removes, chi2 = (RSS0 - RSS1) / sigma^2, F = chi2 / s.
//
// Look-elsewhere, derived in docs/explain.md: the statistic is maximised
// over theta, so its tail is that of the maximum of a chi2_s process over
// the scan. With Z(theta) = W(theta)^T e / sigma (W an orthonormal basis of
// P_perp G(theta), the columns with the model projected out), Rice's formula
// bounds P(max > u) by P(chi2_s > u) plus the expected upcrossings,
//   L u^((s-1)/2) e^(-u/2) 2^(1-s/2) / (sqrt(2 pi) Gamma(s/2)),
// L the length of the path W(theta) traces on the Grassmannian (summed
// principal angles between neighbouring scan points). A parameter taking a
// few discrete values (a rotary order) is a Bonferroni factor instead. The
// family of candidates tried in a step gets a Bonferroni factor m:
// a candidate is a finding when its corrected p-value is below alpha / m.
//
// Detectable amplitude: with the critical value u* of that test, power
// 1 - beta needs the noncentrality lambda* with P(chi2_s(lambda*) > u*) =
// 1 - beta; an effect a v (unit direction v of its coefficients) has
// noncentrality a^2 v^T S v / sigma^2 (S = G^T P_perp G, weighted), so
//   a_min = sqrt(lambda*) sigma / sqrt(v^T S v)
// for the least visible direction; for s = 1 it is (z_alpha + z_beta)
// sigma / ||P_perp g|| of the issue, with z_alpha the corrected two-sided
// critical value.
#pragma once

#include <Eigen/Core>

namespace volmap::explanation {

/// Family-wise false-finding rate of one selection step (over the whole
/// family of candidates tried in it, look-elsewhere included).
inline constexpr double kFamilyAlpha = 0.001;
/// Power the detectable amplitude is quoted at (1 - beta).
inline constexpr double kDetectionPower = 0.95;

/// P(chi2_s > u), regularized upper incomplete gamma.
double chi2_upper_tail(double u, double s);
/// P(F(d1, d2) > f), regularized incomplete beta.
double f_upper_tail(double f, double d1, double d2);
/// P(chi2_s(lambda) > u) of the noncentral chi-square (Poisson mixture).
double noncentral_chi2_upper_tail(double u, double s, double lambda);
/// Expected upcrossings of level u per unit path length by a chi2_s
/// process (Rice): u^((s-1)/2) e^(-u/2) 2^(1-s/2) / (sqrt(2 pi) Gamma(s/2)).
double chi2_upcrossing_rate(double u, double s);

/// The same for the F-field of a statistic u = s F whose sigma is estimated
/// with nu degrees of freedom (Worsley 1994): heavier-tailed than the
/// chi2_s process, to which it tends as nu grows:
/// G((nu+s-1)/2) / (G(nu/2) G(s/2) sqrt(pi)) (u/nu)^((s-1)/2) (1+u/nu)^(-(nu+s-2)/2).
double f_field_upcrossing_rate(double u, double s, double nu);

/// How one candidate is tested: its columns s, the residual degrees of
/// freedom, and its look-elsewhere (path length or discrete count).
struct TestDesign {
  double columns = 1;       ///< s
  double residual_dof = 1;  ///< n - k - s
  double path_length = 0;   ///< L of the scan (continuous nonlinear parameter)
  double discrete = 1;      ///< values of a discrete nonlinear parameter
  double family = 1;        ///< candidates tried in the step (Bonferroni m)
};

/// The corrected p-value of statistic chi2 (= s F) under `d`: the
/// probability that noise alone gives a statistic this large anywhere in
/// the candidate's scan, times the family size; clamped to 1.
double corrected_p_value(double chi2, const TestDesign& d);
/// The statistic at which corrected_p_value reaches kFamilyAlpha.
double critical_chi2(const TestDesign& d);
/// The noncentrality that the test detects with probability kDetectionPower.
double detectable_noncentrality(const TestDesign& d);

/// Length of the path traced by the span of the columns, with the model
/// projected out, as a nonlinear parameter walks a scan. basis_at(i) gives
/// an orthonormal basis (n x s) of the projected columns at scan point i;
/// the path is the sum over neighbours of the RMS principal angle (rad).
/// A step above 0.3 rad is undersampled and bisected, up to three times:
/// midway(i, f) gives the basis at fraction f of the way from point i to
/// point i + 1.
template <typename BasisAt, typename Midway>
double path_length(int points, BasisAt basis_at, Midway midway);

/// The RMS principal angle (rad) between two subspaces with orthonormal bases.
double rms_principal_angle(const Eigen::MatrixXd& Qa, const Eigen::MatrixXd& Qb);

/// An orthonormal basis of the span of A's columns: the eigenvectors of
/// A^T A above `floor` (directions with less squared norm are taken as
/// spanned already), through A.
Eigen::MatrixXd orthonormal_basis(const Eigen::MatrixXd& A, double floor);

/// The path between two bases at fractions f0 and f1 of step i, bisected
/// while a piece turns by more than 0.3 rad (depth levels left).
template <typename Midway>
double walked_step(int i, double f0, double f1, const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                   Midway& midway, int depth) {
  const double direct = rms_principal_angle(a, b);
  if (direct <= 0.3 || depth == 0) return direct;
  const double fm = 0.5 * (f0 + f1);
  const Eigen::MatrixXd m = midway(i, fm);
  return walked_step(i, f0, fm, a, m, midway, depth - 1) +
         walked_step(i, fm, f1, m, b, midway, depth - 1);
}

template <typename BasisAt, typename Midway>
double path_length(int points, BasisAt basis_at, Midway midway) {
  double length = 0;
  if (points < 2) return 0;
  Eigen::MatrixXd prev = basis_at(0);
  for (int i = 0; i + 1 < points; ++i) {
    Eigen::MatrixXd next = basis_at(i + 1);
    length += walked_step(i, 0.0, 1.0, prev, next, midway, 3);
    prev = std::move(next);
  }
  return length;
}

}  // namespace volmap::explanation
