// Nominal backward transformation u = F_b,n(v) (Lei & Hsu 2003, eq. 1) for any
// machine of the machine-definition format with three linear axes and zero or
// two rotary axes, all solutions, and the policy that picks one of them.
// docs/kinematics.md has the derivation and the policy.
//
// Orientation first. With no fixed rotations in the chains (offsets are
// translations), the tool axis in workpiece coordinates is
//   Q = Rot(w1, t1) Rot(w2, t2) a                                  (*)
// where a is the tool axis in the spindle frame and the two rotary joints are
// taken in the order met going from the workpiece down its chain to the base
// and up the tool chain: t = -q for a workpiece-chain joint, +q for a
// tool-chain joint. w1 ("outer": for a table-table machine the table nearest
// the workpiece, C of X'Y'ZA'C') is fixed in workpiece coordinates; w2 is the
// "inner" axis. (*) is Paden-Kahan subproblem 2: up to two closed-form
// solutions. When Q lies along w1 (A = 0 for X'Y'ZA'C') the outer angle is
// free: it is held at its previous value (Lei & Hsu section 4.1) and one
// solution remains. Then the linear axes: with the rotations fixed the tool
// tip is affine in them, so one 3x3 solve places it exactly.
//
// Travel: a rotary angle is taken as the representative (angle + k 360 deg)
// nearest the previous position that lies within the axis's travel (any, for
// an unlimited axis); a solution with no such representative is dropped.
// Linear travel is not a filter; select() prefers solutions inside it.
//
// Units: mm and rad, workpiece coordinates for v (core/machine.h).
#pragma once

#include <Eigen/Core>
#include <array>

#include "core/kinematics/jacobian.h"
#include "core/model/machine.h"

namespace volmap {

/// With the rotary axes held at their values in `u`, the linear axes that
/// put the nominal tool tip at `tip_w_mm` (workpiece coordinates). Exact: with
/// the rotations fixed, the tip is affine in the linear axes, so one 3x3
/// solve does it (columns by differences of nominal_forward). Returns u with
/// its linear entries replaced. Throws std::invalid_argument when the linear
/// axes do not span space (fewer than three, or parallel).
AxisVector linear_axes_for_tip(const Machine& m, const AxisVector& u,
                               const Eigen::Vector3d& tip_w_mm);

/// atan2(y, x) for finite arguments, computed the same way on every machine
/// (fdlibm's atan kernel, Sun 1993: plain double arithmetic, below 1 ulp of
/// the true value; tests/kinematics/kinematics_test.cc compares it with std::atan2).
/// Rotary angles of the backward transformation go through it, as sines and
/// cosines go through sincos_axis (core/trig.h): same input, same bytes.
/// atan2(0, 0) = 0.
double atan2_axis(double y, double x);

/// All solutions of the backward transformation (at most two; fixed storage).
struct BackwardSolutions {
  std::array<AxisVector, 2> u;
  int count = 0;
  /// Q along the outer rotary axis: its angle was free and was held at the
  /// previous value.
  bool singular = false;
};

/// Weighted distance of the selection policy: sum over rotary axes of
/// weight * (q - q_previous)^2 (rad^2), weight 1 by default.
using RotaryWeights = std::array<double, 6>;
inline constexpr RotaryWeights kUnitRotaryWeights = {1, 1, 1, 1, 1, 1};

/// Immutable backward-transformation model of one machine. Construction
/// analyses the chains (throws std::invalid_argument naming the reason for a
/// machine it cannot invert: not three linear axes spanning space, one or more
/// than two rotary axes, parallel rotary axes, tool axis along the inner
/// rotary axis). Per-pose calls allocate nothing.
class Kinematics {
 public:
  explicit Kinematics(Machine m);

  const Machine& machine() const { return machine_; }
  bool has_rotary_axes() const { return outer_ >= 0; }
  /// AxisVector indices of the outer and inner rotary axes (-1: none).
  int outer_index() const { return outer_; }
  int inner_index() const { return inner_; }
  /// Direction of the outer rotary axis in workpiece coordinates (constant).
  const Eigen::Vector3d& outer_axis_w() const { return w1_; }

  /// All solutions u with F_f,n(u) = v_w whose rotary angles lie within
  /// travel, each rotary angle the representative nearest `previous`.
  /// v_w.axis must be a unit vector (|1 - |Q|| <= 1e-6, normalised here;
  /// std::invalid_argument otherwise). Three-axis machine: one solution when
  /// Q is the machine's fixed tool axis, none otherwise. Singular: Q within
  /// singular_sin (sine of the angle) of the outer axis.
  BackwardSolutions backward(const ToolPose& v_w, const AxisVector& previous,
                             double singular_sin = 1e-10) const;

  /// Index of the solution to use after `previous` (-1 when there is none):
  /// solutions within the travel of every axis first; among them the least
  /// weighted rotary distance; ties to the lower index.
  int select(const BackwardSolutions& s, const AxisVector& previous,
             const RotaryWeights& weights = kUnitRotaryWeights) const;

  /// The solution select() picks (unit weights), placing the linear axes
  /// only for the solutions the policy needs to look at (the real-time
  /// path). Throws std::invalid_argument when there is none. *singular (if
  /// given) tells whether the outer axis was held. *J_v_u (if given)
  /// receives the nominal Jacobian at the returned position, from the walk
  /// that placed the tip (what CorrectionSolver::correct needs next).
  AxisVector backward_selected(const ToolPose& v_w, const AxisVector& previous,
                               bool* singular = nullptr, PoseJacobian* J_v_u = nullptr) const;

  /// Linear axes for the tip with the rotary axes of u fixed (exact, as
  /// linear_axes_for_tip, without allocation).
  AxisVector place_tip(const AxisVector& u, const Eigen::Vector3d& tip_w_mm) const;

  /// Rotary angle q (rad) moved to the representative q + k 2pi nearest
  /// `reference` within the axis's travel; false when none lies within it.
  bool representative(int index, double q, double reference, double& out) const;

 private:
  // Rotary angles (outer, inner) of each solution, representatives chosen.
  struct Rotary {
    std::array<std::array<double, 2>, 2> q{};
    int count = 0;
    bool singular = false;
  };
  Rotary rotary_solutions(const ToolPose& v_w, const AxisVector& previous,
                          double singular_sin) const;
  AxisVector placed(const Rotary& r, int k, const AxisVector& previous,
                    const Eigen::Vector3d& tip_w_mm, PoseJacobian* J_v_u = nullptr) const;

  Machine machine_;
  int outer_ = -1, inner_ = -1;
  double s1_ = 1, s2_ = 1;  // t = s q
  Eigen::Vector3d w1_ = Eigen::Vector3d::UnitZ(), w2_ = Eigen::Vector3d::UnitX();
  Eigen::Vector3d a_ = Eigen::Vector3d::UnitZ();  // tool axis, spindle frame
  Eigen::Vector3d e1_ = Eigen::Vector3d::UnitX(), e2_ = Eigen::Vector3d::UnitY();  // frame about w1
  Eigen::Vector3d f1_ = Eigen::Vector3d::UnitZ(), f2_ = Eigen::Vector3d::UnitY();  // frame about w2
  double a_angle_w2_ = 0.0;  // angle of a about w2 in (f1, f2)
  std::array<int, 3> linear_{};
};

}  // namespace volmap
