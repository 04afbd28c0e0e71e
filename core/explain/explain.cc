#include "core/explain/explain.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/common/input_error.h"
#include "core/explain/explain_internal.h"
#include "core/model/error_model.h"
#include "core/model/gain_evaluator.h"
#include "core/model/machine_json.h"
#include "core/model/sensitivity.h"

namespace volmap {
namespace {

using namespace explain_detail;

constexpr double kMinDeltaBic = -10.0;    ///< a step must lower BIC by more than 10
constexpr double kMinHeldoutGain = 0.05;  ///< and the held-out RMS by more than 5 %
constexpr double kAbsorbed = 1e-3;        ///< residual share of a column the model spans
constexpr double kConfoundCorrelation = 0.98;
constexpr double kConfoundGainShare = 0.9;
constexpr double kRidge = 1e-9;  ///< relative to the unit-RMS column scale
constexpr double kDesignCorrelation = 0.95;
constexpr int kSparseTargets = 12;  ///< up to this many targets: a value per target

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
  Eigen::VectorXd beta;  ///< normalised
  Eigen::VectorXd r;     ///< weighted residual
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
        if (mo.per_run[static_cast<std::size_t>(j)] && Xr[rs].col(j).squaredNorm() > 0)
          own.push_back(j);
      if (!own.empty()) {
        const Eigen::Index m_rows = res.size();
        Eigen::MatrixXd P(m_rows, static_cast<Eigen::Index>(own.size()));
        for (std::size_t j = 0; j < own.size(); ++j)
          P.col(static_cast<Eigen::Index>(j)) = Xr[rs].col(own[j]);
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
  const int linear_axes = static_cast<int>(std::count_if(
      d.m.axis_order.begin(), d.m.axis_order.end(), [](AxisName a) { return !is_rotary(a); }));
  if (opt.baseline) {
    description =
        fmt::format("fixed: {} (+ a constant per recorded component)",
                    opt.baseline_file.empty() ? std::string("baseline errors") : opt.baseline_file);
  } else {
    description = fmt::format(
        "rigid-body, fitted: {} component errors of {} linear axis(es) as polynomials (degree {}), "
        "{} location "
        "errors, a constant per recorded component; {} of {} parameters identifiable on this "
        "recording",
        components, linear_axes, degrees, location, keep.size(), cols.size());
  }
  return mo;
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
// One finding per effect and axis; geometric errors missing from a fixed
// baseline are one per error name (EA0Z and EB0Z are both squareness of Z).
std::string used_key(const Candidate& c) {
  std::string k = c.effect + "/" + (c.axis ? axis_str(*c.axis) : "-");
  if (c.effect == "squareness" || c.effect == "straightness" || c.effect == "angular" ||
      (c.effect == "scale" && c.variant.size() > 2))
    k += "/" + c.variant;
  return k;
}

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
        b = x2;
        x2 = x1;
        f2 = f1;
        x1 = b - gr * (b - a);
        f1 = eval(std::exp(x1)).gain.rss;
      } else {
        a = x1;
        x1 = x2;
        f1 = f2;
        x2 = a + gr * (b - a);
        f2 = eval(std::exp(x2)).gain.rss;
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
      const double pk = d.p_b(static_cast<int>(k), static_cast<Eigen::Index>(e)) *
                        d.sw[static_cast<Eigen::Index>(e)];
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
      const double g = det > 1e-12 * (ss * cc + 1e-300)
                           ? (cc * sr * sr - 2 * sc * sr * cr + ss * cr * cr) / det
                           : 0.0;
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
      double lo = 1.0 / c.grid[i > 0 ? i - 1 : i],
             hi = 1.0 / c.grid[i + 1 < c.grid.size() ? i + 1 : i];
      if (lo > hi) std::swap(lo, hi);
      const double gr = (std::sqrt(5.0) - 1) / 2;
      double a = lo, b = hi;
      double x1 = b - gr * (b - a), x2 = a + gr * (b - a);
      double f1 = eval(1.0 / x1).gain.rss, f2 = eval(1.0 / x2).gain.rss;
      for (int it = 0; it < 18; ++it) {
        if (f1 < f2) {
          b = x2;
          x2 = x1;
          f2 = f1;
          x1 = b - gr * (b - a);
          f1 = eval(1.0 / x1).gain.rss;
        } else {
          a = x1;
          x1 = x2;
          f1 = f2;
          x2 = a + gr * (b - a);
          f2 = eval(1.0 / x2).gain.rss;
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
      double a = tr(c.grid[bi > 0 ? bi - 1 : bi]),
             b = tr(c.grid[bi + 1 < c.grid.size() ? bi + 1 : bi]);
      const double gr = (std::sqrt(5.0) - 1) / 2;
      double x1 = b - gr * (b - a), x2 = a + gr * (b - a);
      double f1 = eval(inv(x1)).gain.rss, f2 = eval(inv(x2)).gain.rss;
      for (int it = 0; it < 14; ++it) {
        if (f1 < f2) {
          b = x2;
          x2 = x1;
          f2 = f1;
          x1 = b - gr * (b - a);
          f1 = eval(inv(x1)).gain.rss;
        } else {
          a = x1;
          x1 = x2;
          f1 = f2;
          x2 = a + gr * (b - a);
          f2 = eval(inv(x2)).gain.rss;
        }
      }
      Fitted r = eval(inv(0.5 * (a + b)));
      if (r.gain.rss < best->gain.rss) best = std::move(r);
    }
  }
  if (!best) return std::nullopt;
  best->bic = bic(d, best->gain.rss,
                  static_cast<int>(mo.k() + best->block.cols.cols()) + mo.nonlinear + c.nonlinear);
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
    return "repeat the bidirectional run at a second, very different feed (or with a dwell before "
           "each reading): "
           "servo lag scales with feed, lost motion does not";
  if (has("thermal_drift") && has("setup_shift"))
    return "measure one reference target at the start and at the end of every run (and log the "
           "time of every "
           "reading): a drift moves within a run as well, a set-up shift only between runs";
  if (has("thermal_drift"))
    return "repeat the run in reverse order or add a return sweep, so that time and position no "
           "longer rise together";
  if (has("setup_shift"))
    return "repeat a run without touching the set-up, or measure a reference artefact at the start "
           "of every run";
  if (has("sag"))
    return "measure the deflecting axis at two positions of the other axes, or give the geometric "
           "errors as a "
           "fixed --baseline";
  return "add test points where the two regressors do not move together (other axis positions, "
         "both directions, "
         "another order of the points)";
}

}  // namespace

ExplainResult explain(const Machine& m, const Recordings& rec, const ExplainOptions& opt) {
  if (opt.degree < 0 || opt.degree > 12)
    throw std::invalid_argument("--degree: expected 0 (automatic) or 1..12");
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
  ctx.has_time =
      !rec.t_s.empty() && varies(rec.t_s) &&
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
    res.mismatch = locate_mismatch(d, r_um);
  }

  const std::vector<Candidate> cands = make_candidates(ctx);

  // Design confounding: time and an axis position rise together in every run.
  std::set<std::string> design_blocked;  // thermal_drift/<axis>
  if (ctx.has_time) {
    for (AxisName k : ctx.linear) {
      std::vector<double> tm(static_cast<std::size_t>(d.runs), 0),
          qm(static_cast<std::size_t>(d.runs), 0), cnt(static_cast<std::size_t>(d.runs), 0);
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
            "time and {0} position {1} together in every run (correlation {2:.3f} within runs): a "
            "drift that grows "
            "with time and a scale error that grows with {0} give the same deviations on this "
            "recording",
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
      if (used.count(used_key(c))) continue;
      // Without the machine the rotary axes' lines are a guess: effects of
      // a rotary axis (its wobble, its positioning, a sag driven by its
      // angle) would be fitted to the guess's levers and named with
      // confidence they do not have. Left out; notes says so.
      if (opt.machine_assumed &&
          ((c.axis && is_rotary(*c.axis)) || c.effect == "rotary_wobble" ||
           c.effect == "rotary_positioning" ||
           (c.effect == "sag" && (c.variant == "A" || c.variant == "B" || c.variant == "C"))))
        continue;
      if (c.effect == "thermal_drift" && c.axis && design_blocked.count(axis_str(*c.axis)))
        continue;
      if (c.effect == "scale" && c.axis && design_blocked.count(axis_str(*c.axis))) continue;
      const auto h = hints.find(c.key());
      std::optional<Fitted> f = fit_candidate(
          d, mo, c, h == hints.end() ? std::nullopt : std::optional<double>(h->second));
      if (f && c.refine) hints[c.key()] = f->theta;
      if (!f) continue;
      if (f->gain.absorbed_share < kAbsorbed) {
        const std::string key = used_key(c);
        not_estimable.insert(
            c.effect + (c.axis ? " " + axis_str(*c.axis) : "") +
            (key.size() > c.effect.size() + 2 + (c.axis ? axis_str(*c.axis).size() : 1)
                 ? " (" + c.variant + ")"
                 : ""));
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
      if (ho && ho_current && !(*ho < *ho_current * (1.0 - kMinHeldoutGain)))
        continue;  // does not hold up
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
        const std::string fa = f.cand->axis ? axis_str(*f.cand->axis) : "-";
        const std::string ga = g.cand->axis ? axis_str(*g.cand->axis) : "-";
        c.explanation = fmt::format(
            "{} {} and {} {} explain the same structure on this recording (fitted deviations "
            "correlated {:.3f}, "
            "RMS {:.3g} vs {:.3g} um): the recording cannot tell them apart",
            f.cand->effect, fa, g.cand->effect, ga, rho, rms_of(d, f.gain.rss),
            rms_of(d, g.gain.rss));
        if (f.cand->effect == "reversal" || g.cand->effect == "reversal")
          if (f.cand->effect == "servo_lag" || g.cand->effect == "servo_lag")
            c.explanation +=
                "; the recording has a single feed, so lost motion and lag both flip with "
                "direction";
        c.remedy = remedy_for(f.cand->effect, g.cand->effect);
        bool dup = false;
        for (const Confounded& o : res.confounded)
          dup = dup ||
                (o.axis == c.axis && std::set<std::string>(o.effects.begin(), o.effects.end()) ==
                                         std::set<std::string>(c.effects.begin(), c.effects.end()));
        if (!dup) res.confounded.push_back(c);
        used.insert(used_key(*g.cand));
        break;
      }
      used.insert(used_key(*f.cand));
      s.fitted = std::move(f);
      chosen.push_back(std::move(s));
      mo = std::move(next);
      ho_current = ho;
      accepted = true;
      break;
    }
    if (!accepted) break;
    if (static_cast<int>(std::count_if(chosen.begin(), chosen.end(), [](const Selected& s) {
          return !s.confounded;
        })) >= opt.max_findings)
      break;
  }

  // Backward check: a finding chosen early can become redundant once later
  // ones explain its structure better (a sag that stood in for two
  // squareness errors not yet found). Each finding must still hold up in
  // the final model, by the same two tests as when it entered: removing it
  // raises BIC by more than 10 and the held-out RMS by more than 5 %.
  for (bool dropped = true; dropped;) {
    dropped = false;
    const double bic_full = bic(d, mo.rss, static_cast<int>(mo.k()) + mo.nonlinear);
    for (std::size_t i = 0; i < chosen.size() && !dropped; ++i) {
      Selected& s = chosen[i];
      if (s.confounded) continue;
      const Eigen::Index kc = s.fitted.block.cols.cols();
      Model reduced;
      reduced.X.resize(mo.X.rows(), mo.k() - kc);
      reduced.scale.resize(mo.k() - kc);
      Eigen::Index j = 0;
      for (Eigen::Index col = 0; col < mo.k(); ++col) {
        if (col >= s.first_col && col < s.first_col + kc) continue;
        reduced.X.col(j) = mo.X.col(col);
        reduced.scale[j] = mo.scale[col];
        reduced.per_run.push_back(mo.per_run[static_cast<std::size_t>(col)]);
        ++j;
      }
      reduced.nonlinear = mo.nonlinear - s.fitted.cand->nonlinear;
      reduced.rank = mo.rank;
      fit(d, reduced);
      const double bic_reduced =
          bic(d, reduced.rss, static_cast<int>(reduced.k()) + reduced.nonlinear);
      bool holds = bic_full - bic_reduced <= kMinDeltaBic;
      if (holds && ho_current) {
        const std::optional<double> ho_reduced = heldout_rms(d, reduced);
        holds = !ho_reduced || *ho_current < *ho_reduced * (1.0 - kMinHeldoutGain);
      }
      if (holds) continue;
      for (Selected& later : chosen)
        if (later.first_col > s.first_col) later.first_col -= kc;
      chosen.erase(chosen.begin() + static_cast<std::ptrdiff_t>(i));
      mo = std::move(reduced);
      ho_current = heldout_rms(d, mo);
      dropped = true;
    }
  }
  res.final_rms_um = rms_of(d, mo.rss);
  res.final_heldout_rms_um = ho_current;

  // Parameters from the final model; covariance sigma^2 (X^T X)^-1.
  const double sigma2 =
      mo.rss / std::max(1.0, static_cast<double>(d.n) - static_cast<double>(mo.k()));
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
        cov(a, b) = sigma2 * Ginv(s.first_col + a, s.first_col + b) * mo.scale[s.first_col + a] *
                    mo.scale[s.first_col + b];
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
      auto rss_at = [&](double x) {
        return profile(d, rest, make_block(d, c.build(x), c.per_run)).rss;
      };
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
    const Eigen::VectorXd contrib =
        mo.X.middleCols(s.first_col, kc) * mo.beta.segment(s.first_col, kc);
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
        f.explanation +=
            " The offsets change monotonically in run order and the recording has no time column: "
            "a "
            "slow drift between runs would look the same.";
        Confounded cf;
        cf.effects = {"setup_shift", "thermal_drift"};
        cf.axis = f.axis;
        cf.explanation =
            "the per-run offsets grow monotonically with the run number and no t_s column records "
            "when "
            "the runs were made: a set-up that moved and a machine that drifted between runs give "
            "the "
            "same readings";
        cf.remedy = remedy_for("setup_shift", "thermal_drift");
        res.confounded.push_back(cf);
        // Confounded, not guessed: the pair is reported, not a finding.
        // The per-run offsets stay in the final model (they are real).
        res.notes.push_back(
            fmt::format("per-run offsets of {} are in the final model (largest {:.3g} um); set-up "
                        "shift or drift, see "
                        "confounded",
                        f.axis ? axis_str(*f.axis) : std::string("-"), [&] {
                          double w = 0;
                          for (const auto& v : per) w = std::max(w, std::abs(v.get<double>()));
                          return w;
                        }()));
        continue;
      }
    }
    res.findings.push_back(std::move(f));
  }
  if (opt.machine_assumed && !ctx.rotary.empty())
    res.notes.push_back(
        "no --machine: the rotary axes were taken to turn the workpiece about lines through the "
        "origin along X, Y or Z, so effects of the rotary axes (wobble, positioning, a sag driven "
        "by a rotary angle) were not tried; give the machine that made the recording for them");
  for (const std::string& s : not_estimable)
    res.notes.push_back(
        s + ": not estimable on this recording (the baseline already spans its columns)");
  if (opt.baseline) {
    // Translational location errors of rotary axes (the position of the
    // axis line, ISO 230-7) have no effect name in explain.md: when the
    // fixed baseline lacks one that the recording sees, say so, since
    // findings may stand in for it.
    std::string missing;
    for (std::size_t idx = 0; idx < d.names.size(); ++idx) {
      const std::optional<ErrorName> en = parse_error_name(d.names[idx]);
      if (!en || !en->location || is_angular(en->component) || !is_rotary(en->axis)) continue;
      if (opt.baseline->location.count(d.names[idx])) continue;
      if (d.gp.col(static_cast<Eigen::Index>(idx)).cwiseAbs().maxCoeff() < 1e-12) continue;
      missing += (missing.empty() ? "" : ", ") + d.names[idx];
    }
    if (!missing.empty())
      res.notes.push_back(
          "the baseline lacks " + missing +
          " (the position of a rotary axis line), which explain does not fit; findings on rotary "
          "axes may stand in for them: add them to the baseline, or explain without --baseline");
  }
  return res;
}

}  // namespace volmap
