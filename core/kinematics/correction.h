// The correction du of a commanded axis position (Lei & Hsu 2003, eqs. 3-6):
// the axis position u + du at which the real machine (ErrorModel::actual)
// puts the tool where the nominal machine puts it at u,
//   F_e(u + du) = F_f,n(u) = v                                       (eq. 4)
//
// Sign: volmap's pose error is dv = F_e(u) - F_f,n(u), actual minus nominal
// (ISO 230-2; the paper's eq. 16 has ideal minus actual, erratum E-LH2), so
// to first order J du = -dv and the one-step correction is
//   du = -J^-1 dv                                                   (eq. 6)
// with J = J_v_u the nominal Jacobian at u (core/jacobian.h, eq. 5).
//
// J^-1 of a 6 x 5 Jacobian: the tool axis Q is a unit vector, so the three
// orientation rows have rank 2. The paper keeps the rows dx, dy, dz, di, dj
// (eqs. 18-22), which lose the A axis where k = 0 (its case 2, A = 90 deg).
// volmap solves block-triangularly, as the structure of J allows (linear axes
// do not turn the tool): the rotary corrections by least squares on the three
// orientation rows, dr = (G^T G)^-1 G^T (-dQ), G the 3 x 2 orientation block;
// then the linear corrections exactly from the position rows,
// dl = J_l^-1 (-dP - J_pr dr). For a consistent dv (dQ tangent to the unit
// sphere at Q) this is the exact inverse, equal to eqs. (18)-(22) (with the
// corrected eq. 19, erratum E-LH4); it stays regular at A = 90 deg.
//
// Singular position (Q within singular_sin of the outer rotary axis; A = 0
// for X'Y'ZA'C'): the outer axis's correction is suppressed (section 4.1);
// the inner axis corrects the orientation error along the direction it can
// turn the tool (least squares), the linear axes the position exactly.
// With outer_damping > 0 the damped solve holds there too: its outer
// correction fades continuously to zero as Q reaches the outer axis (at
// most |Q x w_outer| |dQ| / lambda^2) instead of jumping to zero at
// singular_sin; `singular` is still reported.
//
// Iteration (max_iterations > 1): the chord-Newton method on eq. 4 with the
// nominal J at u, du <- du - J^-1 (F_e(u + du) - v), until the residual is
// below the tolerances. Converges at the rate of the errors' relative size
// (1e-4 per step for realistic errors). With the outer axis suppressed the
// fixed point has the position exact and the orientation residual
// perpendicular to what the inner axis can turn. With it damped
// (outer_damping) the step also carries the damping's pull on the outer
// correction already made, so that the fixed point is the damped solution
// of eq. 4 (position exact, |dQ_left|^2 + lambda^2 du_outer^2 least), as
// the one step is of its linearisation: the plain step's fixed point is the
// undamped solution, whose outer correction grows as 1 / |Q x w_outer|
// (75 mrad of C for 134 urad at A = 0.07 deg on the lei-hsu sample), and it
// converges there only at the rate lambda^2 / (sin^2 + lambda^2).
//
// Three-axis machines: J = J_l (3 x 3; +I for a tool on X, Y, Z carriages, so
// du = -dv, and the iteration is the fixed point x_cmd + e(x_cmd) = x_nominal).
//
// Nothing in correct() allocates.
#pragma once

#include <limits>
#include <string>

#include "core/kinematics/jacobian.h"
#include "core/kinematics/kinematics.h"
#include "core/model/error_model.h"

namespace volmap {

struct CorrectionOptions {
  /// 1: the one-step correction of eq. 6. More: iterate to the solution of
  /// eq. 4 (stop earlier once within the tolerances).
  int max_iterations = 1;
  double tolerance_mm = 1e-10;   ///< position residual |P_e - P|
  double tolerance_rad = 1e-12;  ///< orientation residual |Q_e - Q| (controlled part)
  /// Singular when |Q x w_outer| (the sine of the angle between the tool axis
  /// and the outer rotary axis) is at most this: the outer correction is
  /// suppressed. 1e-3 (0.057 deg): a 20 urad orientation error would need
  /// a 1.1 deg turn of C there.
  double singular_sin = 1e-3;
  /// Damping of the outer rotary axis near the singular position (a sine):
  /// the rotary block solves (G^T G + diag(lambda^2, 0)) dr = G^T dQ, so the
  /// outer axis never turns more than 1/(2 lambda) times the orientation
  /// error it corrects; the part of that error it leaves is the tool-axis
  /// error's component that only the outer axis could remove. Also within
  /// singular_sin (continuous down to the singular position) and in the
  /// iteration (its fixed point is the damped solution). 0: eq. 6 as the
  /// paper has it (undamped above singular_sin).
  double outer_damping = 0.0;
  /// Evaluate the residual of a one-step correction too (one more model
  /// evaluation).
  bool residual = false;
  /// Iterate (as max_iterations = kNearSingularIterations) wherever the
  /// sine of the angle between the tool axis and the outer rotary axis is
  /// below this: near the singular position the outer axis turns far and one
  /// step leaves more than a tolerance's worth (1.27 um at A = -3 deg on the
  /// lei-hsu sample, docs/kinematics.md). 0: never.
  double iterate_below_sin = 0.0;
  static constexpr int kNearSingularIterations = 20;

  /// Empty when valid, else what is wrong.
  std::string invalid_reason() const;
};

struct CorrectionResult {
  AxisVector du;  ///< mm and rad, AxisVector order
  bool singular = false;
  int iterations = 0;  ///< J^-1 applications
  /// |F_e(u + du).P - v.P| (mm) and |F_e(u + du).Q - v.Q| (unitless), NaN
  /// when not evaluated.
  double residual_mm = std::numeric_limits<double>::quiet_NaN();
  double residual_axis = std::numeric_limits<double>::quiet_NaN();
};

/// One correction step for a pose error dv = (dP_mm, dQ) from any source
/// (an error model, a table): du with J_v_u du = -dv, solved block-wise as
/// CorrectionSolver does (rotary axes by least squares on the orientation
/// rows, the outer one suppressed at the singular position, then the linear
/// axes exactly). du is resized and overwritten. Returns whether the pose is
/// singular (|Q x w_outer| <= singular_sin); `outer_damping` as
/// CorrectionOptions's.
bool correction_step(const Kinematics& kin, const PoseJacobian& J_v_u, const Eigen::Vector3d& dP_mm,
                     const Eigen::Vector3d& dQ, double singular_sin, AxisVector& du,
                     double outer_damping = 0.0);

/// Computes corrections against one error model. Keeps a reference to
/// `model`, which must outlive it. Immutable; correct() is thread-safe as
/// far as ErrorModel::actual is.
class CorrectionSolver {
 public:
  /// Throws std::invalid_argument for invalid options or a machine the
  /// backward transformation cannot handle (Kinematics).
  explicit CorrectionSolver(const ErrorModel& model, CorrectionOptions options = {});

  const CorrectionOptions& options() const { return options_; }
  const Kinematics& kinematics() const { return kin_; }

  /// du for the commanded (nominal) axis position u, approach directions dir.
  CorrectionResult correct(const AxisVector& u, const ApproachDirections& dir = {}) const;
  /// The same with the nominal Jacobian J_v_u at u given (e.g. from
  /// Kinematics::backward_selected, which has it from placing the tip).
  CorrectionResult correct(const AxisVector& u, const ApproachDirections& dir,
                           const PoseJacobian& J_v_u) const;

 private:
  const ErrorModel& model_;
  CorrectionOptions options_;
  Kinematics kin_;
};

}  // namespace volmap
