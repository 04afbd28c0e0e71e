// sincos_axis against the C library over the angles machines use and beyond.
#include "core/common/trig.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace volmap {
namespace {

TEST(SincosAxis, AgreesWithLibmToTwoUlp) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> wide(-1e4, 1e4), near(-7.0, 7.0);
  for (int k = 0; k < 1000000; ++k) {
    const double x = k % 2 ? wide(rng) : near(rng);
    double s, c;
    sincos_axis(x, s, c);
    ASSERT_NEAR(s, std::sin(x), 4.5e-16) << x;
    ASSERT_NEAR(c, std::cos(x), 4.5e-16) << x;
  }
}

TEST(SincosAxis, ExactAtQuadrants) {
  double s, c;
  sincos_axis(0.0, s, c);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(c, 1.0);
  sincos_axis(M_PI / 2, s, c);
  EXPECT_EQ(s, 1.0);
  EXPECT_NEAR(c, std::cos(M_PI / 2), 1e-30);
  sincos_axis(-M_PI, s, c);
  EXPECT_EQ(c, -1.0);
  EXPECT_NEAR(s, std::sin(-M_PI), 1e-30);  // sin of the double nearest pi
}

}  // namespace
}  // namespace volmap
