// The statistics of explain's detection (detection.h).
#include "core/explain/detection.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace volmap::explanation {
namespace {

constexpr double kTiny = 1e-300;
constexpr int kMaxIterations = 500;
constexpr double kEpsilon = 1e-15;

/// Regularized lower incomplete gamma P(a, x) by its series (x < a + 1).
double gamma_p_series(double a, double x) {
  double term = 1.0 / a, sum = term;
  for (int n = 1; n < kMaxIterations; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::abs(term) < std::abs(sum) * kEpsilon) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

/// Regularized upper incomplete gamma Q(a, x) by its continued fraction
/// (x >= a + 1), modified Lentz.
double gamma_q_fraction(double a, double x) {
  double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
  for (int i = 1; i < kMaxIterations; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < kEpsilon) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

double gamma_q(double a, double x) {
  if (x <= 0) return 1.0;
  return x < a + 1.0 ? 1.0 - gamma_p_series(a, x) : gamma_q_fraction(a, x);
}

/// Continued fraction of the incomplete beta (modified Lentz).
double beta_fraction(double a, double b, double x) {
  const double qab = a + b, qap = a + 1.0, qam = a - 1.0;
  double c = 1.0, d = 1.0 - qab * x / qap;
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m < kMaxIterations; ++m) {
    const int m2 = 2 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < kEpsilon) break;
  }
  return h;
}

/// Regularized incomplete beta I_x(a, b).
double incomplete_beta(double a, double b, double x) {
  if (x <= 0) return 0.0;
  if (x >= 1) return 1.0;
  const double front = std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) +
                                a * std::log(x) + b * std::log1p(-x));
  if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_fraction(a, b, x) / a;
  return 1.0 - front * beta_fraction(b, a, 1.0 - x) / b;
}

/// The largest u in [0, hi] with decreasing f(u) >= target, by bisection.
template <typename F>
double solve_decreasing(F f, double target, double hi) {
  double lo = 0;
  while (f(hi) > target && hi < 1e7) hi *= 2;
  for (int i = 0; i < 200 && hi - lo > 1e-10 * (1 + hi); ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) > target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

double chi2_upper_tail(double u, double s) { return gamma_q(0.5 * s, 0.5 * u); }

double f_upper_tail(double f, double d1, double d2) {
  if (f <= 0) return 1.0;
  return incomplete_beta(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * f));
}

double noncentral_chi2_upper_tail(double u, double s, double lambda) {
  if (lambda <= 0) return chi2_upper_tail(u, s);
  // Poisson(lambda / 2) mixture of central chi2_(s + 2j), summed outward
  // from the mode until the weights vanish.
  const double half = 0.5 * lambda;
  const int mode = static_cast<int>(half);
  const int span = static_cast<int>(12.0 * std::sqrt(half + 1.0)) + 40;
  double sum = 0;
  for (int j = std::max(0, mode - span); j <= mode + span; ++j) {
    const double log_w = -half + j * std::log(half) - std::lgamma(j + 1.0);
    sum += std::exp(log_w) * chi2_upper_tail(u, s + 2.0 * j);
  }
  return std::min(1.0, sum);
}

double chi2_upcrossing_rate(double u, double s) {
  if (u <= 0) return 0;
  return std::exp(0.5 * (s - 1) * std::log(u) - 0.5 * u + (1.0 - 0.5 * s) * std::numbers::ln2 -
                  0.5 * std::log(2 * std::numbers::pi) - std::lgamma(0.5 * s));
}

double f_field_upcrossing_rate(double u, double s, double nu) {
  if (u <= 0) return 0;
  return std::exp(std::lgamma(0.5 * (nu + s - 1)) - std::lgamma(0.5 * nu) - std::lgamma(0.5 * s) -
                  0.5 * std::log(std::numbers::pi) + 0.5 * (s - 1) * std::log(u / nu) -
                  0.5 * (nu + s - 2) * std::log1p(u / nu));
}

double corrected_p_value(double chi2, const TestDesign& d) {
  const double s = std::max(1.0, d.columns);
  double p =
      d.residual_dof > 0 ? f_upper_tail(chi2 / s, s, d.residual_dof) : chi2_upper_tail(chi2, s);
  // sigma estimated from the residual: the F-field's rate (heavier tails)
  const double rate = d.residual_dof > 0 && d.residual_dof < 1e8
                          ? f_field_upcrossing_rate(chi2, s, d.residual_dof)
                          : chi2_upcrossing_rate(chi2, s);
  p = p * std::max(1.0, d.discrete) + d.path_length * rate;
  return std::min(1.0, p * std::max(1.0, d.family));
}

double critical_chi2(const TestDesign& d) {
  return solve_decreasing([&](double u) { return corrected_p_value(u, d); }, kFamilyAlpha, 100.0);
}

double detectable_noncentrality(const TestDesign& d) {
  const double u = critical_chi2(d), s = std::max(1.0, d.columns);
  // power rises with lambda: solve P(chi2_s(lambda) > u) = power on the
  // complement, which falls.
  return solve_decreasing(
      [&](double lambda) { return 1.0 - noncentral_chi2_upper_tail(u, s, lambda); },
      1.0 - kDetectionPower, 4 * u + 100);
}

double rms_principal_angle(const Eigen::MatrixXd& Qa, const Eigen::MatrixXd& Qb) {
  if (Qa.cols() == 0 || Qb.cols() == 0) return 0;
  const Eigen::MatrixXd M = Qa.transpose() * Qb;
  const Eigen::VectorXd cosines = Eigen::JacobiSVD<Eigen::MatrixXd>(M).singularValues();
  const Eigen::Index s = std::max(Qa.cols(), Qb.cols());
  double sum = 0;
  for (Eigen::Index i = 0; i < s; ++i) {
    const double c = i < cosines.size() ? std::clamp(cosines[i], 0.0, 1.0) : 0.0;
    sum += std::acos(c) * std::acos(c);
  }
  return std::sqrt(sum / static_cast<double>(s));
}

Eigen::MatrixXd orthonormal_basis(const Eigen::MatrixXd& A, double floor) {
  if (A.cols() == 0) return A;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A.transpose() * A);
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < eig.eigenvalues().size(); ++i)
    if (eig.eigenvalues()[i] > floor) keep.push_back(i);
  Eigen::MatrixXd Q(A.rows(), static_cast<Eigen::Index>(keep.size()));
  for (std::size_t j = 0; j < keep.size(); ++j)
    Q.col(static_cast<Eigen::Index>(j)) =
        A * eig.eigenvectors().col(keep[j]) / std::sqrt(eig.eigenvalues()[keep[j]]);
  return Q;
}

}  // namespace volmap::explanation
