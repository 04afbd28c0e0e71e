#include "core/measure/identifiability.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <set>

namespace volmap::identification {
namespace {

/// What the parameters are: the machine, the columns and which axes move.
struct ParameterContext {
  const Machine& m;
  const std::vector<ParameterColumn>& cols;
  const std::vector<std::string>& names;  ///< GainEvaluator names
  const std::vector<bool>& moved;         ///< per axis
};

std::string format_coefficient(double c) {
  if (std::abs(c - std::round(c)) < 1e-9)
    return fmt::format("{}", static_cast<long long>(std::round(c)));
  return fmt::format("{:.4g}", c);
}

/// The columns in the order they are fixed by: parameters of axes that do
/// not move, then physical parameters from the end of the list (the rotary
/// block before the linear axes), setup offsets last.
std::vector<int> fixing_preference(const ParameterContext& ctx) {
  const int P = static_cast<int>(ctx.cols.size());
  std::vector<int> preference(static_cast<std::size_t>(P));
  for (int j = 0; j < P; ++j) preference[static_cast<std::size_t>(j)] = j;
  auto rank_of = [&](int j) {
    const ParameterColumn& c = ctx.cols[static_cast<std::size_t>(j)];
    if (c.p.kind == ParameterKind::kSetupOffset) return 4;
    const std::optional<ErrorName> n =
        parse_error_name(ctx.names[static_cast<std::size_t>(c.gain)]);
    const std::optional<int> ai = n ? ctx.m.index_of(n->axis) : std::nullopt;
    if (ai && !ctx.moved[static_cast<std::size_t>(*ai)]) return 1;
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
  return preference;
}

/// The null vectors (rows of V0) in reduced row echelon form with one pivot
/// column each, picked by preference: the parameter fixed at 0.
struct NullSpace {
  Eigen::MatrixXd V0;
  std::vector<int> pivot_of_row;  ///< -1: no pivot found
};

NullSpace fix_one_parameter_per_null_vector(Eigen::MatrixXd V0, const std::vector<int>& preference,
                                            std::vector<bool>& fixed) {
  const auto K0 = static_cast<int>(V0.rows());
  std::vector<int> pivot_of_row(static_cast<std::size_t>(K0), -1);
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
  return {std::move(V0), std::move(pivot_of_row)};
}

/// A rich design (random positions over the whole travel, all three
/// components, one run) tells a redundancy of the parameter set itself from
/// a weakness of this recording's plan.
Eigen::MatrixXd rich_design_jacobian(const ParameterContext& ctx, GainEvaluator& gains) {
  const Machine& m = ctx.m;
  const int P = static_cast<int>(ctx.cols.size());
  constexpr int kRich = 256;
  Eigen::MatrixXd J_rich(3 * kRich, P);
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
      u[i] = L.unlimited ? 2.0 * std::numbers::pi * uniform() : L.min + (L.max - L.min) * uniform();
    }
    gains.at(u);
    for (int j = 0; j < P; ++j) {
      const ParameterColumn& c = ctx.cols[static_cast<std::size_t>(j)];
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      if (c.p.kind == ParameterKind::kSetupOffset) {
        g[c.coordinate] = 1.0;
      } else {
        g = physical_gain_w_um(c, gains, u);
      }
      J_rich.block<3, 1>(3 * k, j) = g;
    }
  }
  return J_rich;
}

/// What the members of a combination are, for the documented rules.
struct CombinationTraits {
  std::set<AxisName> rotary_axes, still_axes;
  bool offset = false, squareness = false, component = false, tilt = false, shift = false;
};

CombinationTraits traits_of(const std::vector<int>& members, const ParameterContext& ctx) {
  CombinationTraits t;
  for (int j : members) {
    const ParameterColumn& c = ctx.cols[static_cast<std::size_t>(j)];
    if (c.p.kind == ParameterKind::kSetupOffset) {
      t.offset = true;
      continue;
    }
    const ErrorName n = *parse_error_name(ctx.names[static_cast<std::size_t>(c.gain)]);
    if (!ctx.moved[static_cast<std::size_t>(*ctx.m.index_of(n.axis))]) t.still_axes.insert(n.axis);
    if (c.p.kind == ParameterKind::kComponent) t.component = true;
    if (n.location && !is_rotary(n.axis)) t.squareness = true;
    if (n.location && is_rotary(n.axis)) {
      t.rotary_axes.insert(n.axis);
      (is_angular(n.component) ? t.tilt : t.shift) = true;
    }
  }
  return t;
}

std::string axis_list(const std::set<AxisName>& s) {
  std::string out;
  for (AxisName a : s) out += std::string(out.empty() ? "" : ", ") + axis_char(a);
  return out;
}

/// Documented rules (docs/identify.md), first match wins: sets
/// u.explanation and u.remedy. `intrinsic`: the combination leaves the tool
/// tip unchanged in the rich design too; `zero_column`: no observation sees
/// the single member.
void explain_combination(UnidentifiableCombination& u, const CombinationTraits& t,
                         std::size_t member_count, bool intrinsic, bool zero_column) {
  if (intrinsic && member_count > 1) {
    u.explanation =
        "these errors move the tool tip identically at every axis position: one error "
        "motion under two names (a redundancy of the parameter set, not of the plan)";
    u.remedy =
        "no tool-tip measurement separates them; keep the fixed one at 0 (the others absorb it)";
  } else if (member_count == 1 && zero_column) {
    u.explanation = fmt::format("no observation is sensitive to {}", u.fixed);
    u.remedy = t.still_axes.empty()
                   ? "record observations whose direction sees it: all of ex, ey, ez, and the ball "
                     "off the rotary axis lines"
                   : fmt::format("move {} during the test", axis_list(t.still_axes));
  } else if (!t.still_axes.empty()) {
    u.explanation = fmt::format(
        "{} does not move in this recording, so its errors act as constants "
        "that other errors imitate",
        axis_list(t.still_axes));
    u.remedy = fmt::format(
        "add positions of {} (for a rotary axis at least three angles; for A on a "
        "table, tilt the table)",
        axis_list(t.still_axes));
  } else if (t.offset) {
    u.explanation =
        "a constant offset of the ball (setup, sphere position) cannot be told from these errors";
    u.remedy = "add a second ball position (another height or radius on the table)";
  } else if (t.rotary_axes.size() >= 2) {
    u.explanation =
        fmt::format("the lines of {} are not separated by this plan", axis_list(t.rotary_axes));
    u.remedy =
        "measure each rotary axis at several positions of the other (e.g. C at several A angles)";
  } else if (t.rotary_axes.size() == 1 && t.tilt && t.shift && !t.squareness) {
    u.explanation =
        fmt::format("tilt and offset of the {} axis: one ball height sees only their combination",
                    axis_list(t.rotary_axes));
    u.remedy = fmt::format("add a second ball at another height along the {} axis",
                           axis_list(t.rotary_axes));
  } else if (t.squareness) {
    u.explanation =
        "squareness of the linear axes vs the other errors: the linear axes move too little";
    u.remedy =
        "move the linear axes over a larger range (a second ball position farther from the "
        "rotary axes)";
  } else if (t.component) {
    u.explanation = "component-error terms that this coverage of the axis cannot separate";
    u.remedy = "cover more of the axis's travel, or lower the degree";
  } else {
    u.explanation = "these errors move the tool alike at every observation";
    u.remedy = "add observations at other axis positions and record all of ex, ey, ez";
  }
}

/// Names the combination of null vector `v` (pivot `piv`, scaled
/// coordinates) in parameter units and says what would separate it.
UnidentifiableCombination describe_combination(const Eigen::RowVectorXd& v, int piv,
                                               const Eigen::VectorXd& D,
                                               const std::vector<bool>& zero_column,
                                               const Eigen::MatrixXd& J_rich,
                                               const ParameterContext& ctx) {
  const int P = static_cast<int>(ctx.cols.size());
  UnidentifiableCombination u;
  u.fixed = ctx.cols[static_cast<std::size_t>(piv)].p.name;
  u.terms.push_back({u.fixed, 1.0});
  u.text = u.fixed;
  std::vector<int> members{piv};
  for (int j = 0; j < P; ++j) {
    if (j == piv || std::abs(v(j)) < 1e-6) continue;
    const double coef = v(j) * D[piv] / D[j];
    u.terms.push_back({ctx.cols[static_cast<std::size_t>(j)].p.name, coef});
    u.text += fmt::format(" {} {} {}", coef < 0 ? "-" : "+", format_coefficient(std::abs(coef)),
                          ctx.cols[static_cast<std::size_t>(j)].p.name);
    members.push_back(j);
  }
  Eigen::VectorXd v_phys = Eigen::VectorXd::Zero(P);
  for (int j : members) v_phys[j] = v(j) / D[j];
  double rich_scale = 0.0;
  for (int j : members) rich_scale += J_rich.col(j).norm() * std::abs(v_phys[j]);
  const bool intrinsic = rich_scale > 0 && (J_rich * v_phys).norm() < 1e-7 * rich_scale;
  explain_combination(u, traits_of(members, ctx), members.size(), intrinsic,
                      zero_column[static_cast<std::size_t>(piv)]);
  return u;
}

}  // namespace

Identifiability analyse_identifiability(Eigen::MatrixXd& J, const Machine& m, GainEvaluator& gains,
                                        const std::vector<ParameterColumn>& cols,
                                        const std::vector<bool>& moved, double rank_tolerance) {
  const int P = static_cast<int>(cols.size());
  const ParameterContext ctx{m, cols, gains.names(), moved};
  Identifiability id;
  Eigen::VectorXd& D = id.column_scale;
  D.resize(P);
  for (int j = 0; j < P; ++j) {
    const double norm = J.col(j).norm();
    D[j] = norm > 0 ? norm : 1.0;
  }
  std::vector<bool> zero_column(static_cast<std::size_t>(P));
  for (int j = 0; j < P; ++j)
    zero_column[static_cast<std::size_t>(j)] = J.col(j).squaredNorm() == 0.0;
  J *= D.cwiseInverse().asDiagonal();  // now J_s, in place (10^4 x 30 doubles: no second copy)
  const Eigen::MatrixXd& Js = J;
  Eigen::MatrixXd& N = id.normal;
  N = Eigen::MatrixXd::Zero(P, P);
  N.selfadjointView<Eigen::Lower>().rankUpdate(Js.transpose());
  N.triangularView<Eigen::StrictlyUpper>() = N.transpose();
  if (P == 0) return id;  // nothing to analyse (and no 0 x 0 eigensolve)
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(N);
  const Eigen::VectorXd lambda = eig.eigenvalues();  // ascending
  const double sigma_max = std::sqrt(std::max(lambda[P - 1], 0.0));
  std::vector<int> null_idx;
  for (int k = P - 1; k >= 0; --k) {
    const double s = std::sqrt(std::max(lambda[k], 0.0));
    id.singular_values.push_back(s);
    if (!(s > rank_tolerance * sigma_max)) null_idx.push_back(k);
  }
  id.rank = P - static_cast<int>(null_idx.size());

  const int K0 = static_cast<int>(null_idx.size());
  Eigen::MatrixXd V0(K0, P);
  for (int r = 0; r < K0; ++r)
    V0.row(r) = eig.eigenvectors().col(null_idx[static_cast<std::size_t>(r)]).transpose();
  id.fixed.assign(static_cast<std::size_t>(P), false);
  const NullSpace null =
      fix_one_parameter_per_null_vector(std::move(V0), fixing_preference(ctx), id.fixed);
  if (K0 == 0) return id;

  // Name the combinations and say what would separate them.
  const Eigen::MatrixXd J_rich = rich_design_jacobian(ctx, gains);
  for (int r = 0; r < K0; ++r) {
    const int piv = null.pivot_of_row[static_cast<std::size_t>(r)];
    if (piv < 0) continue;
    id.unidentifiable.push_back(
        describe_combination(null.V0.row(r), piv, D, zero_column, J_rich, ctx));
  }
  return id;
}

}  // namespace volmap::identification
