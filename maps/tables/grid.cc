#include "maps/tables/grid.h"

#include <fmt/format.h>

#include <stdexcept>

namespace volmap::maps {

namespace {
constexpr double kTwoPi = 2.0 * 3.14159265358979323846;
// The spacing divides the span when the remainder is below this fraction of
// a spacing (absorbs the rounding of decimal spacings such as 0.1 mm).
constexpr double kDivides = 1e-9;
}  // namespace

bool GridAxis::uniform() const {
  const double cells = (end - start) / spacing;
  return std::abs(cells - static_cast<double>(count - 1)) <= kDivides * static_cast<double>(count);
}

std::int64_t node_count(double start, double spacing, double end, std::int64_t max_nodes) {
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    throw std::invalid_argument(fmt::format("spacing {} is not a positive number", spacing));
  if (!(end > start)) throw std::invalid_argument(fmt::format("empty travel {}..{}", start, end));
  const double cells = (end - start) / spacing;
  if (cells + 1.0 > static_cast<double>(max_nodes))
    throw std::invalid_argument(
        fmt::format("spacing {} gives more than {} nodes on one axis", spacing, max_nodes));
  const double whole = std::floor(cells + kDivides);
  std::int64_t n = static_cast<std::int64_t>(whole) + 1;
  // Not a divisor: one more node, the travel end, after a shorter last cell.
  if (cells - whole > kDivides) ++n;
  if (n < 2) n = 2;
  return n;
}

GridAxis make_grid_axis(const Machine& m, int index, double spacing) {
  const AxisLimits& L = m.limits[static_cast<size_t>(index)];
  GridAxis g;
  g.axis = m.axis_order[static_cast<size_t>(index)];
  g.periodic = L.unlimited;
  g.start = L.unlimited ? 0.0 : L.min;
  g.end = L.unlimited ? kTwoPi : L.max;
  g.spacing = spacing;
  g.count = node_count(g.start, g.spacing, g.end);
  return g;
}

std::int64_t total_nodes(const std::vector<GridAxis>& grid) {
  std::int64_t n = 1;
  for (const GridAxis& g : grid) {
    if (g.count > (std::int64_t{1} << 40) / n)
      throw std::invalid_argument("the grid has more than 2^40 nodes; choose a coarser spacing");
    n *= g.count;
  }
  return n;
}

}  // namespace volmap::maps
