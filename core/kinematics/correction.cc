#include "core/kinematics/correction.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/kinematics/fixed_point.h"
#include "core/kinematics/jacobian.h"

namespace volmap {

std::string CorrectionOptions::invalid_reason() const {
  if (max_iterations < 1)
    return fmt::format("max_iterations is {}, must be at least 1", max_iterations);
  if (!(tolerance_mm > 0) || !(tolerance_rad > 0)) return "tolerances must be positive";
  if (!(singular_sin >= 0 && singular_sin < 1))
    return fmt::format("singular_sin is {:g}, must be in [0, 1)", singular_sin);
  if (!(outer_damping >= 0 && outer_damping < 1))
    return fmt::format("outer_damping is {:g}, must be in [0, 1)", outer_damping);
  return {};
}

namespace {

// J^-1 at one axis position, block-triangular (see correction.h).
class InverseJacobian {
 public:
  InverseJacobian(const Kinematics& kin, const PoseJacobian& J, double singular_sin,
                  double outer_damping)
      : kin_(kin) {
    const Machine& m = kin.machine();
    int k = 0;
    for (int i = 0; i < m.axis_count(); ++i)
      if (!is_rotary(m.axis_order[static_cast<size_t>(i)])) lin_[static_cast<size_t>(k++)] = i;
    Eigen::Matrix3d Jl;
    for (int c = 0; c < 3; ++c) Jl.col(c) = J.block<3, 1>(0, lin_[static_cast<size_t>(c)]);
    Jl_inv_ = Jl.inverse();
    if (!kin.has_rotary_axes()) return;
    rot_ = {kin.outer_index(), kin.inner_index()};
    for (int c = 0; c < 2; ++c) {
      J_pr_.col(c) = J.block<3, 1>(0, rot_[static_cast<size_t>(c)]);
      G_.col(c) = J.block<3, 1>(3, rot_[static_cast<size_t>(c)]);
    }
    // |dQ/dq_outer| = |w_outer x Q|: the sine of the angle between them.
    singular_ = G_.col(0).norm() <= singular_sin;
    // Damped, the outer correction fades to zero continuously as Q reaches
    // the outer axis (at most |Q x w_outer| |dQ| / lambda^2): the damped
    // solve holds down to the singular position itself, so that the
    // correction does not jump at singular_sin.
    damped_ = outer_damping > 0;
    if (singular_ && !damped_) {
      g_inner_ls_ = G_.col(1).transpose() / G_.col(1).squaredNorm();
    } else {
      Eigen::Matrix2d N = G_.transpose() * G_;
      damping2_ = outer_damping * outer_damping;
      N(0, 0) += damping2_;
      N_inv_ = N.inverse();
      N_inv_G_t_ = N_inv_ * G_.transpose();
    }
  }

  bool singular() const { return singular_; }
  /// |w_outer x Q|: the sine of the angle between the outer axis and Q.
  double outer_sin() const { return G_.col(0).norm(); }

  // du with J du = b (least squares on the orientation rows).
  void solve(const Eigen::Vector3d& bP, const Eigen::Vector3d& bQ, AxisVector& du) const {
    solve_damped(bP, bQ, 0.0, du);
  }

  // The chord-Newton step at the iterate du_now with residual r = F_e(u +
  // du_now) - v: the step J^-1 r, and with the outer axis damped also the
  // damping's pull on what du_now already turns the outer axis,
  // N^-1 diag(lambda^2, 0) du_now. Its fixed point (a zero step) has the
  // position exact and the gradient of |r_Q|^2 + lambda^2 du_outer^2 zero:
  // the damped solution of eq. 4, where the one step of eq. 6 is the damped
  // solution of the linearised problem. (The plain step's fixed point is the
  // undamped solution, whose outer correction grows as 1/|Q x w_outer|
  // towards the singular position: the iteration would undo the damping.)
  void iteration_step(const Eigen::Vector3d& rP, const Eigen::Vector3d& rQ,
                      const AxisVector& du_now, AxisVector& step) const {
    solve_damped(rP, rQ, kin_.has_rotary_axes() ? damping2_ * du_now[rot_[0]] : 0.0, step);
  }

 private:
  const Kinematics& kin_;
  std::array<int, 3> lin_{};
  std::array<int, 2> rot_{};
  Eigen::Matrix3d Jl_inv_;
  Eigen::Matrix<double, 3, 2> J_pr_ = Eigen::Matrix<double, 3, 2>::Zero();
  Eigen::Matrix<double, 3, 2> G_ = Eigen::Matrix<double, 3, 2>::Zero();
  Eigen::Matrix<double, 2, 3> N_inv_G_t_ = Eigen::Matrix<double, 2, 3>::Zero();
  Eigen::Matrix<double, 1, 3> g_inner_ls_ = Eigen::Matrix<double, 1, 3>::Zero();
  Eigen::Matrix2d N_inv_ = Eigen::Matrix2d::Zero();
  double damping2_ = 0.0;  ///< lambda^2 (0 undamped)
  bool singular_ = false;
  bool damped_ = false;

  // du with J du = b, the rotary block's right-hand side G^T bQ plus
  // (outer_pull, 0).
  void solve_damped(const Eigen::Vector3d& bP, const Eigen::Vector3d& bQ, double outer_pull,
                    AxisVector& du) const {
    Eigen::Vector2d dr = Eigen::Vector2d::Zero();
    if (kin_.has_rotary_axes()) {
      if (singular_ && !damped_)
        dr[1] = g_inner_ls_ * bQ;
      else
        dr = N_inv_G_t_ * bQ + N_inv_.col(0) * outer_pull;
      du[rot_[0]] = dr[0];
      du[rot_[1]] = dr[1];
    }
    const Eigen::Vector3d dl = Jl_inv_ * (bP - J_pr_ * dr);
    for (int c = 0; c < 3; ++c) du[lin_[static_cast<size_t>(c)]] = dl[c];
  }
};

// The chord-Newton iterate: the correction du and the step J^-1 (F_e(u + du) - v)
// subtracted to reach it (the stopping rule measures the step).
struct ChordNewtonIterate {
  AxisVector du;
  AxisVector step;
};

// Whether the step's linear part (mm) and rotary part (rad) are both within
// the tolerances.
bool step_within_tolerances(const Machine& m, const AxisVector& step,
                            const CorrectionOptions& options) {
  double lin = 0, rot = 0;
  for (int i = 0; i < m.axis_count(); ++i)
    (is_rotary(m.axis_order[static_cast<size_t>(i)]) ? rot : lin) += step[i] * step[i];
  return std::sqrt(lin) <= options.tolerance_mm && std::sqrt(rot) <= options.tolerance_rad;
}

}  // namespace

bool correction_step(const Kinematics& kin, const PoseJacobian& J_v_u, const Eigen::Vector3d& dP_mm,
                     const Eigen::Vector3d& dQ, double singular_sin, AxisVector& du,
                     double outer_damping) {
  const InverseJacobian Jinv(kin, J_v_u, singular_sin, outer_damping);
  du = AxisVector::Zero(kin.machine().axis_count());
  Jinv.solve(-dP_mm, -dQ, du);
  return Jinv.singular();
}

CorrectionSolver::CorrectionSolver(const ErrorModel& model, CorrectionOptions options)
    : model_(model), options_(options), kin_(model.machine()) {
  if (const std::string why = options_.invalid_reason(); !why.empty())
    throw std::invalid_argument("correction options: " + why);
}

CorrectionResult CorrectionSolver::correct(const AxisVector& u,
                                           const ApproachDirections& dir) const {
  PoseJacobian J;
  nominal_forward_jacobian(kin_.machine(), u, J);
  return correct(u, dir, J);
}

CorrectionResult CorrectionSolver::correct(const AxisVector& u, const ApproachDirections& dir,
                                           const PoseJacobian& J) const {
  const Machine& m = kin_.machine();
  const InverseJacobian Jinv(kin_, J, options_.singular_sin, options_.outer_damping);
  CorrectionResult r;
  r.singular = Jinv.singular();
  r.du = AxisVector::Zero(m.axis_count());
  // One step: J du = -dv (eq. 6 with dv = actual - nominal). The model
  // carries the nominal pose v = F_f,n(u) along with the actual one.
  ToolPose v;
  const ToolPose a0 = model_.actual_and_nominal(u, dir, v);
  Jinv.solve(-(a0.tip_mm - v.tip_mm), -(a0.axis - v.axis), r.du);
  // Iterate to eq. 4 (core/kinematics/fixed_point.h), stopping once the
  // step is within the tolerances.
  ChordNewtonIterate x{r.du, AxisVector::Zero(m.axis_count())};
  const int max_iterations =
      kin_.has_rotary_axes() && Jinv.outer_sin() < options_.iterate_below_sin
          ? std::max(options_.max_iterations, CorrectionOptions::kNearSingularIterations)
          : options_.max_iterations;
  const FixedPointOutcome outcome = iterate_to_fixed_point(
      x, FixedPointLimits{1, max_iterations},
      [&](const ChordNewtonIterate& previous) {
        ChordNewtonIterate next{previous.du, AxisVector(m.axis_count())};
        const ToolPose a = model_.actual(u + previous.du, dir);
        Jinv.iteration_step(a.tip_mm - v.tip_mm, a.axis - v.axis, previous.du, next.step);
        next.du -= next.step;
        return next;
      },
      [&](const ChordNewtonIterate&, const ChordNewtonIterate& next) {
        return step_within_tolerances(m, next.step, options_);
      });
  r.du = x.du;
  r.iterations = outcome.iterations;
  if (max_iterations > 1 || options_.residual) {
    const ToolPose a = model_.actual(u + r.du, dir);
    r.residual_mm = (a.tip_mm - v.tip_mm).norm();
    r.residual_axis = (a.axis - v.axis).norm();
  }
  return r;
}

}  // namespace volmap
