#include "gcode/nc_path.h"

#include <algorithm>
#include <cmath>

#include "core/common/units.h"

namespace volmap::nc {

ArcGeometry arc_geometry(const Motion& m) {
  static constexpr int kA0[3] = {0, 2, 1}, kA1[3] = {1, 0, 2}, kN[3] = {2, 1, 0};
  ArcGeometry g;
  g.a0 = kA0[m.plane];
  g.a1 = kA1[m.plane];
  g.normal = kN[m.plane];
  const double sx = m.start_mm[g.a0] - m.center_mm[g.a0], sy = m.start_mm[g.a1] - m.center_mm[g.a1];
  const double ex = m.end_mm[g.a0] - m.center_mm[g.a0], ey = m.end_mm[g.a1] - m.center_mm[g.a1];
  g.radius = std::hypot(sx, sy);
  g.start_angle = std::atan2(sy, sx);
  g.end_radius = std::hypot(ex, ey);
  double end_angle = std::atan2(ey, ex);
  double sweep = end_angle - g.start_angle;
  if (m.clockwise) {
    if (sweep >= -1e-12) sweep -= 2 * M_PI;  // same point: a full circle
  } else {
    if (sweep <= 1e-12) sweep += 2 * M_PI;
  }
  sweep += (m.clockwise ? -2 * M_PI : 2 * M_PI) * m.extra_turns;
  g.sweep = sweep;
  return g;
}

Eigen::Vector3d point_on(const Motion& m, double s) {
  if (m.kind != MotionKind::kArc) return m.start_mm + s * (m.end_mm - m.start_mm);
  const ArcGeometry g = arc_geometry(m);
  const double th = g.start_angle + s * g.sweep;
  Eigen::Vector3d p;
  // Radius varies linearly from start to end (a spiral when they differ
  // within the reader's tolerance); s = 1 is the programmed end point.
  const double r = g.radius + s * (g.end_radius - g.radius);
  p[g.a0] = m.center_mm[g.a0] + r * std::cos(th);
  p[g.a1] = m.center_mm[g.a1] + r * std::sin(th);
  p[g.normal] = m.start_mm[g.normal] + s * (m.end_mm[g.normal] - m.start_mm[g.normal]);
  if (s == 1.0) p = m.end_mm;
  return p;
}

double path_length_mm(const Motion& m) {
  if (m.kind != MotionKind::kArc) return (m.end_mm - m.start_mm).norm();
  const ArcGeometry g = arc_geometry(m);
  return std::hypot(g.radius * g.sweep, m.end_mm[g.normal] - m.start_mm[g.normal]);
}

bool linuxcnc_accepts_radii(double r_start, double r_end, bool inch, double margin) {
  const double spiral_abs = (inch ? 0.002 : 0.02) * std::sqrt(2.0);
  const double abs_err = std::abs(r_start - r_end) + margin;
  const double rel_err = abs_err / std::max(r_start, r_end);
  return !(abs_err > spiral_abs * 100.0 || (rel_err > 0.001 && abs_err > spiral_abs));
}

double distance_to_path(const Motion& m, const Eigen::Vector3d& p) {
  if (m.kind != MotionKind::kArc) {
    const Eigen::Vector3d d = m.end_mm - m.start_mm;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - m.start_mm).dot(d) / len2, 0.0, 1.0) : 0.0;
    return (m.start_mm + t * d - p).norm();
  }
  // Arc or helix: the point of the path at the sample's angle, and the ends.
  const ArcGeometry g = arc_geometry(m);
  const double ang = std::atan2(p[g.a1] - m.center_mm[g.a1], p[g.a0] - m.center_mm[g.a0]);
  double best = std::min((p - m.start_mm).norm(), (p - m.end_mm).norm());
  // Every turn of the sweep that passes this angle.
  const double dir = g.sweep >= 0 ? 1.0 : -1.0;
  double rel = dir * (ang - g.start_angle);
  rel = std::fmod(rel, 2 * M_PI);
  if (rel < 0) rel += 2 * M_PI;
  for (double a = rel; a <= std::abs(g.sweep) + 1e-12; a += 2 * M_PI) {
    const double s = a / std::abs(g.sweep);
    best = std::min(best, (point_on(m, std::clamp(s, 0.0, 1.0)) - p).norm());
  }
  return best;
}

Eigen::Vector2d xy_tangent(const Motion& m, bool at_end) {
  if (m.kind == MotionKind::kArc && m.plane == 0) {
    const Eigen::Vector3d& p = at_end ? m.end_mm : m.start_mm;
    const Eigen::Vector2d radial(p.x() - m.center_mm.x(), p.y() - m.center_mm.y());
    // Counter-clockwise: the radius turned +90 degrees.
    const Eigen::Vector2d t = m.clockwise ? Eigen::Vector2d(radial.y(), -radial.x())
                                          : Eigen::Vector2d(-radial.y(), radial.x());
    const double n = t.norm();
    return n > 0 ? Eigen::Vector2d(t / n) : Eigen::Vector2d::Zero();
  }
  const Eigen::Vector2d d(m.end_mm.x() - m.start_mm.x(), m.end_mm.y() - m.start_mm.y());
  const double n = d.norm();
  return n > 0 ? Eigen::Vector2d(d / n) : Eigen::Vector2d::Zero();
}

double xy_turn_rad(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out, int side,
                   bool& inside) {
  const double cross = t_in.x() * t_out.y() - t_in.y() * t_out.x();
  inside = side == 1 ? cross > 0 : cross < 0;
  return std::atan2(std::abs(cross), std::clamp(t_in.dot(t_out), -1.0, 1.0));
}

Eigen::Vector2d polar_end(const Eigen::Vector2d& at, bool absolute, const double* radius,
                          const double* angle_deg) {
  double px = at.x(), py = at.y();
  if (absolute) {
    const double r = radius ? *radius : std::hypot(py, px);
    const double theta = angle_deg ? *angle_deg * units::kRadPerDeg : std::atan2(py, px);
    return {r * std::cos(theta), r * std::sin(theta)};
  }
  if (radius) {
    const double theta = std::atan2(py, px), r = std::hypot(py, px) + *radius;
    px = r * std::cos(theta);
    py = r * std::sin(theta);
  }
  if (angle_deg) {
    const double theta = std::atan2(py, px) + *angle_deg * units::kRadPerDeg,
                 r = std::hypot(py, px);
    px = r * std::cos(theta);
    py = r * std::sin(theta);
  }
  return {px, py};
}

}  // namespace volmap::nc
