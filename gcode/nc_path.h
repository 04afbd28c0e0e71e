// The nominal geometry of a motion: the point at path parameter s in [0, 1]
// (linear in length for lines and helices), and its length.
#pragma once

#include <Eigen/Core>

#include "gcode/nc_interpreter.h"

namespace volmap::nc {

/// Arc parameters in the motion's plane: start angle, signed sweep (rad,
/// negative clockwise, full turns included), radius, in-plane axis indices.
struct ArcGeometry {
  int a0 = 0, a1 = 1, normal = 2;
  double start_angle = 0, sweep = 0, radius = 0;
  double end_radius = 0;  ///< differs from radius within the reader's tolerance: a spiral
};
ArcGeometry arc_geometry(const Motion& m);

/// Point at s in [0, 1] of a line, arc or helix (machine coordinates, mm).
/// Canned cycles and rapids are straight lines from start to end here.
Eigen::Vector3d point_on(const Motion& m, double s);

double path_length_mm(const Motion& m);

/// LinuxCNC's rule for an arc's two radii (interp_arc.cc arc_data_ijk, in
/// program units, `inch` or mm): they may differ by
/// CENTER_ARC_RADIUS_TOLERANCE (0.02 sqrt 2 mm, 0.002 sqrt 2 inch, its
/// default), or by more if that is at most 0.1 % (SPIRAL_RELATIVE_TOLERANCE)
/// of the larger and at most 100 times the tolerance. `margin` (program
/// units) is taken off the allowance.
bool linuxcnc_accepts_radii(double r_start, double r_end, bool inch, double margin = 0.0);

/// Distance (mm) from p to the nearest point of the motion's path.
double distance_to_path(const Motion& m, const Eigen::Vector3d& p);

/// The unit tangent in the XY plane of motion m at its start or its end;
/// zero where m does not move in XY there.
Eigen::Vector2d xy_tangent(const Motion& m, bool at_end);

/// The turn (rad, 0 .. pi) from direction t_in to t_out in XY, and whether
/// it turns towards a tool on `side` (1 left, G41; 2 right, G42): an inside
/// corner of cutter compensation.
double xy_turn_rad(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out, int side,
                   bool& inside);

/// LinuxCNC's polar end point (interp_find.cc, find_ends), in program units
/// from the program origin, from where the tool stands (`at`, program units)
/// and the block's words (null: not given). G90: @ and ^ from the origin, a
/// missing one the standing point's own. G91: @ adds to the standing point's
/// radius, then ^ to its angle. (The reader refuses the indeterminate cases
/// before: gcode/block_motion.cc.) Both depend on where the controller
/// really stands under G91, or with one word under G90: the post writes a
/// polar block as it is only where this end, from its own output, is
/// within half an output unit.
Eigen::Vector2d polar_end(const Eigen::Vector2d& at, bool absolute, const double* radius,
                          const double* angle_deg);

/// LinuxCNC's interpreter goes round a corner of the offset path (an arc
/// outside, the offsets' intersection inside) only where the path turns by
/// more than this; below it the tool jumps from one offset to the next.
inline constexpr double kLinuxCncCornerTurnRad = 0.05;

}  // namespace volmap::nc
