// The per-pose work of the five-axis post-processor: nominal tool pose in
// workpiece coordinates -> nominal axis position (backward transformation,
// Lei & Hsu 2003 eq. 1, with the selection policy, C continuity and the
// singular position of core/kinematics.h) -> commanded axis position u + du
// (the correction of eq. 6, core/correction.h) -> G-code words.
//
// Frames and units: v = (P, Q) in the workpiece frame w of the machine (mm,
// unit vector); u in AxisVector order (mm, rad). Nothing here allocates per
// pose except the output string's growth.
#pragma once

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "core/kinematics/correction.h"
#include "core/kinematics/kinematics.h"
#include "core/model/error_model.h"
#include "maps/tables/volumetric_table.h"

namespace volmap::post {

/// The five-axis post's damping of the outer rotary axis near the singular
/// position (CorrectionOptions::outer_damping, a sine: 0.29 degrees). Without
/// it, a tool axis 0.3 degrees from C's axis needs C corrections of
/// hundreds of times the tool-axis error, which change so fast along a move
/// that 1 um took more than 65536 pieces (real CL files of NX and SOLIDWORKS
/// CAM); with it they post at 1 um (docs/post-five-axis.md, "Near the
/// singular position").
inline constexpr double kPostOuterDamping = 0.005;
/// Within this sine of the singular position (A within 11.5 deg of 0 on an
/// X'Y'ZA'C' machine) the post iterates the correction to eq. 4 instead of
/// one step of eq. 6: there the outer axis turns far, and one step left up
/// to 1.27 um on the sample with its ISO 230-1 location errors
/// (CorrectionOptions::iterate_below_sin). The iteration keeps the damping:
/// it converges to the damped solution, not to the undamped one whose C
/// correction grows without bound towards A = 0 (core/correction.h).
inline constexpr double kPostIterateBelowSin = 0.2;

class FiveAxisTransform {
 public:
  /// Throws std::invalid_argument for a machine the backward transformation
  /// cannot handle. `correction` options: core/correction.h.
  FiveAxisTransform(const Machine& machine, const ErrorSet& errors, OutsidePolicy outside,
                    CorrectionOptions correction = {});
  /// The errors from a five-axis volumetric table (volmap map: channels
  /// ex ey ez ei ej ek, dv per node) instead of the model: the correction is
  /// the one step du = -J^-1 dv(u) of eq. 6 with dv interpolated (the
  /// table's own interpolation method), J the nominal Jacobian at u, solved
  /// block-wise as CorrectionSolver does (the outer axis damped by
  /// kPostOuterDamping, its correction fading to zero at the singular
  /// position); actual() is nominal + dv(u).
  /// Keeps a reference to `table`. Throws std::invalid_argument when the
  /// table does not fit the machine (axis count, channels).
  FiveAxisTransform(const Machine& machine, const maps::VolumetricTable& table,
                    OutsidePolicy outside);

  const Machine& machine() const { return kin_.machine(); }
  const Kinematics& kinematics() const { return kin_; }
  /// The errors are zero everywhere (errors_all_zero): the post writes the
  /// nominal backward transformation exactly, without evaluating a model.
  bool zero() const { return zero_; }

  /// Nominal axes for tool pose v after `previous` (selection policy of
  /// Kinematics::backward_selected: the solution within travel with the
  /// least rotary motion, unlimited axes unwrapped next to previous, the
  /// outer axis held at the singular position). *singular as there.
  /// Near the singular position (|Q x w_outer| <= kSingularSin) the outer
  /// axis is held too, a machining policy: Kinematics::backward_selected
  /// holds it only below 1e-10 and otherwise turns it to the azimuth of the
  /// tilt, however small (exactly, since the stable form of subproblem 2),
  /// which for a tilt of 1e-8 rad means swinging C for an orientation
  /// change no part can see. There the pose's axis is taken as the outer
  /// axis itself (a change below 1e-7 rad).
  AxisVector axes_for_pose(const ToolPose& v_w, const AxisVector& previous,
                           bool* singular = nullptr) const;
  static constexpr double kSingularSin = 1e-7;
  /// Nominal axes for the tip with the rotary angles of `q` (TCP programs:
  /// the program chose the rotary solution): the exact linear placement.
  AxisVector axes_for_angles(const AxisVector& q, const Eigen::Vector3d& tip_w_mm) const {
    return kin_.place_tip(q, tip_w_mm);
  }
  /// The axis position to command so that the real machine puts the tool
  /// where the nominal one does at u_nominal: u + du (exactly u_nominal
  /// when zero()). *du_norm (if given): |du| with rad counted as mm x 1.
  AxisVector command(const AxisVector& u_nominal, bool* singular = nullptr) const;
  /// Actual tool pose at commanded u (the exact model; nominal when zero()).
  ToolPose actual(const AxisVector& u) const;
  /// Nominal tool pose at u.
  ToolPose nominal(const AxisVector& u) const { return nominal_forward(kin_.machine(), u); }

 private:
  // dv from the table at u (mm, unitless), direction layer 0.
  void table_dv(const AxisVector& u, Eigen::Vector3d& dP, Eigen::Vector3d& dQ) const;

  Kinematics kin_;
  const maps::VolumetricTable* table_ = nullptr;
  std::array<int, 6> channel_{};
  OutsidePolicy outside_ = OutsidePolicy::kError;
  std::unique_ptr<ErrorModel> model_;
  std::unique_ptr<CorrectionSolver> solver_;
  bool zero_ = false;
};

/// The transforms of a program's tools, each built when first used: the
/// machine file's tool (number -1) and the tools of a tool table, whose
/// length is the machine file's tool's plus the table's offset (mm; a
/// LinuxCNC .tbl Z, as the three-axis post reads it). The errors stay those
/// measured with the machine file's tool (Machine::measurement_tool_length_mm).
class ToolTransforms {
 public:
  using Build = std::function<std::unique_ptr<FiveAxisTransform>(const Machine&)>;
  ToolTransforms(const Machine& machine, std::map<int, double> offsets_mm, Build build);
  /// Tool `tool`'s transform (-1: the machine file's tool). Throws
  /// std::invalid_argument when the table has no such tool.
  const FiveAxisTransform& get(int tool);
  /// Whether a tool table was given.
  bool has_table() const { return !offsets_mm_.empty(); }
  /// A tool change to `tool` (`moved`: the program moved before it): that
  /// tool's transform. Without a table the machine file's tool is the only
  /// one: a second, different tool after moves throws std::invalid_argument,
  /// as does a tool the table does not have.
  const FiveAxisTransform& change_to(int tool, bool moved);

 private:
  Machine machine_;
  std::map<int, double> offsets_mm_;
  Build build_;
  std::map<int, std::unique_ptr<FiveAxisTransform>> built_;
  int tool_ = -1;  ///< the last tool changed to (-1: none)
};

/// Appends value rounded to `decimals` (value x 10^decimals to the nearest
/// integer, ties to even), trailing zeros and point dropped, never "-0".
/// Equal to nc::format_number except, rarely, at exact decimal ties; about
/// ten times faster (no allocation, no decimal conversion of the double).
void append_number(std::string& out, double value, int decimals);

}  // namespace volmap::post
