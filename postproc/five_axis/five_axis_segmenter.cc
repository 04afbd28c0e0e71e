// FiveAxisPost::segment: a move cut into pieces until the actual tool tip
// and axis stay within the tolerances of the nominal path
// (five_axis_post.h).
#include <algorithm>
#include <cmath>
#include <vector>

#include "postproc/five_axis/five_axis_program_post.h"

namespace volmap::post::five_axis_detail {

void FiveAxisPost::start_if_needed(const FiveAxisMove& m) {
  if (started_) return;
  // The first move starts where the reader's initial pose is.
  const NominalAt n = nominal_at(m, 0.0, u_nom_);
  u_nom_ = n.u;
  c_ = tf_->command(n.u);
  residual_angle_ = tf_->zero() ? 0.0 : angle_between(tf_->actual(c_).axis, n.v.axis);
  started_ = true;
}

void FiveAxisPost::segment(const FiveAxisMove& m, std::vector<Piece>& pieces) {
  pieces.clear();
  // The checks aim at 3/4 of the tolerances: the rest is for the rounding of
  // the written numbers and for the deviation between the checked points.
  const double tol = 0.75 * o_.tolerance_mm, atol = 0.75 * o_.angle_tolerance_rad;
  int n0 = 1;
  if (m.tip.kind == nc::MotionKind::kArc) {
    const nc::ArcGeometry g = nc::arc_geometry(m.tip);
    const double r = std::max(g.radius, g.end_radius);
    const double max_step = r > tol / 4 ? 2.0 * std::acos(1.0 - (tol / 4) / r) : M_PI / 2;
    n0 = std::max(4, static_cast<int>(std::ceil(std::abs(g.sweep) / max_step)));
  }
  if (!m.by_angles && angle_between(m.a0, m.a1) > M_PI - 1e-6)
    fail(
        "the tool axis turns by 180 degrees in one move; its path is undefined: add a point "
        "between");
  const Machine& mach = tf_->machine();
  constexpr int kMaxPieces = 1 << 16;
  std::vector<std::pair<double, double>>& stack = stack_;
  stack.clear();
  double s_prev = 0.0;
  for (int k = 1; k <= n0; ++k) {
    stack.push_back({s_prev, static_cast<double>(k) / n0});
    while (!stack.empty()) {
      const auto [s0, s1] = stack.back();
      stack.pop_back();
      const NominalAt n1 = nominal_at(m, s1, u_nom_);
      const AxisVector c1 = command(n1.u);
      // What the correction leaves of the tool-axis error at the ends (the
      // singular position: the part only the outer axis could turn) is
      // allowed between them too.
      const double r1 = tf_->zero() ? 0.0 : angle_between(tf_->actual(c1).axis, n1.v.axis);
      const double allowed_angle = atol + std::max(residual_angle_, r1);
      bool ok = true;
      for (int k2 = 0; k2 < mach.axis_count() && ok; ++k2)
        if (is_rotary(mach.axis_order[static_cast<size_t>(k2)]) &&
            std::abs(c1[k2] - c_[k2]) >= M_PI / 2)
          ok = false;  // C continuity: never half a turn in one piece
      for (double t : {0.25, 0.5, 0.75}) {
        if (!ok) break;
        const AxisVector u = c_ + t * (c1 - c_);
        const ToolPose a = tf_->actual(u);
        const double s = s0 + t * (s1 - s0);
        const Vector3d q_nom = m.by_angles
                                   ? tf_->nominal(tf_->axes_for_angles(m.q0 + s * (m.q1 - m.q0),
                                                                       nc::point_on(m.tip, s)))
                                         .axis
                                   : slerp_axis(m.a0, m.a1, s);
        if (nc::distance_to_path(m.tip, a.tip_mm) > tol ||
            angle_between(a.axis, q_nom) > allowed_angle)
          ok = false;
      }
      if (ok || s1 - s0 < 1e-7) {
        if (n1.singular) ++report_.singular_poses;
        if (ok)
          turn_.assign(1, Piece{c1, s1, false});
        else
          turn_over_jump(m, s0, s1, n1, c1, tol);
        for (const Piece& pc : turn_) {
          for (int k2 = 0; k2 < mach.axis_count(); ++k2)
            if (is_rotary(mach.axis_order[static_cast<size_t>(k2)]))
              report_.max_rotary_step_rad =
                  std::max(report_.max_rotary_step_rad, std::abs(pc.c[k2] - c_[k2]));
          pieces.push_back(pc);
          c_ = pc.c;
        }
        if (pieces.size() > kMaxPieces)
          fail(fmt::format(
              "more than {} pieces needed to keep {:g} µm and {:g} µrad; raise the tolerances",
              kMaxPieces, o_.tolerance_mm * 1e3, o_.angle_tolerance_rad * 1e6));
        u_nom_ = n1.u;
        residual_angle_ = r1;
        s_prev = s1;
        if (!stack.empty()) {
          const double end = stack.front().second;
          stack.clear();
          stack.push_back({s1, end});
        }
      } else {
        const double mid = 0.5 * (s0 + s1);
        stack.push_back({mid, s1});
        stack.push_back({s0, mid});
      }
    }
  }
}

void FiveAxisPost::turn_over_jump(const FiveAxisMove& m, double s0, double s1, const NominalAt& n1,
                                  const AxisVector& c1, double tol) {
  // The backward solution jumps here (C turning to the new azimuth
  // as the tool leaves the singular position): turn the rotary
  // axes over the jump with the tip held on the path — linear in
  // the rotary axes, each position placing the tip (and corrected)
  // — in as many pieces as the tip tolerance needs.
  const AxisVector u0 = u_nom_;
  for (int n = 2;; n *= 2) {
    turn_.clear();
    bool pass = true;
    AxisVector cprev = c_;
    for (int k = 1; k <= n && pass; ++k) {
      const double t = static_cast<double>(k) / n, s = s0 + t * (s1 - s0);
      const AxisVector uk =
          k == n ? n1.u : tf_->axes_for_angles(u0 + t * (n1.u - u0), nc::point_on(m.tip, s));
      const AxisVector ck = k == n ? c1 : command(uk);
      for (double tt : {0.25, 0.5, 0.75})
        if (nc::distance_to_path(m.tip, tf_->actual(cprev + tt * (ck - cprev)).tip_mm) > tol)
          pass = false;
      turn_.push_back({ck, s, true});
      cprev = ck;
    }
    if (pass || n >= 4096) break;
  }
}

}  // namespace volmap::post::five_axis_detail
