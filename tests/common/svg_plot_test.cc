// The plots' numbers (core/common/svg_plot.h) against values worked out by
// hand: ticks of 1, 2 or 5 times a power of ten within the range, and a
// value written to the digits its standard error supports (two significant
// digits of the error, the value to the same place, its integer part kept).
#include "core/common/svg_plot.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace volmap::svg {
namespace {

std::vector<std::string> texts(const Ticks& t) {
  std::vector<std::string> out;
  for (double v : t.values) out.push_back(t.text(v));
  return out;
}

TEST(NiceTicks, RoundStepsWithinTheRange) {
  // 487 mm of path: 487/5 = 97.4, the nearest round step is 100.
  EXPECT_EQ(texts(nice_ticks(0, 487)), (std::vector<std::string>{"0", "100", "200", "300", "400"}));
  // +-26.69 um in 4: 13.3 -> 10.
  EXPECT_EQ(texts(nice_ticks(-26.69, 26.69, 4)),
            (std::vector<std::string>{"-20", "-10", "0", "10", "20"}));
  // 0.3 .. 26.1 in 4: 6.45 -> 5.
  EXPECT_EQ(texts(nice_ticks(0.3, 26.1, 4)),
            (std::vector<std::string>{"5", "10", "15", "20", "25"}));
  // Small: 0.012 .. 0.019 in 5: 0.0014 -> 0.001, three decimals.
  EXPECT_EQ(texts(nice_ticks(0.012, 0.019)),
            (std::vector<std::string>{"0.012", "0.013", "0.014", "0.015", "0.016", "0.017", "0.018",
                                      "0.019"}));
  // Ends on a tick are kept despite rounding (0.1 * 3 != 0.3 in binary).
  EXPECT_EQ(texts(nice_ticks(0.0, 0.3, 3)), (std::vector<std::string>{"0.0", "0.1", "0.2", "0.3"}));
  // A zero tick is "0", never "-0".
  EXPECT_EQ(nice_ticks(-1, 1, 2).text(-0.0), "0");
}

TEST(NiceRange, OuterTicksAreTheEnds) {
  EXPECT_EQ(nice_range(-5.03, 5.86), (std::pair<double, double>{-6.0, 6.0}));   // step 2
  EXPECT_EQ(nice_range(0.3, 26.1, 4), (std::pair<double, double>{0.0, 30.0}));  // step 5
}

TEST(ValueWithError, TwoDigitsOfTheErrorSetThePlace) {
  EXPECT_EQ(value_with_error(2.04849, 0.2301), "2.05 ± 0.23");
  EXPECT_EQ(value_with_error(988.3, 151.2), "988 ± 150");
  EXPECT_EQ(value_with_error(1234567, 2345), "1234567 ± 2300");
  EXPECT_EQ(value_with_error(0.000123456, 0.0000345), "0.000123 ± 0.000035");
  EXPECT_EQ(value_with_error(-0.0004, 0.03), "0.000 ± 0.030");
  EXPECT_EQ(value_with_error(-12.345, 0.99), "-12.35 ± 0.99");
  // Without a finite error: four significant digits.
  EXPECT_EQ(value_with_error(3.14159265, 0.0), "3.142");
  EXPECT_EQ(value_with_error(1.0 / 0.0, 0.1), "n/a");
}

}  // namespace
}  // namespace volmap::svg
