// Column names of the recordings CSV (shared/spec/recordings.md), shared by
// its reader and its writer.
#pragma once

#include <array>

#include "core/common/axis_name.h"

namespace volmap::recordings_columns {

inline constexpr std::array<const char*, kAxisNameCount> kPositionColumns = {
    "x_mm", "y_mm", "z_mm", "a_deg", "b_deg", "c_deg"};
inline constexpr std::array<const char*, kAxisNameCount> kDirColumns = {"dir_x", "dir_y", "dir_z",
                                                                        "dir_a", "dir_b", "dir_c"};
inline constexpr std::array<const char*, 3> kDeviationColumns = {"ex_um", "ey_um", "ez_um"};
inline constexpr std::array<const char*, 3> kNormalColumns = {"nx", "ny", "nz"};

}  // namespace volmap::recordings_columns
