#include "maps/tables/layer_name.h"

#include <fmt/format.h>

namespace volmap::maps {

std::string layer_label(const VolumetricTable& t, int layer, const char* separator,
                        const char* plus, const char* minus) {
  std::string label;
  const ApproachDirections d = t.layer_directions(layer);
  for (int a : t.bidirectional_axes)
    label += fmt::format("{}{}{}", label.empty() ? "" : separator,
                         axis_char(t.grid[static_cast<size_t>(a)].axis),
                         d[static_cast<size_t>(a)] > 0 ? plus : minus);
  return label;
}

std::string layer_name(const VolumetricTable& t, int layer) {
  if (t.bidirectional_axes.empty()) return "both directions";
  return layer_label(t, layer, " ", "+", "-");
}

}  // namespace volmap::maps
