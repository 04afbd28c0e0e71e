// The grid of a compensation table: one GridAxis per machine axis.
//
// Node rule (shared/spec/cli.md: "grid nodes lie on multiples of the spacing
// from the start of each axis's travel"): node k lies at start + k * spacing
// for every k with start + k * spacing < end, and the last node is the travel
// end itself. When the spacing divides the travel (to 1e-9 of the spacing)
// every cell is one spacing wide ("uniform"); otherwise the last cell is
// shorter. An unlimited rotary axis spans one turn, [0, 2 pi], its last node
// (2 pi) the same angle as the first.
//
// Units: mm for linear axes, rad for rotary axes (internal units; the CLI
// converts degrees at input and output only).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/axis_name.h"
#include "core/model/machine.h"

namespace volmap::maps {

struct GridAxis {
  AxisName axis = AxisName::X;
  double start = 0.0;      ///< first node, mm or rad
  double spacing = 1.0;    ///< mm or rad, > 0
  double end = 0.0;        ///< last node, mm or rad, > start
  std::int64_t count = 2;  ///< nodes, >= 2
  bool periodic = false;   ///< unlimited rotary axis: end = start + 2 pi

  /// Position of node k (0 <= k < count): exact start + k * spacing, and the
  /// end for the last node.
  double node(std::int64_t k) const {
    return k + 1 == count ? end : start + static_cast<double>(k) * spacing;
  }
  /// True when every cell is one spacing wide.
  bool uniform() const;

  /// The cell holding q: i in [0, count - 2] with node(i) <= q <= node(i+1)
  /// and s = (q - node(i)) / (node(i+1) - node(i)) in [0, 1]. q must lie in
  /// [start, end] (callers clamp or wrap first). At a node s is exactly 0
  /// (or exactly 1 at the end), so interpolation returns the node's value.
  void locate(double q, std::int64_t& i, double& s) const {
    std::int64_t k = static_cast<std::int64_t>((q - start) / spacing);
    if (k > count - 2) k = count - 2;
    if (k < 0) k = 0;
    if (q < node(k) && k > 0) --k;
    if (q > node(k + 1) && k + 2 < count) ++k;
    const double x0 = node(k);
    i = k;
    s = (q - x0) / (node(k + 1) - x0);
  }
};

/// Node count for start, spacing, end by the rule above. Throws
/// std::invalid_argument when spacing is not positive and finite or the
/// node count would exceed max_nodes.
std::int64_t node_count(double start, double spacing, double end,
                        std::int64_t max_nodes = std::int64_t{1} << 31);

/// The grid axis of machine axis `index` with the given spacing (mm or rad):
/// the axis's travel, or one turn for an unlimited rotary axis.
GridAxis make_grid_axis(const Machine& m, int index, double spacing);

/// Total node count (product of counts). Throws std::invalid_argument on
/// overflow beyond 2^40.
std::int64_t total_nodes(const std::vector<GridAxis>& grid);

}  // namespace volmap::maps
