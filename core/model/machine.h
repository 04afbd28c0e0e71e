// The nominal geometry of a serial machine tool.
//
// Frames: b is the machine base (reference frame). The workpiece chain runs
// from b to the workpiece frame w, the tool chain from b to the spindle frame
// s; the tool tip t hangs off s. ISO 10791 writes such a machine as
// [w C' A' X' Y' b Z t]: read from w to b, the primed axes carry the workpiece.
//
// A chain is a list of joints, base first. Joint j's frame, nominally:
//   T_parent_j(q) = Trans(offset_mm) * M(q),
//   M(q) = Trans(q * direction)        (linear, q in mm)
//   M(q) = Rot(direction, q)           (rotary, q in rad, right-handed)
// so the origin of a rotary joint's frame lies on its centre line.
//
// Units inside volmap: mm and rad. The machine file uses mm and degrees
// (docs/machine-format.md); conversion happens in machine_json.cc only.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/common/axis_name.h"

namespace volmap {

/// Axis positions in the machine's axis order (Machine::axis_order): mm for
/// linear, rad for rotary. At most six; no heap allocation.
using AxisVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 6, 1>;

struct Joint {
  AxisName axis = AxisName::X;
  bool rotary = false;
  Eigen::Vector3d direction_parent = Eigen::Vector3d::UnitX();  ///< unit
  Eigen::Vector3d offset_parent_mm = Eigen::Vector3d::Zero();
  int index = 0;  ///< position of this axis in AxisVector
};

struct AxisLimits {
  double min = 0.0, max = 0.0;  ///< mm or rad
  bool unlimited = false;       ///< continuous rotary axis
};

enum class ChainSide { kWorkpiece, kTool };

struct Machine {
  std::string name;
  std::string description;
  /// Axes in AxisVector order: canonical X Y Z A B C order of those present.
  std::vector<AxisName> axis_order;
  std::vector<AxisLimits> limits;      ///< by AxisVector index
  AxisVector home;                     ///< by AxisVector index
  std::vector<Joint> workpiece_chain;  ///< base first
  std::vector<Joint> tool_chain;       ///< base first
  /// Workpiece origin in the frame of the last workpiece-chain joint (or b).
  Eigen::Vector3d workpiece_origin_mm = Eigen::Vector3d::Zero();
  /// Spindle gauge point in the frame of the last tool-chain joint (or b).
  Eigen::Vector3d spindle_offset_mm = Eigen::Vector3d::Zero();
  /// Tool axis Q in the spindle frame: unit vector from the tip into the
  /// spindle (Lei & Hsu's Q). The tip is spindle - tool_length_mm * axis.
  Eigen::Vector3d tool_axis = Eigen::Vector3d::UnitZ();
  double tool_length_mm = 0.0;
  /// Tool length of the measurement (kinematic-parameter-independent model:
  /// the tool whose tip the laser saw). NaN: the same as tool_length_mm.
  /// Set when tool_length_mm is changed to model another tool.
  double measurement_tool_length_mm = std::numeric_limits<double>::quiet_NaN();
  /// Kinematic-parameter-independent model (Hsu, section III.B): for each
  /// linear axis, the positions of the other axes while its component errors
  /// were measured at the tool tip (by AxisVector index; own entry unused).
  std::vector<AxisVector> measured_at;

  int axis_count() const { return static_cast<int>(axis_order.size()); }
  std::optional<int> index_of(AxisName a) const;
  bool has_rotary_axes() const;
  /// "[w C' A' X' Y' b Z t]"
  std::string structure_code() const;
};

/// The tool pose in workpiece coordinates: tip P (mm) and axis Q (unit).
struct ToolPose {
  Eigen::Vector3d tip_mm;
  Eigen::Vector3d axis;
};

/// Nominal (error-free) forward transformation u -> v (Lei & Hsu eq. 2,
/// eqs. 8-9 with the [0 0 1 0] direction of erratum E-LH1).
ToolPose nominal_forward(const Machine& m, const AxisVector& u);

/// Nominal frames: T_b_w (workpiece) and T_b_s (spindle) at u.
Eigen::Isometry3d nominal_base_to_workpiece(const Machine& m, const AxisVector& u);
Eigen::Isometry3d nominal_base_to_spindle(const Machine& m, const AxisVector& u);

/// How far outside its travel an axis position may lie and still count as
/// inside (mm or rad): a limit reached up to rounding is inside.
inline constexpr double kTravelSlack = 1e-9;

/// The first of the machine's first `axes` axes whose position u[i] (mm or
/// rad, in axis_order) lies outside its travel, or -1 when none does.
inline int first_axis_outside_travel(const Machine& m, const double* u, int axes) {
  for (int i = 0; i < axes; ++i) {
    const AxisLimits& L = m.limits[static_cast<size_t>(i)];
    if (!L.unlimited && !(u[i] >= L.min - kTravelSlack && u[i] <= L.max + kTravelSlack)) return i;
  }
  return -1;
}

/// Throws std::invalid_argument naming the axis when u is outside travel.
void check_within_travel(const Machine& m, const AxisVector& u);

/// Rotation about unit axis d by angle (rad), right-handed.
Eigen::Matrix3d axis_rotation(const Eigen::Vector3d& d, double angle_rad);

}  // namespace volmap
