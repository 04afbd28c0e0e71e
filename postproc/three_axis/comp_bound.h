// How far a cutter radius compensation the post keeps (G41/G42) can put the
// tool off: the controller offsets the corrected contour, not the nominal
// one, and the two offsets differ by at most g r L (tool radius r, the error
// field's Lipschitz bound L, a factor g of the corner; docs/post.md
// "Cutter compensation" derives it).
#pragma once

#include <Eigen/Core>

#include "gcode/nc_path.h"

namespace volmap::post {

/// g of the corner from a move ending along t_in into one starting along
/// t_out, with the tool on `side` (1 left, G41; 2 right, G42): 2 where the
/// path is smooth or t_in is unknown (zero), and on the outside of a corner
/// (LinuxCNC goes round it on an arc of radius r); inside, the tool stands
/// at the offsets' intersection, 1/c from the corner (c = cos of half the
/// turn), which a turn of the sides by d moves by d/c^2: g = 1/c + 1/c^2.
/// Infinite at a reversal.
double comp_corner_factor(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out, int side);

/// Where the correction may carry a corner's turn across
/// nc::kLinuxCncCornerTurnRad (the turn within margin_rad of it), the change of
/// path that makes: the sagitta r (1 - cos(turn / 2)) of the corner arc
/// outside, the overshoot r (1 - cos turn) of an untrimmed inside corner;
/// else 0 (mm).
double comp_threshold_term_mm(const Eigen::Vector2d& t_in, const Eigen::Vector2d& t_out, int side,
                              double r_mm, double margin_rad);

}  // namespace volmap::post
