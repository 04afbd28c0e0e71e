// The recording as equations (docs/explain.md): every recorded scalar (ex_um,
// ey_um, ez_um cell, or e_um of the projection form) is one equation
// y = p_rec^T d_rec(u), p_rec the unit component or beam direction. In the
// workpiece frame p_w = R_rec_w^T p_rec (R_rec_w = I, or R_b_w for
// "# frame: machine"); in machine directions p_b = R_b_w p_w.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/common/units.h"
#include "core/explain/explain.h"

namespace volmap::explanation {

/// Component of an equation: 0, 1, 2 for ex, ey, ez; kProjection for e_um.
inline constexpr int kProjection = 3;
inline constexpr int kComponentKinds = 4;

/// The recording as equations, and the per-row context the columns need.
struct Observations {
  const Machine& machine;
  const Recordings& recordings;
  std::size_t count = 0;           ///< equations
  std::vector<int> recording_row;  ///< per equation: its row of the recording
  std::vector<int> component;      ///< per equation: 0..2 ex, ey, ez; kProjection
  std::vector<int> run;            ///< per equation: 0-based (one run for none)
  Eigen::VectorXd deviation_um;    ///< recorded value, um (fixed baseline removed)
  Eigen::VectorXd sqrt_weight;
  Eigen::Matrix3Xd direction_wp;    ///< p_w: direction of the equation, workpiece frame
  Eigen::Matrix3Xd direction_base;  ///< p_b = R_b_w p_w: in machine (base) directions
  /// p_w . dP(k) per error name (mm per mm or mm per rad): the first-order gains.
  Eigen::MatrixXd error_gain;
  std::vector<std::string> error_names;  ///< error names of error_gain's columns
  int run_count = 1;
  std::vector<std::vector<int>> equations_of_run;
  /// Per recording row: the unit direction of motion of the linear axes
  /// (X, Y, Z components) on the way to it, from the recorded positions:
  /// the chord from the run's previous row, else to its next row (a laser
  /// pass's first target, the turnaround), else the approach directions.
  /// A circular test's rows get the tangent, a laser's the pass direction.
  Eigen::Matrix3Xd move_direction;
  /// Per recording row: how far each linear axis (X, Y, Z) moved since its
  /// approach direction last flipped within the run (from the turnaround:
  /// the previous row's position), mm; infinite before the first flip.
  Eigen::Matrix3Xd since_reversal_mm;
  bool has_component[kComponentKinds] = {false, false, false, false};

  Observations(const Machine& m, const Recordings& rec) : machine(m), recordings(rec) {}

  /// Position of axis a at recording row i: mm or rad; home when not recorded.
  double position(AxisName a, int i) const {
    const std::vector<double>& v = recordings.position[static_cast<std::size_t>(a)];
    if (!v.empty() && std::isfinite(v[static_cast<std::size_t>(i)]))
      return v[static_cast<std::size_t>(i)];
    const std::optional<int> k = machine.index_of(a);
    return k ? machine.home[*k] : 0.0;
  }
  /// Position in report units (mm, degrees).
  double reported_position(AxisName a, int i) const {
    return is_rotary(a) ? position(a, i) * units::kDegPerRad : position(a, i);
  }
  /// Approach direction of axis a at row i: -1, 0 or +1 (0 when not recorded).
  int approach(AxisName a, int i) const {
    const std::vector<std::int8_t>& v = recordings.dir[static_cast<std::size_t>(a)];
    return v.empty() ? 0 : v[static_cast<std::size_t>(i)];
  }
  double time_s(int i) const {
    return recordings.t_s.empty() ? std::nan("") : recordings.t_s[static_cast<std::size_t>(i)];
  }
  /// Component of the direction of motion along machine axis a at row i.
  double moving(AxisName a, int i) const {
    return is_rotary(a) ? 0.0 : move_direction(static_cast<int>(a), i);
  }
  double feed_mm_per_min(int i) const {
    if (recordings.feed_mm_min.empty()) return 0.0;
    const double f = recordings.feed_mm_min[static_cast<std::size_t>(i)];
    return std::isfinite(f) ? f : 0.0;
  }
};

/// The travel of a linear axis K: s = (q - centre_mm) / half_mm runs over
/// -1..1 (the polynomial variable of its component errors).
struct TravelScale {
  double centre_mm, half_mm;
};
inline TravelScale travel_scale(const Machine& m, AxisName k) {
  const AxisLimits& L = m.limits[static_cast<std::size_t>(*m.index_of(k))];
  return {0.5 * (L.min + L.max), std::max(0.5 * (L.max - L.min), 1e-9)};
}

/// The equations of a recording: every recorded value with its direction,
/// weight, run and the gains of every error name; with a fixed baseline its
/// prediction is already subtracted from deviation_um. Throws InputError for
/// rows the model cannot use.
Observations build_observations(const Machine& m, const Recordings& rec, const ExplainOptions& opt);

}  // namespace volmap::explanation
