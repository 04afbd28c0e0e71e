// CLI11 validators for numeric options: NaN and infinity are refused
// (CLI11's NonNegativeNumber and PositiveNumber let NaN through, since every
// comparison with NaN is false), so they never reach an output.
#pragma once

#include <CLI/CLI.hpp>
#include <cmath>
#include <string>

namespace volmap::cli {

inline CLI::Validator finite_number(double min, bool min_allowed, const std::string& what) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v))
          return "'" + text + "' is not a finite number";
        if (v < min || (!min_allowed && v == min)) return "'" + text + "' is not " + what;
        return {};
      },
      what);
}

/// A finite number > 0.
inline const CLI::Validator kFinitePositive = finite_number(0.0, false, "a number > 0");
/// A finite number >= 0.
inline const CLI::Validator kFiniteNonNegative = finite_number(0.0, true, "a number >= 0");

}  // namespace volmap::cli
