#include "core/measure/identify.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/common/input_error.h"
#include "core/model/gain_evaluator.h"
#include "core/model/sensitivity.h"

namespace volmap {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr int kCurveIntervals = 64;     // knots of a fitted polynomial table
constexpr int kPeriodicIntervals = 72;  // 5 degrees: fitted Fourier table

/// One parameter column.
struct Column {
  IdentifiedParameter p;
  int gain = -1;            ///< GainEvaluator index (location, component)
  double unit_scale = 1.0;  ///< internal units per parameter unit (1e-3 mm/um, 1e-6 rad/urad)
  // component curve basis
  AxisName axis = AxisName::X;
  int axis_index = -1;  ///< AxisVector index
  bool fourier = false;
  int power = 0;  ///< polynomial power, or Fourier order
  bool sine = false;
  double centre = 0.0, half_span = 1.0;  ///< s = (q - centre) / half_span
  // setup offset
  int run = -1, coordinate = 0;
};

double basis(const Column& c, double q) {
  if (c.fourier) return c.sine ? std::sin(c.power * q) : std::cos(c.power * q);
  const double s = (q - c.centre) / c.half_span;
  double v = s;
  for (int k = 1; k < c.power; ++k) v *= s;
  return v;
}
double basis_slope(const Column& c, double q) {
  if (c.fourier) return c.sine ? c.power * std::cos(c.power * q) : -c.power * std::sin(c.power * q);
  const double s = (q - c.centre) / c.half_span;
  double v = 1.0;
  for (int k = 1; k < c.power; ++k) v *= s;
  return c.power * v / c.half_span;
}

struct Equation {
  int row = 0;          ///< index into the used rows
  Eigen::Vector3d p_w;  ///< direction in workpiece coordinates
  double y_um = 0.0;
  double sqrt_w = 1.0;
};

std::string format_coefficient(double c) {
  if (std::abs(c - std::round(c)) < 1e-9)
    return fmt::format("{}", static_cast<long long>(std::round(c)));
  return fmt::format("{:.4g}", c);
}

std::string fixed6(double v) {
  std::string s = fmt::format("{:.6f}", v);
  if (s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

}  // namespace

IdentifyResult identify(const Machine& m, const Recordings& rec, const IdentifyOptions& opt) {
  GainEvaluator gains(m, opt.formulation);
  const std::vector<std::string>& names = gains.names();
  ErrorSet base;
  if (opt.known) base = *opt.known;
  base.file = opt.known ? opt.known->file : std::string("<identified>");

  // ---- parameters --------------------------------------------------------
  std::vector<Column> cols;
  std::set<std::string> taken;
  auto add_location = [&](const std::string& given) {
    const int g = gains.index_of(given);
    const std::optional<ErrorName> n = parse_error_name(given);
    if (g < 0 || !n || !n->location)
      throw std::invalid_argument(
          fmt::format("{} is not a location error of this machine; choose from "
                      "the location errors of `volmap sensitivity`",
                      given));
    const std::string canonical = names[static_cast<std::size_t>(g)];
    if (base.location.count(canonical))
      throw std::invalid_argument(
          fmt::format("{} is given in the known errors ({}); fit it or hold it, "
                      "not both",
                      canonical, base.file));
    if (!taken.insert(canonical).second) return;
    Column c;
    c.p.name = canonical;
    c.p.kind = ParameterKind::kLocation;
    c.gain = g;
    const bool ang = gains.angular(g);
    c.p.unit = ang ? "urad" : "um";
    c.unit_scale = ang ? 1e-6 : 1e-3;
    cols.push_back(c);
  };
  if (opt.parameters.empty()) {
    for (const std::string& n : names) {
      const ErrorName e = *parse_error_name(n);
      if (e.location && !base.location.count(n)) add_location(n);
    }
  } else {
    for (const std::string& n : opt.parameters) add_location(n);
  }
  for (const ComponentFit& f : opt.components) {
    const std::optional<ErrorName> n = parse_error_name(f.name);
    const int g = gains.index_of(f.name);
    if (!n || n->location || g < 0)
      throw std::invalid_argument(
          fmt::format("--component {}: not a component error of this machine "
                      "(e.g. EXX, EZX, ECC)",
                      f.name));
    if (f.degree < 1 || f.degree > 8)
      throw std::invalid_argument(
          fmt::format("--component {}:{}: the degree (order) is 1..8", f.name, f.degree));
    if (base.errors_of(n->axis))
      throw std::invalid_argument(
          fmt::format("--component {}: the known errors ({}) already tabulate axis "
                      "{}; fit components of axes without known tables",
                      f.name, base.file, axis_char(n->axis)));
    const int ai = *m.index_of(n->axis);
    const AxisLimits& L = m.limits[static_cast<std::size_t>(ai)];
    const bool fourier = is_rotary(n->axis) && L.unlimited;
    const bool ang = is_angular(n->component);
    for (int k = 1; k <= f.degree; ++k)
      for (int s = 0; s < (fourier ? 2 : 1); ++s) {
        Column c;
        c.p.kind = ParameterKind::kComponent;
        c.p.unit = ang ? "urad" : "um";
        c.unit_scale = ang ? 1e-6 : 1e-3;
        c.gain = g;
        c.axis = n->axis;
        c.axis_index = ai;
        c.fourier = fourier;
        c.power = k;
        c.sine = s == 1;
        if (!fourier) {
          c.centre = 0.5 * (L.min + L.max);
          c.half_span = 0.5 * (L.max - L.min);
        }
        const std::string canonical = names[static_cast<std::size_t>(g)];
        c.p.name = fourier ? fmt::format("{}.{}{}", canonical, c.sine ? 's' : 'c', k)
                           : fmt::format("{}.p{}", canonical, k);
        if (!taken.insert(c.p.name).second)
          throw std::invalid_argument("--component " + f.name + " given twice");
        cols.push_back(c);
      }
  }

  // ---- observations ------------------------------------------------------
  const std::size_t n_rows = rec.size();
  std::vector<AxisVector> us;
  std::vector<ApproachDirections> dirs;
  std::vector<int> row_run, row_line;
  std::vector<Equation> eqs;
  std::vector<Eigen::Matrix3d> R_rec_w;
  const bool machine_frame = rec.frame == RecordingFrame::kMachine && m.has_rotary_axes();
  for (std::size_t i = 0; i < n_rows; ++i) {
    const double w = rec.weight.empty() ? 1.0 : rec.weight[i];
    if (w <= 0) continue;
    AxisVector u = m.home;
    ApproachDirections d{};
    for (int k = 0; k < m.axis_count(); ++k) {
      const auto a = static_cast<std::size_t>(m.axis_order[static_cast<std::size_t>(k)]);
      if (!rec.position[a].empty()) u[k] = rec.position[a][i];
      if (!rec.dir[a].empty()) d[static_cast<std::size_t>(k)] = rec.dir[a][i];
    }
    const Eigen::Matrix3d R = machine_frame
                                  ? Eigen::Matrix3d(nominal_base_to_workpiece(m, u).linear())
                                  : Eigen::Matrix3d::Identity();
    const int row = static_cast<int>(us.size());
    bool any = false;
    for (int c = 0; c < 3; ++c) {
      if (!rec.has_component(c)) continue;
      const double y = rec.e_um[static_cast<std::size_t>(c)][i];
      if (std::isnan(y)) continue;
      eqs.push_back({row, R.transpose() * Eigen::Vector3d::Unit(c), y, std::sqrt(w)});
      any = true;
    }
    if (rec.has_projection() && !std::isnan(rec.e_along_n_um[i])) {
      const Eigen::Vector3d n(rec.n[0][i], rec.n[1][i], rec.n[2][i]);
      eqs.push_back({row, R.transpose() * n, rec.e_along_n_um[i], std::sqrt(w)});
      any = true;
    }
    if (!any) continue;
    us.push_back(u);
    dirs.push_back(d);
    row_run.push_back(rec.has_run() ? rec.run[i] : -1);
    row_line.push_back(rec.line[i]);
  }
  if (eqs.empty())
    throw InputError(
        rec.file, 0,
        "no recorded deviation to fit (every deviation cell is empty or has weight 0)");

  // Axes that move in the used rows.
  std::vector<bool> moved(static_cast<std::size_t>(m.axis_count()), false);
  for (int k = 0; k < m.axis_count(); ++k) {
    double lo = 1e300, hi = -1e300;
    for (const AxisVector& u : us) {
      lo = std::min(lo, u[k]);
      hi = std::max(hi, u[k]);
    }
    moved[static_cast<std::size_t>(k)] = hi - lo > 1e-9;
  }

  if (opt.setup_offsets) {
    std::set<int> runs(row_run.begin(), row_run.end());
    for (int r : runs)
      for (int c = 0; c < 3; ++c) {
        Column col;
        col.p.kind = ParameterKind::kSetupOffset;
        col.p.unit = "um";
        col.unit_scale = 1e-3;
        col.run = r;
        col.coordinate = c;
        const std::string run_name =
            r < 0 ? std::string("none") : rec.run_names[static_cast<std::size_t>(r)];
        col.p.name = fmt::format("offset_{}.run{}", static_cast<char>('x' + c), run_name);
        cols.push_back(col);
      }
  }
  const int P = static_cast<int>(cols.size());
  const int M = static_cast<int>(eqs.size());
  if (P == 0) throw std::invalid_argument("nothing to identify: every parameter is held fixed");

  // ---- Jacobian (first order, fixed), weighted: J_w = sqrt(W) J ------------
  // Column j holds d(recorded um) / d(parameter unit).
  Eigen::MatrixXd J(M, P);
  {
    std::size_t e = 0;
    for (std::size_t row = 0; row < us.size(); ++row) {
      gains.at(us[row]);
      const std::size_t e_begin = e;
      while (e < eqs.size() && eqs[e].row == static_cast<int>(row)) ++e;
      for (int j = 0; j < P; ++j) {
        const Column& c = cols[static_cast<std::size_t>(j)];
        Eigen::Vector3d g_w;  // workpiece frame, um per parameter unit
        if (c.p.kind == ParameterKind::kSetupOffset) {
          // offsets live in the recording frame: p_rec . e_c = (R p_w) . e_c
          const Eigen::Matrix3d R =
              machine_frame ? Eigen::Matrix3d(nominal_base_to_workpiece(m, us[row]).linear())
                            : Eigen::Matrix3d::Identity();
          g_w = row_run[row] == c.run ? Eigen::Vector3d(R.row(c.coordinate).transpose())
                                      : Eigen::Vector3d::Zero();
        } else {
          g_w = gains.dP(c.gain) * (c.unit_scale * 1e3);
          if (c.p.kind == ParameterKind::kComponent) g_w *= basis(c, us[row][c.axis_index]);
        }
        for (std::size_t k = e_begin; k < e; ++k)
          J(static_cast<Eigen::Index>(k), j) = eqs[k].sqrt_w * eqs[k].p_w.dot(g_w);
      }
    }
  }

  // ---- identifiability: column scaling and eigen-decomposition -----------
  Eigen::VectorXd D(P);
  for (int j = 0; j < P; ++j) {
    const double norm = J.col(j).norm();
    D[j] = norm > 0 ? norm : 1.0;
  }
  std::vector<bool> zero_column(static_cast<std::size_t>(P));
  for (int j = 0; j < P; ++j)
    zero_column[static_cast<std::size_t>(j)] = J.col(j).squaredNorm() == 0.0;
  J *= D.cwiseInverse().asDiagonal();  // now J_s, in place (10^4 x 30 doubles: no second copy)
  const Eigen::MatrixXd& Js = J;
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(P, P);
  N.selfadjointView<Eigen::Lower>().rankUpdate(Js.transpose());
  N.triangularView<Eigen::StrictlyUpper>() = N.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(N);
  const Eigen::VectorXd lambda = eig.eigenvalues();  // ascending
  IdentifyResult res;
  const double sigma_max = std::sqrt(std::max(lambda[P - 1], 0.0));
  std::vector<int> null_idx;
  for (int k = P - 1; k >= 0; --k) {
    const double s = std::sqrt(std::max(lambda[k], 0.0));
    res.singular_values.push_back(s);
    if (!(s > opt.rank_tolerance * sigma_max)) null_idx.push_back(k);
  }
  res.rank = P - static_cast<int>(null_idx.size());

  // Pick one parameter per null vector to fix, by preference: parameters of
  // axes that do not move, then physical parameters from the end of the list
  // (the rotary block before the linear axes), setup offsets last.
  std::vector<int> preference(static_cast<std::size_t>(P));
  for (int j = 0; j < P; ++j) preference[static_cast<std::size_t>(j)] = j;
  auto rank_of = [&](int j) {
    const Column& c = cols[static_cast<std::size_t>(j)];
    if (c.p.kind == ParameterKind::kSetupOffset) return 4;
    const std::optional<ErrorName> n = parse_error_name(names[static_cast<std::size_t>(c.gain)]);
    const std::optional<int> ai = n ? m.index_of(n->axis) : std::nullopt;
    if (ai && !moved[static_cast<std::size_t>(*ai)]) return 1;
    // Zero-position error of a rotary axis (EA0A, EC0C): what a control's
    // zero offset absorbs; fixed before the line's offsets and tilts.
    if (n && n->location && is_rotary(n->axis) &&
        static_cast<int>(n->component) == static_cast<int>(n->axis))
      return 2;
    return 3;
  };
  std::stable_sort(preference.begin(), preference.end(), [&](int a, int b) {
    const int ra = rank_of(a), rb = rank_of(b);
    if (ra != rb) return ra < rb;
    return a > b;
  });
  const int K0 = static_cast<int>(null_idx.size());
  Eigen::MatrixXd V0(K0, P);
  for (int r = 0; r < K0; ++r)
    V0.row(r) = eig.eigenvectors().col(null_idx[static_cast<std::size_t>(r)]).transpose();
  std::vector<int> pivot_of_row(static_cast<std::size_t>(K0), -1);
  std::vector<bool> fixed(static_cast<std::size_t>(P), false);
  for (int j : preference) {
    int best = -1;
    double best_v = 0.0;
    for (int r = 0; r < K0; ++r) {
      if (pivot_of_row[static_cast<std::size_t>(r)] >= 0) continue;
      const double v = std::abs(V0(r, j));
      if (v > 1e-4 * V0.row(r).cwiseAbs().maxCoeff() && v > best_v) {
        best = r;
        best_v = v;
      }
    }
    if (best < 0) continue;
    V0.row(best) /= V0(best, j);
    for (int r = 0; r < K0; ++r)
      if (r != best) V0.row(r) -= V0(r, j) * V0.row(best);
    pivot_of_row[static_cast<std::size_t>(best)] = j;
    fixed[static_cast<std::size_t>(j)] = true;
  }

  // A rich design (random positions over the whole travel, all three
  // components, one run) tells a redundancy of the parameter set itself from
  // a weakness of this recording's plan.
  Eigen::MatrixXd J_rich;
  if (K0 > 0) {
    constexpr int kRich = 256;
    J_rich.resize(3 * kRich, P);
    std::uint64_t state = 0x9E3779B97F4A7C15ull;
    auto uniform = [&state]() {  // splitmix64: deterministic everywhere
      std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
      return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
    };
    for (int k = 0; k < kRich; ++k) {
      AxisVector u(m.axis_count());
      for (int i = 0; i < m.axis_count(); ++i) {
        const AxisLimits& L = m.limits[static_cast<std::size_t>(i)];
        u[i] =
            L.unlimited ? 2.0 * std::numbers::pi * uniform() : L.min + (L.max - L.min) * uniform();
      }
      gains.at(u);
      for (int j = 0; j < P; ++j) {
        const Column& c = cols[static_cast<std::size_t>(j)];
        Eigen::Vector3d g = Eigen::Vector3d::Zero();
        if (c.p.kind == ParameterKind::kSetupOffset) {
          g[c.coordinate] = 1.0;
        } else {
          g = gains.dP(c.gain) * (c.unit_scale * 1e3);
          if (c.p.kind == ParameterKind::kComponent) g *= basis(c, u[c.axis_index]);
        }
        J_rich.block<3, 1>(3 * k, j) = g;
      }
    }
  }

  // Name the combinations and say what would separate them.
  for (int r = 0; r < K0; ++r) {
    const int piv = pivot_of_row[static_cast<std::size_t>(r)];
    if (piv < 0) continue;
    UnidentifiableCombination u;
    u.fixed = cols[static_cast<std::size_t>(piv)].p.name;
    u.terms.push_back({u.fixed, 1.0});
    u.text = u.fixed;
    std::vector<int> members{piv};
    for (int j = 0; j < P; ++j) {
      if (j == piv || std::abs(V0(r, j)) < 1e-6) continue;
      const double coef = V0(r, j) * D[piv] / D[j];
      u.terms.push_back({cols[static_cast<std::size_t>(j)].p.name, coef});
      u.text += fmt::format(" {} {} {}", coef < 0 ? "-" : "+", format_coefficient(std::abs(coef)),
                            cols[static_cast<std::size_t>(j)].p.name);
      members.push_back(j);
    }
    // Documented rules (docs/identify.md), first match wins.
    std::set<AxisName> rotary_axes, still_axes;
    bool offset = false, squareness = false, component = false, tilt = false, shift = false;
    for (int j : members) {
      const Column& c = cols[static_cast<std::size_t>(j)];
      if (c.p.kind == ParameterKind::kSetupOffset) {
        offset = true;
        continue;
      }
      const ErrorName n = *parse_error_name(names[static_cast<std::size_t>(c.gain)]);
      if (!moved[static_cast<std::size_t>(*m.index_of(n.axis))]) still_axes.insert(n.axis);
      if (c.p.kind == ParameterKind::kComponent) component = true;
      if (n.location && !is_rotary(n.axis)) squareness = true;
      if (n.location && is_rotary(n.axis)) {
        rotary_axes.insert(n.axis);
        (is_angular(n.component) ? tilt : shift) = true;
      }
    }
    auto list = [](const std::set<AxisName>& s) {
      std::string out;
      for (AxisName a : s) out += std::string(out.empty() ? "" : ", ") + axis_char(a);
      return out;
    };
    Eigen::VectorXd v_phys = Eigen::VectorXd::Zero(P);
    for (int j : members) v_phys[j] = V0(r, j) / D[j];
    double rich_scale = 0.0;
    for (int j : members) rich_scale += J_rich.col(j).norm() * std::abs(v_phys[j]);
    const bool intrinsic = rich_scale > 0 && (J_rich * v_phys).norm() < 1e-7 * rich_scale;
    if (intrinsic && members.size() > 1) {
      u.explanation =
          "these errors move the tool tip identically at every axis position: one error "
          "motion under two names (a redundancy of the parameter set, not of the plan)";
      u.remedy =
          "no tool-tip measurement separates them; keep the fixed one at 0 (the others absorb it)";
    } else if (members.size() == 1 && zero_column[static_cast<std::size_t>(piv)]) {
      u.explanation = fmt::format("no observation is sensitive to {}", u.fixed);
      u.remedy =
          still_axes.empty()
              ? "record observations whose direction sees it: all of ex, ey, ez, and the ball off "
                "the rotary axis lines"
              : fmt::format("move {} during the test", list(still_axes));
    } else if (!still_axes.empty()) {
      u.explanation = fmt::format(
          "{} does not move in this recording, so its errors act as constants "
          "that other errors imitate",
          list(still_axes));
      u.remedy = fmt::format(
          "add positions of {} (for a rotary axis at least three angles; for A on a "
          "table, tilt the table)",
          list(still_axes));
    } else if (offset) {
      u.explanation =
          "a constant offset of the ball (setup, sphere position) cannot be told from these errors";
      u.remedy = "add a second ball position (another height or radius on the table)";
    } else if (rotary_axes.size() >= 2) {
      u.explanation =
          fmt::format("the lines of {} are not separated by this plan", list(rotary_axes));
      u.remedy =
          "measure each rotary axis at several positions of the other (e.g. C at several A angles)";
    } else if (rotary_axes.size() == 1 && tilt && shift && !squareness) {
      u.explanation =
          fmt::format("tilt and offset of the {} axis: one ball height sees only their combination",
                      list(rotary_axes));
      u.remedy =
          fmt::format("add a second ball at another height along the {} axis", list(rotary_axes));
    } else if (squareness) {
      u.explanation =
          "squareness of the linear axes vs the other errors: the linear axes move too little";
      u.remedy =
          "move the linear axes over a larger range (a second ball position farther from the "
          "rotary axes)";
    } else if (component) {
      u.explanation = "component-error terms that this coverage of the axis cannot separate";
      u.remedy = "cover more of the axis's travel, or lower the degree";
    } else {
      u.explanation = "these errors move the tool alike at every observation";
      u.remedy = "add observations at other axis positions and record all of ex, ey, ez";
    }
    res.unidentifiable.push_back(std::move(u));
  }

  // ---- estimated set ---------------------------------------------------
  std::vector<int> kept;
  for (int j = 0; j < P; ++j)
    if (!fixed[static_cast<std::size_t>(j)]) kept.push_back(j);
  const int Kp = static_cast<int>(kept.size());
  Eigen::MatrixXd Nk(Kp, Kp);
  for (int a = 0; a < Kp; ++a)
    for (int b = 0; b < Kp; ++b)
      Nk(a, b) = N(kept[static_cast<std::size_t>(a)], kept[static_cast<std::size_t>(b)]);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(Nk);
  {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ek(Nk, Eigen::EigenvaluesOnly);
    const double lo = std::max(ek.eigenvalues()[0], 0.0);
    res.condition_number = Kp == 0  ? 0.0
                           : lo > 0 ? std::sqrt(ek.eigenvalues()[Kp - 1] / lo)
                                    : INFINITY;
  }

  // ---- Gauss-Newton on the exact model ------------------------------------
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(P);  // parameter units
  Eigen::VectorXd r(M);                              // weighted residuals, um
  auto build_errors = [&](const Eigen::VectorXd& th) {
    ErrorSet e = base;
    std::map<AxisName, std::vector<int>> by_axis;
    for (int j = 0; j < P; ++j) {
      const Column& c = cols[static_cast<std::size_t>(j)];
      if (c.p.kind == ParameterKind::kLocation) e.location[c.p.name] = th[j] * c.unit_scale;
      if (c.p.kind == ParameterKind::kComponent) by_axis[c.axis].push_back(j);
    }
    for (const auto& [axis, js] : by_axis) {
      const Column& c0 = cols[static_cast<std::size_t>(js.front())];
      const AxisLimits& L = m.limits[static_cast<std::size_t>(c0.axis_index)];
      AxisErrors ax;
      ax.axis = axis;
      AxisErrorTable& t = ax.plus;
      t.axis = axis;
      t.source = "identified";
      t.periodic = c0.fourier;
      const int n_int = c0.fourier ? kPeriodicIntervals : kCurveIntervals;
      const double lo = c0.fourier ? 0.0 : L.min, hi = c0.fourier ? 2.0 * std::numbers::pi : L.max;
      for (int k = 0; k <= n_int; ++k) {
        const double q = lo + (hi - lo) * k / n_int;
        t.position.push_back(q);
        std::array<double, kComponentCount> v{}, s{};
        for (int j : js) {
          const Column& c = cols[static_cast<std::size_t>(j)];
          const ErrorName n = *parse_error_name(names[static_cast<std::size_t>(c.gain)]);
          const auto comp = static_cast<std::size_t>(n.component);
          ax.present[comp] = true;
          v[comp] += th[j] * c.unit_scale * basis(c, q);
          s[comp] += th[j] * c.unit_scale * basis_slope(c, q);
        }
        t.value.push_back(v);
        t.slope.push_back(s);
      }
      prepare_lookup(t);
      e.axis[static_cast<std::size_t>(axis)] = ax;
    }
    return e;
  };
  auto residuals = [&](const Eigen::VectorXd& th) {
    const ErrorModel model(m, build_errors(th),
                           ModelOptions{opt.formulation, OutsidePolicy::kError});
    std::size_t e = 0;
    for (std::size_t row = 0; row < us.size(); ++row) {
      Eigen::Vector3d dv_um;
      try {
        dv_um = model.exact(us[row], dirs[row]).dP_mm * 1e3;
      } catch (const std::exception& ex) {
        throw InputError(rec.file, row_line[row],
                         std::string("the model cannot be evaluated here: ") + ex.what());
      }
      for (; e < eqs.size() && eqs[e].row == static_cast<int>(row); ++e) {
        double pred = eqs[e].p_w.dot(dv_um);
        r[static_cast<Eigen::Index>(e)] = eqs[e].sqrt_w * (eqs[e].y_um - pred);
      }
    }
    // setup offsets are linear: exact through J
    for (int j = 0; j < P; ++j)
      if (cols[static_cast<std::size_t>(j)].p.kind == ParameterKind::kSetupOffset && th[j] != 0.0)
        r -= Js.col(j) * (D[j] * th[j]);
  };
  double weight_sum = 0.0;
  for (const Equation& q : eqs) weight_sum += q.sqrt_w * q.sqrt_w;
  residuals(theta);
  res.rms_before_um = std::sqrt(r.squaredNorm() / weight_sum);
  double previous_step = INFINITY;
  for (res.iterations = 0; res.iterations < opt.max_iterations && Kp > 0;) {
    Eigen::VectorXd g(Kp);
    for (int a = 0; a < Kp; ++a) g[a] = Js.col(kept[static_cast<std::size_t>(a)]).dot(r);
    const Eigen::VectorXd step_s = ldlt.solve(g);
    double max_step = 0.0;
    for (int a = 0; a < Kp; ++a) {
      const int j = kept[static_cast<std::size_t>(a)];
      const double d = step_s[a] / D[j];
      theta[j] += d;
      max_step = std::max(max_step, std::abs(d));
    }
    ++res.iterations;
    residuals(theta);
    // Converged: below the tolerance, or at the rounding floor (steps of a
    // few 1e-10 um that stop shrinking: large residuals times the machine
    // epsilon).
    if (max_step < opt.step_tolerance || (max_step < 1e-6 && max_step > 0.5 * previous_step)) {
      res.converged = true;
      break;
    }
    previous_step = max_step;
  }
  if (Kp == 0) res.converged = true;
  res.rms_after_um = std::sqrt(r.squaredNorm() / weight_sum);
  res.rows_used = us.size();
  res.equations = eqs.size();
  const int dof = M - Kp;
  res.sigma_um = dof > 0 ? std::sqrt(r.squaredNorm() / dof) : std::nan("");

  // ---- covariance ---------------------------------------------------------
  Eigen::MatrixXd cov_s = ldlt.solve(Eigen::MatrixXd::Identity(Kp, Kp));
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
      if (std::abs(res.correlation(a, b)) >= opt.strong_correlation)
        res.strong_correlations.push_back({res.correlation_names[static_cast<std::size_t>(a)],
                                           res.correlation_names[static_cast<std::size_t>(b)],
                                           res.correlation(a, b)});
  std::stable_sort(res.strong_correlations.begin(), res.strong_correlations.end(),
                   [](const IdentifyResult::Pair& x, const IdentifyResult::Pair& y) {
                     return std::abs(x.rho) > std::abs(y.rho);
                   });

  for (int j = 0; j < P; ++j) {
    IdentifiedParameter p = cols[static_cast<std::size_t>(j)].p;
    p.identifiable = !fixed[static_cast<std::size_t>(j)];
    p.estimate = p.identifiable ? theta[j] : 0.0;
    p.std_error = std::nan("");
    if (p.identifiable) {
      const auto a =
          static_cast<Eigen::Index>(std::find(kept.begin(), kept.end(), j) - kept.begin());
      if (dof > 0) p.std_error = std::sqrt(std::max(cov(a, a), 0.0));
    }
    res.parameters.push_back(p);
    if (p.identifiable && p.kind == ParameterKind::kLocation)
      res.location_estimates.push_back(
          {p.name, theta[j] * cols[static_cast<std::size_t>(j)].unit_scale});
  }

  // ---- fitted curves for the errors CSV --------------------------------------
  {
    Eigen::VectorXd th = theta;
    for (int j = 0; j < P; ++j)
      if (fixed[static_cast<std::size_t>(j)]) th[j] = 0.0;
    const ErrorSet e = build_errors(th);
    for (int a = 0; a < kAxisNameCount; ++a) {
      const AxisErrors* ax = e.errors_of(static_cast<AxisName>(a));
      if (!ax || (opt.known && opt.known->errors_of(static_cast<AxisName>(a)))) continue;
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
  return res;
}

void write_identified_errors_csv(std::ostream& out, const IdentifyResult& res,
                                 const std::map<std::string, std::string>& metadata,
                                 const std::string& known_text) {
  std::string text = "# volmap component errors v1\n";
  for (const auto& [k, v] : metadata) text += "# " + k + ": " + v + "\n";
  std::string not_identified;
  for (const IdentifiedParameter& p : res.parameters)
    if (!p.identifiable) {
      if (!not_identified.empty()) not_identified += ", ";
      not_identified += p.name;
    }
  if (!not_identified.empty())
    text +=
        "# not identifiable from these recordings (fixed at 0, not written): " + not_identified +
        "\n";

  // Known errors: their blocks verbatim (comments dropped).
  {
    std::istringstream in(known_text);
    std::string line;
    bool in_block = false;
    while (std::getline(in, line)) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);
      const std::size_t first = line.find_first_not_of(" \t");
      if (first == std::string::npos) {
        in_block = false;
        continue;
      }
      if (line[first] == '#') continue;
      if (!in_block) text += '\n';
      in_block = true;
      text += line;
      text += '\n';
    }
  }
  // Fitted curves, one block per axis.
  std::map<AxisName, std::vector<const FittedCurve*>> by_axis;
  for (const FittedCurve& c : res.curves) by_axis[c.axis].push_back(&c);
  for (const auto& [axis, curves] : by_axis) {
    const bool rotary = is_rotary(axis);
    text += '\n';
    text += axis_char(axis);
    for (const FittedCurve* c : curves) {
      text += ',';
      text += component_error_name(c->component, axis);
    }
    text += '\n';
    for (std::size_t k = 0; k < curves.front()->knots.size(); ++k) {
      text += fixed6(curves.front()->knots[k] * (rotary ? kRadToDeg : 1.0));
      for (const FittedCurve* c : curves) {
        text += ',';
        text += fixed6(c->values[k] * (is_angular(c->component) ? 1e6 : 1e3));
      }
      text += '\n';
    }
  }
  // Location errors grouped by axis (squareness of linear axes, then each
  // rotary axis), in the model's order.
  std::vector<std::pair<std::string, std::vector<std::pair<std::string, double>>>> groups;
  for (const auto& [name, value] : res.location_estimates) {
    const ErrorName n = *parse_error_name(name);
    const std::string key =
        is_rotary(n.axis) ? std::string(1, axis_char(n.axis)) : std::string("linear");
    auto it =
        std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == key; });
    if (it == groups.end()) {
      groups.push_back({key, {}});
      it = groups.end() - 1;
    }
    it->second.push_back({name, value * (is_angular(n.component) ? 1e6 : 1e3)});
  }
  for (const auto& [key, entries] : groups) {
    text += '\n';
    for (std::size_t k = 0; k < entries.size(); ++k) {
      if (k) text += ',';
      text += entries[k].first;
    }
    text += '\n';
    for (std::size_t k = 0; k < entries.size(); ++k) {
      if (k) text += ',';
      text += fixed6(entries[k].second);
    }
    text += '\n';
  }
  out << text;
}

namespace {
nlohmann::ordered_json number_or_null(double v) {
  if (!std::isfinite(v)) return nullptr;
  return v;
}
}  // namespace

nlohmann::ordered_json identify_report_json(const IdentifyResult& r) {
  nlohmann::ordered_json doc;
  doc["format"] = "volmap-identify/1";
  doc["rows"] = r.rows_used;
  doc["observations"] = r.equations;
  doc["parameter_count"] = r.parameters.size();
  doc["rank"] = r.rank;
  doc["condition_number"] = number_or_null(r.condition_number);
  doc["singular_values"] = r.singular_values;
  doc["iterations"] = r.iterations;
  doc["converged"] = r.converged;
  doc["rms_before_um"] = r.rms_before_um;
  doc["rms_after_um"] = r.rms_after_um;
  doc["sigma_um"] = number_or_null(r.sigma_um);
  nlohmann::ordered_json params = nlohmann::ordered_json::array();
  for (const IdentifiedParameter& p : r.parameters) {
    const char* kind = p.kind == ParameterKind::kLocation    ? "location"
                       : p.kind == ParameterKind::kComponent ? "component"
                                                             : "setup_offset";
    params.push_back({{"name", p.name},
                      {"kind", kind},
                      {"unit", p.unit},
                      {"status", p.identifiable ? "estimated" : "not_identifiable"},
                      {"estimate", p.identifiable ? number_or_null(p.estimate)
                                                  : nlohmann::ordered_json(nullptr)},
                      {"std_error", number_or_null(p.std_error)}});
  }
  doc["parameters"] = params;
  nlohmann::ordered_json un = nlohmann::ordered_json::array();
  for (const UnidentifiableCombination& u : r.unidentifiable) {
    nlohmann::ordered_json terms = nlohmann::ordered_json::object();
    for (const auto& [n, c] : u.terms) terms[n] = c;
    un.push_back({{"combination", terms},
                  {"text", u.text},
                  {"fixed", u.fixed},
                  {"explanation", u.explanation},
                  {"remedy", u.remedy}});
  }
  doc["unidentifiable"] = un;
  nlohmann::ordered_json strong = nlohmann::ordered_json::array();
  for (const auto& p : r.strong_correlations)
    strong.push_back({{"a", p.a}, {"b", p.b}, {"rho", p.rho}});
  doc["strong_correlations"] = strong;
  nlohmann::ordered_json matrix = nlohmann::ordered_json::array();
  for (Eigen::Index a = 0; a < r.correlation.rows(); ++a) {
    nlohmann::ordered_json row = nlohmann::ordered_json::array();
    for (Eigen::Index b = 0; b < r.correlation.cols(); ++b) row.push_back(r.correlation(a, b));
    matrix.push_back(row);
  }
  doc["correlation"] = {{"names", r.correlation_names}, {"matrix", matrix}};
  return doc;
}

std::string identify_report_text(const IdentifyResult& r) {
  std::string s;
  s += fmt::format(
      "Identification: {} observations in {} rows, {} parameters, rank {}, condition number "
      "{:.4g}\n",
      r.equations, r.rows_used, r.parameters.size(), r.rank, r.condition_number);
  s += fmt::format(
      "RMS residual {:.4g} um before, {:.4g} um after ({} Gauss-Newton iterations{}); sigma {:.4g} "
      "um\n\n",
      r.rms_before_um, r.rms_after_um, r.iterations, r.converged ? "" : ", NOT converged",
      r.sigma_um);
  s += fmt::format("{:<16} {:>14} {:>12}  {}\n", "parameter", "estimate", "std error", "");
  for (const IdentifiedParameter& p : r.parameters) {
    if (p.identifiable)
      s += fmt::format("{:<16} {:>11.4f} {:<4} {:>10.4f}\n", p.name, p.estimate, p.unit,
                       p.std_error);
    else
      s += fmt::format("{:<16} {:>16} {:>10}  not identifiable: fixed at 0\n", p.name, "-", "-");
  }
  if (!r.unidentifiable.empty()) {
    s += "\nCombinations these recordings cannot separate:\n";
    for (const UnidentifiableCombination& u : r.unidentifiable)
      s += fmt::format("  {}: {}; {} fixed at 0.\n    To separate: {}.\n", u.text, u.explanation,
                       u.fixed, u.remedy);
  }
  if (!r.strong_correlations.empty()) {
    s += "\nStrongly correlated estimates (|rho| >= 0.9):\n";
    for (const auto& p : r.strong_correlations)
      s += fmt::format("  {} ~ {}: {:+.4f}\n", p.a, p.b, p.rho);
  }
  return s;
}

}  // namespace volmap
