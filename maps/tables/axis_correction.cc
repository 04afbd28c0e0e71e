#include "maps/tables/axis_correction.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <algorithm>
#include <stdexcept>

#include "core/kinematics/fixed_point.h"

namespace volmap::maps {

ThreeAxisCorrection::ThreeAxisCorrection(const ErrorModel& model) : model_(model) {
  const Machine& m = model.machine();
  if (m.axis_count() != 3 || m.has_rotary_axes())
    throw std::invalid_argument(fmt::format(
        "the three-axis correction needs a machine with the linear axes X, Y, Z; {} has {}", m.name,
        m.structure_code()));
  // A = d p / d x, exact by differences since p is affine in linear axes.
  AxisVector x0 = m.home;
  const Eigen::Vector3d p0 = nominal_forward(m, x0).tip_mm;
  Eigen::Matrix3d A;
  for (int i = 0; i < 3; ++i) {
    AxisVector x1 = x0;
    x1[i] += 1.0;
    A.col(i) = nominal_forward(m, x1).tip_mm - p0;
  }
  Eigen::FullPivLU<Eigen::Matrix3d> lu(A);
  if (!lu.isInvertible())
    throw std::invalid_argument(
        fmt::format("machine {}: the axis directions are not independent", m.name));
  A_inv_ = lu.inverse();
  for (int i = 0; i < 3; ++i) {
    min_mm_[i] = m.limits[static_cast<size_t>(i)].min;
    max_mm_[i] = m.limits[static_cast<size_t>(i)].max;
  }
}

ThreeAxisCorrection::Result ThreeAxisCorrection::solve(const AxisVector& x_nominal,
                                                       const ApproachDirections& dir) const {
  return solve(x_nominal, dir, model_.exact(x_nominal, dir).dP_mm);
}

ThreeAxisCorrection::Result ThreeAxisCorrection::solve(const AxisVector& x_nominal,
                                                       const ApproachDirections& dir,
                                                       const Eigen::Vector3d& dP_nominal_mm) const {
  Result r;
  // First iterate: x_1 = x_n - A^-1 e(x_n); then the fixed point
  // (core/kinematics/fixed_point.h), the iterate clamped into travel.
  Eigen::Vector3d du = -A_inv_ * dP_nominal_mm;
  AxisVector x(3);
  const FixedPointOutcome outcome = iterate_to_fixed_point(
      du, FixedPointLimits{1, kMaxIterations},
      [&](const Eigen::Vector3d& previous) -> Eigen::Vector3d {
        for (int i = 0; i < 3; ++i) {
          const double q = x_nominal[i] + previous[i];
          x[i] = std::clamp(q, min_mm_[i], max_mm_[i]);
          r.clamped |= x[i] != q;
        }
        return -A_inv_ * model_.exact(x, dir).dP_mm;
      },
      [](const Eigen::Vector3d& previous, const Eigen::Vector3d& next) {
        return (next - previous).cwiseAbs().maxCoeff() <= kStepTolerance_mm;
      });
  r.iterations = outcome.iterations;
  r.converged = outcome.converged;
  r.du_mm = du;
  return r;
}

}  // namespace volmap::maps
