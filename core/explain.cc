#include "core/explain.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include "core/error_model.h"
#include "core/gain_evaluator.h"
#include "core/input_error.h"
#include "core/machine_json.h"
#include "core/sensitivity.h"

namespace volmap {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kRadToDeg = 180.0 / kPi;
constexpr double kMinDeltaBic = -10.0;     ///< a step must lower BIC by more than 10
constexpr double kMinHeldoutGain = 0.02;   ///< and the held-out RMS by more than 2 %
constexpr double kAbsorbed = 1e-3;         ///< residual share of a column the model spans
constexpr double kConfoundCorrelation = 0.98;
constexpr double kConfoundGainShare = 0.9;
constexpr double kRidge = 1e-9;            ///< relative to the unit-RMS column scale
constexpr double kDesignCorrelation = 0.95;
constexpr int kSparseTargets = 12;        ///< up to this many targets: a value per target
constexpr const char* kGroupName[4] = {"ex", "ey", "ez", "e"};

// ---------------------------------------------------------------- data ----

/// The recording as equations, and the per-row context the columns need.
struct Data {
  const Machine& m;
  const Recordings& rec;
  std::size_t n = 0;
  std::vector<int> row, group, run;  ///< per equation; run 0-based (one run for none)
  Eigen::VectorXd y, sw;             ///< um (fixed baseline removed), sqrt(weight)
  Eigen::Matrix3Xd p_w, p_b;         ///< direction of the equation
  Eigen::MatrixXd gp;                ///< p_w . dP(k) per error name (mm per mm or mm per rad)
  std::vector<std::string> names;    ///< error names of gp's columns
  int runs = 1;
  std::vector<std::vector<int>> run_eq;  ///< equations of each run
  bool has_groups[4] = {false, false, false, false};

  Data(const Machine& machine, const Recordings& r) : m(machine), rec(r) {}

  /// Position of axis a at recording row i: mm or rad; home when not recorded.
  double q(AxisName a, int i) const {
    const std::vector<double>& v = rec.position[static_cast<std::size_t>(a)];
    if (!v.empty() && std::isfinite(v[static_cast<std::size_t>(i)])) return v[static_cast<std::size_t>(i)];
    const std::optional<int> k = m.index_of(a);
    return k ? m.home[*k] : 0.0;
  }
  /// Position in report units (mm, degrees).
  double q_user(AxisName a, int i) const { return is_rotary(a) ? q(a, i) * kRadToDeg : q(a, i); }
  int s(AxisName a, int i) const {
    const std::vector<std::int8_t>& v = rec.dir[static_cast<std::size_t>(a)];
    return v.empty() ? 0 : v[static_cast<std::size_t>(i)];
  }
  double t(int i) const { return rec.t_s.empty() ? std::nan("") : rec.t_s[static_cast<std::size_t>(i)]; }
  double feed(int i) const {
    if (rec.feed_mm_min.empty()) return 0.0;
    const double f = rec.feed_mm_min[static_cast<std::size_t>(i)];
    return std::isfinite(f) ? f : 0.0;
  }
};

std::string axis_str(AxisName a) { return std::string(1, axis_char(a)); }
std::string lower_axis(AxisName a) { return std::string(1, static_cast<char>(std::tolower(axis_char(a)))); }
std::string position_name(AxisName a) { return lower_axis(a) + (is_rotary(a) ? "_deg" : "_mm"); }

Data build_data(const Machine& m, const Recordings& rec, const ExplainOptions& opt) {
  Data d(m, rec);
  for (int a = 0; a < kAxisNameCount; ++a) {
    const AxisName ax = static_cast<AxisName>(a);
    if (rec.has_axis(ax) && !m.index_of(ax))
      throw InputError(rec.file, 0, fmt::format("the recording has a {} column but the machine has no {} axis; "
                                                "give the machine that made the recording (--machine)",
                                                position_column_name(ax), axis_str(ax)));
  }
  const std::size_t rows = rec.size();
  d.runs = rec.has_run() ? std::max<int>(1, static_cast<int>(rec.run_names.size())) : 1;
  GainEvaluator gains(m, Formulation::kIndependent);
  d.names = gains.names();
  std::optional<ErrorModel> model;
  if (opt.baseline) model.emplace(m, *opt.baseline);

  std::vector<Eigen::Vector3d> pw, pb;
  std::vector<double> y, w;
  std::vector<std::vector<double>> gp_rows;
  const std::size_t nn = d.names.size();
  std::vector<double> gp_flat;
  gp_flat.reserve(rows * 2 * nn);
  AxisVector u(m.axis_count());
  for (std::size_t i = 0; i < rows; ++i) {
    const int ii = static_cast<int>(i);
    for (int k = 0; k < m.axis_count(); ++k) u[k] = d.q(m.axis_order[static_cast<std::size_t>(k)], ii);
    const Eigen::Matrix3d R_b_w = nominal_base_to_workpiece(m, u).linear();
    const Eigen::Matrix3d R_rec_w =
        rec.frame == RecordingFrame::kMachine ? R_b_w : Eigen::Matrix3d::Identity();
    const double weight = rec.weight.empty() ? 1.0 : rec.weight[i];
    if (!(weight >= 0) || !std::isfinite(weight))
      throw InputError(rec.file, rec.line[i], "weight must be a finite number >= 0");
    bool gains_ready = false;
    Eigen::Vector3d pred_w_um = Eigen::Vector3d::Zero();
    bool pred_ready = false;
    auto add = [&](const Eigen::Vector3d& p_rec, double value, int group) {
      if (!std::isfinite(value) || weight == 0) return;
      if (!gains_ready) {
        gains.at(u);
        gains_ready = true;
      }
      if (model && !pred_ready) {
        ApproachDirections dir{};
        for (int k = 0; k < m.axis_count(); ++k)
          dir[static_cast<std::size_t>(k)] = static_cast<std::int8_t>(d.s(m.axis_order[static_cast<std::size_t>(k)], ii));
        try {
          pred_w_um = model->exact(u, dir).dP_mm * 1e3;
        } catch (const std::exception& e) {
          throw InputError(rec.file, rec.line[i], fmt::format("the baseline cannot be evaluated here: {}", e.what()));
        }
        pred_ready = true;
      }
      const Eigen::Vector3d p_w = R_rec_w.transpose() * p_rec;
      pw.push_back(p_w);
      pb.push_back(R_b_w * p_w);
      y.push_back(value - p_w.dot(pred_w_um));
      w.push_back(weight);
      d.row.push_back(ii);
      d.group.push_back(group);
      d.run.push_back(rec.has_run() && rec.run[i] >= 0 ? rec.run[i] : 0);
      d.has_groups[group] = true;
      for (std::size_t k = 0; k < nn; ++k) gp_flat.push_back(p_w.dot(gains.dP(static_cast<int>(k))));
    };
    for (int c = 0; c < 3; ++c)
      if (rec.has_component(c)) add(Eigen::Vector3d::Unit(c), rec.e_um[static_cast<std::size_t>(c)][i], c);
    if (rec.has_projection()) {
      const Eigen::Vector3d nv(rec.n[0][i], rec.n[1][i], rec.n[2][i]);
      if (nv.allFinite()) add(nv, rec.e_along_n_um[i], 3);
    }
  }
  d.n = y.size();
  if (d.n < 4)
    throw InputError(rec.file, 0, fmt::format("{} usable observations; explain needs at least 4", d.n));
  d.y = Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(d.n));
  d.sw.resize(static_cast<Eigen::Index>(d.n));
  d.p_w.resize(3, static_cast<Eigen::Index>(d.n));
  d.p_b.resize(3, static_cast<Eigen::Index>(d.n));
  for (std::size_t e = 0; e < d.n; ++e) {
    d.sw[static_cast<Eigen::Index>(e)] = std::sqrt(w[e]);
    d.p_w.col(static_cast<Eigen::Index>(e)) = pw[e];
    d.p_b.col(static_cast<Eigen::Index>(e)) = pb[e];
  }
  d.gp = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      gp_flat.data(), static_cast<Eigen::Index>(d.n), static_cast<Eigen::Index>(nn));
  d.run_eq.assign(static_cast<std::size_t>(d.runs), {});
  for (std::size_t e = 0; e < d.n; ++e) d.run_eq[static_cast<std::size_t>(d.run[e])].push_back(static_cast<int>(e));
  // Runs without equations do not count.
  std::vector<std::vector<int>> nonempty;
  std::vector<int> remap(static_cast<std::size_t>(d.runs), -1);
  for (int r = 0; r < d.runs; ++r)
    if (!d.run_eq[static_cast<std::size_t>(r)].empty()) {
      remap[static_cast<std::size_t>(r)] = static_cast<int>(nonempty.size());
      nonempty.push_back(d.run_eq[static_cast<std::size_t>(r)]);
    }
  for (int& r : d.run) r = remap[static_cast<std::size_t>(r)];
  d.run_eq = nonempty;
  d.runs = static_cast<int>(nonempty.size());
  return d;
}

// ------------------------------------------------------------- algebra ----

/// A block of columns: unweighted physical units (um per parameter unit).
struct Block {
  Eigen::MatrixXd cols;   ///< n x k, already multiplied by sqrt(weight), unit RMS
  Eigen::VectorXd scale;  ///< physical = normalised / scale (per column)
  bool per_run = false;   ///< setup_shift: each column lives in one run
};

/// Weights and normalises physical columns; zero columns keep scale 1.
Block make_block(const Data& d, Eigen::MatrixXd phys, bool per_run = false) {
  Block b;
  b.per_run = per_run;
  b.scale.resize(phys.cols());
  for (Eigen::Index j = 0; j < phys.cols(); ++j) {
    phys.col(j) = phys.col(j).cwiseProduct(d.sw);
    const double rms = std::sqrt(phys.col(j).squaredNorm() / static_cast<double>(d.n));
    b.scale[j] = rms > 0 ? 1.0 / rms : 1.0;
    phys.col(j) *= b.scale[j];
  }
  b.cols = std::move(phys);
  return b;
}

/// The model so far: baseline plus selected blocks, with its fit.
struct Model {
  Eigen::MatrixXd X;          ///< n x k, weighted, normalised
  Eigen::VectorXd scale;      ///< per column
  std::vector<bool> per_run;  ///< per column
  int nonlinear = 0;          ///< nonlinear parameters, for BIC
  // fit
  Eigen::LDLT<Eigen::MatrixXd> G_ldlt;
  Eigen::VectorXd beta;       ///< normalised
  Eigen::VectorXd r;          ///< weighted residual
  double rss = 0.0;
  int rank = 0;

  Eigen::Index k() const { return X.cols(); }
};

double ridge_of(const Data& d) { return kRidge * static_cast<double>(d.n); }

void fit(const Data& d, Model& mo) {
  const Eigen::VectorXd yw = d.y.cwiseProduct(d.sw);
  if (mo.k() == 0) {
    mo.beta.resize(0);
    mo.r = yw;
    mo.rss = yw.squaredNorm();
    return;
  }
  Eigen::MatrixXd G = mo.X.transpose() * mo.X;
  G.diagonal().array() += ridge_of(d);
  mo.G_ldlt.compute(G);
  mo.beta = mo.G_ldlt.solve(mo.X.transpose() * yw);
  mo.r = yw - mo.X * mo.beta;
  mo.rss = mo.r.squaredNorm();
}

double bic(const Data& d, double rss, int k) {
  const double n = static_cast<double>(d.n);
  return n * std::log(std::max(rss, 1e-300) / n) + k * std::log(n);
}

/// Greedy rank: keeps the columns (in order) that are not spanned by the kept
/// ones (Schur complement of the Gram matrix > kAbsorbed of the column's square).
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
      for (std::size_t b = 0; b < a; ++b) v -= L(kept[a], static_cast<Eigen::Index>(b)) * l[static_cast<Eigen::Index>(b)];
      l[static_cast<Eigen::Index>(a)] = v / L(kept[a], static_cast<Eigen::Index>(a));
    }
    const double dj = G(j, j) - l.squaredNorm();
    if (dj <= 1e-8 * G(j, j)) continue;
    for (std::size_t a = 0; a < kept.size(); ++a) L(j, static_cast<Eigen::Index>(a)) = l[static_cast<Eigen::Index>(a)];
    L(j, static_cast<Eigen::Index>(kept.size())) = std::sqrt(dj);
    kept.push_back(static_cast<int>(j));
  }
  return kept;
}

/// What a candidate block adds to the model on the full data (profile).
struct Gain {
  double rss = 0.0;
  double absorbed_share = 1.0;  ///< largest residual share of a column after the model
  Eigen::VectorXd fitted;       ///< the part of the residual the block explains (weighted)
};

Gain profile(const Data& d, const Model& mo, const Block& b, bool want_fitted = false) {
  // Gram form: S = C^T C - (X^T C)^T G^-1 (X^T C) is the Gram matrix of the
  // columns with the model projected out; C~^T r = C^T r since r is
  // orthogonal to X. Costs n k kc (one product), not a projected copy of C.
  Gain g;
  const Eigen::MatrixXd& C = b.cols;
  const Eigen::MatrixXd CtC = C.transpose() * C;
  Eigen::MatrixXd S = CtC;
  Eigen::MatrixXd A;
  if (mo.k() > 0) {
    const Eigen::MatrixXd XtC = mo.X.transpose() * C;
    A = mo.G_ldlt.solve(XtC);
    S.noalias() -= XtC.transpose() * A;
  }
  g.absorbed_share = 0.0;
  for (Eigen::Index j = 0; j < S.rows(); ++j)
    if (CtC(j, j) > 0) g.absorbed_share = std::max(g.absorbed_share, S(j, j) / CtC(j, j));
  S.diagonal().array() += ridge_of(d);
  const Eigen::VectorXd Ctr = C.transpose() * mo.r;
  const Eigen::VectorXd gamma = S.ldlt().solve(Ctr);
  g.rss = mo.rss - Ctr.dot(gamma);
  if (want_fitted) {
    g.fitted = C * gamma;
    if (mo.k() > 0) g.fitted -= mo.X * (A * gamma);
  }
  return g;
}

Model with_block(const Model& mo, const Block& b, int nonlinear) {
  Model out;
  out.X.resize(mo.X.rows(), mo.k() + b.cols.cols());
  if (mo.k() > 0) out.X.leftCols(mo.k()) = mo.X;
  out.X.rightCols(b.cols.cols()) = b.cols;
  out.scale.resize(out.X.cols());
  if (mo.k() > 0) out.scale.head(mo.k()) = mo.scale;
  out.scale.tail(b.cols.cols()) = b.scale;
  out.per_run = mo.per_run;
  for (Eigen::Index j = 0; j < b.cols.cols(); ++j) out.per_run.push_back(b.per_run);
  out.nonlinear = mo.nonlinear + nonlinear;
  out.rank = mo.rank;
  return out;
}

/// Leave-one-run-out RMS (um). Each run is predicted by the model fitted to
/// the others; a per-run column (setup_shift) of the held-out run is
/// estimated on half of its rows and tested on the other half.
std::optional<double> heldout_rms(const Data& d, const Model& mo) {
  if (d.runs < 2) return std::nullopt;
  const Eigen::VectorXd yw = d.y.cwiseProduct(d.sw);
  const Eigen::Index k = mo.k();
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(k);
  std::vector<Eigen::MatrixXd> Gr(static_cast<std::size_t>(d.runs));
  std::vector<Eigen::VectorXd> br(static_cast<std::size_t>(d.runs));
  std::vector<Eigen::MatrixXd> Xr(static_cast<std::size_t>(d.runs));
  std::vector<Eigen::VectorXd> yr(static_cast<std::size_t>(d.runs));
  for (int r = 0; r < d.runs; ++r) {
    const std::vector<int>& eq = d.run_eq[static_cast<std::size_t>(r)];
    Eigen::MatrixXd Xs(static_cast<Eigen::Index>(eq.size()), k);
    Eigen::VectorXd ys(static_cast<Eigen::Index>(eq.size()));
    for (std::size_t e = 0; e < eq.size(); ++e) {
      if (k > 0) Xs.row(static_cast<Eigen::Index>(e)) = mo.X.row(eq[e]);
      ys[static_cast<Eigen::Index>(e)] = yw[eq[e]];
    }
    Gr[static_cast<std::size_t>(r)] = Xs.transpose() * Xs;
    br[static_cast<std::size_t>(r)] = Xs.transpose() * ys;
    G += Gr[static_cast<std::size_t>(r)];
    b += br[static_cast<std::size_t>(r)];
    Xr[static_cast<std::size_t>(r)] = std::move(Xs);
    yr[static_cast<std::size_t>(r)] = std::move(ys);
  }
  double sse = 0.0, wsum = 0.0;
  for (int r = 0; r < d.runs; ++r) {
    const std::size_t rs = static_cast<std::size_t>(r);
    Eigen::VectorXd res = yr[rs];
    if (k > 0) {
      Eigen::MatrixXd Gt = G - Gr[rs];
      Gt.diagonal().array() += ridge_of(d);
      const Eigen::VectorXd beta = Gt.ldlt().solve(b - br[rs]);
      res -= Xr[rs] * beta;
      // Per-run columns alive in this run: two-fold within the run.
      std::vector<Eigen::Index> own;
      for (Eigen::Index j = 0; j < k; ++j)
        if (mo.per_run[static_cast<std::size_t>(j)] && Xr[rs].col(j).squaredNorm() > 0) own.push_back(j);
      if (!own.empty()) {
        const Eigen::Index m_rows = res.size();
        Eigen::MatrixXd P(m_rows, static_cast<Eigen::Index>(own.size()));
        for (std::size_t j = 0; j < own.size(); ++j) P.col(static_cast<Eigen::Index>(j)) = Xr[rs].col(own[j]);
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
        res = out;
      }
    }
    sse += res.squaredNorm();
    for (int e : d.run_eq[rs]) wsum += d.sw[e] * d.sw[e];
  }
  return std::sqrt(sse / std::max(wsum, 1e-300));
}

double rms_of(const Data& d, double rss) {
  return std::sqrt(rss / std::max(d.sw.squaredNorm(), 1e-300));
}

// ----------------------------------------------------------- candidates ---

enum class Law : std::uint8_t { kNone, kSettling, kRate, kTemperature };

struct Candidate {
  std::string effect;
  std::optional<AxisName> axis;
  std::string variant;  ///< "offset", "scale", sensor, error name, ...
  // column builder: theta -> physical columns (n x kc)
  std::function<Eigen::MatrixXd(double)> build;
  std::vector<double> grid;  ///< theta values to scan; empty: no nonlinear parameter
  bool refine = false;       ///< golden-section refinement between grid neighbours
  bool log_refine = false;
  bool per_run = false;
  int nonlinear = 0;
  // reporting
  std::function<void(const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double theta, double theta_se,
                     Finding& f)>
      report;
  std::function<double(int row)> plot_x;  ///< the regressor that gives it away
  std::string plot_label;
  std::function<int(int row)> plot_group;
  std::string key() const { return effect + "/" + (axis ? axis_str(*axis) : "-") + "/" + variant; }
};

double round_sig(double v, int digits = 6) {
  if (!std::isfinite(v) || v == 0) return v == 0 ? 0.0 : v;
  return std::stod(fmt::format("{:.{}g}", v, digits));
}

nlohmann::json num(double v) {
  if (!std::isfinite(v)) return nullptr;
  return round_sig(v);
}

std::vector<double> unique_sorted(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }), v.end());
  return v;
}

/// sqrt(g^T cov g) for a function with gradient g.
double delta_se(const Eigen::VectorXd& g, const Eigen::MatrixXd& cov) {
  return std::sqrt(std::max(0.0, g.dot(cov * g)));
}

void amplitude_phase(const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, int i_sin, int i_cos,
                     double& amp, double& amp_se, double& phase_deg) {
  const double a = beta[i_sin], b = beta[i_cos];
  amp = std::hypot(a, b);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(beta.size());
  if (amp > 0) {
    g[i_sin] = a / amp;
    g[i_cos] = b / amp;
  }
  amp_se = delta_se(g, cov);
  phase_deg = std::atan2(b, a) * kRadToDeg;
}

struct Context {
  const Data& d;
  const ExplainOptions& opt;
  std::vector<AxisName> linear, rotary;     ///< machine axes with varying recorded positions
  std::vector<AxisName> dir_axes;           ///< axes approached from both sides
  bool has_time = false, feed_varies = false, has_feed = false;
  double duration_s = 0.0;
};

bool varies(const std::vector<double>& v) {
  double lo = INFINITY, hi = -INFINITY;
  for (double x : v)
    if (std::isfinite(x)) {
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  return hi > lo;
}

std::vector<Candidate> make_candidates(const Context& c) {
  const Data& d = c.d;
  const Eigen::Index n = static_cast<Eigen::Index>(d.n);
  std::vector<Candidate> out;
  auto along = [&](AxisName k) {  // p_b[K] per equation
    Eigen::VectorXd v(n);
    for (Eigen::Index e = 0; e < n; ++e) v[e] = d.p_b(static_cast<int>(k), e);
    return v;
  };
  auto has_along = [&](AxisName k) { return along(k).cwiseAbs().maxCoeff() > 1e-9; };

  // Every linear axis of the machine may deflect (the recording need not move it).
  std::vector<AxisName> deflecting;
  for (AxisName a : d.m.axis_order)
    if (!is_rotary(a)) deflecting.push_back(a);
  const auto moves = [&](AxisName a) { return std::find(c.linear.begin(), c.linear.end(), a) != c.linear.end(); };
  for (AxisName k : deflecting) {
    if (!has_along(k)) continue;
    const Eigen::VectorXd pk = along(k);
    // cyclic: period scan over the sampled positions.
    {
      std::vector<double> qs;
      for (std::size_t i = 0; i < d.rec.size(); ++i) qs.push_back(d.q(k, static_cast<int>(i)));
      const std::vector<double> uq = unique_sorted(qs);
      if (uq.size() >= 8) {
        std::vector<double> gaps;
        for (std::size_t i = 1; i < uq.size(); ++i) gaps.push_back(uq[i] - uq[i - 1]);
        std::sort(gaps.begin(), gaps.end());
        const double gap = gaps[gaps.size() / 2];
        const double span = uq.back() - uq.front();
        // At least three periods over the span: a longer 'period' is smooth geometry.
        const double p_min = std::max(2.2 * gap, 1e-3), p_max = span / 3.0;
        if (p_max > 1.5 * p_min) {  // else too few positions per period to scan a period at all
          Candidate cand;
          cand.effect = "cyclic";
          cand.axis = k;
          cand.variant = "";
          cand.nonlinear = 1;
          cand.refine = true;
          const double f_lo = 1.0 / p_max, f_hi = 1.0 / p_min;
          const double df = std::max(1.0 / (4.0 * span), (f_hi - f_lo) / 600.0);
          for (double f = f_lo; f <= f_hi; f += df) cand.grid.push_back(1.0 / f);
          cand.build = [&d, k, pk, n](double period) {
            Eigen::MatrixXd C(n, 2);
            for (Eigen::Index e = 0; e < n; ++e) {
              const double ph = 2 * kPi * d.q(k, d.row[static_cast<std::size_t>(e)]) / period;
              C(e, 0) = pk[e] * std::sin(ph);
              C(e, 1) = pk[e] * std::cos(ph);
            }
            return C;
          };
          cand.report = [k](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double period, double period_se,
                            Finding& f) {
            double amp = 0, amp_se = 0, phase = 0;
            amplitude_phase(beta, cov, 0, 1, amp, amp_se, phase);
            f.parameters = {{"period_mm", num(period)}, {"amplitude_um", num(amp)}, {"phase_deg", num(phase)}};
            f.std_errors = {{"period_mm", period_se}, {"amplitude_um", amp_se}};
            f.explanation = fmt::format(
                "{0} deviates periodically along {0} with a period of {1:.4g} mm and an amplitude of {2:.3g} um: "
                "a screw-pitch or scale/encoder interpolation error, which a smooth polynomial cannot follow.",
                axis_str(k), period, amp);
          };
          cand.plot_x = [&d, k](int i) { return d.q_user(k, i); };
          cand.plot_label = position_name(k);
          out.push_back(cand);
        }
      }
    }
    // reversal and servo lag: approach direction.
    if (std::find(c.dir_axes.begin(), c.dir_axes.end(), k) != c.dir_axes.end()) {
      Candidate rev;
      rev.effect = "reversal";
      rev.axis = k;
      rev.build = [&d, k, pk, n](double) {
        Eigen::MatrixXd C(n, 1);
        for (Eigen::Index e = 0; e < n; ++e) C(e, 0) = pk[e] * 0.5 * d.s(k, d.row[static_cast<std::size_t>(e)]);
        return C;
      };
      rev.report = [k](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double, Finding& f) {
        f.parameters = {{"value_um", num(beta[0])}};
        f.std_errors = {{"value_um", std::sqrt(cov(0, 0))}};
        f.explanation = fmt::format(
            "{0} deviates {1:.3g} um {2} when approached from +{0} than from -{0} (reversal value B = {3:.3g} um): "
            "lost motion (backlash) in the {0} drive, absent from the rigid-body model.",
            axis_str(k), std::abs(beta[0]), beta[0] >= 0 ? "more" : "less", beta[0]);
      };
      rev.plot_x = [&d, k](int i) { return d.q_user(k, i); };
      rev.plot_label = position_name(k);
      rev.plot_group = [&d, k](int i) { return d.s(k, i); };
      out.push_back(rev);
      if (c.has_feed) {
        Candidate sl;
        sl.effect = "servo_lag";
        sl.axis = k;
        sl.build = [&d, k, pk, n](double) {
          Eigen::MatrixXd C(n, 1);
          for (Eigen::Index e = 0; e < n; ++e) {
            const int i = d.row[static_cast<std::size_t>(e)];
            C(e, 0) = -pk[e] * d.feed(i) / 1000.0 * d.s(k, i);
          }
          return C;
        };
        sl.report = [k](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double, Finding& f) {
          f.parameters = {{"um_per_m_min", num(beta[0])}};
          f.std_errors = {{"um_per_m_min", std::sqrt(cov(0, 0))}};
          f.explanation = fmt::format(
              "{0} lags {1:.3g} um behind the command per m/min of feed, against the direction of motion: "
              "servo mismatch / following error, which grows with feed and is absent at standstill.",
              axis_str(k), beta[0]);
        };
        sl.plot_x = [&d, k](int i) { return d.feed(i) * d.s(k, i); };
        sl.plot_label = "feed_mm_min * dir_" + lower_axis(k);
        out.push_back(sl);
      }
    }
    // thermal drift: offset or scale, settling / rate / temperature.
    const int ki = static_cast<int>(k);
    for (int scale = 0; scale < (moves(k) ? 2 : 1); ++scale) {
      auto factor = [&d, k, scale](int i) { return scale ? d.q(k, i) / 1000.0 : 1.0; };
      const std::string kind = scale ? "scale" : "offset";
      if (c.has_time) {
        Candidate settle;
        settle.effect = "thermal_drift";
        settle.axis = k;
        settle.variant = kind + "/settling";
        settle.nonlinear = 1;
        settle.refine = true;
        settle.log_refine = true;
        for (int j = 0; j <= 16; ++j)
          settle.grid.push_back(c.duration_s / 30.0 * std::pow(150.0, j / 16.0));  // T/30 .. 5 T
        settle.build = [&d, pk, n, factor](double tau) {
          Eigen::MatrixXd C(n, 1);
          for (Eigen::Index e = 0; e < n; ++e) {
            const int i = d.row[static_cast<std::size_t>(e)];
            C(e, 0) = pk[e] * factor(i) * (1.0 - std::exp(-d.t(i) / tau));
          }
          return C;
        };
        settle.report = [k, kind](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double tau,
                                  double tau_se, Finding& f) {
          f.parameters = {{"kind", kind}, {"amplitude_um", num(beta[0])}, {"tau_s", num(tau)}};
          if (kind == "scale") f.parameters.push_back({"reference_length_mm", 1000});
          f.std_errors = {{"amplitude_um", std::sqrt(cov(0, 0))}, {"tau_s", tau_se}};
          f.explanation = fmt::format(
              "{0} drifts with time, settling to {1:.3g} um{2} with a time constant of {3:.0f} s: thermal "
              "growth of the {0} drive (screw or scale expansion) as the machine warms up.",
              axis_str(k), beta[0], kind == "scale" ? " per 1000 mm of travel" : "", tau);
        };
        settle.plot_x = [&d](int i) { return d.t(i); };
        settle.plot_label = "t_s";
        out.push_back(settle);

        Candidate rate = settle;
        rate.variant = kind + "/rate";
        rate.grid.clear();
        rate.nonlinear = 0;
        rate.refine = false;
        rate.build = [&d, pk, n, factor](double) {
          Eigen::MatrixXd C(n, 1);
          for (Eigen::Index e = 0; e < n; ++e) {
            const int i = d.row[static_cast<std::size_t>(e)];
            C(e, 0) = pk[e] * factor(i) * d.t(i) / 3600.0;
          }
          return C;
        };
        rate.report = [k, kind](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double, Finding& f) {
          f.parameters = {{"kind", kind}, {"rate_um_per_h", num(beta[0])}};
          if (kind == "scale") f.parameters.push_back({"reference_length_mm", 1000});
          f.std_errors = {{"rate_um_per_h", std::sqrt(cov(0, 0))}};
          f.explanation = fmt::format(
              "{0} drifts steadily by {1:.3g} um per hour{2}: thermal growth that had not settled during the test.",
              axis_str(k), beta[0], kind == "scale" ? " per 1000 mm of travel" : "");
        };
        out.push_back(rate);
      }
      for (const NamedColumn& tc : d.rec.temperature_c) {
        if (!varies(tc.values)) continue;
        bool complete = true;
        for (double v : tc.values) complete = complete && std::isfinite(v);
        if (!complete) continue;
        Candidate temp;
        temp.effect = "thermal_drift";
        temp.axis = k;
        temp.variant = kind + "/" + tc.name;
        const std::vector<double>* values = &tc.values;
        temp.build = [&d, pk, n, factor, values](double) {
          Eigen::MatrixXd C(n, 1);
          for (Eigen::Index e = 0; e < n; ++e) {
            const int i = d.row[static_cast<std::size_t>(e)];
            C(e, 0) = pk[e] * factor(i) * (*values)[static_cast<std::size_t>(i)];
          }
          return C;
        };
        const std::string sensor = tc.name.substr(5, tc.name.size() - 7);
        temp.report = [k, kind, sensor](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                                        Finding& f) {
          f.parameters = {{"kind", kind}, {"um_per_k", num(beta[0])}, {"sensor", sensor}};
          if (kind == "scale") f.parameters.push_back({"reference_length_mm", 1000});
          f.std_errors = {{"um_per_k", std::sqrt(cov(0, 0))}};
          f.explanation = fmt::format(
              "{0} moves {1:.3g} um per kelvin of temp_{2}_c{3}: thermal expansion the rigid-body model leaves out.",
              axis_str(k), beta[0], sensor, kind == "scale" ? " per 1000 mm of travel" : "");
        };
        temp.plot_x = [values](int i) { return (*values)[static_cast<std::size_t>(i)]; };
        temp.plot_label = tc.name;
        out.push_back(temp);
      }
    }
    (void)ki;
    // setup shift: a constant per run along K.
    if (d.runs >= 2) {
      Candidate ss;
      ss.effect = "setup_shift";
      ss.axis = k;
      ss.per_run = true;
      const int runs = d.runs;
      ss.build = [&d, pk, n, runs](double) {
        Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, runs);
        for (Eigen::Index e = 0; e < n; ++e) C(e, d.run[static_cast<std::size_t>(e)]) = pk[e];
        return C;
      };
      ss.report = [k, runs](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double, Finding& f) {
        nlohmann::json per = nlohmann::json::array(), se = nlohmann::json::array();
        double worst = 0;
        for (int r = 0; r < runs; ++r) {
          const double v = beta[r] - beta[0];
          per.push_back(num(v));
          worst = std::max(worst, std::abs(v));
          f.std_errors.push_back({fmt::format("per_run_um/{}", r),
                                  std::sqrt(std::max(0.0, cov(r, r) + cov(0, 0) - 2 * cov(r, 0)))});
        }
        f.parameters = {{"per_run_um", per}, {"relative_to", "first run"}};
        f.explanation = fmt::format(
            "The runs sit at different {0} offsets (up to {1:.3g} um from the first run), constant within each "
            "run: the set-up (instrument, ball or fixture) moved between runs.",
            axis_str(k), worst);
      };
      ss.plot_x = [&d](int i) { return d.rec.has_run() ? static_cast<double>(d.rec.run[static_cast<std::size_t>(i)] + 1) : 1.0; };
      ss.plot_label = "run";
      out.push_back(ss);
    }
  }

  // sag: K deflects with the position of another axis J, quadratically.
  std::vector<AxisName> inputs = c.linear;
  inputs.insert(inputs.end(), c.rotary.begin(), c.rotary.end());
  for (AxisName k : deflecting) {
    if (!has_along(k)) continue;
    const Eigen::VectorXd pk = along(k);
    for (AxisName j : inputs) {
      if (j == k) continue;
      std::vector<double> qs;
      for (std::size_t i = 0; i < d.rec.size(); ++i) qs.push_back(d.q_user(j, static_cast<int>(i)));
      const std::vector<double> uq = unique_sorted(qs);
      if (uq.size() < 4) continue;
      const double centre = 0.5 * (uq.front() + uq.back());
      Candidate sag;
      sag.effect = "sag";
      sag.axis = k;
      sag.variant = axis_str(j);
      sag.build = [&d, pk, n, j, centre](double) {
        Eigen::MatrixXd C(n, 2);
        for (Eigen::Index e = 0; e < n; ++e) {
          const double x = d.q_user(j, d.row[static_cast<std::size_t>(e)]) - centre;
          C(e, 0) = pk[e] * x * x;
          C(e, 1) = pk[e] * x;
        }
        return C;
      };
      sag.report = [k, j, centre](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double,
                                  Finding& f) {
        const double c2 = beta[0], c1 = beta[1];
        const double origin = c2 != 0 ? centre - c1 / (2 * c2) : centre;
        Eigen::VectorXd g(2);
        g << c1 / (2 * c2 * c2), -1 / (2 * c2);
        f.parameters = {{"input_axis", axis_str(j)}, {"coefficient", num(c2)}, {"power", 2}, {"origin", num(origin)}};
        f.std_errors = {{"coefficient", std::sqrt(cov(0, 0))}, {"origin", delta_se(g, cov)}};
        f.explanation = fmt::format(
            "{0} deflects with the square of the {1} position ({2:.3g} um per {3}^2 about {1} = {4:.4g}): sag under "
            "gravity or load as {1} moves, which the rigid-body errors of {0} cannot produce.",
            axis_str(k), axis_str(j), c2, is_rotary(j) ? "deg" : "mm", origin);
      };
      sag.plot_x = [&d, j](int i) { return d.q_user(j, i); };
      sag.plot_label = position_name(j);
      out.push_back(sag);
    }
  }

  // rotary axes: wobble and positioning, order 1..4.
  for (AxisName rax : c.rotary) {
    const int own = static_cast<int>(rax) - 3;
    int perp[2] = {-1, -1}, self = -1;
    int np = 0;
    for (int comp = 0; comp < 3; ++comp) {
      const std::string name = component_error_name(static_cast<Component>(comp + 3), rax);
      const auto it = std::find(d.names.begin(), d.names.end(), name);
      const int idx = it == d.names.end() ? -1 : static_cast<int>(it - d.names.begin());
      if (comp == own) self = idx;
      else perp[np++] = idx;
    }
    // gp is mm per rad; the parameters are urad, the columns um per urad: 1e-3.
    if (perp[0] >= 0 && perp[1] >= 0) {
      Candidate wob;
      wob.effect = "rotary_wobble";
      wob.axis = rax;
      wob.grid = {1, 2, 3, 4};
      wob.nonlinear = 1;
      wob.build = [&d, n, rax, perp](double order) {
        Eigen::MatrixXd C(n, 2);
        for (Eigen::Index e = 0; e < n; ++e) {
          const double th = order * d.q(rax, d.row[static_cast<std::size_t>(e)]);
          const double ga = d.gp(e, perp[0]) * 1e-3, gb = d.gp(e, perp[1]) * 1e-3;
          // EA = a cos - b sin, EB = b cos + a sin  (amplitude (a, b) = A (cos phi, sin phi))
          C(e, 0) = ga * std::cos(th) + gb * std::sin(th);
          C(e, 1) = -ga * std::sin(th) + gb * std::cos(th);
        }
        return C;
      };
      wob.report = [rax](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double order, double,
                         Finding& f) {
        double amp = 0, amp_se = 0, phase = 0;
        amplitude_phase(beta, cov, 0, 1, amp, amp_se, phase);
        f.parameters = {{"order", static_cast<int>(order)}, {"amplitude_urad", num(amp)}, {"phase_deg", num(phase)}};
        f.std_errors = {{"amplitude_urad", amp_se}};
        f.explanation = fmt::format(
            "The {0} axis tilts by {1:.3g} urad, {2} times per turn: an angle-dependent error motion "
            "(wobble, ISO 230-7) of the {0} bearing, beyond the constant tilts of the location errors.",
            axis_str(rax), amp, static_cast<int>(order));
      };
      wob.plot_x = [&d, rax](int i) { return d.q_user(rax, i); };
      wob.plot_label = position_name(rax);
      out.push_back(wob);
    }
    if (self >= 0) {
      Candidate pos;
      pos.effect = "rotary_positioning";
      pos.axis = rax;
      pos.grid = {1, 2, 3, 4};
      pos.nonlinear = 1;
      pos.build = [&d, n, rax, self](double order) {
        Eigen::MatrixXd C(n, 2);
        for (Eigen::Index e = 0; e < n; ++e) {
          const double th = order * d.q(rax, d.row[static_cast<std::size_t>(e)]);
          const double g = d.gp(e, self) * 1e-3;
          C(e, 0) = g * std::sin(th);
          C(e, 1) = g * std::cos(th);
        }
        return C;
      };
      pos.report = [rax](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double order, double,
                         Finding& f) {
        double amp = 0, amp_se = 0, phase = 0;
        amplitude_phase(beta, cov, 0, 1, amp, amp_se, phase);
        f.parameters = {{"order", static_cast<int>(order)}, {"amplitude_urad", num(amp)}, {"phase_deg", num(phase)}};
        f.std_errors = {{"amplitude_urad", amp_se}};
        f.explanation = fmt::format(
            "The {0} axis mispositions by {1:.3g} urad, {2} times per turn: an angular positioning error of {0} "
            "(encoder or gear eccentricity) that varies with the angle.",
            axis_str(rax), amp, static_cast<int>(order));
      };
      pos.plot_x = [&d, rax](int i) { return d.q_user(rax, i); };
      pos.plot_label = position_name(rax);
      out.push_back(pos);
    }
  }

  // Fixed baseline: geometric errors it may lack, per linear axis K.
  if (c.opt.baseline) {
    for (AxisName k : c.linear) {
      const AxisLimits& L = d.m.limits[static_cast<std::size_t>(*d.m.index_of(k))];
      const double centre = 0.5 * (L.min + L.max), half = std::max(0.5 * (L.max - L.min), 1e-9);
      for (int comp = 0; comp < 6; ++comp) {
        const std::string name = component_error_name(static_cast<Component>(comp), k);
        const auto it = std::find(d.names.begin(), d.names.end(), name);
        if (it == d.names.end()) continue;
        const int idx = static_cast<int>(it - d.names.begin());
        if (d.gp.col(idx).cwiseAbs().maxCoeff() < 1e-12) continue;
        // Only errors the baseline lacks: the errors file defines the others.
        const AxisErrors* given = c.opt.baseline->errors_of(k);
        if (given && given->present[static_cast<std::size_t>(comp)]) continue;
        const bool angular = comp >= 3;
        const std::string effect = angular ? "angular" : (comp == static_cast<int>(k) ? "scale" : "squareness");
        Candidate lin;
        lin.effect = effect;
        lin.axis = k;
        lin.variant = name;
        // The positioning error of K (EKK): scale (linear) and its curvature
        // (s^2, s^3 at the ends of the travel), as a laser calibration gives it.
        const bool positioning = !angular && comp == static_cast<int>(k);
        lin.build = [&d, n, k, idx, angular, positioning, centre, half](double) {
          Eigen::MatrixXd C(n, positioning ? 3 : 1);
          for (Eigen::Index e = 0; e < n; ++e) {
            // error = slope * q / 1000 (um or urad per m); deviation um.
            const double qm = d.q(k, d.row[static_cast<std::size_t>(e)]);
            C(e, 0) = d.gp(e, idx) * (angular ? 1e-3 : 1.0) * qm / 1000.0;
            if (positioning) {
              const double sc = (qm - centre) / half;
              C(e, 1) = d.gp(e, idx) * sc * sc;
              C(e, 2) = d.gp(e, idx) * sc * sc * sc;
            }
          }
          return C;
        };
        const std::string unit = angular ? "urad_per_m" : "um_per_m";
        lin.report = [k, name, unit, effect, positioning](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov,
                                                          double, double, Finding& f) {
          f.parameters = {{"error", name}, {unit, num(beta[0])}};
          f.std_errors = {{unit, std::sqrt(cov(0, 0))}};
          if (positioning) {
            f.parameters.push_back({"quadratic_um", num(beta[1])});
            f.parameters.push_back({"cubic_um", num(beta[2])});
            f.std_errors.push_back({"quadratic_um", std::sqrt(cov(1, 1))});
            f.std_errors.push_back({"cubic_um", std::sqrt(cov(2, 2))});
            f.explanation = fmt::format(
                "The positioning error {} of {} is missing from the baseline: {:.3g} um per m of travel (scale), "
                "with {:.3g} um quadratic and {:.3g} um cubic curvature at the ends of the travel.",
                name, axis_str(k), beta[0], beta[1], beta[2]);
          } else {
            f.explanation = fmt::format("{} of {} grows linearly along {}: {} {:.3g} {} missing from the baseline.",
                                        name, axis_str(k), axis_str(k), effect, beta[0], unit);
          }
        };
        lin.plot_x = [&d, k](int i) { return d.q_user(k, i); };
        lin.plot_label = position_name(k);
        out.push_back(lin);
        if (!angular && comp != static_cast<int>(k)) {
          Candidate st;
          st.effect = "straightness";
          st.axis = k;
          st.variant = name;
          st.build = [&d, n, k, idx, centre, half](double) {
            Eigen::MatrixXd C(n, 2);
            for (Eigen::Index e = 0; e < n; ++e) {
              const double s = (d.q(k, d.row[static_cast<std::size_t>(e)]) - centre) / half;
              C(e, 0) = d.gp(e, idx) * s * s;
              C(e, 1) = d.gp(e, idx) * s * s * s;
            }
            return C;
          };
          st.report = [k, name](const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double, double, Finding& f) {
            f.parameters = {{"error", name}, {"quadratic_um", num(beta[0])}, {"cubic_um", num(beta[1])}};
            f.std_errors = {{"quadratic_um", std::sqrt(cov(0, 0))}, {"cubic_um", std::sqrt(cov(1, 1))}};
            f.explanation = fmt::format("{} of {} is curved ({:.3g} um quadratic, {:.3g} um cubic at the ends of "
                                        "the travel): straightness missing from the baseline.",
                                        name, axis_str(k), beta[0], beta[1]);
          };
          st.plot_x = [&d, k](int i) { return d.q_user(k, i); };
          st.plot_label = position_name(k);
          out.push_back(st);
        }
      }
    }
  }
  return out;
}

// -------------------------------------------------------------- baseline --

/// Constant per recorded component plus, without a fixed baseline, every
/// location error and every component error of the linear axes (degree).
Model baseline_model(const Data& d, const ExplainOptions& opt, std::string& description) {
  const Eigen::Index n = static_cast<Eigen::Index>(d.n);
  std::vector<Eigen::VectorXd> cols;
  for (int g = 0; g < 4; ++g) {
    if (!d.has_groups[g]) continue;
    Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
    for (Eigen::Index e = 0; e < n; ++e)
      if (d.group[static_cast<std::size_t>(e)] == g) c[e] = 1.0;
    cols.push_back(c);
  }
  int location = 0, components = 0;
  // Degree per linear axis: opt.degree, or (0, automatic) a value per target
  // for an axis run through at most kSparseTargets targets (as ISO 230-2
  // evaluates a positioning test: the mean deviation of each target), else cubic.
  std::array<int, kAxisNameCount> degree_of{};
  std::string degrees;
  for (AxisName a : d.m.axis_order) {
    if (is_rotary(a)) continue;
    std::vector<double> qs;
    for (std::size_t e = 0; e < d.n; ++e) qs.push_back(d.q(a, d.row[e]));
    const int targets = static_cast<int>(unique_sorted(qs).size());
    int deg = opt.degree;
    if (deg == 0) deg = targets <= kSparseTargets ? std::max(1, targets - 1) : 3;
    degree_of[static_cast<std::size_t>(a)] = deg;
    degrees += fmt::format("{}{} {}", degrees.empty() ? "" : ", ", axis_str(a), deg);
  }
  if (!opt.baseline) {
    for (std::size_t k = 0; k < d.names.size(); ++k) {
      const ErrorName en = *parse_error_name(d.names[k]);
      const Eigen::VectorXd g = d.gp.col(static_cast<Eigen::Index>(k));
      if (en.location) {
        cols.push_back(g);
        ++location;
        continue;
      }
      if (is_rotary(en.axis)) continue;
      const AxisLimits& L = d.m.limits[static_cast<std::size_t>(*d.m.index_of(en.axis))];
      const double centre = 0.5 * (L.min + L.max), half = std::max(0.5 * (L.max - L.min), 1e-9);
      const int degree = degree_of[static_cast<std::size_t>(en.axis)];
      for (int p = 1; p <= degree; ++p) {
        Eigen::VectorXd c(n);
        for (Eigen::Index e = 0; e < n; ++e) {
          const double s = (d.q(en.axis, d.row[static_cast<std::size_t>(e)]) - centre) / half;
          c[e] = g[e] * std::pow(s, p);
        }
        cols.push_back(c);
      }
      ++components;
    }
  }
  Eigen::MatrixXd phys(n, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t j = 0; j < cols.size(); ++j) phys.col(static_cast<Eigen::Index>(j)) = cols[j];
  Block b = make_block(d, phys);
  const std::vector<int> keep = independent_columns(b.cols);
  Model mo;
  mo.X.resize(n, static_cast<Eigen::Index>(keep.size()));
  mo.scale.resize(static_cast<Eigen::Index>(keep.size()));
  for (std::size_t j = 0; j < keep.size(); ++j) {
    mo.X.col(static_cast<Eigen::Index>(j)) = b.cols.col(keep[j]);
    mo.scale[static_cast<Eigen::Index>(j)] = b.scale[keep[j]];
  }
  mo.per_run.assign(keep.size(), false);
  mo.rank = static_cast<int>(keep.size());
  const int linear_axes = static_cast<int>(std::count_if(d.m.axis_order.begin(), d.m.axis_order.end(),
                                                         [](AxisName a) { return !is_rotary(a); }));
  if (opt.baseline) {
    description = fmt::format("fixed: {} (+ a constant per recorded component)",
                              opt.baseline_file.empty() ? std::string("baseline errors") : opt.baseline_file);
  } else {
    description = fmt::format(
        "rigid-body, fitted: {} component errors of {} linear axis(es) as polynomials (degree {}), {} location "
        "errors, a constant per recorded component; {} of {} parameters identifiable on this recording",
        components, linear_axes, degrees, location, keep.size(), cols.size());
  }
  return mo;
}

// ------------------------------------------------------------- mismatch ---

struct Regressor {
  std::string name;
  std::vector<double> value;  ///< per recording row (NaN: not recorded)
  bool categorical = false;
  std::function<std::string(double lo, double hi, double mean_um)> where;
};

std::vector<Mismatch> locate(const Data& d, const Eigen::VectorXd& r_um, const std::vector<Regressor>& regs) {
  std::vector<Mismatch> out;
  for (int g = 0; g < 4; ++g) {
    if (!d.has_groups[g]) continue;
    std::vector<int> eq;
    for (std::size_t e = 0; e < d.n; ++e)
      if (d.group[e] == g) eq.push_back(static_cast<int>(e));
    if (eq.size() < 12) continue;
    double mean = 0;
    for (int e : eq) mean += r_um[e];
    mean /= static_cast<double>(eq.size());
    double sst = 0;
    for (int e : eq) sst += (r_um[e] - mean) * (r_um[e] - mean);
    if (sst <= 0) continue;
    for (const Regressor& reg : regs) {
      std::vector<std::pair<double, double>> xv;
      for (int e : eq) {
        const double x = reg.value[static_cast<std::size_t>(d.row[static_cast<std::size_t>(e)])];
        if (std::isfinite(x)) xv.push_back({x, r_um[e]});
      }
      if (xv.size() < 12) continue;
      std::sort(xv.begin(), xv.end());
      // Bins: the levels of a categorical regressor, else up to 8 quantile bins.
      std::vector<std::size_t> edges{0};
      if (reg.categorical) {
        for (std::size_t i = 1; i < xv.size(); ++i)
          if (xv[i].first != xv[i - 1].first) edges.push_back(i);
      } else {
        const std::size_t bins = std::min<std::size_t>(8, xv.size() / 4);
        for (std::size_t b = 1; b < bins; ++b) {
          std::size_t i = b * xv.size() / bins;
          while (i < xv.size() && i > 0 && xv[i].first == xv[i - 1].first) ++i;
          if (i < xv.size() && i > edges.back()) edges.push_back(i);
        }
      }
      edges.push_back(xv.size());
      const std::size_t k = edges.size() - 1;
      if (k < 2) continue;
      double m_all = 0;
      for (auto& p : xv) m_all += p.second;
      m_all /= static_cast<double>(xv.size());
      double ssb = 0, sstot = 0, best = 0, best_lo = 0, best_hi = 0;
      for (auto& p : xv) sstot += (p.second - m_all) * (p.second - m_all);
      for (std::size_t b = 0; b < k; ++b) {
        double s = 0;
        for (std::size_t i = edges[b]; i < edges[b + 1]; ++i) s += xv[i].second;
        const double cnt = static_cast<double>(edges[b + 1] - edges[b]);
        const double mb = s / cnt;
        ssb += cnt * (mb - m_all) * (mb - m_all);
        if (std::abs(mb - m_all) > std::abs(best)) {
          best = mb - m_all;
          best_lo = xv[edges[b]].first;
          best_hi = xv[edges[b + 1] - 1].first;
        }
      }
      if (sstot <= 0) continue;
      const double nn = static_cast<double>(xv.size());
      const double adj = 1.0 - ((sstot - ssb) / (nn - static_cast<double>(k))) / (sstot / (nn - 1));
      if (adj < 0.05) continue;
      out.push_back({kGroupName[g], reg.name, reg.where(best_lo, best_hi, best), std::min(1.0, adj)});
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const Mismatch& a, const Mismatch& b) { return a.strength > b.strength; });
  if (out.size() > 10) out.resize(10);
  return out;
}

std::vector<Regressor> regressors(const Data& d) {
  const Recordings& rec = d.rec;
  std::vector<Regressor> regs;
  const std::size_t rows = rec.size();
  for (AxisName a : d.m.axis_order) {
    if (!rec.has_axis(a)) continue;
    Regressor pos;
    pos.name = position_name(a);
    for (std::size_t i = 0; i < rows; ++i) pos.value.push_back(d.q_user(a, static_cast<int>(i)));
    if (!varies(pos.value)) continue;
    const std::string unit = is_rotary(a) ? "deg" : "mm";
    pos.where = [a, unit](double lo, double hi, double m) {
      return fmt::format("{} {:.4g}..{:.4g} {}: mean residual {:+.3g} um (the region that departs most)",
                         axis_str(a), lo, hi, unit, m);
    };
    regs.push_back(pos);
    if (!rec.dir[static_cast<std::size_t>(a)].empty()) {
      Regressor dir;
      dir.name = dir_column_name(a);
      dir.categorical = true;
      bool plus = false, minus = false;
      for (std::size_t i = 0; i < rows; ++i) {
        const int s = rec.dir[static_cast<std::size_t>(a)][i];
        plus = plus || s > 0;
        minus = minus || s < 0;
        dir.value.push_back(s == 0 ? std::nan("") : s);
      }
      if (!(plus && minus)) continue;
      dir.where = [a](double lo, double, double m) {
        return fmt::format("all {} sweeps: approached from {}{}, mean residual {:+.3g} um", axis_str(a),
                           lo > 0 ? "+" : "-", axis_str(a), m);
      };
      regs.push_back(dir);
    }
  }
  if (d.runs >= 2) {
    Regressor run;
    run.name = "run";
    run.categorical = true;
    for (std::size_t i = 0; i < rows; ++i) run.value.push_back(rec.run[i] >= 0 ? rec.run[i] : std::nan(""));
    run.where = [&rec](double lo, double, double m) {
      const std::size_t r = static_cast<std::size_t>(lo);
      return fmt::format("run {}: mean residual {:+.3g} um", r < rec.run_names.size() ? rec.run_names[r] : "?", m);
    };
    regs.push_back(run);
  }
  auto continuous = [&](const std::string& name, const std::vector<double>& v, const std::string& unit) {
    if (v.empty() || !varies(v)) return;
    Regressor r;
    r.name = name;
    r.value = v;
    r.where = [name, unit](double lo, double hi, double m) {
      return fmt::format("{} {:.4g}..{:.4g} {}: mean residual {:+.3g} um", name, lo, hi, unit, m);
    };
    regs.push_back(r);
  };
  continuous("t_s", rec.t_s, "s");
  continuous("feed_mm_min", rec.feed_mm_min, "mm/min");
  for (const NamedColumn& t : rec.temperature_c) continuous(t.name, t.values, "degC");
  for (const ExtraColumn& x : rec.extra) continuous(x.name, x.value, "");
  return regs;
}

// ------------------------------------------------------------ selection ---

struct Fitted {
  const Candidate* cand = nullptr;
  double theta = 0.0;
  Block block;
  Gain gain;
  double bic = 0.0;
};

/// Fits a candidate's nonlinear parameter (grid, then golden section) by the
/// profile RSS given the model.
std::optional<Fitted> fit_candidate(const Data& d, const Model& mo, const Candidate& c,
                                    std::optional<double> hint = std::nullopt) {
  auto eval = [&](double theta) {
    Fitted f;
    f.cand = &c;
    f.theta = theta;
    f.block = make_block(d, c.build(theta), c.per_run);
    f.gain = profile(d, mo, f.block);
    return f;
  };
  std::optional<Fitted> best;
  if (c.grid.empty()) {
    best = eval(0.0);
  } else if (hint && c.refine) {
    // A later step: the parameter was scanned before; refine around it
    // (+-15 %) with the current model.
    const double gr = (std::sqrt(5.0) - 1) / 2;
    double a = std::log(*hint / 1.15), b = std::log(*hint * 1.15);
    double x1 = b - gr * (b - a), x2 = a + gr * (b - a);
    double f1 = eval(std::exp(x1)).gain.rss, f2 = eval(std::exp(x2)).gain.rss;
    for (int it = 0; it < 10; ++it) {
      if (f1 < f2) {
        b = x2; x2 = x1; f2 = f1; x1 = b - gr * (b - a); f1 = eval(std::exp(x1)).gain.rss;
      } else {
        a = x1; x1 = x2; f1 = f2; x2 = a + gr * (b - a); f2 = eval(std::exp(x2)).gain.rss;
      }
    }
    best = eval(std::exp(0.5 * (a + b)));
    Fitted at_hint = eval(*hint);
    if (at_hint.gain.rss < best->gain.rss) best = std::move(at_hint);
  } else if (c.effect == "cyclic") {
    // Coarse periodogram of the current residual (2x2 per period, unique
    // positions aggregated), then the full profile at the best peaks.
    std::vector<std::pair<double, double>> score;
    // Aggregate residual and weight per position.
    std::map<double, std::array<double, 2>> agg;
    const AxisName k = *c.axis;
    for (std::size_t e = 0; e < d.n; ++e) {
      const double pk = d.p_b(static_cast<int>(k), static_cast<Eigen::Index>(e)) * d.sw[static_cast<Eigen::Index>(e)];
      auto& a = agg[d.q(k, d.row[e])];
      a[0] += pk * mo.r[static_cast<Eigen::Index>(e)];
      a[1] += pk * pk;
    }
    for (double period : c.grid) {
      double ss = 0, cc = 0, sc = 0, sr = 0, cr = 0;
      for (const auto& [q, a] : agg) {
        const double ph = 2 * kPi * q / period, s = std::sin(ph), co = std::cos(ph);
        ss += a[1] * s * s;
        cc += a[1] * co * co;
        sc += a[1] * s * co;
        sr += a[0] * s;
        cr += a[0] * co;
      }
      const double det = ss * cc - sc * sc;
      const double g = det > 1e-12 * (ss * cc + 1e-300) ? (cc * sr * sr - 2 * sc * sr * cr + ss * cr * cr) / det : 0.0;
      score.push_back({g, period});
    }
    std::vector<std::size_t> order(score.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return score[a].first != score[b].first ? score[a].first > score[b].first : a < b;
    });
    for (std::size_t t = 0; t < std::min<std::size_t>(3, order.size()); ++t) {
      const std::size_t i = order[t];
      Fitted f = eval(c.grid[i]);
      // refine between the neighbours in frequency
      double lo = 1.0 / c.grid[i > 0 ? i - 1 : i], hi = 1.0 / c.grid[i + 1 < c.grid.size() ? i + 1 : i];
      if (lo > hi) std::swap(lo, hi);
      const double gr = (std::sqrt(5.0) - 1) / 2;
      double a = lo, b = hi;
      double x1 = b - gr * (b - a), x2 = a + gr * (b - a);
      double f1 = eval(1.0 / x1).gain.rss, f2 = eval(1.0 / x2).gain.rss;
      for (int it = 0; it < 18; ++it) {
        if (f1 < f2) {
          b = x2; x2 = x1; f2 = f1; x1 = b - gr * (b - a); f1 = eval(1.0 / x1).gain.rss;
        } else {
          a = x1; x1 = x2; f1 = f2; x2 = a + gr * (b - a); f2 = eval(1.0 / x2).gain.rss;
        }
      }
      Fitted r = eval(1.0 / (0.5 * (a + b)));
      if (r.gain.rss > f.gain.rss) r = f;
      if (!best || r.gain.rss < best->gain.rss) best = std::move(r);
    }
  } else {
    std::size_t bi = 0;
    std::vector<double> rss(c.grid.size());
    for (std::size_t i = 0; i < c.grid.size(); ++i) {
      Fitted f = eval(c.grid[i]);
      rss[i] = f.gain.rss;
      if (!best || f.gain.rss < best->gain.rss) {
        best = std::move(f);
        bi = i;
      }
    }
    if (c.refine && c.grid.size() >= 3) {
      auto tr = [&](double x) { return c.log_refine ? std::log(x) : x; };
      auto inv = [&](double x) { return c.log_refine ? std::exp(x) : x; };
      double a = tr(c.grid[bi > 0 ? bi - 1 : bi]), b = tr(c.grid[bi + 1 < c.grid.size() ? bi + 1 : bi]);
      const double gr = (std::sqrt(5.0) - 1) / 2;
      double x1 = b - gr * (b - a), x2 = a + gr * (b - a);
      double f1 = eval(inv(x1)).gain.rss, f2 = eval(inv(x2)).gain.rss;
      for (int it = 0; it < 14; ++it) {
        if (f1 < f2) {
          b = x2; x2 = x1; f2 = f1; x1 = b - gr * (b - a); f1 = eval(inv(x1)).gain.rss;
        } else {
          a = x1; x1 = x2; f1 = f2; x2 = a + gr * (b - a); f2 = eval(inv(x2)).gain.rss;
        }
      }
      Fitted r = eval(inv(0.5 * (a + b)));
      if (r.gain.rss < best->gain.rss) best = std::move(r);
    }
  }
  if (!best) return std::nullopt;
  best->bic = bic(d, best->gain.rss, static_cast<int>(mo.k() + best->block.cols.cols()) + mo.nonlinear + c.nonlinear);
  return best;
}

double correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const double na = a.norm(), nb = b.norm();
  return na > 0 && nb > 0 ? a.dot(b) / (na * nb) : 0.0;
}

struct Selected {
  Fitted fitted;
  bool confounded = false;
  double rms_before = 0, rms_after = 0;
  std::optional<double> ho_before, ho_after;
  double delta_bic = 0;
  Eigen::Index first_col = 0;
};

std::string remedy_for(const std::string& a, const std::string& b) {
  auto has = [&](const std::string& x) { return a == x || b == x; };
  if (has("reversal") && has("servo_lag"))
    return "repeat the bidirectional run at a second, very different feed (or with a dwell before each reading): "
           "servo lag scales with feed, lost motion does not";
  if (has("thermal_drift") && has("setup_shift"))
    return "measure one reference target at the start and at the end of every run (and log the time of every "
           "reading): a drift moves within a run as well, a set-up shift only between runs";
  if (has("thermal_drift"))
    return "repeat the run in reverse order or add a return sweep, so that time and position no longer rise together";
  if (has("setup_shift"))
    return "repeat a run without touching the set-up, or measure a reference artefact at the start of every run";
  if (has("sag"))
    return "measure the deflecting axis at two positions of the other axes, or give the geometric errors as a "
           "fixed --baseline";
  return "add test points where the two regressors do not move together (other axis positions, both directions, "
         "another order of the points)";
}

}  // namespace

// ============================================================= public ====

Machine cartesian_machine_for(const Recordings& rec) {
  nlohmann::ordered_json doc;
  doc["format"] = "volmap-machine/1";
  doc["name"] = "cartesian";
  doc["description"] = "Cartesian machine with the axes of the recording (explain, no --machine)";
  nlohmann::ordered_json axes = nlohmann::ordered_json::object();
  nlohmann::ordered_json tool = nlohmann::ordered_json::array();
  nlohmann::ordered_json work = nlohmann::ordered_json::array();
  for (int a = 0; a < kAxisNameCount; ++a) {
    const AxisName ax = static_cast<AxisName>(a);
    if (!rec.has_axis(ax)) continue;
    double lo = INFINITY, hi = -INFINITY;
    for (double v : rec.position[static_cast<std::size_t>(a)])
      if (std::isfinite(v)) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    if (!std::isfinite(lo)) lo = hi = 0;
    const double k = is_rotary(ax) ? kRadToDeg : 1.0;
    lo *= k;
    hi *= k;
    if (hi <= lo) hi = lo + 1;
    nlohmann::ordered_json dirv = {a % 3 == 0 ? 1 : 0, a % 3 == 1 ? 1 : 0, a % 3 == 2 ? 1 : 0};
    nlohmann::ordered_json ad;
    ad["type"] = is_rotary(ax) ? "rotary" : "linear";
    ad["direction"] = dirv;
    ad[is_rotary(ax) ? "travel_deg" : "travel_mm"] = {lo, hi};
    ad[is_rotary(ax) ? "home_deg" : "home_mm"] = std::clamp(0.0, lo, hi);
    axes[axis_str(ax)] = ad;
    nlohmann::ordered_json joint;
    joint["axis"] = axis_str(ax);
    joint["offset_mm"] = {0, 0, 0};
    (is_rotary(ax) ? work : tool).push_back(joint);
  }
  doc["axes"] = axes;
  doc["workpiece_chain"] = work;
  doc["tool_chain"] = tool;
  doc["spindle_offset_mm"] = {0, 0, 0};
  doc["tool"] = {{"length_mm", 0}, {"axis", {0, 0, 1}}};
  doc["workpiece_origin_mm"] = {0, 0, 0};
  std::istringstream in(doc.dump());
  return read_machine_json(in, rec.file + " (Cartesian machine of its axes)");
}

ExplainResult explain(const Machine& m, const Recordings& rec, const ExplainOptions& opt) {
  if (opt.degree < 0 || opt.degree > 12) throw std::invalid_argument("--degree: expected 0 (automatic) or 1..12");
  ExplainResult res;
  res.recordings_file = rec.file;
  const Data d = build_data(m, rec, opt);
  res.observations = d.n;
  res.runs = static_cast<std::size_t>(d.runs);

  Context ctx{d, opt, {}, {}, {}};
  for (AxisName a : m.axis_order) {
    if (!rec.has_axis(a) || !varies(rec.position[static_cast<std::size_t>(a)])) continue;
    (is_rotary(a) ? ctx.rotary : ctx.linear).push_back(a);
    bool plus = false, minus = false;
    for (std::int8_t s : rec.dir[static_cast<std::size_t>(a)]) {
      plus = plus || s > 0;
      minus = minus || s < 0;
    }
    if (plus && minus && !is_rotary(a)) ctx.dir_axes.push_back(a);
  }
  ctx.has_time = !rec.t_s.empty() && varies(rec.t_s) &&
                 std::all_of(rec.t_s.begin(), rec.t_s.end(), [](double t) { return std::isfinite(t); });
  if (ctx.has_time) ctx.duration_s = *std::max_element(rec.t_s.begin(), rec.t_s.end());
  ctx.has_feed = !rec.feed_mm_min.empty() && varies(rec.feed_mm_min);
  if (!rec.feed_mm_min.empty() && !ctx.has_feed) {
    // one feed: servo lag is indistinguishable from lost motion
    bool any = false;
    for (double f : rec.feed_mm_min) any = any || (std::isfinite(f) && f > 0);
    ctx.has_feed = any;
  }

  Model mo = baseline_model(d, opt, res.baseline_description);
  fit(d, mo);
  res.baseline_rms_um = rms_of(d, mo.rss);
  res.baseline_heldout_rms_um = heldout_rms(d, mo);

  // Locate: baseline residuals (um) against every regressor.
  {
    Eigen::VectorXd r_um(static_cast<Eigen::Index>(d.n));
    for (Eigen::Index e = 0; e < r_um.size(); ++e) r_um[e] = d.sw[e] > 0 ? mo.r[e] / d.sw[e] : 0.0;
    res.mismatch = locate(d, r_um, regressors(d));
  }

  const std::vector<Candidate> cands = make_candidates(ctx);

  // Design confounding: time and an axis position rise together in every run.
  std::set<std::string> design_blocked;  // thermal_drift/<axis>
  if (ctx.has_time) {
    for (AxisName k : ctx.linear) {
      std::vector<double> tm(static_cast<std::size_t>(d.runs), 0), qm(static_cast<std::size_t>(d.runs), 0),
          cnt(static_cast<std::size_t>(d.runs), 0);
      for (std::size_t e = 0; e < d.n; ++e) {
        const std::size_t r = static_cast<std::size_t>(d.run[e]);
        tm[r] += d.t(d.row[e]);
        qm[r] += d.q(k, d.row[e]);
        cnt[r] += 1;
      }
      double stq = 0, stt = 0, sqq = 0;
      for (std::size_t e = 0; e < d.n; ++e) {
        const std::size_t r = static_cast<std::size_t>(d.run[e]);
        const double a = d.t(d.row[e]) - tm[r] / cnt[r], b = d.q(k, d.row[e]) - qm[r] / cnt[r];
        stq += a * b;
        stt += a * a;
        sqq += b * b;
      }
      const double rho = stt > 0 && sqq > 0 ? stq / std::sqrt(stt * sqq) : 0.0;
      if (std::abs(rho) > kDesignCorrelation) {
        design_blocked.insert(axis_str(k));
        Confounded c;
        c.effects = {"thermal_drift", "scale"};
        c.axis = k;
        c.explanation = fmt::format(
            "time and {0} position {1} together in every run (correlation {2:.3f} within runs): a drift that grows "
            "with time and a scale error that grows with {0} give the same deviations on this recording",
            axis_str(k), rho > 0 ? "rise" : "move opposite", rho);
        c.remedy = remedy_for("thermal_drift", "scale");
        res.confounded.push_back(c);
      }
    }
  }

  std::vector<Selected> chosen;
  std::set<std::string> used;  // effect/axis taken
  std::optional<double> ho_current = res.baseline_heldout_rms_um;
  std::set<std::string> not_estimable;
  std::map<std::string, double> hints;  // nonlinear parameters scanned at an earlier step
  for (int step = 0; step < opt.max_findings + 4; ++step) {
    std::vector<Fitted> fits;
    for (const Candidate& c : cands) {
      const std::string ea = c.effect + "/" + (c.axis ? axis_str(*c.axis) : "-");
      if (used.count(ea)) continue;
      if (c.effect == "thermal_drift" && c.axis && design_blocked.count(axis_str(*c.axis))) continue;
      if (c.effect == "scale" && c.axis && design_blocked.count(axis_str(*c.axis))) continue;
      const auto h = hints.find(c.key());
      std::optional<Fitted> f =
          fit_candidate(d, mo, c, h == hints.end() ? std::nullopt : std::optional<double>(h->second));
      if (f && c.refine) hints[c.key()] = f->theta;
      if (!f) continue;
      if (f->gain.absorbed_share < kAbsorbed) {
        not_estimable.insert(c.effect + (c.axis ? " " + axis_str(*c.axis) : ""));
        continue;
      }
      fits.push_back(std::move(*f));
    }
    std::sort(fits.begin(), fits.end(), [](const Fitted& a, const Fitted& b) {
      return a.bic != b.bic ? a.bic < b.bic : a.cand->key() < b.cand->key();
    });
    const double bic_now = bic(d, mo.rss, static_cast<int>(mo.k()) + mo.nonlinear);
    bool accepted = false;
    for (Fitted& f : fits) {
      if (f.bic - bic_now > kMinDeltaBic) break;
      Model next = with_block(mo, f.block, f.cand->nonlinear);
      fit(d, next);
      const std::optional<double> ho = heldout_rms(d, next);
      if (ho && ho_current && !(*ho < *ho_current * (1.0 - kMinHeldoutGain))) continue;  // does not hold up
      Selected s;
      s.delta_bic = f.bic - bic_now;
      s.rms_before = rms_of(d, mo.rss);
      s.rms_after = rms_of(d, next.rss);
      s.ho_before = ho_current;
      s.ho_after = ho;
      s.first_col = mo.k();
      // Confounding: another candidate explains the same structure almost as well.
      const double gain_best = mo.rss - f.gain.rss;
      for (const Fitted& g : fits) {
        if (&g == &f) continue;
        if (g.cand->effect == f.cand->effect && g.cand->axis == f.cand->axis) continue;
        // Nearly as good by the same measure (BIC within the selection margin)
        // and the same structure (fitted deviations correlated).
        if (g.bic - f.bic > -kMinDeltaBic) continue;
        if (mo.rss - g.gain.rss < kConfoundGainShare * gain_best) continue;
        if (f.gain.fitted.size() == 0) f.gain = profile(d, mo, f.block, true);
        const Eigen::VectorXd g_fitted = profile(d, mo, g.block, true).fitted;
        const double rho = correlation(f.gain.fitted, g_fitted);
        if (std::abs(rho) < kConfoundCorrelation) continue;
        s.confounded = true;
        Confounded c;
        c.effects = {f.cand->effect, g.cand->effect};
        c.axis = f.cand->axis;
        const std::string fa = f.cand->axis ? axis_str(*f.cand->axis) : "";
        const std::string ga = g.cand->axis ? axis_str(*g.cand->axis) : "";
        c.explanation = fmt::format(
            "{} {} and {} {} explain the same structure on this recording (fitted deviations correlated {:.3f}, "
            "RMS {:.3g} vs {:.3g} um): the recording cannot tell them apart",
            f.cand->effect, fa, g.cand->effect, ga, rho,
            rms_of(d, f.gain.rss), rms_of(d, g.gain.rss));
        if (f.cand->effect == "reversal" || g.cand->effect == "reversal")
          if (f.cand->effect == "servo_lag" || g.cand->effect == "servo_lag")
            c.explanation += "; the recording has a single feed, so lost motion and lag both flip with direction";
        c.remedy = remedy_for(f.cand->effect, g.cand->effect);
        bool dup = false;
        for (const Confounded& o : res.confounded)
          dup = dup || (o.axis == c.axis && std::set<std::string>(o.effects.begin(), o.effects.end()) ==
                                                std::set<std::string>(c.effects.begin(), c.effects.end()));
        if (!dup) res.confounded.push_back(c);
        used.insert(g.cand->effect + "/" + ga);
        break;
      }
      used.insert(f.cand->effect + "/" + (f.cand->axis ? axis_str(*f.cand->axis) : "-"));
      s.fitted = std::move(f);
      chosen.push_back(std::move(s));
      mo = std::move(next);
      ho_current = ho;
      accepted = true;
      break;
    }
    if (!accepted) break;
    if (static_cast<int>(std::count_if(chosen.begin(), chosen.end(), [](const Selected& s) { return !s.confounded; })) >=
        opt.max_findings)
      break;
  }
  res.final_rms_um = rms_of(d, mo.rss);
  res.final_heldout_rms_um = ho_current;

  // Parameters from the final model; covariance sigma^2 (X^T X)^-1.
  const double sigma2 = mo.rss / std::max(1.0, static_cast<double>(d.n) - static_cast<double>(mo.k()));
  Eigen::MatrixXd G = mo.X.transpose() * mo.X;
  G.diagonal().array() += ridge_of(d);
  const Eigen::MatrixXd Ginv = G.ldlt().solve(Eigen::MatrixXd::Identity(G.rows(), G.cols()));
  for (const Selected& s : chosen) {
    if (s.confounded) continue;
    const Candidate& c = *s.fitted.cand;
    const Eigen::Index kc = s.fitted.block.cols.cols();
    Eigen::VectorXd beta(kc);
    Eigen::MatrixXd cov(kc, kc);
    for (Eigen::Index a = 0; a < kc; ++a) {
      beta[a] = mo.beta[s.first_col + a] * mo.scale[s.first_col + a];
      for (Eigen::Index b = 0; b < kc; ++b)
        cov(a, b) = sigma2 * Ginv(s.first_col + a, s.first_col + b) * mo.scale[s.first_col + a] * mo.scale[s.first_col + b];
    }
    // Standard error of the nonlinear parameter from the curvature of the
    // profile RSS (other terms of the final model held).
    double theta_se = std::nan("");
    if (c.refine) {
      Model rest;
      rest.X.resize(mo.X.rows(), mo.k() - kc);
      rest.scale.resize(mo.k() - kc);
      Eigen::Index j = 0;
      for (Eigen::Index col = 0; col < mo.k(); ++col) {
        if (col >= s.first_col && col < s.first_col + kc) continue;
        rest.X.col(j) = mo.X.col(col);
        rest.scale[j] = mo.scale[col];
        rest.per_run.push_back(mo.per_run[static_cast<std::size_t>(col)]);
        ++j;
      }
      fit(d, rest);
      const double th = s.fitted.theta, h = th * 1e-3;
      auto rss_at = [&](double x) { return profile(d, rest, make_block(d, c.build(x), c.per_run)).rss; };
      const double f0 = rss_at(th), fp = rss_at(th + h), fm = rss_at(th - h);
      const double curv = (fp - 2 * f0 + fm) / (h * h);
      if (curv > 0) theta_se = std::sqrt(2 * sigma2 / curv);
    }
    Finding f;
    f.effect = c.effect;
    f.axis = c.axis;
    c.report(beta, cov, s.fitted.theta, theta_se, f);
    f.rms_before_um = s.rms_before;
    f.rms_after_um = s.rms_after;
    f.heldout_rms_before_um = s.ho_before;
    f.heldout_rms_after_um = s.ho_after;
    f.delta_bic = s.delta_bic;
    // Plot: partial residual (final residual + this term) before, final residual after.
    f.plot.regressor = c.plot_label;
    const Eigen::VectorXd contrib = mo.X.middleCols(s.first_col, kc) * mo.beta.segment(s.first_col, kc);
    const std::size_t stride = std::max<std::size_t>(1, d.n / 1500);
    for (std::size_t e = 0; e < d.n; e += stride) {
      const Eigen::Index ei = static_cast<Eigen::Index>(e);
      if (d.sw[ei] <= 0) continue;
      f.plot.x.push_back(c.plot_x(d.row[e]));
      f.plot.after_um.push_back(mo.r[ei] / d.sw[ei]);
      f.plot.before_um.push_back((mo.r[ei] + contrib[ei]) / d.sw[ei]);
      if (c.plot_group) f.plot.group.push_back(c.plot_group(d.row[e]));
    }
    if (f.effect == "setup_shift" && !ctx.has_time && d.runs >= 3) {
      const nlohmann::json& per = f.parameters.front().second;
      bool up = true, down = true;
      for (std::size_t r = 1; r < per.size(); ++r) {
        up = up && per[r].get<double>() > per[r - 1].get<double>();
        down = down && per[r].get<double>() < per[r - 1].get<double>();
      }
      if (up || down) {
        f.explanation += " The offsets change monotonically in run order and the recording has no time column: a "
                         "slow drift between runs would look the same.";
        Confounded cf;
        cf.effects = {"setup_shift", "thermal_drift"};
        cf.axis = f.axis;
        cf.explanation = "the per-run offsets grow monotonically with the run number and no t_s column records when "
                         "the runs were made: a set-up that moved and a machine that drifted between runs give the "
                         "same readings";
        cf.remedy = remedy_for("setup_shift", "thermal_drift");
        res.confounded.push_back(cf);
      }
    }
    res.findings.push_back(std::move(f));
  }
  for (const std::string& s : not_estimable)
    res.notes.push_back(s + ": not estimable on this recording (the baseline already spans its columns)");
  return res;
}

}  // namespace volmap
