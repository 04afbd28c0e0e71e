#include "core/kinematics/jacobian.h"

#include <array>
#include <cassert>
#include <stdexcept>

#include "core/common/trig.h"

namespace volmap {
namespace {

constexpr int kMaxJoints = 6;

// One joint's line at u, in base coordinates: direction d_b (unit) and a
// point c_b on it (the joint frame's origin), and the chain's sign.
struct JointLine {
  Eigen::Vector3d d_b;
  Eigen::Vector3d c_b;
  double sign;
  int index;
  bool rotary;
};

// R <- R Rot(d, q): a plane rotation of two columns when d is a coordinate
// axis (the usual case), Rodrigues otherwise. Deterministic sine and cosine.
inline void post_rotate(Eigen::Matrix3d& R, const Eigen::Vector3d& d, double q) {
  int a = -1;
  for (int k = 0; k < 3; ++k)
    if (d[k] == 1.0) a = k;
  if (a < 0) {
    R = R * axis_rotation(d, q);
    return;
  }
  double s, c;
  sincos_axis(q, s, c);
  const int i = (a + 1) % 3, k = (a + 2) % 3;  // Rot_a mixes columns i and k
  const Eigen::Vector3d ci = R.col(i), ck = R.col(k);
  R.col(i) = c * ci + s * ck;
  R.col(k) = c * ck - s * ci;
}

// Walks a chain base first: T_b <- T_b Trans(offset) M(q). Records each
// joint's line; leaves R_b_end, t_b_end as the chain end's pose.
void walk(const std::vector<Joint>& chain, const AxisVector& u, double sign,
          std::array<JointLine, kMaxJoints>& lines, int& n, Eigen::Matrix3d& R_b_end,
          Eigen::Vector3d& t_b_end_mm) {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  bool identity = true;  // R is still I: skip the products
  for (const Joint& j : chain) {
    assert(n < kMaxJoints);
    JointLine& L = lines[static_cast<size_t>(n++)];
    if (identity) {
      t += j.offset_parent_mm;
      L.d_b = j.direction_parent;
    } else {
      t += R * j.offset_parent_mm;
      L.d_b = R * j.direction_parent;
    }
    L.c_b = t;
    L.sign = sign;
    L.index = j.index;
    L.rotary = j.rotary;
    const double q = u[j.index];
    if (j.rotary) {
      post_rotate(R, j.direction_parent, q);
      identity = false;
    } else {
      t += q * L.d_b;
    }
  }
  R_b_end = R;
  t_b_end_mm = t;
}

}  // namespace

namespace {

// Both chains walked at one axis position.
struct MachineWalk {
  std::array<JointLine, kMaxJoints> lines;
  int n = 0;
  Eigen::Matrix3d R_b_w, R_b_s;
  Eigen::Vector3d t_b_w, t_b_s;
};

void walk_machine(const Machine& m, const AxisVector& u, MachineWalk& w) {
  w.n = 0;
  walk(m.workpiece_chain, u, -1.0, w.lines, w.n, w.R_b_w, w.t_b_w);
  walk(m.tool_chain, u, +1.0, w.lines, w.n, w.R_b_s, w.t_b_s);
}

// The pose and the Jacobian from a walk.
ToolPose pose_and_jacobian(const Machine& m, const MachineWalk& w, PoseJacobian& J_v_u,
                           bool rotary_columns) {
  const Eigen::Vector3d t_b_w = w.t_b_w + w.R_b_w * m.workpiece_origin_mm;
  const Eigen::Vector3d t_b_s = w.t_b_s + w.R_b_s * m.spindle_offset_mm;
  const Eigen::Vector3d tip_b = t_b_s - m.tool_length_mm * (w.R_b_s * m.tool_axis);
  const Eigen::Vector3d axis_b = w.R_b_s * m.tool_axis;
  const Eigen::Matrix3d R_w_b = w.R_b_w.transpose();
  ToolPose v{R_w_b * (tip_b - t_b_w), R_w_b * axis_b};

  J_v_u.resize(6, m.axis_count());
  J_v_u.setZero();
  for (int k = 0; k < w.n; ++k) {
    const JointLine& L = w.lines[static_cast<size_t>(k)];
    const Eigen::Vector3d d_w = R_w_b * L.d_b;
    if (!L.rotary) {
      J_v_u.block<3, 1>(0, L.index) = L.sign * d_w;
    } else if (rotary_columns) {
      const Eigen::Vector3d c_w = R_w_b * (L.c_b - t_b_w);
      J_v_u.block<3, 1>(0, L.index) = L.sign * d_w.cross(v.tip_mm - c_w);
      J_v_u.block<3, 1>(3, L.index) = L.sign * d_w.cross(v.axis);
    }
  }
  return v;
}

}  // namespace

ToolPose nominal_forward_jacobian(const Machine& m, const AxisVector& u, PoseJacobian& J_v_u,
                                  bool rotary_columns) {
  MachineWalk w;
  walk_machine(m, u, w);
  return pose_and_jacobian(m, w, J_v_u, rotary_columns);
}

ToolPose nominal_place_tip(const Machine& m, AxisVector& u, const Eigen::Vector3d& tip_w_mm,
                           PoseJacobian* J_v_u) {
  MachineWalk w;
  walk_machine(m, u, w);
  // The tip and the linear axes' columns of J (as pose_and_jacobian).
  const Eigen::Matrix3d R_w_b = w.R_b_w.transpose();
  const Eigen::Vector3d t_b_w = w.t_b_w + w.R_b_w * m.workpiece_origin_mm;
  const Eigen::Vector3d tip_b =
      w.t_b_s + w.R_b_s * m.spindle_offset_mm - m.tool_length_mm * (w.R_b_s * m.tool_axis);
  const ToolPose v{R_w_b * (tip_b - t_b_w), R_w_b * (w.R_b_s * m.tool_axis)};
  std::array<int, 3> lin{};
  Eigen::Matrix3d Jl;
  int n_lin = 0;
  for (int k = 0; k < w.n; ++k) {
    const JointLine& L = w.lines[static_cast<size_t>(k)];
    if (L.rotary) continue;
    if (n_lin == 3)
      throw std::invalid_argument("placing the tool tip needs exactly three linear axes");
    lin[static_cast<size_t>(n_lin)] = L.index;
    Jl.col(n_lin++) = L.sign * (R_w_b * L.d_b);
  }
  if (n_lin != 3)
    throw std::invalid_argument("placing the tool tip needs exactly three linear axes");
  // The tip is affine in the linear axes: one Newton step is exact.
  const Eigen::Vector3d dl = Jl.inverse() * (tip_w_mm - v.tip_mm);
  AxisVector step = AxisVector::Zero(m.axis_count());
  for (int k = 0; k < 3; ++k) step[lin[static_cast<size_t>(k)]] = dl[k];
  for (int k = 0; k < 3; ++k) u[lin[static_cast<size_t>(k)]] += dl[k];
  if (J_v_u == nullptr) {
    ToolPose placed = v;
    placed.tip_mm = tip_w_mm;
    return placed;
  }
  // The linear joints translate what follows them in their chain and turn
  // nothing: shift the recorded lines and chain ends instead of walking again.
  Eigen::Vector3d shift_w = Eigen::Vector3d::Zero(), shift_s = Eigen::Vector3d::Zero();
  for (int k = 0; k < w.n; ++k) {
    JointLine& L = w.lines[static_cast<size_t>(k)];
    Eigen::Vector3d& shift = L.sign < 0 ? shift_w : shift_s;
    L.c_b += shift;
    if (!L.rotary) shift += step[L.index] * L.d_b;
  }
  w.t_b_w += shift_w;
  w.t_b_s += shift_s;
  return pose_and_jacobian(m, w, *J_v_u, /*rotary_columns=*/true);
}

PoseJacobian nominal_jacobian(const Machine& m, const AxisVector& u) {
  PoseJacobian J;
  nominal_forward_jacobian(m, u, J);
  return J;
}

}  // namespace volmap
