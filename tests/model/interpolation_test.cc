// PCHIP slopes and error-table evaluation (core/error_set.h): exact on linear
// data and at knots, shape preserving, C1, hand-derived values, merged tables
// equal to each component's own interpolant, the outside policy, periodic
// wrap and the bidirectional mean.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model/error_set.h"
#include "core/model/errors_csv.h"

namespace volmap {
namespace {

constexpr double kPi = std::numbers::pi;
using Values = std::array<double, kComponentCount>;

/// A table whose component `c` holds y at knots x (its own PCHIP), the other
/// components zero.
AxisErrorTable single_component_table(const std::vector<double>& x, const std::vector<double>& y,
                                      int c = 0, bool periodic = false) {
  AxisErrorTable t;
  t.position = x;
  t.periodic = periodic;
  t.source = "test.csv:7";
  const std::vector<double> m = periodic ? pchip_slopes_periodic(x, y) : pchip_slopes(x, y);
  t.value.assign(x.size(), Values{});
  t.slope.assign(x.size(), Values{});
  for (std::size_t i = 0; i < x.size(); ++i) {
    t.value[i][c] = y[i];
    t.slope[i][c] = m[i];
  }
  return t;
}

double eval(const AxisErrorTable& t, double q, int c = 0) {
  Values out{};
  evaluate_table(t, q, OutsidePolicy::kError, out);
  return out[c];
}

std::vector<double> linspace(double a, double b, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = i == n - 1 ? b : a + (b - a) * i / (n - 1);
  return v;
}

// ---------------------------------------------------------------------------
// Slopes

TEST(PchipSlopes, HandDerivedMonotoneExample) {
  // x = {0, 1, 2, 4}, y = {0, 1, 3, 4}: h = {1, 1, 2}, secants d = {1, 2, 1/2}.
  // Knot 1 (h_b = 1, h_a = 1, d_b = 1, d_a = 2): w_b = (h_b + 2h_a)/(3(h_b+h_a))
  //   = 3/6, w_a = (2h_b + h_a)/6 = 3/6; 1/m = (1/2)/1 + (1/2)/2 = 3/4, m = 4/3.
  // Knot 2 (h_b = 1, h_a = 2, d_b = 2, d_a = 1/2): 3(h_b+h_a) = 9,
  //   w_b = (1 + 4)/9 = 5/9, w_a = (2 + 2)/9 = 4/9;
  //   1/m = (5/9)/2 + (4/9)/(1/2) = 5/18 + 16/18 = 21/18, m = 6/7.
  // Knot 0 (h0 = 1, h1 = 1, d0 = 1, d1 = 2): ((2h0 + h1) d0 - h0 d1)/(h0 + h1)
  //   = (3 - 2)/2 = 1/2; same sign as d0, d0 and d1 agree in sign: m = 1/2.
  // Knot 3 (h0 = 2, h1 = 1, d0 = 1/2, d1 = 2): (5 * 1/2 - 2 * 2)/3 = -1/2;
  //   sign differs from d0: m = 0.
  const std::vector<double> x = {0, 1, 2, 4}, y = {0, 1, 3, 4};
  const std::vector<double> m = pchip_slopes(x, y);
  ASSERT_EQ(m.size(), 4u);
  EXPECT_DOUBLE_EQ(m[0], 0.5);
  EXPECT_DOUBLE_EQ(m[1], 4.0 / 3.0);
  EXPECT_DOUBLE_EQ(m[2], 6.0 / 7.0);
  EXPECT_DOUBLE_EQ(m[3], 0.0);

  // Values. q = 0.5 on [0, 1], s = 1/2: h00 = h01 = 1/2, h10 = 1/8, h11 = -1/8:
  //   p = 0 + (1/8)(1)(1/2) + (1/2)(1) - (1/8)(1)(4/3) = 3/48 + 24/48 - 8/48 = 19/48.
  // q = 3 on [2, 4], h = 2, s = 1/2:
  //   p = (1/2) 3 + (1/8)(2)(6/7) + (1/2) 4 - (1/8)(2)(0) = 7/2 + 3/14 = 26/7.
  const AxisErrorTable t = single_component_table(x, y);
  EXPECT_NEAR(eval(t, 0.5), 19.0 / 48.0, 1e-15);
  EXPECT_NEAR(eval(t, 3.0), 26.0 / 7.0, 1e-15);
}

TEST(PchipSlopes, HandDerivedEndSlopeLimits) {
  // x = {0, 1, 2}, y = {0, 1, -9}: h = {1, 1}, d = {1, -10}.
  // Knot 1: secants of opposite sign, a local maximum: m = 0.
  // Knot 0: (3 * 1 - 1 * (-10))/2 = 6.5, same sign as d0, but d0 and d1
  //   differ in sign and |6.5| > 3 |d0| = 3: m = 3 d0 = 3.
  // Knot 2 (h0 = 1, h1 = 1, d0 = -10, d1 = 1): (3 * (-10) - 1)/2 = -15.5,
  //   same sign as d0, |-15.5| <= 30: m = -15.5.
  const std::vector<double> m = pchip_slopes({0, 1, 2}, {0, 1, -9});
  EXPECT_DOUBLE_EQ(m[0], 3.0);
  EXPECT_DOUBLE_EQ(m[1], 0.0);
  EXPECT_DOUBLE_EQ(m[2], -15.5);
}

TEST(PchipSlopes, TwoKnotsLinearOneKnotConstant) {
  EXPECT_EQ(pchip_slopes({1, 3}, {2, 6}), (std::vector<double>{2, 2}));
  EXPECT_EQ(pchip_slopes({1}, {5}), (std::vector<double>{0}));
  const AxisErrorTable two = single_component_table({1, 3}, {2, 6});
  EXPECT_DOUBLE_EQ(eval(two, 2.5), 5.0);
  const AxisErrorTable one = single_component_table({1}, {5});
  EXPECT_EQ(eval(one, 1.0), 5.0);
}

TEST(PchipSlopes, HandDerivedPeriodicWrap) {
  // x = {0, 1, 2, 4} (one period of 4), y = {1, 2, 0, 1}: h = {1, 1, 2},
  // d = {1, -2, 1/2}. Knots 1 and 2 are extrema: m = 0.
  // Knot 0 = knot 3: the interval before is the last one (h_b = 2, d_b = 1/2),
  // the one after the first (h_a = 1, d_a = 1): 3(h_b + h_a) = 9,
  // w_b = (2 + 2)/9 = 4/9, w_a = (4 + 1)/9 = 5/9;
  // 1/m = (4/9)/(1/2) + (5/9)/1 = 13/9, m = 9/13.
  const std::vector<double> m = pchip_slopes_periodic({0, 1, 2, 4}, {1, 2, 0, 1});
  EXPECT_DOUBLE_EQ(m[0], 9.0 / 13.0);
  EXPECT_DOUBLE_EQ(m[1], 0.0);
  EXPECT_DOUBLE_EQ(m[2], 0.0);
  EXPECT_DOUBLE_EQ(m[3], 9.0 / 13.0);
  EXPECT_EQ(pchip_slopes_periodic({0, 1}, {3, 3}), (std::vector<double>{0, 0}));
}

// ---------------------------------------------------------------------------
// Interpolant properties

TEST(Pchip, ReproducesLinearDataExactly) {
  const std::vector<double> x = {-3.0, -2.5, 0.0, 0.1, 4.0, 10.0};
  std::vector<double> y;
  for (double xi : x) y.push_back(2.0 * xi - 3.0);
  for (double m : pchip_slopes(x, y)) EXPECT_NEAR(m, 2.0, 1e-14);
  const AxisErrorTable t = single_component_table(x, y);
  for (double q : linspace(-3.0, 10.0, 1001)) EXPECT_NEAR(eval(t, q), 2.0 * q - 3.0, 1e-13);
}

TEST(Pchip, HitsKnotsExactly) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> step(0.1, 10.0), value(-5.0, 5.0);
  std::vector<double> x = {0.0}, y = {value(rng)};
  for (int i = 0; i < 30; ++i) {
    x.push_back(x.back() + step(rng));
    y.push_back(value(rng));
  }
  const AxisErrorTable t = single_component_table(x, y, 3);
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_EQ(eval(t, x[i], 3), y[i]) << i;
}

TEST(Pchip, MonotoneDataStaysMonotoneWithoutOvershoot) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> step(0.05, 20.0), rise(0.0, 3.0);
  std::bernoulli_distribution flat(0.25);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> x = {0.0}, y = {0.0};
    for (int i = 0; i < 12; ++i) {
      x.push_back(x.back() + step(rng));
      y.push_back(y.back() + (flat(rng) ? 0.0 : rise(rng) * rise(rng) * rise(rng)));
    }
    for (int sign : {+1, -1}) {
      std::vector<double> ys = y;
      for (double& v : ys) v *= sign;
      const AxisErrorTable t = single_component_table(x, ys);
      const double lo = *std::min_element(ys.begin(), ys.end());
      const double hi = *std::max_element(ys.begin(), ys.end());
      double previous = eval(t, x.front());
      for (double q : linspace(x.front(), x.back(), 5001)) {
        const double p = eval(t, q);
        EXPECT_GE(p, lo - 1e-12);
        EXPECT_LE(p, hi + 1e-12);
        EXPECT_GE(sign * (p - previous), -1e-12) << "trial " << trial << " q " << q;
        previous = p;
      }
    }
  }
}

TEST(Pchip, EachIntervalStaysBetweenItsKnotValues) {
  // Shape preservation on non-monotone data: no invented extremum.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> step(0.1, 5.0), value(-1.0, 1.0);
  std::vector<double> x = {0.0}, y = {value(rng)};
  for (int i = 0; i < 40; ++i) {
    x.push_back(x.back() + step(rng));
    y.push_back(value(rng));
  }
  const AxisErrorTable t = single_component_table(x, y);
  for (std::size_t i = 0; i + 1 < x.size(); ++i) {
    const double lo = std::min(y[i], y[i + 1]), hi = std::max(y[i], y[i + 1]);
    for (double q : linspace(x[i], x[i + 1], 101)) {
      EXPECT_GE(eval(t, q), lo - 1e-12);
      EXPECT_LE(eval(t, q), hi + 1e-12);
    }
  }
}

TEST(Pchip, IsC1AtKnots) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> step(0.5, 5.0), value(-2.0, 2.0);
  std::vector<double> x = {0.0}, y = {value(rng)};
  for (int i = 0; i < 15; ++i) {
    x.push_back(x.back() + step(rng));
    y.push_back(value(rng));
  }
  const std::vector<double> m = pchip_slopes(x, y);
  const AxisErrorTable t = single_component_table(x, y);
  const double e = 1e-6;
  for (std::size_t k = 1; k + 1 < x.size(); ++k) {
    const double left = (eval(t, x[k]) - eval(t, x[k] - e)) / e;
    const double right = (eval(t, x[k] + e) - eval(t, x[k])) / e;
    EXPECT_NEAR(left, m[k], 1e-4) << k;
    EXPECT_NEAR(right, m[k], 1e-4) << k;
  }
}

// ---------------------------------------------------------------------------
// Merged tables

TEST(MergedTable, EqualsEachComponentsOwnInterpolant) {
  // Each component tabulated at its own positions; the reader merges them
  // onto the union of knots.
  std::istringstream in(
      "X,EXX,EAX\n0,0,1\n70,3,-2\n100,5,0\n260,2,4\n300,1,1\n\n"
      "X,EYX\n0,-1\n40,2\n150,2.5\n180,-3\n300,0\n\n"
      "X,EBX\n0,4\n300,-2\n");
  const ErrorSet set = read_errors_csv(in, "merge.csv");
  const AxisErrors& x = *set.errors_of(AxisName::X);
  EXPECT_EQ(x.plus.position, (std::vector<double>{0, 40, 70, 100, 150, 180, 260, 300}));
  const double um = 1e-3, urad = 1e-6;
  const AxisErrorTable exx =
      single_component_table({0, 70, 100, 260, 300}, {0, 3 * um, 5 * um, 2 * um, um}, 0);
  const AxisErrorTable eax =
      single_component_table({0, 70, 100, 260, 300}, {urad, -2 * urad, 0, 4 * urad, urad}, 3);
  const AxisErrorTable eyx =
      single_component_table({0, 40, 150, 180, 300}, {-um, 2 * um, 2.5 * um, -3 * um, 0}, 1);
  const AxisErrorTable ebx = single_component_table({0, 300}, {4 * urad, -2 * urad}, 4);
  for (double q : linspace(0.0, 300.0, 3001)) {
    Values merged{};
    evaluate_axis(x, q, 0, OutsidePolicy::kError, merged);
    EXPECT_NEAR(merged[0], eval(exx, q, 0), 1e-17) << q;
    EXPECT_NEAR(merged[1], eval(eyx, q, 1), 1e-17) << q;
    EXPECT_NEAR(merged[3], eval(eax, q, 3), 1e-20) << q;
    EXPECT_NEAR(merged[4], eval(ebx, q, 4), 1e-20) << q;
    EXPECT_EQ(merged[2], 0.0);
    EXPECT_EQ(merged[5], 0.0);
  }
}

TEST(MergedTable, ShorterComponentIsHeldAtItsEndValue) {
  // EYX covers 100..200 only (two rows: slope 1e-3/100 per mm); the table
  // covers -100..400. Beyond its ends it takes its end value with zero slope
  // at every merged knot; in the first merged interval past each end
  // (0..100, 200..300) the cubic blends its end slope to zero, further out
  // it is constant.
  std::istringstream in("X,EXX\n-100,-1\n0,0\n300,3\n400,4\n\nX,EYX\n100,1\n200,2\n");
  const ErrorSet set = read_errors_csv(in, "short.csv");
  const AxisErrorTable& t = set.errors_of(AxisName::X)->plus;
  const double y_end = 2e-3, m_end = 1e-5, h = 100.0;
  for (double q : linspace(-100.0, 0.0, 11)) EXPECT_DOUBLE_EQ(eval(t, q, 1), 1e-3) << q;
  for (double q : linspace(0.0, 100.0, 11)) {
    const double s = q / h;  // h11 term only: slope 0 at 0, m_end at 100
    EXPECT_NEAR(eval(t, q, 1), 1e-3 + s * s * (s - 1) * h * m_end, 1e-17) << q;
  }
  for (double q : linspace(100.0, 200.0, 11))
    EXPECT_NEAR(eval(t, q, 1), 1e-3 + (q - 100.0) * 1e-5, 1e-17) << q;
  for (double q : linspace(200.0, 300.0, 11)) {
    const double s = (q - 200.0) / h;
    EXPECT_NEAR(eval(t, q, 1), y_end + s * (1 - s) * (1 - s) * h * m_end, 1e-17) << q;
  }
  for (double q : linspace(300.0, 400.0, 11)) EXPECT_DOUBLE_EQ(eval(t, q, 1), y_end) << q;
}

// ---------------------------------------------------------------------------
// Outside the table

TEST(OutsidePolicy, ErrorThrowsWithSourcePositionAndRange) {
  AxisErrorTable t = single_component_table({10, 20, 40}, {1, 2, 3});
  t.axis = AxisName::Y;
  Values out{};
  try {
    evaluate_table(t, 41.5, OutsidePolicy::kError, out);
    FAIL() << "no exception";
  } catch (const std::out_of_range& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("test.csv:7: ", 0), 0u) << what;
    EXPECT_NE(what.find("Y axis position 41.5 mm"), std::string::npos) << what;
    EXPECT_NE(what.find("10 mm .. 40 mm"), std::string::npos) << what;
    EXPECT_NE(what.find("clamp"), std::string::npos) << what;
  }
  EXPECT_THROW(evaluate_table(t, 9.999, OutsidePolicy::kError, out), std::out_of_range);
  EXPECT_THROW(evaluate_table(t, std::nan(""), OutsidePolicy::kClamp, out), std::out_of_range);

  AxisErrorTable r = single_component_table({0, kPi / 2}, {1, 2});
  r.axis = AxisName::B;
  try {
    evaluate_table(r, kPi, OutsidePolicy::kError, out);
    FAIL() << "no exception";
  } catch (const std::out_of_range& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("B axis position 180 deg"), std::string::npos) << what;
    EXPECT_NE(what.find("0 deg .. 90 deg"), std::string::npos) << what;
  }
}

TEST(OutsidePolicy, ClampHoldsTheEndValueAndCounts) {
  const AxisErrorTable t = single_component_table({10, 20, 40}, {1, 2, 3}, 2);
  Values out{};
  std::uint64_t clamped = 0;
  evaluate_table(t, 25.0, OutsidePolicy::kClamp, out, &clamped);
  EXPECT_EQ(clamped, 0u);
  evaluate_table(t, 5.0, OutsidePolicy::kClamp, out, &clamped);
  EXPECT_EQ(out[2], 1.0);
  EXPECT_EQ(clamped, 1u);
  evaluate_table(t, 1e9, OutsidePolicy::kClamp, out, &clamped);
  EXPECT_EQ(out[2], 3.0);
  EXPECT_EQ(clamped, 2u);
  evaluate_table(t, 1e9, OutsidePolicy::kClamp, out);  // no counter: fine
  EXPECT_EQ(out[2], 3.0);
  // Ends themselves are inside.
  evaluate_table(t, 40.0, OutsidePolicy::kError, out, &clamped);
  EXPECT_EQ(out[2], 3.0);
  EXPECT_EQ(clamped, 2u);
}

// A position equal to an end up to rounding is at the end (issue 23: a
// backward transformation gave A = 30.000000000000004 deg against a table
// ending at 30 deg and was refused): within the travel check's 1e-9 slack
// it takes the end value, uncounted; beyond it the policy applies.
TEST(OutsidePolicy, RoundingAtAnEndIsInside) {
  AxisErrorTable a = single_component_table({-100 * kPi / 180, 0, 30 * kPi / 180}, {1, 2, 3}, 2);
  a.axis = AxisName::A;
  Values out{};
  std::uint64_t clamped = 0;
  const double a_rounded = 30.000000000000004 * kPi / 180;  // what the issue saw
  ASSERT_GT(a_rounded, a.position.back());
  evaluate_table(a, a_rounded, OutsidePolicy::kError, out, &clamped);
  EXPECT_EQ(out[2], 3.0);
  evaluate_table(a, -100 * kPi / 180 - 5e-10, OutsidePolicy::kError, out, &clamped);
  EXPECT_EQ(out[2], 1.0);
  EXPECT_EQ(clamped, 0u);
  EXPECT_THROW(evaluate_table(a, 30 * kPi / 180 + 2e-9, OutsidePolicy::kError, out),
               std::out_of_range);
}

// ---------------------------------------------------------------------------
// Periodic tables

TEST(Periodic, WrapsByFullTurns) {
  const ErrorSet set =
      load_errors_csv(std::string(VOLMAP_SOURCE_DIR) + "/tests/data/errors/periodic_c.csv");
  const AxisErrors& c = *set.errors_of(AxisName::C);
  ASSERT_TRUE(c.plus.periodic);
  for (double q : linspace(0.0, 2 * kPi, 73)) {
    Values base{}, up{}, down{}, far{};
    evaluate_axis(c, q, 1, OutsidePolicy::kError, base);
    evaluate_axis(c, q + 2 * kPi, 1, OutsidePolicy::kError, up);
    evaluate_axis(c, q - 2 * kPi, 1, OutsidePolicy::kError, down);
    evaluate_axis(c, q - 10 * kPi, 1, OutsidePolicy::kError, far);
    for (int k = 0; k < kComponentCount; ++k) {
      EXPECT_NEAR(up[k], base[k], 1e-15) << q;
      EXPECT_NEAR(down[k], base[k], 1e-15) << q;
      EXPECT_NEAR(far[k], base[k], 1e-14) << q;
    }
  }
}

TEST(Periodic, IsC1ThroughTheWrap) {
  const std::vector<double> x = {0, kPi / 2, kPi, 3 * kPi / 2, 2 * kPi};
  const std::vector<double> y = {0, 2, 1, -3, 0};
  const AxisErrorTable t = single_component_table(x, y, 5, true);
  const double e = 1e-7;
  const double left = (eval(t, 2 * kPi, 5) - eval(t, 2 * kPi - e, 5)) / e;
  const double right = (eval(t, e, 5) - eval(t, 0.0, 5)) / e;
  const double across = (eval(t, e, 5) - eval(t, -e, 5)) / (2 * e);
  EXPECT_GT(std::abs(right), 0.1);  // a real slope through the wrap
  EXPECT_NEAR(left, right, 1e-5);
  EXPECT_NEAR(across, right, 1e-5);
  EXPECT_NEAR(eval(t, -kPi / 2, 5), -3.0, 1e-14);
}

// ---------------------------------------------------------------------------
// Directions

TEST(Bidirectional, DirectionSelectsTableAndZeroTakesTheMean) {
  AxisErrors e;
  e.plus = single_component_table({0, 100}, {1, 3}, 0);
  e.minus = single_component_table({0, 50, 100}, {-1, 0, 5}, 0);
  Values out{};
  evaluate_axis(e, 50.0, +1, OutsidePolicy::kError, out);
  EXPECT_DOUBLE_EQ(out[0], 2.0);
  evaluate_axis(e, 50.0, -1, OutsidePolicy::kError, out);
  EXPECT_DOUBLE_EQ(out[0], 0.0);
  evaluate_axis(e, 50.0, 0, OutsidePolicy::kError, out);
  EXPECT_DOUBLE_EQ(out[0], 1.0);
  for (double q : linspace(0.0, 100.0, 37)) {
    Values p{}, m{}, mean{};
    evaluate_axis(e, q, +1, OutsidePolicy::kError, p);
    evaluate_axis(e, q, -1, OutsidePolicy::kError, m);
    evaluate_axis(e, q, 0, OutsidePolicy::kError, mean);
    EXPECT_DOUBLE_EQ(mean[0], 0.5 * (p[0] + m[0])) << q;
  }
  // Clamping in both tables counts as one clamped evaluation of the axis.
  std::uint64_t clamped = 0;
  evaluate_axis(e, 150.0, 0, OutsidePolicy::kClamp, out, &clamped);
  EXPECT_DOUBLE_EQ(out[0], 4.0);
  EXPECT_EQ(clamped, 1u);
}

TEST(Bidirectional, MinusFallsBackToPlusWhenNotBidirectional) {
  AxisErrors e;
  e.plus = single_component_table({0, 100}, {1, 3}, 4);
  ASSERT_FALSE(e.bidirectional());
  for (int dir : {-1, 0, 1}) {
    Values out{};
    evaluate_axis(e, 25.0, dir, OutsidePolicy::kError, out);
    EXPECT_DOUBLE_EQ(out[4], 1.5) << dir;
  }
}

}  // namespace
}  // namespace volmap
