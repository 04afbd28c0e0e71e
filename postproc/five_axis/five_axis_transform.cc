#include "postproc/five_axis/five_axis_transform.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>

#include "core/kinematics/jacobian.h"

namespace volmap::post {

FiveAxisTransform::FiveAxisTransform(const Machine& machine, const ErrorSet& errors,
                                     OutsidePolicy outside, CorrectionOptions correction)
    : kin_(machine), zero_(errors_all_zero(errors)) {
  if (!kin_.has_rotary_axes())
    throw std::invalid_argument("the five-axis post needs a machine with two rotary axes");
  if (!zero_) {
    ModelOptions mo;
    mo.outside = outside;
    model_ = std::make_unique<ErrorModel>(machine, errors, mo);
    solver_ = std::make_unique<CorrectionSolver>(*model_, correction);
  }
}

AxisVector FiveAxisTransform::axes_for_pose(const ToolPose& v_w, const AxisVector& previous,
                                            bool* singular) const {
  const Eigen::Vector3d& w1 = kin_.outer_axis_w();
  if (v_w.axis.cross(w1).norm() > kSingularSin)
    return kin_.backward_selected(v_w, previous, singular);
  // Within kSingularSin of the outer axis: the axis itself (an orientation
  // change below 1e-7 rad), so that the outer angle is held.
  const ToolPose snapped{v_w.tip_mm,
                         v_w.axis.dot(w1) >= 0 ? Eigen::Vector3d(w1) : Eigen::Vector3d(-w1)};
  return kin_.backward_selected(snapped, previous, singular);
}

FiveAxisTransform::FiveAxisTransform(const Machine& machine, const maps::VolumetricTable& table,
                                     OutsidePolicy outside)
    : kin_(machine), table_(&table), outside_(outside) {
  if (!kin_.has_rotary_axes())
    throw std::invalid_argument("the five-axis post needs a machine with two rotary axes");
  if (table.axis_count() != machine.axis_count())
    throw std::invalid_argument(fmt::format("the table has {} axes, machine \"{}\" {}",
                                            table.axis_count(), machine.name,
                                            machine.axis_count()));
  if (table.channel_count() > 16) throw std::invalid_argument("the table has too many channels");
  static constexpr const char* kNames[6] = {"ex", "ey", "ez", "ei", "ej", "ek"};
  for (size_t c = 0; c < 6; ++c) {
    const std::optional<int> k = table.channel(kNames[c]);
    if (!k)
      throw std::invalid_argument(std::string("the table has no channel ") + kNames[c] +
                                  "; build it for the five-axis machine with volmap map");
    channel_[c] = *k;
  }
}

void FiveAxisTransform::table_dv(const AxisVector& u, Eigen::Vector3d& dP,
                                 Eigen::Vector3d& dQ) const {
  double v[16];
  maps::interpolate(*table_, u, 0, table_->checked_with, outside_, v);
  dP = Eigen::Vector3d(v[channel_[0]], v[channel_[1]], v[channel_[2]]);
  dQ = Eigen::Vector3d(v[channel_[3]], v[channel_[4]], v[channel_[5]]);
}

AxisVector FiveAxisTransform::command(const AxisVector& u_nominal, bool* singular) const {
  if (zero_) {
    if (singular) *singular = false;
    return u_nominal;
  }
  if (table_) {
    // du = -J^-1 dv (eq. 6), block-wise as the model's correction.
    PoseJacobian J;
    nominal_forward_jacobian(kin_.machine(), u_nominal, J);
    Eigen::Vector3d dP, dQ;
    table_dv(u_nominal, dP, dQ);
    AxisVector du;
    const bool sing =
        correction_step(kin_, J, dP, dQ, CorrectionOptions{}.singular_sin, du, kPostOuterDamping);
    const AxisVector c = u_nominal + du;
    if (singular) *singular = sing;
    return c;
  }
  const CorrectionResult r = solver_->correct(u_nominal);
  if (singular) *singular = r.singular;
  return u_nominal + r.du;
}

ToolPose FiveAxisTransform::actual(const AxisVector& u) const {
  if (zero_) return nominal_forward(kin_.machine(), u);
  if (table_) {
    ToolPose v = nominal_forward(kin_.machine(), u);
    Eigen::Vector3d dP, dQ;
    table_dv(u, dP, dQ);
    v.tip_mm += dP;
    v.axis = (v.axis + dQ).normalized();
    return v;
  }
  return model_->actual(u);
}

void append_number(std::string& out, double value, int decimals) {
  static constexpr double kPow10[] = {1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
  if (decimals < 0 || decimals > 9 || !std::isfinite(value) ||
      std::abs(value) * kPow10[decimals] > 9e15) {
    std::string s = fmt::format("{:.{}f}", value, decimals < 0 ? 0 : decimals);
    if (s.find('.') != std::string::npos) {
      while (s.back() == '0') s.pop_back();
      if (s.back() == '.') s.pop_back();
    }
    if (s == "-0") s = "0";
    out += s;
    return;
  }
  const double scaled = std::nearbyint(value * kPow10[decimals]);
  std::int64_t n = static_cast<std::int64_t>(scaled);
  if (n == 0) {
    out += '0';
    return;
  }
  char buf[24];
  char* end = buf + sizeof buf;
  char* p = end;
  const bool negative = n < 0;
  if (negative) n = -n;
  // Drop trailing zeros of the fraction.
  int d = decimals;
  while (d > 0 && n % 10 == 0) {
    n /= 10;
    --d;
  }
  for (int k = 0; k < d; ++k) {
    *--p = static_cast<char>('0' + n % 10);
    n /= 10;
  }
  if (d > 0) *--p = '.';
  do {
    *--p = static_cast<char>('0' + n % 10);
    n /= 10;
  } while (n > 0);
  if (negative) *--p = '-';
  out.append(p, static_cast<size_t>(end - p));
}

ToolTransforms::ToolTransforms(const Machine& machine, std::map<int, double> offsets_mm,
                               Build build)
    : machine_(machine), offsets_mm_(std::move(offsets_mm)), build_(std::move(build)) {}

const FiveAxisTransform& ToolTransforms::get(int tool) {
  auto& slot = built_[tool];
  if (slot) return *slot;
  Machine m = machine_;
  if (tool >= 0) {
    const auto it = offsets_mm_.find(tool);
    if (it == offsets_mm_.end())
      throw std::invalid_argument("tool T" + std::to_string(tool) + " is not in the tool table");
    if (std::isnan(m.measurement_tool_length_mm)) m.measurement_tool_length_mm = m.tool_length_mm;
    m.tool_length_mm += it->second;
  }
  slot = build_(m);
  return *slot;
}

const FiveAxisTransform& ToolTransforms::change_to(int tool, bool moved) {
  if (!has_table()) {
    if (moved && tool_ >= 0 && tool != tool_)
      throw std::invalid_argument(
          "a second tool (T" + std::to_string(tool) + " after T" + std::to_string(tool_) +
          "): the machine axes are computed for the machine file's tool length; give "
          "--tool-table with the program's tools, or post each tool's part separately");
    tool_ = tool;
    return get(-1);
  }
  try {
    const FiveAxisTransform& t = get(tool);
    tool_ = tool;
    return t;
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(e.what()) + "; add it to the tool table");
  }
}

}  // namespace volmap::post
