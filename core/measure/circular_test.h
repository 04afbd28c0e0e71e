// The path of a circular test (ISO 230-4; the telescoping ballbar): two
// linear axes interpolate a circle about a centre, one run per direction,
// a lead-in overshoot arc before the data-capture arc of 360° and a
// lead-out arc after it (no readings on either), a reading every step. The
// instrument records the radial deviation: the projection form of
// recordings.md with the radial unit vector as the beam.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/model/machine.h"

namespace volmap {

struct CircularTestPath {
  AxisName first = AxisName::X, second = AxisName::Y;  ///< first -> second turns counter-clockwise
  AxisVector centre;  ///< machine positions at the centre (internal units)
  double radius_mm = 100;
  double start_deg = 0;       ///< angle of the first reading, from `first` towards `second`
  double step_deg = 1;        ///< between readings
  double overshoot_deg = 90;  ///< lead-in and lead-out arcs
};

/// One stop on the path: where the axes are, the radial unit vector
/// (workpiece frame), whether a reading is taken there, and its angle.
struct CircularStop {
  AxisVector u;
  Eigen::Vector3d radial = Eigen::Vector3d::Zero();  ///< of the tool tip, workpiece frame
  bool capture = false;
  double angle_deg = 0;
};

/// The stops of one run in one direction (counter-clockwise: the angle
/// rises). Throws std::invalid_argument for a radius or step <= 0, a step
/// above 90°, or an overshoot outside 0..360°.
std::vector<CircularStop> circular_run(const Machine& m, const CircularTestPath& p,
                                       bool counter_clockwise);

}  // namespace volmap
