// The baseline of explain (baseline_model.h).
#include "core/explain/baseline_model.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "core/explain/axis_labels.h"
#include "core/explain/detection.h"
#include "core/explain/distinct_values.h"

namespace volmap::explanation {
namespace {

constexpr int kSparseTargets = 12;     ///< up to this many targets: a value per target
constexpr int kMaxAdaptiveDegree = 6;  ///< the automatic degree of a densely sampled axis

/// Polynomial degree of the component errors of each linear axis; adaptive:
/// automatic and densely sampled (the degree is raised while the data
/// demands it).
struct PolynomialDegrees {
  std::array<int, kAxisNameCount> of_axis{};
  std::array<bool, kAxisNameCount> adaptive{};
  /// The degrees as the description lists them ("X 3, Y 1").
  std::string text(const Machine& m) const {
    std::string t;
    for (AxisName a : m.axis_order)
      if (!is_rotary(a))
        t += fmt::format("{}{} {}", t.empty() ? "" : ", ", axis_letter(a),
                         of_axis[static_cast<std::size_t>(a)]);
    return t;
  }
};

// Degree per linear axis: opt.degree, or (0, automatic) a value per target
// for an axis run through at most kSparseTargets targets (as ISO 230-2
// evaluates a positioning test: the mean deviation of each target), else
// cubic to start with (raise_degrees).
PolynomialDegrees polynomial_degrees(const Observations& obs, const ExplainOptions& opt) {
  PolynomialDegrees degrees;
  for (AxisName a : obs.machine.axis_order) {
    if (is_rotary(a)) continue;
    std::vector<double> positions;
    for (std::size_t e = 0; e < obs.count; ++e)
      positions.push_back(obs.position(a, obs.recording_row[e]));
    const int targets = static_cast<int>(unique_sorted(positions).size());
    int deg = opt.degree;
    const std::size_t ai = static_cast<std::size_t>(a);
    if (deg == 0) {
      deg = targets <= kSparseTargets ? std::max(1, targets - 1) : 3;
      degrees.adaptive[ai] = targets > kSparseTargets;
    }
    degrees.of_axis[ai] = deg;
  }
  return degrees;
}

/// The instrument zero: a constant per recorded component. A projection
/// reading also sees where the instrument was set up: a constant offset in
/// each direction, p_w . c (a ballbar's centre against the programmed one;
/// along a fixed beam it is the constant again, which the rank test drops).
void add_component_constants(const Observations& obs, std::vector<Eigen::VectorXd>& cols) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  for (int g = 0; g < kComponentKinds; ++g) {
    if (!obs.has_component[g]) continue;
    Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
    for (Eigen::Index e = 0; e < n; ++e)
      if (obs.component[static_cast<std::size_t>(e)] == g) c[e] = 1.0;
    cols.push_back(c);
  }
  if (!obs.has_component[kProjection]) return;
  for (int k = 0; k < 3; ++k) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
    for (Eigen::Index e = 0; e < n; ++e)
      if (obs.component[static_cast<std::size_t>(e)] == kProjection) c[e] = obs.direction_wp(k, e);
    cols.push_back(c);
  }
}

/// A component error's gain g times s^p, s the position of axis a scaled
/// over its travel.
Eigen::VectorXd power_column(const Observations& obs, AxisName a, const Eigen::VectorXd& g, int p) {
  const TravelScale travel = travel_scale(obs.machine, a);
  Eigen::VectorXd c(g.size());
  for (Eigen::Index e = 0; e < g.size(); ++e) {
    const double s =
        (obs.position(a, obs.recording_row[static_cast<std::size_t>(e)]) - travel.centre_mm) /
        travel.half_mm;
    c[e] = g[e] * std::pow(s, p);
  }
  return c;
}

/// The fitted rigid body: every location error, and every component error
/// of a linear axis as s^1..s^degree. Counts what it adds.
void add_rigid_body_errors(const Observations& obs, const PolynomialDegrees& degrees,
                           std::vector<Eigen::VectorXd>& cols, int& location, int& components) {
  for (std::size_t k = 0; k < obs.error_names.size(); ++k) {
    const ErrorName en = *parse_error_name(obs.error_names[k]);
    const Eigen::VectorXd g = obs.error_gain.col(static_cast<Eigen::Index>(k));
    if (en.location) {
      cols.push_back(g);
      ++location;
      continue;
    }
    if (is_rotary(en.axis)) continue;
    const int degree = degrees.of_axis[static_cast<std::size_t>(en.axis)];
    for (int p = 1; p <= degree; ++p) cols.push_back(power_column(obs, en.axis, g, p));
    ++components;
  }
}

/// The columns of every component error of linear axis a at power p, as a
/// block (weighted, normalised).
ColumnBlock power_block(const Observations& obs, AxisName a, int p) {
  std::vector<Eigen::VectorXd> cols;
  for (std::size_t k = 0; k < obs.error_names.size(); ++k) {
    const ErrorName en = *parse_error_name(obs.error_names[k]);
    if (en.location || en.axis != a) continue;
    cols.push_back(power_column(obs, a, obs.error_gain.col(static_cast<Eigen::Index>(k)), p));
  }
  Eigen::MatrixXd phys(static_cast<Eigen::Index>(obs.count),
                       static_cast<Eigen::Index>(cols.size()));
  for (std::size_t j = 0; j < cols.size(); ++j) phys.col(static_cast<Eigen::Index>(j)) = cols[j];
  return make_column_block(obs, phys);
}

/// The model of the columns not spanned by earlier ones.
LinearModel independent_model(const Observations& obs, const std::vector<Eigen::VectorXd>& cols) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  Eigen::MatrixXd phys(n, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t j = 0; j < cols.size(); ++j) phys.col(static_cast<Eigen::Index>(j)) = cols[j];
  ColumnBlock b = make_column_block(obs, phys);
  const std::vector<int> keep = independent_columns(b.cols);
  LinearModel model;
  model.X.resize(n, static_cast<Eigen::Index>(keep.size()));
  model.scale.resize(static_cast<Eigen::Index>(keep.size()));
  for (std::size_t j = 0; j < keep.size(); ++j) {
    model.X.col(static_cast<Eigen::Index>(j)) = b.cols.col(keep[j]);
    model.scale[static_cast<Eigen::Index>(j)] = b.scale[keep[j]];
  }
  model.per_run.assign(keep.size(), false);
  model.rank = static_cast<int>(keep.size());
  return model;
}

/// The baseline's model at given degrees, fitted, and what it holds.
struct BaselineBuild {
  LinearModel model;
  std::size_t columns = 0;  ///< before the rank test
  int location = 0, components = 0;
};

BaselineBuild build_baseline(const Observations& obs, const ExplainOptions& opt,
                             const PolynomialDegrees& degrees) {
  std::vector<Eigen::VectorXd> cols;
  add_component_constants(obs, cols);
  BaselineBuild b;
  if (!opt.baseline) add_rigid_body_errors(obs, degrees, cols, b.location, b.components);
  b.columns = cols.size();
  b.model = independent_model(obs, cols);
  fit(obs, b.model);
  return b;
}

// A densely sampled axis's component errors need not be cubic (a laser
// table interpolated linearly has kinks): its degree is raised, one axis at
// a time, the most significant first, while the added powers pass the
// detection test (detection.h, at the same family-wise level as a finding,
// the adaptive axes being the family), up to kMaxAdaptiveDegree. Without
// this, a smooth error the cubic misses would be named as a scanned effect.
void raise_degrees(const Observations& obs, const ExplainOptions& opt, PolynomialDegrees& degrees,
                   BaselineBuild& b) {
  const double family =
      static_cast<double>(std::count(degrees.adaptive.begin(), degrees.adaptive.end(), true));
  const double n = static_cast<double>(obs.count);
  bool raised = false;
  while (true) {
    // Each axis's next power tried as a block beside the model (its profile
    // gain and projected rank), then the winner built in (one full build).
    std::optional<std::pair<double, AxisName>> best;
    for (AxisName a : obs.machine.axis_order) {
      const std::size_t ai = static_cast<std::size_t>(a);
      if (!degrees.adaptive[ai] || degrees.of_axis[ai] >= kMaxAdaptiveDegree) continue;
      const ColumnBlock next = power_block(obs, a, degrees.of_axis[ai] + 1);
      if (next.cols.cols() == 0) continue;
      const Eigen::VectorXd ev =
          Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(projected_gram(b.model, next))
              .eigenvalues();
      const double added = static_cast<double>((ev.array() > 1e-6 * n).count());
      if (added <= 0) continue;
      TestDesign d;
      d.columns = added;
      d.residual_dof = std::max(1.0, n - static_cast<double>(b.model.k()) - added);
      d.family = family;
      const double rss = profile(obs, b.model, next).rss;
      const double sigma2 = std::max(rss, 1e-300) / d.residual_dof;
      const double p = corrected_p_value(std::max(0.0, b.model.rss - rss) / sigma2, d);
      if (p < kFamilyAlpha && (!best || p < best->first)) best = {p, a};
    }
    if (!best) break;
    // beside the model for the next round (a full build once at the end)
    const std::size_t ai = static_cast<std::size_t>(best->second);
    b.model = with_block(b.model, power_block(obs, best->second, ++degrees.of_axis[ai]), 0);
    fit(obs, b.model);
    raised = true;
  }
  if (raised) b = build_baseline(obs, opt, degrees);
}

}  // namespace

LinearModel baseline_model(const Observations& obs, const ExplainOptions& opt,
                           std::string& description) {
  PolynomialDegrees degrees = polynomial_degrees(obs, opt);
  BaselineBuild b = build_baseline(obs, opt, degrees);
  if (!opt.baseline) raise_degrees(obs, opt, degrees, b);
  LinearModel& model = b.model;
  const int location = b.location, components = b.components;
  const int linear_axes =
      static_cast<int>(std::count_if(obs.machine.axis_order.begin(), obs.machine.axis_order.end(),
                                     [](AxisName a) { return !is_rotary(a); }));
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
        components, linear_axes, degrees.text(obs.machine), location, model.k(), b.columns);
  }
  return std::move(model);
}

}  // namespace volmap::explanation
