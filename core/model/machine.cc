#include "core/model/machine.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "core/common/trig.h"
#include "core/common/units.h"

namespace volmap {

std::optional<int> Machine::index_of(AxisName a) const {
  for (int i = 0; i < axis_count(); ++i)
    if (axis_order[static_cast<size_t>(i)] == a) return i;
  return std::nullopt;
}

bool Machine::has_rotary_axes() const {
  for (AxisName a : axis_order)
    if (is_rotary(a)) return true;
  return false;
}

std::string Machine::structure_code() const {
  std::string s = "[w";
  for (auto it = workpiece_chain.rbegin(); it != workpiece_chain.rend(); ++it) {
    s += ' ';
    s += axis_char(it->axis);
    s += '\'';
  }
  s += " b";
  for (const Joint& j : tool_chain) {
    s += ' ';
    s += axis_char(j.axis);
  }
  s += " t]";
  return s;
}

Eigen::Matrix3d axis_rotation(const Eigen::Vector3d& d, double angle_rad) {
  // Exact for the unit axes the machine files use; Rodrigues otherwise.
  double s, c;
  sincos_axis(angle_rad, s, c);
  Eigen::Matrix3d K;
  K << 0, -d.z(), d.y(), d.z(), 0, -d.x(), -d.y(), d.x(), 0;
  return Eigen::Matrix3d::Identity() * c + s * K + (1 - c) * d * d.transpose();
}

namespace {
Eigen::Isometry3d chain_pose(const std::vector<Joint>& chain, const AxisVector& u) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (const Joint& j : chain) {
    const double q = u[j.index];
    T.translate(j.offset_parent_mm);
    if (j.rotary)
      T.rotate(axis_rotation(j.direction_parent, q));
    else
      T.translate(q * j.direction_parent);
  }
  return T;
}
}  // namespace

Eigen::Isometry3d nominal_base_to_workpiece(const Machine& m, const AxisVector& u) {
  Eigen::Isometry3d T_b_w = chain_pose(m.workpiece_chain, u);
  T_b_w.translate(m.workpiece_origin_mm);
  return T_b_w;
}

Eigen::Isometry3d nominal_base_to_spindle(const Machine& m, const AxisVector& u) {
  Eigen::Isometry3d T_b_s = chain_pose(m.tool_chain, u);
  T_b_s.translate(m.spindle_offset_mm);
  return T_b_s;
}

ToolPose nominal_forward(const Machine& m, const AxisVector& u) {
  const Eigen::Isometry3d T_b_w = nominal_base_to_workpiece(m, u);
  const Eigen::Isometry3d T_b_s = nominal_base_to_spindle(m, u);
  const Eigen::Isometry3d T_w_s = T_b_w.inverse(Eigen::Isometry) * T_b_s;
  const Eigen::Vector3d tip_s = -m.tool_length_mm * m.tool_axis;
  return ToolPose{T_w_s * tip_s, T_w_s.linear() * m.tool_axis};
}

void check_within_travel(const Machine& m, const AxisVector& u) {
  const int i = first_axis_outside_travel(m, u.data(), m.axis_count());
  if (i < 0) return;
  const AxisLimits& L = m.limits[static_cast<size_t>(i)];
  const AxisName a = m.axis_order[static_cast<size_t>(i)];
  const double k = is_rotary(a) ? units::kDegPerRad : 1.0;
  const char* unit = is_rotary(a) ? "deg" : "mm";
  throw std::invalid_argument(fmt::format("{}={:g} {} is outside the travel {:g}..{:g} {}",
                                          axis_char(a), u[i] * k, unit, L.min * k, L.max * k,
                                          unit));
}

}  // namespace volmap
