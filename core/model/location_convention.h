// Conversion of location errors between their two meanings (docs/model.md,
// "Location errors"): ISO 230-1 (the contract) and Lei & Hsu's link errors.
//
// Per joint, frames base first, A = Trans(offset), C(q) the joint's motion
// with its component errors (Trans(q d) E(q), or E(q) Rot(d, q)):
//   link:  A L C(q)            ISO 230-1:  A L' C(q) P'^-1
// Walking each chain from the base, the two products agree up to a constant
// rigid transform K carried to the next joint: link prefix = ISO prefix * K.
// Joint j takes the part of A^-1 K A L that its convention can hold; what is
// left, N (a shift along a rotary line; a shift or a turn about its own line
// for a linear axis), commutes with the motion and moves into K. At the end
// of each chain K is the set-up part that separates the conventions:
//   link model = ISO model with the workpiece moved by K_w (what probing the
//   part's origin absorbs) and the spindle by K_t (the tool's length and the
//   spindle's alignment).
// The conversion is exact for the location errors. N and a component error's
// rotation do not commute exactly: their product, second order (a shift of
// tens of um times an error rotation of tens of urad: below 1.1 nm on every
// sample), is the only difference left; convert() measures it on a grid of
// poses. Towards link errors the joint takes from A^-1 K^-1 A L'.
#pragma once

#include <Eigen/Geometry>
#include <string>

#include "core/model/error_model.h"

namespace volmap {

struct ConventionConversion {
  ErrorSet errors;  ///< the input with its location errors in the target meaning
  /// Set-up parts, link model = ISO model with these at the chain ends
  /// (last workpiece-chain frame, last tool-chain frame).
  Eigen::Isometry3d workpiece_setup = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d tool_setup = Eigen::Isometry3d::Identity();
  /// Largest difference of tool tip (mm) and tool axis (rad) between the
  /// input's model and the output's model with the set-up parts, over a grid
  /// of poses within travel.
  double check_tip_mm = 0.0;
  double check_axis_rad = 0.0;
  int check_poses = 0;
};

/// Re-expresses the location errors of `errors` (in errors.convention) in
/// `target`, for machine m (formulation f: the pivot of a linear axis's
/// squareness). Component errors are kept as they are. Throws
/// std::invalid_argument when the errors do not fit the machine.
ConventionConversion convert_location_convention(const Machine& m, const ErrorSet& errors,
                                                 LocationConvention target,
                                                 Formulation formulation);

/// (x, y, z) translation in um and (a, b, c) angles in urad, R = Rz(c) Ry(b)
/// Rx(a), of a small rigid transform: for reports.
void small_transform_parts(const Eigen::Isometry3d& T, Eigen::Vector3d& t_um,
                           Eigen::Vector3d& angles_urad);

}  // namespace volmap
