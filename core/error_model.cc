#include "core/error_model.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace volmap {
namespace {

// sin and cos of a small angle: Taylor series to beyond double precision for
// |x| < 1e-2 (next term x^9/9! < 3e-24), std::sin/cos otherwise.
inline void small_sincos(double x, double& s, double& c) {
  if (std::abs(x) < 1e-2) {
    const double x2 = x * x;
    s = x * (1 - x2 / 6 * (1 - x2 / 20 * (1 - x2 / 42)));
    c = 1 - x2 / 2 * (1 - x2 / 12 * (1 - x2 / 30 * (1 - x2 / 56)));
  } else {
    s = std::sin(x);
    c = std::cos(x);
  }
}

inline Eigen::Vector3d to_vec(const std::array<double, 6>& e, int first) {
  return {e[static_cast<size_t>(first)], e[static_cast<size_t>(first + 1)],
          e[static_cast<size_t>(first + 2)]};
}

inline Eigen::Isometry3d small_transform_exact(const SmallTransform& e) {
  Eigen::Isometry3d T;
  T.linear() = small_rotation_exact(e.eps_rad);
  T.translation() = e.delta_mm;
  T.makeAffine();
  return T;
}

// Nominal location frames T_b_F (F = frame after Trans(offset), before the
// location errors and motion) of every joint of a chain, and the chain end.
void nominal_location_frames(const std::vector<Joint>& chain,
                             const AxisVector& u,
                             std::vector<Eigen::Isometry3d>& T_b_F,
                             Eigen::Isometry3d& T_b_end) {
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
  double sa, ca, sb, cb, sc, cc;
  small_sincos(eps_rad.x(), sa, ca);
  small_sincos(eps_rad.y(), sb, cb);
  small_sincos(eps_rad.z(), sc, cc);
  // Rz(c) * Ry(b) * Rx(a)
  Eigen::Matrix3d R;
  R << cc * cb, cc * sb * sa - sc * ca, cc * sb * ca + sc * sa,  //
      sc * cb, sc * sb * sa + cc * ca, sc * sb * ca - cc * sa,   //
      -sb, cb * sa, cb * ca;
  return R;
}

ErrorModel::ErrorModel(Machine machine, ErrorSet errors, ModelOptions options)
    : machine_(std::move(machine)),
      errors_(std::move(errors)),
      options_(options) {
  // Every axis the errors name must be an axis of the machine.
  for (int a = 0; a < kAxisNameCount; ++a) {
    if (errors_.axis[static_cast<size_t>(a)] &&
        !machine_.index_of(static_cast<AxisName>(a)))
      throw std::invalid_argument(fmt::format(
          "{}: the errors give axis {}, which machine \"{}\" does not have",
          errors_.file, axis_char(static_cast<AxisName>(a)), machine_.name));
  }
  for (const auto& [name, value] : errors_.location) {
    const std::optional<ErrorName> n = parse_error_name(name);
    if (!n || !machine_.index_of(n->axis))
      throw std::invalid_argument(fmt::format(
          "{}: location error {} names an axis that machine \"{}\" does not have",
          errors_.file, name, machine_.name));
  }

  const Eigen::Vector3d tip_s = -machine_.tool_length_mm * machine_.tool_axis;
  auto bind = [&](const std::vector<Joint>& chain, ChainSide side,
                  std::vector<BoundJoint>& out) {
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
      bj.independent =
          options_.formulation == Formulation::kIndependent && !j.rotary;
      out.push_back(bj);
    }
  };
  // Bind against the stored machine_ (the joints must outlive the model).
  bind(machine_.workpiece_chain, ChainSide::kWorkpiece, workpiece_);
  bind(machine_.tool_chain, ChainSide::kTool, tool_);

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
  // independent pivot folded into L's translation.
  for (auto* chain : {&workpiece_, &tool_}) {
    for (BoundJoint& bj : *chain) {
      SmallTransform L = bj.location;
      const Eigen::Matrix3d R_L = small_rotation_exact(L.eps_rad);
      if (bj.independent)
        L.delta_mm -= (R_L - Eigen::Matrix3d::Identity()) * bj.r_meas_mm;
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.translate(bj.joint->offset_parent_mm);
      T = T * small_transform_exact(L);
      bj.T_parent_loc = T;
    }
  }
}

SmallTransform ErrorModel::component_errors(const BoundJoint& bj, double q,
                                            int dir) const {
  SmallTransform e;
  if (!bj.components) return e;
  std::array<double, kComponentCount> v;
  std::uint64_t clamped = 0;
  try {
    evaluate_axis(*bj.components, q, dir, options_.outside, v, &clamped);
  } catch (const std::out_of_range& ex) {
    throw std::out_of_range(ex.what());
  }
  if (clamped) clamped_->fetch_add(clamped, std::memory_order_relaxed);
  e.delta_mm = to_vec(v, 0);
  e.eps_rad = to_vec(v, 3);
  return e;
}

Eigen::Isometry3d ErrorModel::chain_actual(const std::vector<BoundJoint>& chain,
                                           const AxisVector& u,
                                           const ApproachDirections& dir) const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (const BoundJoint& bj : chain) {
    const Joint& j = *bj.joint;
    const double q = u[j.index];
    T = T * bj.T_parent_loc;
    SmallTransform e = component_errors(bj, q, dir[static_cast<size_t>(j.index)]);
    const Eigen::Matrix3d R_e = small_rotation_exact(e.eps_rad);
    if (bj.independent) {
      const Eigen::Vector3d r = bj.side == ChainSide::kWorkpiece
                                    ? Eigen::Vector3d(bj.r_meas_mm - q * j.direction_parent)
                                    : bj.r_meas_mm;
      e.delta_mm -= (R_e - Eigen::Matrix3d::Identity()) * r;
    }
    if (j.rotary) {
      // E(q) * Rot(d, q)
      T.translation() += T.linear() * e.delta_mm;
      T.linear() = T.linear() * (R_e * axis_rotation(j.direction_parent, q));
    } else {
      // Trans(q d) * E(q)
      T.translation() += T.linear() * (q * j.direction_parent + e.delta_mm);
      T.linear() = T.linear() * R_e;
    }
  }
  return T;
}

ToolPose ErrorModel::actual(const AxisVector& u,
                            const ApproachDirections& dir) const {
  Eigen::Isometry3d T_b_w = chain_actual(workpiece_, u, dir);
  T_b_w.translate(machine_.workpiece_origin_mm);
  Eigen::Isometry3d T_b_s = chain_actual(tool_, u, dir);
  T_b_s.translate(machine_.spindle_offset_mm);
  const Eigen::Isometry3d T_w_s = T_b_w.inverse(Eigen::Isometry) * T_b_s;
  const Eigen::Vector3d tip_s = -machine_.tool_length_mm * machine_.tool_axis;
  return ToolPose{T_w_s * tip_s, T_w_s.linear() * machine_.tool_axis};
}

PoseError ErrorModel::exact(const AxisVector& u,
                            const ApproachDirections& dir) const {
  const ToolPose a = actual(u, dir);
  const ToolPose n = nominal_forward(machine_, u);
  return PoseError{a.tip_mm - n.tip_mm, a.axis - n.axis};
}

void ErrorModel::levers(const AxisVector& u, std::vector<JointLever>& out) const {
  out.clear();
  const Eigen::Isometry3d T_b_w = nominal_base_to_workpiece(machine_, u);
  const Eigen::Isometry3d T_b_s = nominal_base_to_spindle(machine_, u);
  const Eigen::Vector3d tip_b =
      T_b_s * (-machine_.tool_length_mm * machine_.tool_axis);
  const Eigen::Vector3d axis_b = T_b_s.linear() * machine_.tool_axis;
  const Eigen::Matrix3d R_w_b = T_b_w.linear().transpose();
  std::vector<Eigen::Isometry3d> frames;
  Eigen::Isometry3d T_end;
  auto add = [&](const std::vector<BoundJoint>& chain,
                 const std::vector<Joint>& joints, double sign) {
    nominal_location_frames(joints, u, frames, T_end);
    for (size_t k = 0; k < chain.size(); ++k) {
      const BoundJoint& bj = chain[k];
      const Joint& j = *bj.joint;
      const double q = u[j.index];
      const Eigen::Isometry3d T_L_b = frames[k].inverse(Eigen::Isometry);
      JointLever L{j.axis, j.rotary, sign, R_w_b * frames[k].linear(),
                   T_L_b * tip_b, Eigen::Vector3d::Zero(),
                   T_L_b.linear() * axis_b};
      // Component frame C: L moved by the linear motion, or L itself for a
      // rotary joint (its errors live in the non-rotating frame).
      L.lever_component_mm = L.lever_location_mm;
      if (!j.rotary) L.lever_component_mm -= q * j.direction_parent;
      if (bj.independent) {
        L.lever_location_mm -= bj.r_meas_mm;
        L.lever_component_mm -=
            bj.side == ChainSide::kWorkpiece
                ? Eigen::Vector3d(bj.r_meas_mm - q * j.direction_parent)
                : bj.r_meas_mm;
      }
      out.push_back(L);
    }
  };
  add(workpiece_, machine_.workpiece_chain, -1.0);
  add(tool_, machine_.tool_chain, +1.0);
}

PoseError ErrorModel::first_order(const AxisVector& u,
                                  const ApproachDirections& dir) const {
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
      dv.dP_mm += L.sign * L.R_w_L *
                  (loc.delta_mm + loc.eps_rad.cross(L.lever_location_mm) +
                   e.delta_mm + e.eps_rad.cross(L.lever_component_mm));
      dv.dQ += L.sign * L.R_w_L * (loc.eps_rad + e.eps_rad).cross(L.axis_L);
    }
  }
  return dv;
}

}  // namespace volmap
