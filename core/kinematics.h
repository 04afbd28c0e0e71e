// Nominal kinematics beyond the forward transformation (machine.h).
#pragma once

#include <Eigen/Core>

#include "core/machine.h"

namespace volmap {

/// With the rotary axes held at their values in `u`, the linear axes that
/// put the nominal tool tip at `tip_w_mm` (workpiece coordinates). Exact: with
/// the rotations fixed, the tip is affine in the linear axes, so one 3x3
/// solve does it (columns by differences of nominal_forward). Returns u with
/// its linear entries replaced. Throws std::invalid_argument when the linear
/// axes do not span space (fewer than three, or parallel).
AxisVector linear_axes_for_tip(const Machine& m, const AxisVector& u,
                               const Eigen::Vector3d& tip_w_mm);

}  // namespace volmap
