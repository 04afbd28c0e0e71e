#include "gcode/nc_path.h"

#include <cmath>

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

}  // namespace volmap::nc
