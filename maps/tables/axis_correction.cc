#include "maps/tables/axis_correction.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <algorithm>
#include <stdexcept>

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
  Eigen::Vector3d du = -A_inv_ * dP_nominal_mm;  // first iterate: x_1 = x_n - A^-1 e(x_n)
  AxisVector x(3);
  for (r.iterations = 1; r.iterations < kMaxIterations; ++r.iterations) {
    for (int i = 0; i < 3; ++i) {
      const double q = x_nominal[i] + du[i];
      x[i] = std::clamp(q, min_mm_[i], max_mm_[i]);
      r.clamped |= x[i] != q;
    }
    const Eigen::Vector3d next = -A_inv_ * model_.exact(x, dir).dP_mm;
    const double step = (next - du).cwiseAbs().maxCoeff();
    du = next;
    if (step <= kStepTolerance_mm) {
      r.converged = true;
      break;
    }
  }
  r.du_mm = du;
  return r;
}

}  // namespace volmap::maps
