#include "postproc/three_axis/comp_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "gcode/nc_path.h"

namespace volmap::post {

double comp_corner_factor(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out, int side) {
  if (t_in.isZero(0.0) || t_out.isZero(0.0)) return 2.0;
  bool inside = false;
  const double turn = nc::xy_turn_rad(t_in, t_out, side, inside);
  if (!inside || turn <= nc::kLinuxCncCornerTurnRad) return 2.0;
  const double c = std::cos(turn / 2);
  if (c < 1e-6) return std::numeric_limits<double>::infinity();
  return 1 / c + 1 / (c * c);
}

double comp_threshold_term_mm(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out, int side,
                              double r_mm, double margin_rad) {
  if (t_in.isZero(0.0) || t_out.isZero(0.0)) return 0.0;
  bool inside = false;
  const double turn = nc::xy_turn_rad(t_in, t_out, side, inside);
  if (std::abs(turn - nc::kLinuxCncCornerTurnRad) > margin_rad) return 0.0;
  const double t = std::max(turn, nc::kLinuxCncCornerTurnRad) + margin_rad;
  return inside ? r_mm * (1 - std::cos(t)) : r_mm * (1 - std::cos(t / 2));
}

}  // namespace volmap::post
