// Measurement plans for `volmap simulate` (format "volmap-plan/1",
// docs/simulate.md): what an instrument would record on a machine, expanded
// into a sequence of planned observations.
//
// Tests: "laser" (a line along one linear axis, ISO 230-2 style, uni- or
// bidirectional, repeated cycles, optionally along a beam direction:
// projection form), "probe_ball" (sphere test: ball centres in workpiece
// coordinates, rotary angles listed or gridded, the linear axes from
// linear_axes_for_tip), "grid" (a grid of axis positions), "points"
// (listed axis positions). Each test may run at several feeds.
//
// Time: one clock for the whole plan. Each point costs its move (distance /
// feed when a feed is given, else move_s) and then dwell_s; the reading is
// taken at the end of the dwell. pause_s separates cycles.
// Approach direction: each axis keeps the direction of its last move (the
// side its drive's lost motion was taken up on); laser passes approach every
// target in the pass direction (an overrun before the pass, ISO 230-2).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "core/measure/recordings.h"
#include "core/model/error_model.h"
#include "core/model/machine.h"

namespace volmap {

/// One planned observation. Units: internal (mm, rad), seconds, mm/min.
struct PlannedPoint {
  AxisVector u;
  ApproachDirections dir{};
  double t_s = 0.0;
  int run = 0;               ///< 1-based run number (a cycle of a test at one feed)
  double feed_mm_min = 0.0;  ///< 0 when the test gives no feed
  /// Unit direction of the last linear move, in linear-axis coordinates
  /// (X, Y, Z axis values); zero before the first move.
  Eigen::Vector3d move_direction = Eigen::Vector3d::Zero();
  /// How far each linear axis (X, Y, Z) has moved since its motion last
  /// reversed, mm; infinite before its first reversal.
  Eigen::Vector3d since_reversal_mm = Eigen::Vector3d::Constant(INFINITY);
  std::uint8_t record_mask = 0;                    ///< bit c: component c (ex, ey, ez) recorded
  bool projection = false;                         ///< recorded along `beam` (e_um) instead
  Eigen::Vector3d beam = Eigen::Vector3d::Zero();  ///< unit, recording frame
};

/// A temperature sensor the plan records: T(t) = start_c + rise_c (1 -
/// exp(-t / tau_s)) + rate_c_per_h t / 3600 (tau_s = 0: no settling term).
struct PlannedTemperature {
  std::string sensor;  ///< column temp_<sensor>_c
  double start_c = 20.0, rise_c = 0.0, tau_s = 0.0, rate_c_per_h = 0.0;
  double at(double t_s) const;
};

struct Plan {
  std::string file;
  std::uint64_t seed = 1;
  double noise_um = 0.0;  ///< standard deviation of the reading noise
  RecordingFrame frame = RecordingFrame::kWorkpiece;
  std::optional<PlannedTemperature> temperature;
  bool any_feed = false;
  bool any_projection = false;
  std::uint8_t record_union = 0;  ///< components recorded anywhere
  std::vector<PlannedPoint> points;
};

/// Reads and expands a plan for machine m. Throws InputError naming the
/// file and JSON path (or line:column for malformed JSON), including for
/// points outside the machine's travel.
Plan read_plan_json(std::istream& in, const std::string& file, const Machine& m);
Plan load_plan_json(const std::string& path, const Machine& m);

}  // namespace volmap
