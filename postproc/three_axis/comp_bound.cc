#include "postproc/three_axis/comp_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "gcode/nc_path.h"

namespace volmap::post {

Eigen::Vector2d xy_tangent(const nc::Motion& m, bool at_end) {
  if (m.kind == nc::MotionKind::kArc && m.plane == 0) {
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

namespace {

// The turn (rad, 0 .. pi) from t_in to t_out and whether it is towards the
// tool's side (an inside corner).
double turn_of(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out, int side, bool& inside) {
  const double cross = t_in.x() * t_out.y() - t_in.y() * t_out.x();
  inside = side == 1 ? cross > 0 : cross < 0;
  return std::atan2(std::abs(cross), std::clamp(t_in.dot(t_out), -1.0, 1.0));
}

}  // namespace

double comp_corner_factor(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out, int side) {
  if (t_in.isZero(0.0) || t_out.isZero(0.0)) return 2.0;
  bool inside = false;
  const double turn = turn_of(t_in, t_out, side, inside);
  if (!inside || turn <= kLinuxCncCornerTurnRad) return 2.0;
  const double c = std::cos(turn / 2);
  if (c < 1e-6) return std::numeric_limits<double>::infinity();
  return 1 / c + 1 / (c * c);
}

double comp_threshold_term_mm(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out, int side,
                              double r_mm, double margin_rad) {
  if (t_in.isZero(0.0) || t_out.isZero(0.0)) return 0.0;
  bool inside = false;
  const double turn = turn_of(t_in, t_out, side, inside);
  if (std::abs(turn - kLinuxCncCornerTurnRad) > margin_rad) return 0.0;
  const double t = std::max(turn, kLinuxCncCornerTurnRad) + margin_rad;
  return inside ? r_mm * (1 - std::cos(t)) : r_mm * (1 - std::cos(t / 2));
}

}  // namespace volmap::post
