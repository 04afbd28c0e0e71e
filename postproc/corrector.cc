#include "postproc/corrector.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/LU>

namespace volmap::post {

Corrector::Corrector(const Machine& machine, const ErrorSet& errors,
                     double tool_length_mm, OutsidePolicy outside) {
  if (machine.axis_count() != 3 || machine.has_rotary_axes())
    throw std::invalid_argument("the three-axis post-processor needs a machine with axes X, Y, Z only");
  // Reference tool: machine coordinates are axis values. Tip is affine in u.
  const AxisVector zero = AxisVector::Zero(3);
  const Eigen::Vector3d tip0 = nominal_forward(machine, zero).tip_mm;
  Eigen::Matrix3d A;  // d tip / d u
  for (int k = 0; k < 3; ++k) {
    AxisVector e = zero;
    e[k] = 1.0;
    A.col(k) = nominal_forward(machine, e).tip_mm - tip0;
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(A);
  if (!lu.isInvertible()) throw std::invalid_argument("the machine's linear axes do not span space");
  M_u_tip_ = lu.inverse();
  Machine with_tool = machine;
  if (std::isnan(with_tool.measurement_tool_length_mm))
    with_tool.measurement_tool_length_mm = machine.tool_length_mm;
  with_tool.tool_length_mm = tool_length_mm;
  const Eigen::Vector3d tipL = nominal_forward(with_tool, zero).tip_mm;
  axis_shift_mm_ = M_u_tip_ * (tip0 - tipL);
  bool any = !errors.location.empty();
  for (const auto& a : errors.axis) any = any || a.has_value();
  zero_ = !any;
  for (int a = 0; a < 3; ++a) {
    const AxisErrors* ax = errors.errors_of(machine.axis_order[static_cast<size_t>(a)]);
    bidirectional_[static_cast<size_t>(a)] = ax && ax->bidirectional();
  }
  model_ = std::make_unique<ErrorModel>(std::move(with_tool), errors, ModelOptions{Formulation::kIndependent, outside});
}

Eigen::Vector3d Corrector::error_at(const Eigen::Vector3d& p, const ApproachDirections& dir) const {
  if (zero_) return Eigen::Vector3d::Zero();
  AxisVector u(3);
  u << p.x() + axis_shift_mm_.x(), p.y() + axis_shift_mm_.y(), p.z() + axis_shift_mm_.z();
  return M_u_tip_ * model_->exact(u, dir).dP_mm;
}

Eigen::Vector3d Corrector::error_with_play(const Eigen::Vector3d& p, const Eigen::Vector3d& h) const {
  if (zero_) return Eigen::Vector3d::Zero();
  Eigen::Vector3d e = error_at(p, ApproachDirections{});
  for (int a = 0; a < 3; ++a) {
    if (!bidirectional_[static_cast<size_t>(a)] || h[a] == 0.0) continue;
    ApproachDirections plus{}, minus{};
    plus[static_cast<size_t>(a)] = 1;
    minus[static_cast<size_t>(a)] = -1;
    e += h[a] * 0.5 * (error_at(p, plus) - error_at(p, minus));
  }
  return e;
}

double Corrector::play_width_mm(int a, const Eigen::Vector3d& p) const {
  if (!bidirectional_[static_cast<size_t>(a)]) return 0.0;
  const Machine& m = model_->machine();
  const AxisName name = m.axis_order[static_cast<size_t>(a)];
  const AxisErrors* ax = model_->errors().errors_of(name);
  std::array<double, kComponentCount> plus, minus;
  const double q = p[a] + axis_shift_mm_[a];
  evaluate_axis(*ax, q, 1, model_->options().outside, plus);
  evaluate_axis(*ax, q, -1, model_->options().outside, minus);
  const int own = static_cast<int>(name);  // EXX for X, EYY for Y, EZZ for Z
  return std::abs(plus[static_cast<size_t>(own)] - minus[static_cast<size_t>(own)]);
}

Eigen::Vector3d Corrector::command_for(const Eigen::Vector3d& p_nominal,
                                       const ApproachDirections& dir) const {
  if (zero_) return p_nominal;
  // Fixed point of x = p - e(x): e varies by micrometres per 100 mm, so the
  // map is a strong contraction; a handful of steps reach 1e-12 mm.
  Eigen::Vector3d x = p_nominal - error_at(p_nominal, dir);
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector3d next = p_nominal - error_at(x, dir);
    const double step = (next - x).norm();
    x = next;
    if (step < 1e-12) break;
  }
  return x;
}

}  // namespace volmap::post
