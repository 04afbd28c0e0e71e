// How explain names an axis in its messages and keys: the letter ("X").
// Column names (x_mm, dir_x) are core/measure/recordings.h's.
#pragma once

#include <string>

#include "core/common/axis_name.h"

namespace volmap::explanation {

inline std::string axis_letter(AxisName a) { return std::string(1, axis_char(a)); }

}  // namespace volmap::explanation
