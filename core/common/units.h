// The unit conversions volmap makes at its edges (README, Conventions: mm and
// degrees in files and on the command line, errors in um and urad, mm and rad
// inside). Use these names instead of bare factors; where code is replaced,
// keep the same arithmetic (x * kRadPerDeg is not bit for bit
// x * M_PI / 180.0), since outputs are compared byte for byte.
#pragma once

#include <cmath>

namespace volmap::units {

inline constexpr double kMmPerInch = 25.4;  ///< G20 / UNITS/INCHES
inline constexpr double kUmPerMm = 1000.0;
inline constexpr double kUradPerRad = 1e6;
inline constexpr double kRadPerDeg = M_PI / 180.0;
inline constexpr double kDegPerRad = 180.0 / M_PI;

}  // namespace volmap::units
