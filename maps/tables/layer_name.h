// Names of a table's direction layers: each bidirectional axis with its
// approach direction, as `volmap map`, the map report and the exports show
// them.
#pragma once

#include <string>

#include "maps/tables/volumetric_table.h"

namespace volmap::maps {

/// The bidirectional axes of `layer` with their directions, joined by
/// `separator`: axis letter then `plus` or `minus` ("X+ Y-", "X_pos_Y_neg").
/// Empty for a table without bidirectional axes.
std::string layer_label(const VolumetricTable& table, int layer, const char* separator,
                        const char* plus, const char* minus);

/// The name `volmap map` and the report show: "both directions" for a table
/// without bidirectional axes, else "X+", "X- Y+".
std::string layer_name(const VolumetricTable& table, int layer);

}  // namespace volmap::maps
