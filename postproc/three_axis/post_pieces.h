// The small pieces every path of the three-axis post shares (internal to
// postproc/three_axis/): approach directions and how a creep settles them,
// the commanded points of a move, and how a block writes its words.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "core/model/error_model.h"
#include "gcode/nc_block.h"
#include "gcode/nc_path.h"

namespace volmap::post {

using Eigen::Vector3d;

// The direction each axis approaches `to` from `from`; an axis that does not
// move keeps the direction it last moved in (it stands where its last move
// left it, lost motion taken up that way).
inline ApproachDirections directions_of(const Vector3d& from, const Vector3d& to,
                                        const ApproachDirections& last) {
  ApproachDirections d = last;
  for (int a = 0; a < 3; ++a) {
    const double delta = to[a] - from[a];
    if (delta > 0) d[static_cast<size_t>(a)] = 1;
    if (delta < 0) d[static_cast<size_t>(a)] = -1;
  }
  return d;
}

// An axis the nominal path does not move may still be commanded to creep
// (the correction varies along the path). A creep against the direction the
// axis last moved in is eaten by lost motion unless the command takes it up:
// such an axis gets the direction of its commanded motion, so the command
// for it includes the take-up step (and the piece containing the step is
// split until the step stands alone). Returns whether d changed.
inline bool settle_directions(const Vector3d& c0, const Vector3d& c1, const Vector3d& n0,
                              const Vector3d& n1, ApproachDirections& d) {
  bool changed = false;
  for (int a = 0; a < 3; ++a) {
    if (n1[a] != n0[a]) continue;  // the nominal motion sets the direction
    const double creep = c1[a] - c0[a];
    const std::int8_t want = creep > 0 ? 1 : (creep < 0 ? -1 : d[static_cast<size_t>(a)]);
    if (want != d[static_cast<size_t>(a)]) {
      d[static_cast<size_t>(a)] = want;
      changed = true;
    }
  }
  return changed;
}

// One commanded point of the output and the nominal path parameter it ends.
struct Piece {
  Vector3d command_mm;
  double s_end;
};

/// How a block writes its words: the indices of its X, Y and Z words (-1:
/// none), as nc::block_uses_lowercase (the case of the first letter, '@' and
/// '^' have none) and nc::block_uses_spaces (a gap between two words; a lone
/// word: spaces).
struct BlockStyle {
  int axis_index[3] = {-1, -1, -1};
  bool lower = false;
  bool spaces = false;
};
BlockStyle block_style(const nc::Block& b);
/// The index of the block's word with letter L, or -1.
inline int word_index(const nc::Block& b, char L) {
  for (size_t k = 0; k < b.words.size(); ++k)
    if (b.words[k].letter == L) return static_cast<int>(k);
  return -1;
}

/// The axis of an arc's plane (a0, a1) that turns round at angle q pi/2: at
/// 0 and pi the a0 coordinate (r cos) is extreme, at pi/2 and 3 pi/2 the a1
/// coordinate (r sin).
inline int turning_axis(const nc::ArcGeometry& g, double q) {
  return static_cast<long long>(std::llround(q)) % 2 == 0 ? g.a0 : g.a1;
}

/// The directions of the plane's axes where the arc m (geometry g) runs at
/// path parameter s: the way each moves over a milliradian of the arc from
/// there (at an end, into the arc), an axis that does not move keeping d's;
/// the normal axis of a helix the way it climbs. (Not the tangent at the
/// point itself: at a turning point the tangent of an axis is zero, and the
/// sign of what is left is that of the arc's spiral, its radii's rounding,
/// not of where the axis goes.)
inline ApproachDirections arc_tangent_directions(const nc::Motion& m, const nc::ArcGeometry& g,
                                                 double s, ApproachDirections d) {
  const double h = std::min(0.25, 1e-3 / std::max(std::abs(g.sweep), 1e-9));
  const Vector3d t = nc::point_on(m, std::min(1.0, s + h)) - nc::point_on(m, std::max(0.0, s - h));
  for (int a : {g.a0, g.a1})
    if (t[a] != 0) d[static_cast<size_t>(a)] = t[a] > 0 ? 1 : -1;
  if (m.end_mm[g.normal] != m.start_mm[g.normal])
    d[static_cast<size_t>(g.normal)] = m.end_mm[g.normal] > m.start_mm[g.normal] ? 1 : -1;
  return d;
}

}  // namespace volmap::post
