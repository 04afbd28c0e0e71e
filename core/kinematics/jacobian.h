// The Jacobian of the nominal forward transformation, J_v_u = dF_f,n/du
// (Lei & Hsu 2003, eq. 5), analytic, for any machine of the machine-definition
// format (docs/machine-format.md).
//
// Rows: dx, dy, dz (mm) and di, dj, dk (unitless) of the tool pose v = (P, Q)
// in workpiece coordinates; columns: the machine's axes in AxisVector order
// (mm for linear, rad for rotary). From the chain (docs/kinematics.md):
//   linear joint j:  dP/dq =  s_j d_w                 dQ/dq = 0
//   rotary joint j:  dP/dq =  s_j d_w x (P - c_w)     dQ/dq = s_j d_w x Q
// with d_w the joint's direction and c_w a point on its line, both in
// workpiece coordinates at u, and s_j = +1 for a tool-chain joint, -1 for a
// workpiece-chain joint (moving the workpiece by +x moves the tool by -x
// relative to it). For Lei & Hsu's X'Y'ZA'C' this is the derivative of
// eqs. (10)-(15); tests/kinematics/jacobian_test.cc checks it against central finite
// differences of nominal_forward and against the paper's inverse, eqs. (18)-(22).
//
// Fixed-size storage (at most 6 axes): nothing here allocates.
#pragma once

#include <Eigen/Core>

#include "core/model/machine.h"

namespace volmap {

/// J_v_u: 6 rows (dx, dy, dz, di, dj, dk), one column per axis (at most 6).
using PoseJacobian = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;

/// Nominal tool pose v = F_f,n(u) (equal to nominal_forward) and J_v_u in one
/// pass over the chains. No allocation. With rotary_columns false only the
/// linear axes' columns are filled (the rest zero): what placing the tool
/// tip needs.
ToolPose nominal_forward_jacobian(const Machine& m, const AxisVector& u, PoseJacobian& J_v_u,
                                  bool rotary_columns = true);

/// Moves the linear axes of u so that the nominal tool tip is at tip_w_mm
/// (workpiece coordinates), the rotary axes held: the tip is affine in the
/// linear axes, so one 3 x 3 solve is exact. Returns the nominal pose at the
/// new u and, when J_v_u is given, fills J_v_u at the new u, from the same
/// walk over the chains (a linear joint translates what follows it and turns
/// nothing). Throws std::invalid_argument unless the machine has three
/// linear axes.
ToolPose nominal_place_tip(const Machine& m, AxisVector& u, const Eigen::Vector3d& tip_w_mm,
                           PoseJacobian* J_v_u = nullptr);

/// J_v_u alone.
PoseJacobian nominal_jacobian(const Machine& m, const AxisVector& u);

}  // namespace volmap
