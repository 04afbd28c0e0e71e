#include "core/kinematics.h"

#include <stdexcept>
#include <vector>

#include <Eigen/LU>

namespace volmap {

AxisVector linear_axes_for_tip(const Machine& m, const AxisVector& u,
                               const Eigen::Vector3d& tip_w_mm) {
  std::vector<int> linear;
  for (int i = 0; i < m.axis_count(); ++i)
    if (!is_rotary(m.axis_order[static_cast<size_t>(i)])) linear.push_back(i);
  if (linear.size() != 3)
    throw std::invalid_argument("placing the tool tip needs exactly three linear axes");
  AxisVector base = u;
  for (int i : linear) base[i] = 0.0;
  const Eigen::Vector3d p0 = nominal_forward(m, base).tip_mm;
  Eigen::Matrix3d J;
  for (int k = 0; k < 3; ++k) {
    AxisVector e = base;
    e[linear[static_cast<size_t>(k)]] = 1.0;  // affine: a unit step is exact
    J.col(k) = nominal_forward(m, e).tip_mm - p0;
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(J);
  if (!lu.isInvertible())
    throw std::invalid_argument("the linear axes do not span space at this rotary position");
  const Eigen::Vector3d x = lu.solve(tip_w_mm - p0);
  AxisVector out = u;
  for (int k = 0; k < 3; ++k) out[linear[static_cast<size_t>(k)]] = x[k];
  return out;
}

}  // namespace volmap
