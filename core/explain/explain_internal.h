// Internals of `volmap explain` shared by core/explain*.cc; not a public
// API (core/explain.h is). Data: the recording as equations. Candidate: one
// effect of explain.md as columns of a linear model, with its nonlinear
// parameter (if any) and its report. docs/explain.md describes the method.
#pragma once

#include <Eigen/Core>
#include <cctype>
#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "core/explain/explain.h"

namespace volmap::explain_detail {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kRadToDeg = 180.0 / kPi;

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
    if (!v.empty() && std::isfinite(v[static_cast<std::size_t>(i)]))
      return v[static_cast<std::size_t>(i)];
    const std::optional<int> k = m.index_of(a);
    return k ? m.home[*k] : 0.0;
  }
  /// Position in report units (mm, degrees).
  double q_user(AxisName a, int i) const { return is_rotary(a) ? q(a, i) * kRadToDeg : q(a, i); }
  int s(AxisName a, int i) const {
    const std::vector<std::int8_t>& v = rec.dir[static_cast<std::size_t>(a)];
    return v.empty() ? 0 : v[static_cast<std::size_t>(i)];
  }
  double t(int i) const {
    return rec.t_s.empty() ? std::nan("") : rec.t_s[static_cast<std::size_t>(i)];
  }
  double feed(int i) const {
    if (rec.feed_mm_min.empty()) return 0.0;
    const double f = rec.feed_mm_min[static_cast<std::size_t>(i)];
    return std::isfinite(f) ? f : 0.0;
  }
};

inline std::string axis_str(AxisName a) { return std::string(1, axis_char(a)); }
inline std::string lower_axis(AxisName a) {
  return std::string(1, static_cast<char>(std::tolower(axis_char(a))));
}
inline std::string position_name(AxisName a) {
  return lower_axis(a) + (is_rotary(a) ? "_deg" : "_mm");
}

/// The equations of a recording: every recorded value with its direction,
/// weight, run and the gains of every error name; with a fixed baseline its
/// prediction is already subtracted from y. Throws InputError for rows the
/// model cannot use.
Data build_data(const Machine& m, const Recordings& rec, const ExplainOptions& opt);

/// One candidate effect: build(theta) gives its columns (n x kc, um per
/// parameter unit, unweighted) for the nonlinear parameter theta (ignored
/// when grid is empty); report() turns the fitted coefficients into the
/// parameters of explain.md.
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
  std::function<void(const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, double theta,
                     double theta_se, Finding& f)>
      report;
  std::function<double(int row)> plot_x;  ///< the regressor that gives it away
  std::string plot_label;
  std::function<int(int row)> plot_group;
  std::string key() const { return effect + "/" + (axis ? axis_str(*axis) : "-") + "/" + variant; }
};

struct Context {
  const Data& d;
  const ExplainOptions& opt;
  std::vector<AxisName> linear, rotary;  ///< machine axes with varying recorded positions
  std::vector<AxisName> dir_axes;        ///< axes approached from both sides
  bool has_time = false, feed_varies = false, has_feed = false;
  double duration_s = 0.0;
};

/// Sorted distinct values (1e-9 apart).
std::vector<double> unique_sorted(std::vector<double> v);
/// True when the finite values are not all equal.
bool varies(const std::vector<double>& v);
/// Every candidate the recording can support (docs/explain.md, table).
std::vector<Candidate> make_candidates(const Context& c);
/// Residuals (um, per equation) against every regressor of the recording.
std::vector<Mismatch> locate_mismatch(const Data& d, const Eigen::VectorXd& r_um);

}  // namespace volmap::explain_detail
