// The baseline of explain (baseline_model.h).
#include "core/explain/baseline_model.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/explain/axis_labels.h"
#include "core/explain/distinct_values.h"

namespace volmap::explanation {
namespace {

constexpr int kSparseTargets = 12;  ///< up to this many targets: a value per target

/// Polynomial degree of the component errors of each linear axis, and the
/// degrees as the description lists them ("X 3, Y 1").
struct PolynomialDegrees {
  std::array<int, kAxisNameCount> of_axis{};
  std::string text;
};

// Degree per linear axis: opt.degree, or (0, automatic) a value per target
// for an axis run through at most kSparseTargets targets (as ISO 230-2
// evaluates a positioning test: the mean deviation of each target), else cubic.
PolynomialDegrees polynomial_degrees(const Observations& obs, const ExplainOptions& opt) {
  PolynomialDegrees degrees;
  for (AxisName a : obs.machine.axis_order) {
    if (is_rotary(a)) continue;
    std::vector<double> positions;
    for (std::size_t e = 0; e < obs.count; ++e)
      positions.push_back(obs.position(a, obs.recording_row[e]));
    const int targets = static_cast<int>(unique_sorted(positions).size());
    int deg = opt.degree;
    if (deg == 0) deg = targets <= kSparseTargets ? std::max(1, targets - 1) : 3;
    degrees.of_axis[static_cast<std::size_t>(a)] = deg;
    degrees.text += fmt::format("{}{} {}", degrees.text.empty() ? "" : ", ", axis_letter(a), deg);
  }
  return degrees;
}

/// The instrument zero: a constant per recorded component.
void add_component_constants(const Observations& obs, std::vector<Eigen::VectorXd>& cols) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  for (int g = 0; g < kComponentKinds; ++g) {
    if (!obs.has_component[g]) continue;
    Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
    for (Eigen::Index e = 0; e < n; ++e)
      if (obs.component[static_cast<std::size_t>(e)] == g) c[e] = 1.0;
    cols.push_back(c);
  }
}

/// The fitted rigid body: every location error, and every component error
/// of a linear axis as s^1..s^degree. Counts what it adds.
void add_rigid_body_errors(const Observations& obs, const PolynomialDegrees& degrees,
                           std::vector<Eigen::VectorXd>& cols, int& location, int& components) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.count);
  for (std::size_t k = 0; k < obs.error_names.size(); ++k) {
    const ErrorName en = *parse_error_name(obs.error_names[k]);
    const Eigen::VectorXd g = obs.error_gain.col(static_cast<Eigen::Index>(k));
    if (en.location) {
      cols.push_back(g);
      ++location;
      continue;
    }
    if (is_rotary(en.axis)) continue;
    const TravelScale travel = travel_scale(obs.machine, en.axis);
    const double centre = travel.centre_mm, half = travel.half_mm;
    const int degree = degrees.of_axis[static_cast<std::size_t>(en.axis)];
    for (int p = 1; p <= degree; ++p) {
      Eigen::VectorXd c(n);
      for (Eigen::Index e = 0; e < n; ++e) {
        const double s =
            (obs.position(en.axis, obs.recording_row[static_cast<std::size_t>(e)]) - centre) / half;
        c[e] = g[e] * std::pow(s, p);
      }
      cols.push_back(c);
    }
    ++components;
  }
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

}  // namespace

LinearModel baseline_model(const Observations& obs, const ExplainOptions& opt,
                           std::string& description) {
  std::vector<Eigen::VectorXd> cols;
  add_component_constants(obs, cols);
  int location = 0, components = 0;
  const PolynomialDegrees degrees = polynomial_degrees(obs, opt);
  if (!opt.baseline) add_rigid_body_errors(obs, degrees, cols, location, components);
  LinearModel model = independent_model(obs, cols);
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
        components, linear_axes, degrees.text, location, model.k(), cols.size());
  }
  return model;
}

}  // namespace volmap::explanation
