// The homogeneous-transformation (HTM) error model of a serial machine, in
// two forms:
//  - exact: full products of 4x4 transforms (stored as Eigen::Isometry3d),
//    error rotations R(EA,EB,EC) = Rz(EC) Ry(EB) Rx(EA) evaluated exactly;
//  - first order: small angles, products of two errors dropped (Hsu eq. 13-16
//    "using small-angle approximations ... second-order errors negligible";
//    Lei & Hsu section 3). The two agree to second order in the errors.
//
// Joint j with errors (Hsu eqs. 1, 4, 5, 6 generalised; frames base first):
//   linear:  T_parent_j = Trans(offset) * L * Trans(q d) * E(q)
//   rotary:  T_parent_j = Trans(offset) * L * E(q) * Rot(d, q)
// L = [R(EA0K,EB0K,EC0K) | (EX0K,EY0K,EZ0K)] holds the location errors,
// E(q) = [R(EAK,EBK,ECK) | (EXK,EYK,EZK)] the component errors at q. Rotary
// component errors are error motions in the non-rotating frame (ISO 230-7).
//
// Pose error dv = (dP, dQ): actual minus nominal tool tip and tool axis, in
// workpiece coordinates (Lei & Hsu eqs. 16-17 with ISO 230-2 sign; the paper
// writes ideal minus actual, erratum E-LH2 in docs/errata.md).
//
// Formulations (Hsu):
//  - kDependent (Table I): lever arms from the kinematic parameters (offsets).
//  - kIndependent (Table II): each linear axis's translational component
//    errors are as measured at the tool tip with the other axes at the
//    machine's measured_at pose, so they already hold the Abbe terms of that
//    pose; the lever of an angular error is the tool tip's displacement from
//    that pose. Location errors of linear axes pivot at the tool tip of the
//    measurement pose with the axis itself at 0. Rotary axes are unchanged.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/model/error_set.h"
#include "core/model/machine.h"

namespace volmap {

enum class Formulation : std::uint8_t { kDependent, kIndependent };

struct ModelOptions {
  Formulation formulation = Formulation::kIndependent;
  OutsidePolicy outside = OutsidePolicy::kError;
};

/// Tool pose error in workpiece coordinates: dP in mm, dQ unitless.
struct PoseError {
  Eigen::Vector3d dP_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d dQ = Eigen::Vector3d::Zero();
};

/// Approach direction per AxisVector index: +1, -1, or 0 (unknown / mean).
using ApproachDirections = std::array<std::int8_t, 6>;

/// Small transform of one error frame: translation delta (mm), rotation eps
/// (rad, about the frame's x, y, z).
struct SmallTransform {
  Eigen::Vector3d delta_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d eps_rad = Eigen::Vector3d::Zero();
};

/// Exact rotation Rz(c) Ry(b) Rx(a) for small angles (a, b, c) = eps.
Eigen::Matrix3d small_rotation_exact(const Eigen::Vector3d& eps_rad);

class ErrorModel {
 public:
  /// Binds the errors to the machine's joints. Throws std::invalid_argument
  /// when the errors name an axis the machine does not have.
  ErrorModel(Machine machine, ErrorSet errors, ModelOptions options = {});

  const Machine& machine() const { return machine_; }
  const ErrorSet& errors() const { return errors_; }
  const ModelOptions& options() const { return options_; }

  /// Actual tool pose (exact HTM products) at axis position u.
  ToolPose actual(const AxisVector& u, const ApproachDirections& dir = {}) const;
  /// Actual tool pose, and the nominal one at the same u in *nominal.
  ToolPose actual_and_nominal(const AxisVector& u, const ApproachDirections& dir,
                              ToolPose& nominal) const {
    ToolPose a;
    evaluate(u, dir, a, nominal);
    return a;
  }
  /// dv = actual - nominal, exact.
  PoseError exact(const AxisVector& u, const ApproachDirections& dir = {}) const;
  /// dv to first order in the errors.
  PoseError first_order(const AxisVector& u, const ApproachDirections& dir = {}) const;

  /// First-order lever data of one joint at u: how a small transform of its
  /// location frame L or component frame C moves the tool pose in workpiece
  /// coordinates:  dP = sign R_w_L (delta + eps x lever),  dQ = sign R_w_L
  /// (eps x axis_L). sign is -1 for the workpiece chain (an error that moves
  /// the workpiece by +delta moves the tool by -delta relative to it).
  struct JointLever {
    AxisName axis;
    bool rotary;
    double sign;
    Eigen::Matrix3d R_w_L;
    Eigen::Vector3d lever_location_mm;   ///< for the location errors
    Eigen::Vector3d lever_component_mm;  ///< for the component errors
    Eigen::Vector3d axis_L;              ///< tool axis in frame L
    /// ISO 230-1 location errors (LocationConvention::kIso230): the joint
    /// is L C(q) P^-1, so a location error also acts, reversed, after the
    /// motion M(q) = [R_M | t_M] (frame L). own: a rotary axis's own
    /// angular component (its zero error, not in P); -1 for linear axes.
    bool iso = false;
    int own = -1;
    Eigen::Matrix3d R_M = Eigen::Matrix3d::Identity();
    Eigen::Vector3d t_M_mm = Eigen::Vector3d::Zero();

    /// First-order gain of location error component c (0..2: EX0K EY0K
    /// EZ0K per mm, 3..5: EA0K EB0K EC0K per rad), workpiece frame:
    ///   link:  dP = sign R_w_L (e + e' x r), dQ = sign R_w_L (e' x a)
    ///   ISO:   dP = sign R_w_L ((I - R_M) e + e' x r - (R_M e') x (r - t_M)),
    ///          dQ = sign R_w_L ((e' - R_M e') x a)
    /// (e: translational unit, e': angular unit, r = lever_location_mm,
    /// a = axis_L); the zero error keeps the link form.
    void location_gain(int c, Eigen::Vector3d& dP, Eigen::Vector3d& dQ) const;
    /// First-order gain of component c of this joint's location errors
    /// (location_gain) or component errors: dP = sign R_w_L e (c < 3), or
    /// dP = sign R_w_L (e' x lever_component), dQ = sign R_w_L (e' x a).
    void gain(int c, bool location, Eigen::Vector3d& dP, Eigen::Vector3d& dQ) const;
  };
  /// Levers of every joint, workpiece chain then tool chain (base first).
  void levers(const AxisVector& u, std::vector<JointLever>& out) const;

  /// The point a linear axis's squareness turns about, in its location
  /// frame (mm): the tool tip of the measurement pose in the independent
  /// formulation, else the frame's origin (zero; also for rotary axes).
  Eigen::Vector3d location_pivot_mm(AxisName axis) const;

  /// Whether every joint is linear (a three-axis machine): tip_error_linear
  /// applies.
  bool all_joints_linear() const { return all_linear_; }
  /// exact(u, dir).dP_mm for a machine whose joints are all linear, bit for
  /// bit the same numbers (the same operations in the same order), without
  /// the tool axis and the nominal lane's rotations. u: the axis values by
  /// AxisVector index (mm). The three-axis post-processor's hot path
  /// (docs/post.md "Speed"). With clamped_out, the clamped evaluations
  /// (OutsidePolicy::kClamp) are added there instead of to clamped_count()
  /// (an evaluation made ahead, counted only if its result is used).
  Eigen::Vector3d tip_error_linear(const double* u, const ApproachDirections& dir,
                                   std::uint64_t* clamped_out = nullptr) const;

  /// Number of evaluations that were clamped (OutsidePolicy::kClamp).
  std::uint64_t clamped_count() const { return clamped_->load(); }

 private:
  struct BoundJoint {
    const Joint* joint = nullptr;
    ChainSide side = ChainSide::kWorkpiece;
    const AxisErrors* components = nullptr;  ///< null: no component errors
    SmallTransform location;                 ///< effective, see .cc
    /// Trans(offset) * L, exact: p_parent = R_parent_loc p + t_parent_loc_mm.
    Eigen::Matrix3d R_parent_loc = Eigen::Matrix3d::Identity();
    Eigen::Vector3d t_parent_loc_mm = Eigen::Vector3d::Zero();
    bool has_location_rotation = false;
    int coordinate_axis = -1;  ///< rotary line along +x, +y, +z: 0, 1, 2
    /// ISO 230-1 (LocationConvention::kIso230): the joint is
    /// Trans(offset) L C(q) P^-1, P = [R_P | t_P] the placement of the axis
    /// line (L without a rotary axis's zero error). conjugated: P is not the
    /// identity, so evaluation applies it.
    bool conjugated = false;
    Eigen::Matrix3d R_P = Eigen::Matrix3d::Identity();
    Eigen::Vector3d t_P_mm = Eigen::Vector3d::Zero();
    /// Independent formulation: tool tip in this joint's location frame at
    /// the measurement pose with the joint at 0 (nominal). Zero otherwise.
    Eigen::Vector3d r_meas_mm = Eigen::Vector3d::Zero();
    bool independent = false;
  };

  /// The joint's constant frames (R_parent_loc, t_parent_loc_mm, P) from
  /// its location errors, in ISO 230-1 (iso) or link meaning.
  static void set_location_frames(BoundJoint& bj, bool iso);
  SmallTransform component_errors(const BoundJoint& bj, double q, int dir) const;
  /// E(q) = [R | delta] of one joint (independent pivot folded into delta);
  /// identity when the joint has no component errors.
  void joint_error(const BoundJoint& bj, double q, int dir, Eigen::Matrix3d& R,
                   Eigen::Vector3d& delta, std::uint64_t& clamped) const;
  void evaluate(const AxisVector& u, const ApproachDirections& dir, ToolPose& actual_pose,
                ToolPose& nominal_pose) const;

  /// tip_error_linear's plan (all_linear_ only): each joint's constants
  /// copied flat, in evaluate()'s phase-1 order (workpiece chain base first,
  /// then tool chain base first), so the hot loop reads one contiguous block.
  struct LinearJoint {
    const AxisErrors* components = nullptr;  ///< null: no component errors
    int index = 0;                           ///< AxisVector index of the axis
    bool workpiece = false;
    bool independent = false;
    bool has_location_rotation = false;
    bool conjugated = false;   ///< ISO 230-1: P = [R_loc | t_P_mm] applied
    double t_P_mm[3] = {};     ///< t_P_mm
    double direction[3] = {};  ///< direction_parent
    double offset_mm[3] = {};  ///< offset_parent_mm
    double t_loc_mm[3] = {};   ///< t_parent_loc_mm
    double R_loc[3][3] = {};   ///< R_parent_loc, R_loc[i][j] = R(i, j)
    double r_meas_mm[3] = {};  ///< r_meas_mm
    // The same numbers laid out for two-lane (rows 0 and 1) arithmetic.
    alignas(16) double R_loc_col01[3][2] = {};  ///< {R(0, j), R(1, j)}
    alignas(16) double r_meas_pair[3][2] = {};  ///< {r_meas_mm[j], r_meas_mm[j]}
  };
  static constexpr int kMaxLinearJoints = 6;
  std::array<LinearJoint, kMaxLinearJoints> linear_{};
  int linear_work_ = 0;              ///< joints of the workpiece chain in linear_
  int linear_count_ = 0;             ///< all joints in linear_
  double linear_start_mm_[3] = {};   ///< spindle_offset - tool_length * tool_axis
  double linear_origin_mm_[3] = {};  ///< workpiece_origin_mm

  Machine machine_;
  ErrorSet errors_;
  ModelOptions options_;
  std::vector<BoundJoint> workpiece_;
  std::vector<BoundJoint> tool_;
  bool all_linear_ = false;
  std::shared_ptr<std::atomic<std::uint64_t>> clamped_ =
      std::make_shared<std::atomic<std::uint64_t>>(0);
};

}  // namespace volmap
