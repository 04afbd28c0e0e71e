// Least-squares identification of Lei & Hsu (2003), section 3 ("the unknown
// link errors can be identified by using the least square estimation
// method"): the parameter set (identify_columns), the observations and the
// weighted Jacobian (identify_observations), the identifiability report
// (identifiability), then here the weighted Gauss-Newton iteration on the
// exact model, the covariance and the result.
#include "core/measure/identify.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "core/common/input_error.h"
#include "core/common/internal_error.h"
#include "core/common/units.h"
#include "core/measure/identifiability.h"
#include "core/measure/identify_columns.h"
#include "core/measure/identify_observations.h"
#include "core/model/gain_evaluator.h"

namespace volmap {
namespace {

using identification::Equation;
using identification::Identifiability;
using identification::Observations;
using identification::ParameterColumn;

/// The parameters the fit estimates (not fixed), and their normal matrix.
struct EstimatedSet {
  std::vector<int> kept;   ///< column indices
  Eigen::MatrixXd normal;  ///< N restricted to `kept`
  Eigen::LDLT<Eigen::MatrixXd> ldlt;
  double condition_number = 0.0;  ///< of J_s restricted to `kept`
};

EstimatedSet estimated_set(const Identifiability& id) {
  EstimatedSet s;
  const int P = static_cast<int>(id.fixed.size());
  for (int j = 0; j < P; ++j)
    if (!id.fixed[static_cast<std::size_t>(j)]) s.kept.push_back(j);
  const int Kp = static_cast<int>(s.kept.size());
  Eigen::MatrixXd& Nk = s.normal;
  Nk.resize(Kp, Kp);
  for (int a = 0; a < Kp; ++a)
    for (int b = 0; b < Kp; ++b)
      Nk(a, b) =
          id.normal(s.kept[static_cast<std::size_t>(a)], s.kept[static_cast<std::size_t>(b)]);
  s.ldlt.compute(Nk);
  // Nothing left to estimate (every parameter fixed): Eigen's eigensolver
  // must not see a 0 x 0 matrix (it read past it and crashed, on a one-axis
  // laser recording with the three-axis sample machine).
  if (Kp == 0) return s;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ek(Nk, Eigen::EigenvaluesOnly);
  const double lo = std::max(ek.eigenvalues()[0], 0.0);
  s.condition_number = lo > 0 ? std::sqrt(ek.eigenvalues()[Kp - 1] / lo) : INFINITY;
  return s;
}

/// The weighted residuals r = sqrt(W) (y - prediction), um, of the exact
/// model (ErrorModel::exact, HTM products) at parameters theta.
class ExactResiduals {
 public:
  ExactResiduals(const Machine& m, const ErrorSet& known, const std::vector<ParameterColumn>& cols,
                 const std::vector<std::string>& gain_names, const Observations& obs,
                 const Eigen::MatrixXd& Js, const Eigen::VectorXd& D, const Recordings& rec,
                 Formulation formulation)
      : m_(m),
        known_(known),
        cols_(cols),
        names_(gain_names),
        obs_(obs),
        Js_(Js),
        D_(D),
        rec_(rec),
        formulation_(formulation) {}

  void evaluate(const Eigen::VectorXd& th, Eigen::VectorXd& r) const {
    const std::vector<Equation>& eqs = obs_.equations;
    const ErrorModel model(m_, identification::errors_at(m_, known_, cols_, names_, th),
                           ModelOptions{formulation_, OutsidePolicy::kError});
    std::size_t e = 0;
    for (std::size_t row = 0; row < obs_.u.size(); ++row) {
      Eigen::Vector3d dv_um;
      try {
        dv_um = model.exact(obs_.u[row], obs_.dir[row]).dP_mm * units::kUmPerMm;
      } catch (const std::exception& ex) {
        throw_if_unexpected(ex, rec_.file, obs_.line[row]);  // a bug is said to be one
        throw InputError(rec_.file, obs_.line[row],
                         std::string("the model cannot be evaluated here: ") + ex.what());
      }
      for (; e < eqs.size() && eqs[e].row == static_cast<int>(row); ++e) {
        double pred = eqs[e].p_w.dot(dv_um);
        r[static_cast<Eigen::Index>(e)] = eqs[e].sqrt_w * (eqs[e].y_um - pred);
      }
    }
    // setup offsets are linear: exact through J
    for (int j = 0; j < static_cast<int>(cols_.size()); ++j)
      if (cols_[static_cast<std::size_t>(j)].p.kind == ParameterKind::kSetupOffset && th[j] != 0.0)
        r -= Js_.col(j) * (D_[j] * th[j]);
  }

 private:
  const Machine& m_;
  const ErrorSet& known_;
  const std::vector<ParameterColumn>& cols_;
  const std::vector<std::string>& names_;
  const Observations& obs_;
  const Eigen::MatrixXd& Js_;
  const Eigen::VectorXd& D_;
  const Recordings& rec_;
  Formulation formulation_;
};

/// Gauss-Newton on the exact model with the first-order J_s held fixed:
/// theta += D^-1 (J_k^T J_k)^-1 J_k^T r over the estimated columns k.
/// Leaves theta (parameter units) and r (weighted residuals, um) at the
/// last iterate; sets res.iterations and res.converged.
void gauss_newton(const ExactResiduals& residuals, const EstimatedSet& est,
                  const Eigen::MatrixXd& Js, const Eigen::VectorXd& D, int max_iterations,
                  double step_tolerance, Eigen::VectorXd& theta, Eigen::VectorXd& r,
                  IdentifyResult& res, const IdentifyOptions& opt) {
  const int Kp = static_cast<int>(est.kept.size());
  double previous_step = INFINITY;
  for (res.iterations = 0; res.iterations < max_iterations && Kp > 0;) {
    if (opt.progress)
      opt.progress("Gauss-Newton iteration", static_cast<std::size_t>(res.iterations),
                   static_cast<std::size_t>(max_iterations));
    Eigen::VectorXd g(Kp);
    for (int a = 0; a < Kp; ++a) g[a] = Js.col(est.kept[static_cast<std::size_t>(a)]).dot(r);
    const Eigen::VectorXd step_s = est.ldlt.solve(g);
    double max_step = 0.0;
    for (int a = 0; a < Kp; ++a) {
      const int j = est.kept[static_cast<std::size_t>(a)];
      const double d = step_s[a] / D[j];
      theta[j] += d;
      max_step = std::max(max_step, std::abs(d));
    }
    ++res.iterations;
    residuals.evaluate(theta, r);
    // Converged: below the tolerance, or at the rounding floor (steps of a
    // few 1e-10 um that stop shrinking: large residuals times the machine
    // epsilon).
    if (max_step < step_tolerance || (max_step < 1e-6 && max_step > 0.5 * previous_step)) {
      res.converged = true;
      break;
    }
    previous_step = max_step;
  }
  if (Kp == 0) res.converged = true;
}

/// Covariance sigma^2 (J^T W J)^-1 of the estimated parameters (parameter
/// units), and into res their correlation matrix and strongly correlated
/// pairs.
Eigen::MatrixXd covariance_and_correlations(const EstimatedSet& est, const Eigen::VectorXd& D,
                                            const std::vector<ParameterColumn>& cols,
                                            double strong_correlation, IdentifyResult& res) {
  const int Kp = static_cast<int>(est.kept.size());
  const std::vector<int>& kept = est.kept;
  Eigen::MatrixXd cov_s = est.ldlt.solve(Eigen::MatrixXd::Identity(Kp, Kp));
  Eigen::MatrixXd cov(Kp, Kp);
  for (int a = 0; a < Kp; ++a)
    for (int b = 0; b < Kp; ++b)
      cov(a, b) = res.sigma_um * res.sigma_um * cov_s(a, b) /
                  (D[kept[static_cast<std::size_t>(a)]] * D[kept[static_cast<std::size_t>(b)]]);
  res.correlation.resize(Kp, Kp);
  for (int a = 0; a < Kp; ++a) {
    res.correlation_names.push_back(
        cols[static_cast<std::size_t>(kept[static_cast<std::size_t>(a)])].p.name);
    for (int b = 0; b < Kp; ++b) {
      const double ss = cov_s(a, a) * cov_s(b, b);
      res.correlation(a, b) = ss > 0 ? cov_s(a, b) / std::sqrt(ss) : 0.0;
    }
  }
  for (int a = 0; a < Kp; ++a)
    for (int b = a + 1; b < Kp; ++b)
      if (std::abs(res.correlation(a, b)) >= strong_correlation)
        res.strong_correlations.push_back({res.correlation_names[static_cast<std::size_t>(a)],
                                           res.correlation_names[static_cast<std::size_t>(b)],
                                           res.correlation(a, b)});
  std::stable_sort(res.strong_correlations.begin(), res.strong_correlations.end(),
                   [](const IdentifyResult::Pair& x, const IdentifyResult::Pair& y) {
                     return std::abs(x.rho) > std::abs(y.rho);
                   });
  return cov;
}

/// Every parameter with its estimate and standard error (fixed ones at 0),
/// and the identifiable location errors in internal units.
void report_parameters(const std::vector<ParameterColumn>& cols, const Identifiability& id,
                       const EstimatedSet& est, const Eigen::VectorXd& theta,
                       const Eigen::MatrixXd& cov, int dof, IdentifyResult& res) {
  const Eigen::MatrixXd cov_s = est.ldlt.solve(Eigen::MatrixXd::Identity(
      static_cast<Eigen::Index>(est.kept.size()), static_cast<Eigen::Index>(est.kept.size())));
  const std::vector<int>& kept = est.kept;
  for (int j = 0; j < static_cast<int>(cols.size()); ++j) {
    IdentifiedParameter p = cols[static_cast<std::size_t>(j)].p;
    p.identifiable = !id.fixed[static_cast<std::size_t>(j)];
    p.estimate = p.identifiable ? theta[j] : 0.0;
    p.std_error = std::nan("");
    if (p.identifiable) {
      const auto a =
          static_cast<Eigen::Index>(std::find(kept.begin(), kept.end(), j) - kept.begin());
      if (dof > 0) p.std_error = std::sqrt(std::max(cov(a, a), 0.0));
      p.inflation = std::sqrt(std::max(cov_s(a, a) * est.normal(a, a), 0.0));
    }
    res.parameters.push_back(p);
    if (p.identifiable && p.kind == ParameterKind::kLocation)
      res.location_estimates.push_back(
          {p.name, theta[j] * cols[static_cast<std::size_t>(j)].unit_scale});
  }
}

/// The fitted component curves for the errors CSV: the identifiable terms
/// tabulated, axes that `known` tabulates left out.
void report_curves(const Machine& m, const ErrorSet& known, const ErrorSet* given_known,
                   const std::vector<ParameterColumn>& cols,
                   const std::vector<std::string>& gain_names, const Identifiability& id,
                   const Eigen::VectorXd& theta, IdentifyResult& res) {
  Eigen::VectorXd th = theta;
  for (int j = 0; j < static_cast<int>(cols.size()); ++j)
    if (id.fixed[static_cast<std::size_t>(j)]) th[j] = 0.0;
  const ErrorSet e = identification::errors_at(m, known, cols, gain_names, th);
  for (int a = 0; a < kAxisNameCount; ++a) {
    const AxisErrors* ax = e.errors_of(static_cast<AxisName>(a));
    if (!ax || (given_known && given_known->errors_of(static_cast<AxisName>(a)))) continue;
    for (int c = 0; c < kComponentCount; ++c) {
      if (!ax->present[static_cast<std::size_t>(c)]) continue;
      FittedCurve fc;
      fc.axis = static_cast<AxisName>(a);
      fc.component = static_cast<Component>(c);
      fc.periodic = ax->plus.periodic;
      fc.knots = ax->plus.position;
      for (const auto& v : ax->plus.value) fc.values.push_back(v[static_cast<std::size_t>(c)]);
      res.curves.push_back(std::move(fc));
    }
  }
}

}  // namespace

ComponentFitError::ComponentFitError(const std::string& detail)
    : std::invalid_argument("component " + detail), detail_(detail) {}

IdentifyResult identify(const Machine& m, const Recordings& rec, const IdentifyOptions& opt) {
  if (opt.known && !opt.known->location.empty() && opt.known->convention != opt.convention)
    throw std::invalid_argument(fmt::format(
        "{} gives its location errors in the {} convention, and they are to be identified in the "
        "{} convention; convert the file first (volmap convert --machine M.json --errors {} --to "
        "{} -o K2.csv), or identify with --convention {}",
        opt.known->file, location_convention_name(opt.known->convention),
        location_convention_name(opt.convention), opt.known->file,
        location_convention_name(opt.convention), location_convention_name(opt.known->convention)));
  GainEvaluator gains(m, opt.formulation, opt.convention);
  ErrorSet base;
  if (opt.known) base = *opt.known;
  base.convention = opt.convention;
  base.file = opt.known ? opt.known->file : std::string("<identified>");

  if (opt.progress) opt.progress("computing the sensitivities", 0, 0);
  std::vector<ParameterColumn> cols = identification::physical_columns(m, gains, base, opt);
  const Observations obs = identification::gather_observations(m, rec);
  const std::vector<bool> moved = identification::moved_axes(m, obs.u);
  if (opt.setup_offsets) identification::append_setup_offset_columns(cols, obs.run, rec);
  const int P = static_cast<int>(cols.size());
  const int M = static_cast<int>(obs.equations.size());
  if (P == 0) throw std::invalid_argument("nothing to identify: every parameter is held fixed");

  // J_w = sqrt(W) J, scaled in place to J_s by the identifiability analysis.
  Eigen::MatrixXd J = identification::weighted_jacobian(m, gains, obs, cols);
  const Identifiability id =
      identification::analyse_identifiability(J, m, gains, cols, moved, opt.rank_tolerance);
  const Eigen::MatrixXd& Js = J;
  const Eigen::VectorXd& D = id.column_scale;
  IdentifyResult res;
  res.singular_values = id.singular_values;
  res.rank = id.rank;
  res.unidentifiable = id.unidentifiable;
  const EstimatedSet est = estimated_set(id);
  res.condition_number = est.condition_number;
  const int Kp = static_cast<int>(est.kept.size());

  Eigen::VectorXd theta = Eigen::VectorXd::Zero(P);  // parameter units
  Eigen::VectorXd r(M);                              // weighted residuals, um
  const ExactResiduals residuals(m, base, cols, gains.names(), obs, Js, D, rec, opt.formulation);
  double weight_sum = 0.0;
  for (const Equation& q : obs.equations) weight_sum += q.sqrt_w * q.sqrt_w;
  residuals.evaluate(theta, r);
  res.rms_before_um = std::sqrt(r.squaredNorm() / weight_sum);
  gauss_newton(residuals, est, Js, D, opt.max_iterations, opt.step_tolerance, theta, r, res, opt);
  res.rms_after_um = std::sqrt(r.squaredNorm() / weight_sum);
  res.rows_used = obs.u.size();
  res.equations = obs.equations.size();
  const int dof = M - Kp;
  res.sigma_um = dof > 0 ? std::sqrt(r.squaredNorm() / dof) : std::nan("");

  const Eigen::MatrixXd cov =
      covariance_and_correlations(est, D, cols, opt.strong_correlation, res);
  report_parameters(cols, id, est, theta, cov, dof, res);
  report_curves(m, base, opt.known, cols, gains.names(), id, theta, res);
  if (const auto it = rec.metadata.find("noise_um"); it != rec.metadata.end()) {
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (end != it->second.c_str() && *end == '\0' && v > 0 && std::isfinite(v))
      res.stated_noise_um = v;
  }
  res.warnings = identification::fit_warnings(res, dof);
  return res;
}

}  // namespace volmap
