#include "core/kinematics/kinematics.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/kinematics/jacobian.h"

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

namespace {

// fdlibm s_atan.c: atan(x) for x >= 0.
double atan_nonneg(double x) {
  static constexpr double atanhi[] = {4.63647609000806093515e-01, 7.85398163397448278999e-01,
                                      9.82793723247329054082e-01, 1.57079632679489655800e+00};
  static constexpr double atanlo[] = {2.26987774529616870924e-17, 3.06161699786838301793e-17,
                                      1.39033110312309984516e-17, 6.12323399573676603587e-17};
  static constexpr double aT[] = {
      3.33333333333329318027e-01,  -1.99999999998764832476e-01, 1.42857142725034663711e-01,
      -1.11111104054623557880e-01, 9.09088713343650656196e-02,  -7.69187620504482999495e-02,
      6.66107313738753120669e-02,  -5.83357013379057348645e-02, 4.97687799461593236017e-02,
      -3.65315727442169155270e-02, 1.62858201153657823623e-02};
  if (x >= 7.3786976294838206464e19) return atanhi[3] + atanlo[3];  // 2^66
  int id;
  if (x < 0.4375) {
    if (x < 7.450580596923828125e-9) return x;  // 2^-27
    id = -1;
  } else if (x < 1.1875) {
    if (x < 0.6875) {
      id = 0;
      x = (2.0 * x - 1.0) / (2.0 + x);
    } else {
      id = 1;
      x = (x - 1.0) / (x + 1.0);
    }
  } else if (x < 2.4375) {
    id = 2;
    x = (x - 1.5) / (1.0 + 1.5 * x);
  } else {
    id = 3;
    x = -1.0 / x;
  }
  const double z = x * x, w = z * z;
  const double s1 =
      z * (aT[0] + w * (aT[2] + w * (aT[4] + w * (aT[6] + w * (aT[8] + w * aT[10])))));
  const double s2 = w * (aT[1] + w * (aT[3] + w * (aT[5] + w * (aT[7] + w * aT[9]))));
  if (id < 0) return x - x * (s1 + s2);
  return atanhi[id] - ((x * (s1 + s2) - atanlo[id]) - x);
}

constexpr double kTwoPi = 2.0 * M_PI;

// Paden-Kahan subproblem 1: the angle t with Rot(w, t) p = z (w unit; p and
// z with equal components along w and equal lengths).
double subproblem1(const Eigen::Vector3d& w, const Eigen::Vector3d& p, const Eigen::Vector3d& z) {
  const Eigen::Vector3d pp = p - w * w.dot(p);
  const Eigen::Vector3d zp = z - w * w.dot(z);
  return atan2_axis(w.dot(pp.cross(zp)), pp.dot(zp));
}

// Rot(w, t) v by Rodrigues (w unit); deterministic sine and cosine.
Eigen::Vector3d rotate(const Eigen::Vector3d& w, double t, const Eigen::Vector3d& v) {
  return axis_rotation(w, t) * v;
}

bool within_travel(const Machine& m, const AxisVector& u) {
  return first_axis_outside_travel(m, u.data(), m.axis_count()) < 0;
}

}  // namespace

double atan2_axis(double y, double x) {
  // fdlibm e_atan2.c for finite arguments.
  constexpr double kPi = 3.1415926535897931160e+00, kPiLo = 1.2246467991473531772e-16;
  constexpr double kPiO2 = 1.5707963267948965580e+00;
  const double ax = std::abs(x), ay = std::abs(y);
  if (ay == 0.0) return x < 0 ? (std::signbit(y) ? -kPi : kPi) : y;
  if (ax == 0.0) return y > 0 ? kPiO2 : -kPiO2;
  double z;
  if (ay > 1.152921504606846976e18 * ax)  // |y/x| > 2^60
    z = kPiO2 + 0.5 * kPiLo;
  else if (x < 0 && ay * 1.152921504606846976e18 < ax)  // |y/x| < 2^-60, x < 0
    z = 0.0;
  else
    z = atan_nonneg(ay / ax);
  if (x > 0) return y < 0 ? -z : z;
  return y < 0 ? (z - kPiLo) - kPi : kPi - (z - kPiLo);
}

Kinematics::Kinematics(Machine m) : machine_(std::move(m)) {
  int n_linear = 0;
  for (int i = 0; i < machine_.axis_count(); ++i) {
    if (is_rotary(machine_.axis_order[static_cast<size_t>(i)])) continue;
    if (n_linear < 3) linear_[static_cast<size_t>(n_linear)] = i;
    ++n_linear;
  }
  if (n_linear != 3)
    throw std::invalid_argument(fmt::format(
        "machine \"{}\": the backward transformation needs exactly three linear axes, it has {}",
        machine_.name, n_linear));
  // Rotary joints from the workpiece down its chain, then up the tool chain.
  struct Rot {
    const Joint* j;
    double s;
  };
  std::vector<Rot> seq;
  for (auto it = machine_.workpiece_chain.rbegin(); it != machine_.workpiece_chain.rend(); ++it)
    if (it->rotary) seq.push_back({&*it, -1.0});
  for (const Joint& j : machine_.tool_chain)
    if (j.rotary) seq.push_back({&j, +1.0});
  a_ = machine_.tool_axis.normalized();
  if (seq.size() == 2) {
    outer_ = seq[0].j->index;
    inner_ = seq[1].j->index;
    s1_ = seq[0].s;
    s2_ = seq[1].s;
    w1_ = seq[0].j->direction_parent.normalized();
    w2_ = seq[1].j->direction_parent.normalized();
    if (w1_.cross(w2_).norm() < 1e-9)
      throw std::invalid_argument(fmt::format(
          "machine \"{}\": the two rotary axes are parallel; the tool axis cannot be inverted",
          machine_.name));
    if (a_.cross(w2_).norm() < 1e-9)
      throw std::invalid_argument(fmt::format(
          "machine \"{}\": the tool axis lies along rotary axis {}, which cannot tilt it",
          machine_.name, axis_char(seq[1].j->axis)));
    // Frames of the subproblem-2 angles (rotary_solutions): e1 along the
    // part of w2 perpendicular to w1, e2 = w1 x e1; f1 along the part of w1
    // perpendicular to w2, f2 = w2 x f1; and the angle of the tool axis
    // about w2 in the f frame, a constant of the machine.
    const double g = w1_.dot(w2_);
    e1_ = (w2_ - g * w1_).normalized();
    e2_ = w1_.cross(e1_);
    f1_ = (w1_ - g * w2_).normalized();
    f2_ = w2_.cross(f1_);
    a_angle_w2_ = atan2_axis(a_.dot(f2_), a_.dot(f1_));
  } else if (!seq.empty()) {
    throw std::invalid_argument(fmt::format(
        "machine \"{}\": the backward transformation handles zero or two rotary axes, it has {}",
        machine_.name, seq.size()));
  }
  // The linear axes must span space (checked at home).
  PoseJacobian J;
  nominal_forward_jacobian(machine_, machine_.home, J);
  Eigen::Matrix3d Jl;
  for (int k = 0; k < 3; ++k) Jl.col(k) = J.block<3, 1>(0, linear_[static_cast<size_t>(k)]);
  if (std::abs(Jl.determinant()) < 1e-9)
    throw std::invalid_argument(
        fmt::format("machine \"{}\": the linear axes do not span space", machine_.name));
}

bool Kinematics::representative(int index, double q, double reference, double& out) const {
  const AxisLimits& L = machine_.limits[static_cast<size_t>(index)];
  const double c = q + kTwoPi * std::nearbyint((reference - q) / kTwoPi);
  if (L.unlimited) {
    out = c;
    return true;
  }
  bool found = false;
  for (double cand : {c, c - kTwoPi, c + kTwoPi}) {
    if (cand < L.min - kTravelSlack || cand > L.max + kTravelSlack) continue;
    if (!found || std::abs(cand - reference) < std::abs(out - reference)) out = cand;
    found = true;
  }
  return found;
}

AxisVector Kinematics::place_tip(const AxisVector& u, const Eigen::Vector3d& tip_w_mm) const {
  AxisVector out = u;
  nominal_place_tip(machine_, out, tip_w_mm);
  return out;
}

Kinematics::Rotary Kinematics::rotary_solutions(const ToolPose& v_w, const AxisVector& previous,
                                                double singular_sin) const {
  if (previous.size() != machine_.axis_count())
    throw std::invalid_argument(fmt::format("backward: previous position has {} axes, expected {}",
                                            previous.size(), machine_.axis_count()));
  const double len = v_w.axis.norm();
  if (!(std::abs(len - 1.0) <= 1e-6))
    throw std::invalid_argument(
        fmt::format("the tool axis ({:g}, {:g}, {:g}) has length {:g}; expected a unit vector",
                    v_w.axis.x(), v_w.axis.y(), v_w.axis.z(), len));
  const Eigen::Vector3d Q = v_w.axis / len;
  Rotary out;
  if (outer_ < 0) {
    // No rotation: the tool axis in workpiece coordinates is the machine's.
    if ((Q - a_).norm() <= 1e-9) out.count = 1;
    return out;
  }
  auto add = [&](double t1, double t2) {
    std::array<double, 2>& q = out.q[static_cast<size_t>(out.count)];
    if (!representative(outer_, s1_ * t1, previous[outer_], q[0])) return;
    if (!representative(inner_, s2_ * t2, previous[inner_], q[1])) return;
    ++out.count;
  };
  if (Q.cross(w1_).norm() <= singular_sin) {
    // Q along the outer axis: its angle is free; hold it (section 4.1).
    out.singular = true;
    const double t1 = s1_ * previous[outer_];
    const Eigen::Vector3d z = rotate(w1_, -t1, Q);              // Rot(w2, t2) a = z
    if (std::abs(w2_.dot(z) - w2_.dot(a_)) > 1e-9) return out;  // unreachable
    add(t1, subproblem1(w2_, a_, z));
    return out;
  }
  // Paden-Kahan subproblem 2: z = Rot(w2, t2) a = Rot(w1, -t1) Q keeps its
  // components along w2 (from a) and w1 (from Q): z = al w1 + be w2 + ga n.
  const double g = w1_.dot(w2_);
  const double den = 1.0 - g * g;
  const double al = (w1_.dot(Q) - g * w2_.dot(a_)) / den;
  const double be = (w2_.dot(a_) - g * w1_.dot(Q)) / den;
  const Eigen::Vector3d n = w1_.cross(w2_);
  // |z| = 1 would give ga^2 |n|^2 = 1 - al^2 - be^2 - 2 al be g, which
  // cancels catastrophically near the singular position (al -> 1 keeps no
  // trace of a tilt below ~1e-8). Rotation about w1 keeps the length of the
  // part perpendicular to w1, so |z_perp|^2 = |w1 x Q|^2 = rho^2, and with
  // z_perp = be (w2 - g w1) + ga n (two orthogonal parts, |w2 - g w1|^2 =
  // |n|^2 = 1 - g^2):  ga^2 = (rho^2 - be^2 |n|^2) / |n|^2, from the tilt
  // itself. z_perp, not z - w1 (w1.z), goes into the outer angle for the
  // same reason.
  const double rho2 = w1_.cross(Q).squaredNorm();
  const double n2 = n.squaredNorm();
  const double ga2 = (rho2 - be * be * n2) / n2;
  if (ga2 < -1e-12) return out;  // the orientation is out of reach
  const double ga = std::sqrt(std::max(0.0, ga2));
  // Subproblem 1 twice per solution, in closed form: with n = w1 x w2 =
  // |w2 - g w1| e2 = -|w1 - g w2| f2, the parts of z = al w1 + be w2 + s ga n
  // perpendicular to w1 and w2 are proportional to (be, s ga) in (e1, e2)
  // and (al, -s ga) in (f1, f2). The outer angle turns z onto Q about w1,
  // the inner one a onto z about w2:
  //   t1 = angle(Q; e) - atan2(s ga, be),  t2 = atan2(-s ga, al) - angle(a; f).
  // Three atan2 per pose for both solutions (atan2_axis is odd in y, so the
  // second solution's are negations).
  const double q_angle = atan2_axis(Q.dot(e2_), Q.dot(e1_));
  const double outer_offset = atan2_axis(ga, be), inner_angle = atan2_axis(ga, al);
  add(q_angle - outer_offset, -inner_angle - a_angle_w2_);
  if (ga != 0.0) add(q_angle + outer_offset, inner_angle - a_angle_w2_);  // else a double root
  return out;
}

AxisVector Kinematics::placed(const Rotary& r, int k, const AxisVector& previous,
                              const Eigen::Vector3d& tip_w_mm, PoseJacobian* J_v_u) const {
  AxisVector u = previous;
  if (outer_ >= 0) {
    u[outer_] = r.q[static_cast<size_t>(k)][0];
    u[inner_] = r.q[static_cast<size_t>(k)][1];
  }
  nominal_place_tip(machine_, u, tip_w_mm, J_v_u);
  return u;
}

BackwardSolutions Kinematics::backward(const ToolPose& v_w, const AxisVector& previous,
                                       double singular_sin) const {
  const Rotary r = rotary_solutions(v_w, previous, singular_sin);
  BackwardSolutions out;
  out.singular = r.singular;
  for (int k = 0; k < r.count; ++k)
    out.u[static_cast<size_t>(out.count++)] = placed(r, k, previous, v_w.tip_mm);
  return out;
}

int Kinematics::select(const BackwardSolutions& s, const AxisVector& previous,
                       const RotaryWeights& weights) const {
  int best = -1;
  bool best_in = false;
  double best_d = 0;
  for (int k = 0; k < s.count; ++k) {
    const AxisVector& u = s.u[static_cast<size_t>(k)];
    const bool in = within_travel(machine_, u);
    double d = 0;
    for (int i = 0; i < machine_.axis_count(); ++i)
      if (is_rotary(machine_.axis_order[static_cast<size_t>(i)]))
        d += weights[static_cast<size_t>(i)] * (u[i] - previous[i]) * (u[i] - previous[i]);
    if (best < 0 || (in && !best_in) || (in == best_in && d < best_d)) {
      best = k;
      best_in = in;
      best_d = d;
    }
  }
  return best;
}

AxisVector Kinematics::backward_selected(const ToolPose& v_w, const AxisVector& previous,
                                         bool* singular, PoseJacobian* J_v_u) const {
  // The policy of select() with unit weights, placing the linear axes only
  // for the solutions it has to look at: the one with the least rotary
  // travel, and the other only when the first leaves the linear travel.
  const Rotary r = rotary_solutions(v_w, previous, 1e-10);
  if (singular) *singular = r.singular;
  if (r.count == 0)
    throw std::invalid_argument(fmt::format(
        "no axis position of machine \"{}\" reaches the tool axis ({:g}, {:g}, {:g}) within travel",
        machine_.name, v_w.axis.x(), v_w.axis.y(), v_w.axis.z()));
  auto dist = [&](int k) {
    if (outer_ < 0) return 0.0;
    const double d0 = r.q[static_cast<size_t>(k)][0] - previous[outer_];
    const double d1 = r.q[static_cast<size_t>(k)][1] - previous[inner_];
    return d0 * d0 + d1 * d1;
  };
  const int first = r.count == 2 && dist(1) < dist(0) ? 1 : 0;
  AxisVector u = placed(r, first, previous, v_w.tip_mm, J_v_u);
  if (r.count == 2 && !within_travel(machine_, u)) {
    PoseJacobian J_other;
    AxisVector other = placed(r, 1 - first, previous, v_w.tip_mm, J_v_u ? &J_other : nullptr);
    if (within_travel(machine_, other)) {
      if (J_v_u) *J_v_u = J_other;
      return other;
    }
  }
  return u;
}

}  // namespace volmap
