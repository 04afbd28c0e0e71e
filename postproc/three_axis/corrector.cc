#include "postproc/three_axis/corrector.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/kinematics/fixed_point.h"
#include "maps/tables/volumetric_table.h"

namespace volmap::post {
namespace {

// Maxima over a table's range of |value|, |slope| and |second derivative| of
// each component's cubic Hermite interpolant, interval by interval: p'' is
// linear on an interval (its maximum is at an end), p' is quadratic (its
// maximum is at an end or at its vertex), |p| <= max(|y0|, |y1|) + 4/27 h (|m0| + |m1|) (the
// Hermite basis functions of the slopes stay below 4/27 h).
struct ComponentMaxima {
  std::array<double, kComponentCount> value{}, slope{}, second{};
};

void add_table_maxima(const AxisErrorTable& t, ComponentMaxima& b) {
  const std::size_t n = t.position.size();
  for (int c = 0; c < kComponentCount; ++c) {
    const auto k = static_cast<std::size_t>(c);
    if (n == 1) b.value[k] = std::max(b.value[k], std::abs(t.value[0][k]));
    for (std::size_t i = 0; i + 1 < n; ++i) {
      const double h = t.position[i + 1] - t.position[i];
      const double y0 = t.value[i][k], y1 = t.value[i + 1][k];
      const double m0 = t.slope[i][k], m1 = t.slope[i + 1][k];
      const double d = (y1 - y0) / h;
      const double p2 =
          std::max(std::abs(6 * d - 4 * m0 - 2 * m1), std::abs(-6 * d + 2 * m0 + 4 * m1)) / h;
      b.second[k] = std::max(b.second[k], p2);
      // p'(s) = a s^2 + b s + m0 on s in [0, 1]: its largest size is at an
      // end or at the vertex.
      const double qa = (6 * (y0 - y1) / h + 3 * (m0 + m1)), qb = (6 * d - 4 * m0 - 2 * m1);
      double p1 = std::max(std::abs(m0), std::abs(m1));
      if (qa != 0) {
        const double sv = -qb / (2 * qa);
        if (sv > 0 && sv < 1) p1 = std::max(p1, std::abs((qa * sv + qb) * sv + m0));
      }
      b.slope[k] = std::max(b.slope[k], p1);
      b.value[k] = std::max(b.value[k], std::max(std::abs(y0), std::abs(y1)) +
                                            4.0 / 27.0 * h * (std::abs(m0) + std::abs(m1)));
    }
  }
}

double norm3(const std::array<double, kComponentCount>& v, int first) {
  const auto f = static_cast<std::size_t>(first);
  return std::sqrt(v[f] * v[f] + v[f + 1] * v[f + 1] + v[f + 2] * v[f + 2]);
}

double operator_norm(const Eigen::Matrix3d& A) {
  return Eigen::JacobiSVD<Eigen::Matrix3d>(A).singularValues()(0);
}

// d(machine coordinate)/d(tip, workpiece frame) of a three-linear-axis
// machine: the inverse of d tip / d u, exact by differences since the tip is
// affine in u.
Eigen::Matrix3d machine_per_tip(const Machine& machine) {
  const AxisVector zero = AxisVector::Zero(3);
  const Eigen::Vector3d tip0 = nominal_forward(machine, zero).tip_mm;
  Eigen::Matrix3d A;  // d tip / d u
  for (int k = 0; k < 3; ++k) {
    AxisVector e = zero;
    e[k] = 1.0;
    A.col(k) = nominal_forward(machine, e).tip_mm - tip0;
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(A);
  if (!lu.isInvertible())
    throw std::invalid_argument("the machine's linear axes do not span space");
  return lu.inverse();
}

}  // namespace

Corrector::Corrector(const Machine& machine, const ErrorSet& errors, double tool_length_mm,
                     OutsidePolicy outside) {
  if (machine.axis_count() != 3 || machine.has_rotary_axes())
    throw std::invalid_argument(
        "the three-axis post-processor needs a machine with axes X, Y, Z only");
  // Reference tool: machine coordinates are axis values.
  M_u_tip_ = machine_per_tip(machine);
  const AxisVector zero = AxisVector::Zero(3);
  const Eigen::Vector3d tip0 = nominal_forward(machine, zero).tip_mm;
  Machine with_tool = machine;
  if (std::isnan(with_tool.measurement_tool_length_mm))
    with_tool.measurement_tool_length_mm = machine.tool_length_mm;
  with_tool.tool_length_mm = tool_length_mm;
  const Eigen::Vector3d tipL = nominal_forward(with_tool, zero).tip_mm;
  axis_shift_mm_ = M_u_tip_ * (tip0 - tipL);
  zero_ = errors_all_zero(errors);
  for (int a = 0; a < 3; ++a) {
    const AxisErrors* ax = errors.errors_of(machine.axis_order[static_cast<size_t>(a)]);
    bidirectional_[static_cast<size_t>(a)] = ax && ax->bidirectional();
  }
  model_ = std::make_unique<ErrorModel>(std::move(with_tool), errors,
                                        ModelOptions{Formulation::kIndependent, outside});
  compute_bounds(machine, errors);
  finish_setup();
}

void Corrector::finish_setup() {
  const double L = lipschitz_;
  step_factor_ = L < 0.5 ? L / (1.0 - L) : std::numeric_limits<double>::infinity();
  identity_u_tip_ = M_u_tip_ == Eigen::Matrix3d::Identity();
}

Corrector::Corrector(const Machine& machine, const maps::VolumetricTable& table,
                     OutsidePolicy outside)
    : table_(&table), outside_(outside) {
  if (machine.axis_count() != 3 || machine.has_rotary_axes())
    throw std::invalid_argument(
        "the three-axis post-processor needs a machine with axes X, Y, Z only");
  if (table.axis_count() != 3 || !table.three_axis_correction())
    throw std::invalid_argument(
        "the table is not a three-axis table (volmap map of a machine with axes X, Y, Z)");
  if (table.machine_name != machine.name)
    throw std::invalid_argument(
        fmt::format("the table was made for machine \"{}\", not \"{}\"; "
                    "make it again with volmap map for this machine",
                    table.machine_name, machine.name));
  for (int c = 0; c < 3; ++c)
    if (table.channel(std::string("e") + "xyz"[c]) != c)
      throw std::invalid_argument("the table's first channels are not ex ey ez");
  M_u_tip_ = machine_per_tip(machine);
  axis_shift_mm_.setZero();  // the machine file's tool: machine coordinates are axis values
  zero_ = true;
  for (int layer = 0; layer < table.layer_count() && zero_; ++layer)
    for (std::int64_t node = 0; node < table.node_count() && zero_; ++node) {
      const double* v = table.at(layer, node);
      zero_ = v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0;
    }
  for (int a : table.bidirectional_axes) bidirectional_[static_cast<size_t>(a)] = true;
  for (int a = 0; a < 3; ++a) {
    const maps::GridAxis& g = table.grid[static_cast<size_t>(a)];
    box_lo_[a] = g.start;
    box_hi_[a] = g.end;
  }
  lipschitz_ = curvature_ = std::numeric_limits<double>::infinity();
  finish_setup();
}

Eigen::Vector3d Corrector::table_error(const Eigen::Vector3d& u_mm,
                                       const ApproachDirections& dir) const {
  const maps::VolumetricTable& t = *table_;
  AxisVector u(3);
  u << u_mm.x(), u_mm.y(), u_mm.z();
  // The layers the directions allow: an axis with a direction fixes its
  // bit; one without (not moved yet) takes both, averaged.
  double v[64];
  if (t.channel_count() > 64) throw std::invalid_argument("the table has too many channels");
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int used = 0;
  for (int layer = 0; layer < t.layer_count(); ++layer) {
    const ApproachDirections ld = t.layer_directions(layer);
    bool fits = true;
    for (int a : t.bidirectional_axes)
      fits = fits && (dir[static_cast<size_t>(a)] == 0 ||
                      dir[static_cast<size_t>(a)] == ld[static_cast<size_t>(a)]);
    if (!fits) continue;
    maps::interpolate(t, u, layer, t.checked_with, outside_, v);
    sum += Eigen::Vector3d(v[0], v[1], v[2]);
    ++used;
  }
  return sum / static_cast<double>(used);
}

void Corrector::compute_bounds(const Machine& machine, const ErrorSet& errors) {
  // The box: every axis inside its tables (both directions), or inside its
  // travel when it has no table.
  Eigen::Vector3d lo, hi;
  std::array<ComponentMaxima, kAxisNameCount> maxima{};
  for (int a = 0; a < 3; ++a) {
    const auto k = static_cast<std::size_t>(a);
    const AxisName name = machine.axis_order[k];
    lo[a] = machine.limits[k].min;
    hi[a] = machine.limits[k].max;
    if (const AxisErrors* ax = errors.errors_of(name)) {
      lo[a] = ax->plus.min_position();
      hi[a] = ax->plus.max_position();
      add_table_maxima(ax->plus, maxima[static_cast<std::size_t>(name)]);
      if (ax->bidirectional()) {
        lo[a] = std::max(lo[a], ax->minus.min_position());
        hi[a] = std::min(hi[a], ax->minus.max_position());
        add_table_maxima(ax->minus, maxima[static_cast<std::size_t>(name)]);
      }
    }
  }
  box_lo_ = lo - axis_shift_mm_;
  box_hi_ = hi - axis_shift_mm_;
  if (!(lo.array() <= hi.array()).all()) {  // no box: no bound
    lipschitz_ = curvature_ = std::numeric_limits<double>::infinity();
    return;
  }
  // Levers of the angular errors: affine in the axes on a three-linear-axis
  // machine, so their largest length is at a corner of the box and their
  // derivative is constant (a unit step of each axis).
  std::vector<ErrorModel::JointLever> lv, lv_step;
  AxisVector u(3);
  std::vector<double> lever_max;
  for (int corner = 0; corner < 8; ++corner) {
    for (int a = 0; a < 3; ++a) u[a] = (corner >> a) & 1 ? hi[a] : lo[a];
    model_->levers(u, lv);
    lever_max.resize(lv.size(), 0.0);
    for (std::size_t j = 0; j < lv.size(); ++j)
      lever_max[j] = std::max(lever_max[j], lv[j].lever_component_mm.norm());
  }
  u = lo;
  model_->levers(u, lv);
  std::vector<Eigen::Matrix3d> d_lever(lv.size(), Eigen::Matrix3d::Zero());
  std::vector<Eigen::Matrix3d> d_lever_location(lv.size(), Eigen::Matrix3d::Zero());
  for (int a = 0; a < 3; ++a) {
    AxisVector us = u;
    us[a] += 1.0;
    model_->levers(us, lv_step);
    for (std::size_t j = 0; j < lv.size(); ++j) {
      d_lever[j].col(a) = lv_step[j].lever_component_mm - lv[j].lever_component_mm;
      d_lever_location[j].col(a) = lv_step[j].lever_location_mm - lv[j].lever_location_mm;
    }
  }
  // First order: e = sum_j sign R_w_L (delta_j(q_j) + eps_j(q_j) x r_j(u)
  // + eps0_j x r0_j(u)) (eps0: the constant location tilts), so
  //   |De v|      <= |v|   sum_j |delta'| + |eps'| |r| + |eps| |Dr| + |eps0| |Dr0|
  //   |D2e[v, v]| <= |v|^2 sum_j |delta''| + |eps''| |r| + 2 |eps'| |Dr|.
  double k1 = 0.0, k2 = 0.0;
  for (std::size_t j = 0; j < lv.size(); ++j) {
    const ComponentMaxima& m = maxima[static_cast<std::size_t>(lv[j].axis)];
    const double dr = operator_norm(d_lever[j]);
    double eps0 = 0.0;
    for (int c = 3; c < kComponentCount; ++c) {
      const double v =
          errors.location_error(error_name_string({static_cast<Component>(c), lv[j].axis, true}));
      eps0 += v * v;
    }
    k1 += norm3(m.slope, 0) + norm3(m.slope, 3) * lever_max[j] + norm3(m.value, 3) * dr +
          std::sqrt(eps0) * operator_norm(d_lever_location[j]);
    k2 += norm3(m.second, 0) + norm3(m.second, 3) * lever_max[j] + 2 * norm3(m.slope, 3) * dr;
  }
  constexpr double kSafety = 1.5;  // terms of second order in the errors
  const double to_machine = operator_norm(M_u_tip_);
  lipschitz_ = kSafety * to_machine * k1;
  curvature_ = kSafety * to_machine * k2;
}

bool Corrector::in_bound_box(const Eigen::Vector3d& p) const {
  return (p.array() >= box_lo_.array()).all() && (p.array() <= box_hi_.array()).all();
}

double Corrector::chord_deviation_bound(const Eigen::Vector3d& c0,
                                        const Eigen::Vector3d& c1) const {
  if (!in_bound_box(c0) || !in_bound_box(c1)) return std::numeric_limits<double>::infinity();
  return curvature_ * (c1 - c0).squaredNorm() / 8.0;
}

Eigen::Vector3d Corrector::error_at(const Eigen::Vector3d& p, const ApproachDirections& dir) const {
  if (zero_) return Eigen::Vector3d::Zero();
  if (table_) return M_u_tip_ * table_error(p + axis_shift_mm_, dir);
  const double u[3] = {p.x() + axis_shift_mm_.x(), p.y() + axis_shift_mm_.y(),
                       p.z() + axis_shift_mm_.z()};
  // (The identity's product is the vector itself, but for the sign of an
  // exact zero, which no written number shows.)
  if (identity_u_tip_) return model_->tip_error_linear(u, dir);
  return M_u_tip_ * model_->tip_error_linear(u, dir);
}

Eigen::Vector3d Corrector::error_with_play(const Eigen::Vector3d& p,
                                           const Eigen::Vector3d& h) const {
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

double Corrector::reversal_jump_mm(const Eigen::Vector3d& p, int a, ApproachDirections d) const {
  if (!bidirectional(a)) return 0.0;
  d[static_cast<size_t>(a)] = 1;
  const Eigen::Vector3d plus = error_at(p, d);
  d[static_cast<size_t>(a)] = -1;
  return (plus - error_at(p, d)).norm();
}

void Corrector::take_up_play(const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                             Eigen::Vector3d& h) const {
  for (int a = 0; a < 3; ++a) {
    const double travel = to[a] - from[a];
    if (travel == 0.0 || !bidirectional(a)) continue;
    const double w = play_width_mm(a, to);
    h[a] = w < 1e-9 ? (travel > 0 ? 1.0 : -1.0) : std::clamp(h[a] + 2.0 * travel / w, -1.0, 1.0);
  }
}

double Corrector::play_width_mm(int a, const Eigen::Vector3d& p) const {
  if (!bidirectional_[static_cast<size_t>(a)]) return 0.0;
  if (table_) {  // the difference of the two layers' tip errors along the axis
    ApproachDirections plus{}, minus{};
    plus[static_cast<size_t>(a)] = 1;
    minus[static_cast<size_t>(a)] = -1;
    const Eigen::Vector3d u = p + axis_shift_mm_;
    return std::abs((M_u_tip_ * (table_error(u, plus) - table_error(u, minus)))[a]);
  }
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
  return iterate(p_nominal, dir, p_nominal, 1e-12);
}

Eigen::Vector3d Corrector::command_for(const Eigen::Vector3d& p_nominal,
                                       const ApproachDirections& dir,
                                       const Eigen::Vector3d& nearby_correction,
                                       double accuracy_mm) const {
  if (zero_) return p_nominal;
  return iterate(p_nominal, dir, p_nominal + nearby_correction, accuracy_mm);
}

// Fixed point of x = p - e(x): e varies by micrometres per 100 mm, so the
// map is a strong contraction (factor L = lipschitz_bound(), about 1e-4).
// Stops when the step is below 1e-12 mm, or, inside the bound box, when the
// distance to the fixed point, at most L / (1 - L) times the step, is below
// accuracy_mm. The iteration is core/kinematics/fixed_point.h's.
Eigen::Vector3d Corrector::iterate(const Eigen::Vector3d& p, const ApproachDirections& dir,
                                   Eigen::Vector3d x, double accuracy_mm) const {
  const double factor = step_factor_;
  iterate_to_fixed_point(
      x, FixedPointLimits{0, 21},
      [&](const Eigen::Vector3d& previous) -> Eigen::Vector3d {
        return p - error_at(previous, dir);
      },
      [&](const Eigen::Vector3d& previous, const Eigen::Vector3d& next) {
        const double step = (next - previous).norm();
        return step < 1e-12 ||
               (factor * step < accuracy_mm && in_bound_box(previous) && in_bound_box(next));
      });
  return x;
}

}  // namespace volmap::post
