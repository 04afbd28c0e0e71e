// The functions of Fanuc Custom Macro B as ValueReader reads them in the
// Fanuc dialect (expression.h), after Fanuc's Series 0i-MF operator's
// manual (B-64604EN), "Arithmetic and logic operation": trig in degrees;
// FIX and FUP cut toward and away from zero; what depends on the
// control's parameters refused (ATAN and ASIN below 0 by 6004#0, ROUND in
// an address by the least input increment).
#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "gcode/flatten/expression.h"

namespace volmap::nc::flatten {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;

}  // namespace

double ValueReader::fanuc_function(std::string_view fn, std::size_t begin, std::size_t& i) const {
  if (!is_shared_function(fn))
    fail(begin, fmt::format("'{}' is not read: volmap reads the Fanuc functions ABS ACOS ASIN "
                            "ATAN COS EXP FIX FUP LN ROUND SIN SQRT TAN",
                            fn));
  if (at(i) != '[') fail(i, fmt::format("{} needs its argument in [ ]", fn));
  const std::size_t arg_at = i;
  const double x = expression(i);
  if (std::isnan(x)) fail(arg_at, fmt::format("{} of a vacant variable (never set)", fn));
  // An angle below zero is given as it is or plus 360 by parameter 6004#0.
  auto above_zero = [&](double a) {
    if (a < 0.0)
      fail(begin, fmt::format("{} gives {:g} or {:g} degrees here, as parameter 6004#0 (NAT) of "
                              "the control says; add 360 or not in the program",
                              fn == "atan" ? "ATAN" : "ASIN", a, a + 360.0));
    return a;
  };
  if (fn == "atan") {
    if (at(i) != '/' || at(i + 1) != '[') fail(i, "ATAN takes two arguments here: ATAN[y]/[x]");
    ++i;
    const std::size_t x_at = i;
    const double x2 = expression(i);
    if (std::isnan(x2)) fail(x_at, "ATAN of a vacant variable (never set)");
    return above_zero(std::atan2(x, x2) * kDegPerRad);
  }
  if (fn == "asin") {
    if (x < -1.0 || x > 1.0) fail(begin, fmt::format("argument to ASIN out of range: {}", x));
    return above_zero(std::asin(x) * kDegPerRad);
  }
  if (fn == "acos") {
    if (x < -1.0 || x > 1.0) fail(begin, fmt::format("argument to ACOS out of range: {}", x));
    return std::acos(x) * kDegPerRad;
  }
  if (fn == "round") {
    if (in_address_)
      fail(begin,
           "ROUND in an NC address rounds to the control's least input increment, which "
           "the program does not say; round in a variable first (#1 = ROUND[...])");
    return std::trunc(x + (x < 0.0 ? -0.5 : 0.5));
  }
  if (fn == "fix") return std::trunc(x);                           // FIX[-1.2] = -1
  if (fn == "fup") return x < 0.0 ? std::floor(x) : std::ceil(x);  // FUP[-1.2] = -2
  if (fn == "abs") return std::abs(x);
  if (fn == "cos") return std::cos(x * kRadPerDeg);
  if (fn == "sin") return std::sin(x * kRadPerDeg);
  if (fn == "tan") return std::tan(x * kRadPerDeg);
  if (fn == "exp") return std::exp(x);
  if (fn == "ln") {
    if (x <= 0.0) fail(begin, fmt::format("zero or negative argument to LN: {}", x));
    return std::log(x);
  }
  if (x < 0.0) fail(begin, fmt::format("negative argument to SQRT: {}", x));
  return std::sqrt(x);
}

}  // namespace volmap::nc::flatten
