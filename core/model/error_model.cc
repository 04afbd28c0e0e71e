#include "core/model/error_model.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "core/common/trig.h"
#include "core/model/small_rotation.h"

namespace volmap {
namespace {

using small_rotation_detail::small_rotation_into;

inline Eigen::Vector3d to_vec(const std::array<double, 6>& e, int first) {
  return {e[static_cast<size_t>(first)], e[static_cast<size_t>(first + 1)],
          e[static_cast<size_t>(first + 2)]};
}

// Nominal location frames T_b_F (F = frame after Trans(offset), before the
// location errors and motion) of every joint of a chain, and the chain end.
void nominal_location_frames(const std::vector<Joint>& chain, const AxisVector& u,
                             std::vector<Eigen::Isometry3d>& T_b_F, Eigen::Isometry3d& T_b_end) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T_b_F.clear();
  for (const Joint& j : chain) {
    T.translate(j.offset_parent_mm);
    T_b_F.push_back(T);
    const double q = u[j.index];
    if (j.rotary)
      T.rotate(axis_rotation(j.direction_parent, q));
    else
      T.translate(q * j.direction_parent);
  }
  T_b_end = T;
}

}  // namespace

Eigen::Matrix3d small_rotation_exact(const Eigen::Vector3d& eps_rad) {
  Eigen::Matrix3d R;
  small_rotation_into(eps_rad, R);
  return R;
}

ErrorModel::ErrorModel(Machine machine, ErrorSet errors, ModelOptions options)
    : machine_(std::move(machine)), errors_(std::move(errors)), options_(options) {
  prepare_lookup(errors_);
  // Every axis the errors name must be an axis of the machine.
  for (int a = 0; a < kAxisNameCount; ++a) {
    if (errors_.axis[static_cast<size_t>(a)] && !machine_.index_of(static_cast<AxisName>(a)))
      throw std::invalid_argument(
          fmt::format("{}: the errors give axis {}, which machine \"{}\" does not have",
                      errors_.file, axis_char(static_cast<AxisName>(a)), machine_.name));
  }
  for (const auto& [name, value] : errors_.location) {
    const std::optional<ErrorName> n = parse_error_name(name);
    if (!n || !machine_.index_of(n->axis))
      throw std::invalid_argument(
          fmt::format("{}: location error {} names an axis that machine \"{}\" does not have",
                      errors_.file, name, machine_.name));
  }

  // The measurement levers use the tool of the measurement.
  const double measured_tool_mm = std::isnan(machine_.measurement_tool_length_mm)
                                      ? machine_.tool_length_mm
                                      : machine_.measurement_tool_length_mm;
  const Eigen::Vector3d tip_s = -measured_tool_mm * machine_.tool_axis;
  auto bind = [&](const std::vector<Joint>& chain, ChainSide side, std::vector<BoundJoint>& out) {
    for (const Joint& j : chain) {
      BoundJoint bj;
      bj.joint = &j;
      bj.side = side;
      bj.components = errors_.errors_of(j.axis);
      for (int c = 0; c < kComponentCount; ++c) {
        ErrorName n{static_cast<Component>(c), j.axis, true};
        const double v = errors_.location_error(error_name_string(n));
        if (c < 3)
          bj.location.delta_mm[c] = v;
        else
          bj.location.eps_rad[c - 3] = v;
      }
      bj.independent = options_.formulation == Formulation::kIndependent && !j.rotary;
      out.push_back(bj);
    }
  };
  // Bind against the stored machine_ (the joints must outlive the model).
  bind(machine_.workpiece_chain, ChainSide::kWorkpiece, workpiece_);
  bind(machine_.tool_chain, ChainSide::kTool, tool_);
  all_linear_ = workpiece_.size() + tool_.size() <= 6;
  for (const auto* chain : {&workpiece_, &tool_})
    for (const BoundJoint& bj : *chain) all_linear_ = all_linear_ && !bj.joint->rotary;

  // Measurement levers of the independent formulation.
  std::vector<Eigen::Isometry3d> frames;
  Eigen::Isometry3d T_end;
  auto levers = [&](std::vector<BoundJoint>& chain, const std::vector<Joint>& joints) {
    for (size_t k = 0; k < chain.size(); ++k) {
      BoundJoint& bj = chain[k];
      if (!bj.independent) continue;
      AxisVector pose = machine_.measured_at[static_cast<size_t>(bj.joint->index)];
      pose[bj.joint->index] = 0.0;
      const Eigen::Isometry3d T_b_s = nominal_base_to_spindle(machine_, pose);
      const Eigen::Vector3d tip_b = T_b_s * tip_s;
      nominal_location_frames(joints, pose, frames, T_end);
      bj.r_meas_mm = frames[k].inverse(Eigen::Isometry) * tip_b;
    }
  };
  levers(workpiece_, machine_.workpiece_chain);
  levers(tool_, machine_.tool_chain);

  // Constant part of each joint: Trans(offset) * L (exact), with the
  // independent pivot folded into L's translation; and ISO 230-1's P.
  const bool iso = errors_.convention == LocationConvention::kIso230;
  for (auto* chain : {&workpiece_, &tool_})
    for (BoundJoint& bj : *chain) set_location_frames(bj, iso);

  // tip_error_linear's flat plan: the same numbers, copied.
  if (all_linear_) {
    const Eigen::Vector3d start =
        machine_.spindle_offset_mm - machine_.tool_length_mm * machine_.tool_axis;
    for (int i = 0; i < 3; ++i) {
      linear_start_mm_[i] = start[i];
      linear_origin_mm_[i] = machine_.workpiece_origin_mm[i];
    }
    int k = 0;
    for (const auto* chain : {&workpiece_, &tool_}) {
      for (const BoundJoint& bj : *chain) {
        LinearJoint& J = linear_[static_cast<size_t>(k++)];
        J.components = bj.components;
        J.index = bj.joint->index;
        J.workpiece = bj.side == ChainSide::kWorkpiece;
        J.independent = bj.independent;
        J.has_location_rotation = bj.has_location_rotation;
        J.conjugated = bj.conjugated;
        for (int i = 0; i < 3; ++i) {
          J.direction[i] = bj.joint->direction_parent[i];
          J.offset_mm[i] = bj.joint->offset_parent_mm[i];
          J.t_loc_mm[i] = bj.t_parent_loc_mm[i];
          J.r_meas_mm[i] = bj.r_meas_mm[i];
          J.t_P_mm[i] = bj.t_P_mm[i];
          for (int j = 0; j < 3; ++j) J.R_loc[i][j] = bj.R_parent_loc(i, j);
          J.R_loc_col01[i][0] = bj.R_parent_loc(0, i);
          J.R_loc_col01[i][1] = bj.R_parent_loc(1, i);
          J.r_meas_pair[i][0] = J.r_meas_pair[i][1] = bj.r_meas_mm[i];
        }
      }
    }
    linear_work_ = static_cast<int>(workpiece_.size());
    linear_count_ = k;
  }
}

void ErrorModel::set_location_frames(BoundJoint& bj, bool iso) {
  SmallTransform L = bj.location;
  Eigen::Matrix3d R_L = small_rotation_exact(L.eps_rad);
  const int own = bj.joint->rotary ? static_cast<int>(bj.joint->axis) - 3 : -1;
  if (iso && own >= 0) {
    // ISO 230-1: P places the axis line (offsets and tilts), the zero error
    // turns about the actual line: L = P Rot(e_own, zero).
    Eigen::Vector3d eps_line = L.eps_rad;
    eps_line[own] = 0.0;
    bj.R_P = small_rotation_exact(eps_line);
    R_L = bj.R_P * axis_rotation(Eigen::Vector3d::Unit(own), L.eps_rad[own]);
  }
  if (bj.independent) L.delta_mm -= (R_L - Eigen::Matrix3d::Identity()) * bj.r_meas_mm;
  if (iso && own < 0) bj.R_P = R_L;  // a linear axis's P is its L
  bj.t_P_mm = L.delta_mm;
  bj.conjugated = iso && !(bj.R_P.isIdentity(0.0) && bj.t_P_mm.isZero(0.0));
  // Trans(offset) * L = [R_L | offset + delta_L]
  bj.R_parent_loc = R_L;
  bj.has_location_rotation = !L.eps_rad.isZero(0.0);
  if (bj.joint->rotary)
    for (int a = 0; a < 3; ++a)
      if (bj.joint->direction_parent == Eigen::Vector3d::Unit(a)) bj.coordinate_axis = a;
  bj.t_parent_loc_mm = bj.joint->offset_parent_mm + L.delta_mm;
}

Eigen::Vector3d ErrorModel::location_pivot_mm(AxisName axis) const {
  for (const auto* chain : {&workpiece_, &tool_})
    for (const BoundJoint& bj : *chain)
      if (bj.joint->axis == axis && bj.independent) return bj.r_meas_mm;
  return Eigen::Vector3d::Zero();
}

SmallTransform ErrorModel::component_errors(const BoundJoint& bj, double q, int dir) const {
  SmallTransform e;
  if (!bj.components) return e;
  std::array<double, kComponentCount> v;
  std::uint64_t clamped = 0;
  evaluate_axis(*bj.components, q, dir, options_.outside, v, &clamped);
  if (clamped) clamped_->fetch_add(clamped, std::memory_order_relaxed);
  e.delta_mm = to_vec(v, 0);
  e.eps_rad = to_vec(v, 3);
  return e;
}

namespace {
// A point (lane 0) and a direction (lane 1) carried through the chain
// together: c[i] = (p_i, q_i). One packed multiply serves both, and packed
// IEEE operations round exactly as the scalar ones, so results do not depend
// on the vector width (GCC/Clang vector extension; SSE2 on x86-64).
using v2d = double __attribute__((vector_size(16)));
struct PointDir {
  v2d c[3];
  PointDir(const Eigen::Vector3d& p, const Eigen::Vector3d& q)
      : c{v2d{p.x(), q.x()}, v2d{p.y(), q.y()}, v2d{p.z(), q.z()}} {}
  Eigen::Vector3d point() const { return {c[0][0], c[1][0], c[2][0]}; }
  Eigen::Vector3d direction() const { return {c[0][1], c[1][1], c[2][1]}; }
  // p <- R p, q <- R q (sums in the column order of Eigen's product).
  [[gnu::always_inline]] void rotate(const Eigen::Matrix3d& R) {
    const v2d a = c[0], b = c[1], d = c[2];
    for (int i = 0; i < 3; ++i) c[i] = R(i, 0) * a + R(i, 1) * b + R(i, 2) * d;
  }
  // p <- R^T p, q <- R^T q.
  [[gnu::always_inline]] void rotate_transposed(const Eigen::Matrix3d& R) {
    const v2d a = c[0], b = c[1], d = c[2];
    for (int i = 0; i < 3; ++i) c[i] = R(0, i) * a + R(1, i) * b + R(2, i) * d;
  }
  // p <- p + t; the direction takes + (-0.0) and - (+0.0), the exact
  // identities of IEEE arithmetic (signed zeros included), so both lanes stay
  // in one register.
  [[gnu::always_inline]] void translate(const Eigen::Vector3d& t) {
    for (int i = 0; i < 3; ++i) c[i] += v2d{t[i], -0.0};
  }
  [[gnu::always_inline]] void translate_back(const Eigen::Vector3d& t) {
    for (int i = 0; i < 3; ++i) c[i] -= v2d{t[i], 0.0};
  }
};

// Rotation about a rotary joint's line by an angle: a plane rotation when
// the line is a coordinate axis (two coordinates mix), else the matrix.
class AxisTurn {
 public:
  AxisTurn(int coordinate_axis, const Eigen::Vector3d& d, double angle_rad)
      : axis_(coordinate_axis), i_((coordinate_axis + 1) % 3), k_((coordinate_axis + 2) % 3) {
    sincos_axis(angle_rad, s_, c_);
    if (axis_ < 0) R_ = axis_rotation(d, angle_rad);
  }
  [[gnu::always_inline]] void apply(PointDir& v) const {
    if (axis_ < 0) {
      v.rotate(R_);
      return;
    }
    const v2d vi = v.c[i_], vk = v.c[k_];
    v.c[i_] = c_ * vi - s_ * vk;
    v.c[k_] = s_ * vi + c_ * vk;
  }

 private:
  int axis_, i_, k_;  // the turn mixes coordinates i_ and k_
  double c_ = 1, s_ = 0;
  Eigen::Matrix3d R_;
};
}  // namespace

[[gnu::always_inline]] inline void ErrorModel::joint_error(const BoundJoint& bj, double q, int dir,
                                                           Eigen::Matrix3d& R,
                                                           Eigen::Vector3d& delta,
                                                           std::uint64_t& clamped) const {
  if (!bj.components) {
    R.setIdentity();
    delta.setZero();
    return;
  }
  std::array<double, kComponentCount> v;
  evaluate_axis(*bj.components, q, dir, options_.outside, v, &clamped);
  small_rotation_into(Eigen::Vector3d(v[3], v[4], v[5]), R);
  delta = Eigen::Vector3d(v[0], v[1], v[2]);
  if (bj.independent) {
    const Eigen::Vector3d r = bj.side == ChainSide::kWorkpiece
                                  ? Eigen::Vector3d(bj.r_meas_mm - q * bj.joint->direction_parent)
                                  : bj.r_meas_mm;
    delta -= R * r - r;
  }
}

// The exact model as point and direction transformations, never matrix
// products: the tool tip and tool axis are carried from the spindle down the
// tool chain to the base (p_b = T_b_s p_s), then up the workpiece chain into
// the workpiece frame (p_w = T_w_b p_b, applying each joint's inverse). This
// is the same product of HTMs as eq. (7) of Lei & Hsu, evaluated right to
// left on two vectors: a third of the work of 4x4 products. The nominal pose
// is carried along in the same pass, sharing the rotary axes' sin and cos.
void ErrorModel::evaluate(const AxisVector& u, const ApproachDirections& dir, ToolPose& actual_pose,
                          ToolPose& nominal_pose) const {
  // Phase 1: every joint's error transform E = [R_e | delta_e], independent
  // of the others (the table lookups overlap in the pipeline instead of
  // waiting on the chain).
  constexpr int kMaxJoints = 6;
  std::array<Eigen::Matrix3d, kMaxJoints> R_e;
  std::array<Eigen::Vector3d, kMaxJoints> delta_e;
  const int n_work = static_cast<int>(workpiece_.size());
  const int n_tool = static_cast<int>(tool_.size());
  std::uint64_t clamped = 0;
  for (int k = 0; k < n_work + n_tool; ++k) {
    const BoundJoint& bj =
        k < n_work ? workpiece_[static_cast<size_t>(k)] : tool_[static_cast<size_t>(k - n_work)];
    const int i = bj.joint->index;
    joint_error(bj, u[i], dir[static_cast<size_t>(i)], R_e[static_cast<size_t>(k)],
                delta_e[static_cast<size_t>(k)], clamped);
  }
  if (clamped) clamped_->fetch_add(clamped, std::memory_order_relaxed);

  // Phase 2: tool chain, spindle to base: p <- T_parent_j p.
  PointDir a(machine_.spindle_offset_mm - machine_.tool_length_mm * machine_.tool_axis,
             machine_.tool_axis);
  PointDir n = a;
  for (int k = n_tool - 1; k >= 0; --k) {
    const BoundJoint& bj = tool_[static_cast<size_t>(k)];
    const Joint& j = *bj.joint;
    const double q = u[j.index];
    const Eigen::Matrix3d& R = R_e[static_cast<size_t>(n_work + k)];
    const Eigen::Vector3d& delta = delta_e[static_cast<size_t>(n_work + k)];
    if (bj.conjugated) {  // ISO 230-1: P^-1 first
      a.translate_back(bj.t_P_mm);
      a.rotate_transposed(bj.R_P);
    }
    if (j.rotary) {
      const AxisTurn turn(bj.coordinate_axis, j.direction_parent, q);
      turn.apply(n);
      turn.apply(a);
      a.rotate(R);  // E(q) Rot(d, q)
      a.translate(delta);
    } else {
      n.translate(q * j.direction_parent);
      a.rotate(R);  // Trans(q d) E(q)
      a.translate(delta);
      a.translate(q * j.direction_parent);
    }
    n.translate(j.offset_parent_mm);
    if (bj.has_location_rotation) a.rotate(bj.R_parent_loc);
    a.translate(bj.t_parent_loc_mm);
  }
  // Phase 3: workpiece chain, base to workpiece: p <- T_parent_j^-1 p.
  for (int k = 0; k < n_work; ++k) {
    const BoundJoint& bj = workpiece_[static_cast<size_t>(k)];
    const Joint& j = *bj.joint;
    const double q = u[j.index];
    const Eigen::Matrix3d& R = R_e[static_cast<size_t>(k)];
    const Eigen::Vector3d& delta = delta_e[static_cast<size_t>(k)];
    n.translate_back(j.offset_parent_mm);
    a.translate_back(bj.t_parent_loc_mm);
    if (bj.has_location_rotation) a.rotate_transposed(bj.R_parent_loc);
    if (j.rotary) {
      const AxisTurn turn(bj.coordinate_axis, j.direction_parent, -q);
      a.translate_back(delta);
      a.rotate_transposed(R);
      turn.apply(n);
      turn.apply(a);
    } else {
      n.translate_back(q * j.direction_parent);
      a.translate_back(delta);
      a.translate_back(q * j.direction_parent);
      a.rotate_transposed(R);
    }
    if (bj.conjugated) {  // ISO 230-1: P last
      a.rotate(bj.R_P);
      a.translate(bj.t_P_mm);
    }
  }
  actual_pose.tip_mm = a.point() - machine_.workpiece_origin_mm;
  actual_pose.axis = a.direction();
  nominal_pose.tip_mm = n.point() - machine_.workpiece_origin_mm;
  nominal_pose.axis = n.direction();
}

ToolPose ErrorModel::actual(const AxisVector& u, const ApproachDirections& dir) const {
  ToolPose a, n;
  evaluate(u, dir, a, n);
  return a;
}

PoseError ErrorModel::exact(const AxisVector& u, const ApproachDirections& dir) const {
  ToolPose a, n;
  evaluate(u, dir, a, n);
  return PoseError{a.tip_mm - n.tip_mm, a.axis - n.axis};
}

void ErrorModel::levers(const AxisVector& u, std::vector<JointLever>& out) const {
  out.clear();
  const bool iso = errors_.convention == LocationConvention::kIso230;
  const Eigen::Isometry3d T_b_w = nominal_base_to_workpiece(machine_, u);
  const Eigen::Isometry3d T_b_s = nominal_base_to_spindle(machine_, u);
  const Eigen::Vector3d tip_b = T_b_s * (-machine_.tool_length_mm * machine_.tool_axis);
  const Eigen::Vector3d axis_b = T_b_s.linear() * machine_.tool_axis;
  const Eigen::Matrix3d R_w_b = T_b_w.linear().transpose();
  std::vector<Eigen::Isometry3d> frames;
  Eigen::Isometry3d T_end;
  auto add = [&](const std::vector<BoundJoint>& chain, const std::vector<Joint>& joints,
                 double sign) {
    nominal_location_frames(joints, u, frames, T_end);
    for (size_t k = 0; k < chain.size(); ++k) {
      const BoundJoint& bj = chain[k];
      const Joint& j = *bj.joint;
      const double q = u[j.index];
      const Eigen::Isometry3d T_L_b = frames[k].inverse(Eigen::Isometry);
      JointLever L{j.axis,
                   j.rotary,
                   sign,
                   R_w_b * frames[k].linear(),
                   T_L_b * tip_b,
                   Eigen::Vector3d::Zero(),
                   T_L_b.linear() * axis_b};
      // Component frame C: L moved by the linear motion, or L itself for a
      // rotary joint (its errors live in the non-rotating frame).
      L.lever_component_mm = L.lever_location_mm;
      if (!j.rotary) L.lever_component_mm -= q * j.direction_parent;
      if (bj.independent) {
        L.lever_location_mm -= bj.r_meas_mm;
        L.lever_component_mm -= bj.side == ChainSide::kWorkpiece
                                    ? Eigen::Vector3d(bj.r_meas_mm - q * j.direction_parent)
                                    : bj.r_meas_mm;
      }
      if (iso) {
        L.iso = true;
        if (j.rotary) {
          L.own = static_cast<int>(j.axis) - 3;
          L.R_M = axis_rotation(j.direction_parent, q);
        } else {
          // A squareness turns the motion alone: e' x t_M, whatever the pivot.
          L.t_M_mm = q * j.direction_parent;
          L.lever_location_mm = L.t_M_mm;
        }
      }
      out.push_back(L);
    }
  };
  add(workpiece_, machine_.workpiece_chain, -1.0);
  add(tool_, machine_.tool_chain, +1.0);
}

void ErrorModel::JointLever::location_gain(int c, Eigen::Vector3d& dP, Eigen::Vector3d& dQ) const {
  const Eigen::Vector3d e = Eigen::Vector3d::Unit(c % 3);
  const bool conjugate = iso && !(own >= 0 && c - 3 == own);
  if (c < 3) {
    dP = sign * (R_w_L * (conjugate ? Eigen::Vector3d(e - R_M * e) : e));
    dQ.setZero();
    return;
  }
  Eigen::Vector3d p = e.cross(lever_location_mm), a = e.cross(axis_L);
  if (conjugate) {
    const Eigen::Vector3d e_moved = R_M * e;
    p -= e_moved.cross(lever_location_mm - t_M_mm);
    a -= e_moved.cross(axis_L);
  }
  dP = sign * (R_w_L * p);
  dQ = sign * (R_w_L * a);
}

void ErrorModel::JointLever::gain(int c, bool location, Eigen::Vector3d& dP,
                                  Eigen::Vector3d& dQ) const {
  if (location) {
    location_gain(c, dP, dQ);
    return;
  }
  if (c < 3) {
    dP = sign * R_w_L.col(c);
    dQ.setZero();
    return;
  }
  const Eigen::Vector3d e = Eigen::Vector3d::Unit(c - 3);
  dP = sign * (R_w_L * e.cross(lever_component_mm));
  dQ = sign * (R_w_L * e.cross(axis_L));
}

PoseError ErrorModel::first_order(const AxisVector& u, const ApproachDirections& dir) const {
  std::vector<JointLever> lv;
  levers(u, lv);
  PoseError dv;
  size_t k = 0;
  for (const auto* chain : {&workpiece_, &tool_}) {
    for (const BoundJoint& bj : *chain) {
      const JointLever& L = lv[k++];
      const int i = bj.joint->index;
      const SmallTransform e = component_errors(bj, u[i], dir[static_cast<size_t>(i)]);
      const SmallTransform& loc = bj.location;
      dv.dP_mm += L.sign * L.R_w_L * (e.delta_mm + e.eps_rad.cross(L.lever_component_mm));
      dv.dQ += L.sign * L.R_w_L * e.eps_rad.cross(L.axis_L);
      for (int c = 0; c < kComponentCount; ++c) {
        const double value = c < 3 ? loc.delta_mm[c] : loc.eps_rad[c - 3];
        if (value == 0.0) continue;
        Eigen::Vector3d gP, gQ;
        L.location_gain(c, gP, gQ);
        dv.dP_mm += value * gP;
        dv.dQ += value * gQ;
      }
    }
  }
  return dv;
}

}  // namespace volmap
