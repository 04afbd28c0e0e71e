// The nominal backward transformation (core/kinematics.h): against the closed
// form of Lei & Hsu eqs. (10)-(15) for X'Y'ZA'C', round trips
// backward(forward(u)) = u on both five-axis samples, travel limits, the
// singular position, the selection policy. `volmap kinematics` as scripts
// call it: kinematics_cli_test.cc.
#include "core/kinematics/kinematics.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>

#include "core/model/machine_json.h"
#include "tests/kinematics/lei_hsu_poses.h"
#include "tests/support/cli_run.h"
#include "tests/support/samples.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

using test::random_pose;
using test_kinematics::eq10_15;
using test_kinematics::kDeg;
using test_kinematics::kXw0;
using test_kinematics::kYw0;
using test_kinematics::kZ3;
using test_kinematics::kZw0;
using test_kinematics::load;
using test_kinematics::pose;

// The closed-form backward transformation derived from eqs. (10)-(15):
// A = +-acos(k); C = atan2(i, j) when sin A > 0, atan2(-i, -j) when sin A < 0
// (eqs. 13-14 divided by sin A); the linear axes from eqs. (10)-(12), whose
// 3x3 matrix M (columns: coefficients of x_m, y_m, z_m) is orthogonal, so
// (x_m, y_m, z_m) = M^T (x + Xw0, y + Yw0, z + Z3 + Zw0).
struct ClosedForm {
  double xm, ym, zm, a, c;
};
ClosedForm closed_form(const ToolPose& v, double a) {
  const double i = v.axis.x(), j = v.axis.y();
  const double c = std::sin(a) > 0 ? std::atan2(i, j) : std::atan2(-i, -j);
  const double X = v.tip_mm.x() + kXw0, Y = v.tip_mm.y() + kYw0, Z = v.tip_mm.z() + kZ3 + kZw0;
  const double sa = std::sin(a), ca = std::cos(a), sc = std::sin(c), cc = std::cos(c);
  return {-cc * X + sc * Y, -sc * ca * X - cc * ca * Y + sa * Z, sc * sa * X + cc * sa * Y + ca * Z,
          a, c};
}

double wrap_near(double q, double ref) { return q + 2 * M_PI * std::round((ref - q) / (2 * M_PI)); }

void expect_same_pose(const ToolPose& a, const ToolPose& b, const std::string& what) {
  EXPECT_LT((a.tip_mm - b.tip_mm).norm(), 1e-9) << what;
  EXPECT_LT((a.axis - b.axis).norm(), 1e-12) << what;
}

// The deterministic atan2 against libm: within 1 ulp, same quadrants and
// special values.
TEST(Atan2Axis, AgreesWithLibm) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> d(-1.0, 1.0);
  std::uniform_int_distribution<int> e(-40, 40);
  for (int t = 0; t < 1000000; ++t) {
    const double y = std::ldexp(d(rng), e(rng)), x = std::ldexp(d(rng), e(rng));
    const double got = atan2_axis(y, x), ref = std::atan2(y, x);
    ASSERT_LE(std::abs(got - ref), 1.0 * std::abs(std::nextafter(ref, 10.0) - ref) + 1e-300)
        << y << " " << x;
  }
  for (double y : {0.0, 1.0, -1.0, 1e-300, -1e300})
    for (double x : {1.0, -1.0, 1e-300, -1e300, 0.0}) {
      if (y == 0.0 && x == 0.0) continue;
      EXPECT_NEAR(atan2_axis(y, x), std::atan2(y, x), 1e-15) << y << " " << x;
    }
  EXPECT_EQ(atan2_axis(0.0, 0.0), 0.0);
  EXPECT_EQ(atan2_axis(-0.0, -1.0), -M_PI);
}

TEST(Backward, LeiHsuMatchesTheClosedFormOfEqs10To15) {
  const Machine m = load("lei-hsu-xyzac");
  const Kinematics kin(m);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> offset(-3 * M_PI, 3 * M_PI);
  int two = 0;
  for (int t = 0; t < 1000; ++t) {
    const AxisVector u = random_pose(m, rng);
    const ToolPose v = eq10_15(u[0], u[1], u[2], u[3], u[4]);
    AxisVector prev = random_pose(m, rng);
    prev[4] = offset(rng);
    const BackwardSolutions s = kin.backward(v, prev);
    // Expected: A = +-acos(k) within the A travel -100..30 deg.
    const double a0 = std::acos(std::clamp(v.axis.z(), -1.0, 1.0));
    int expected = 0;
    for (double a : {a0, -a0}) {
      if (a < -100 * kDeg || a > 30 * kDeg) continue;
      ++expected;
      const ClosedForm cf = closed_form(v, a);
      // The closed form reproduces eqs. (10)-(15): it is a solution.
      expect_same_pose(eq10_15(cf.xm, cf.ym, cf.zm, cf.a, cf.c), v, "closed form");
      bool found = false;
      for (int k = 0; k < s.count; ++k) {
        const AxisVector& g = s.u[static_cast<size_t>(k)];
        if (std::abs(g[3] - a) > 1e-9) continue;
        found = true;
        EXPECT_NEAR(g[0], cf.xm, 1e-9);
        EXPECT_NEAR(g[1], cf.ym, 1e-9);
        EXPECT_NEAR(g[2], cf.zm, 1e-9);
        EXPECT_NEAR(g[4], wrap_near(cf.c, prev[4]), 1e-9);  // C nearest the previous C
        EXPECT_LE(std::abs(g[4] - prev[4]), M_PI + 1e-12);
      }
      EXPECT_TRUE(found) << "A = " << a / kDeg;
    }
    EXPECT_EQ(s.count, expected);
    two += s.count == 2;
  }
  EXPECT_GT(two, 50);  // |A| <= 30 deg: both solutions are within travel
}

// backward(forward(u)) = u; every solution reproduces v.
void round_trip(const std::string& name, unsigned seed) {
  const Machine m = load(name);
  const Kinematics kin(m);
  std::mt19937 rng(seed);
  int twos = 0;
  for (int t = 0; t < 2000; ++t) {
    const AxisVector u = random_pose(m, rng);
    const ToolPose v = nominal_forward(m, u);
    const BackwardSolutions s = kin.backward(v, u);
    ASSERT_GE(s.count, 1);
    EXPECT_FALSE(s.singular);
    int same = -1;
    for (int k = 0; k < s.count; ++k) {
      const AxisVector& g = s.u[static_cast<size_t>(k)];
      expect_same_pose(nominal_forward(m, g), v, name);
      if ((g - u).cwiseAbs().maxCoeff() < 1e-9) same = k;
    }
    ASSERT_GE(same, 0) << name << " u = " << u.transpose();
    // Starting from u itself, the policy keeps u.
    EXPECT_EQ(kin.select(s, u), same);
    twos += s.count == 2;
  }
  EXPECT_GT(twos, 200) << name;
}

TEST(Backward, RoundTripLeiHsuXYZAC) { round_trip("lei-hsu-xyzac", 21); }
TEST(Backward, RoundTripBCTableTable) { round_trip("bc-table-table", 22); }

// A tilted, offset machine: the code uses the chains, not the sample's shape.
TEST(Backward, RoundTripGeneralGeometry) {
  Machine m = load("bc-table-table");
  m.workpiece_chain[1].direction_parent = Eigen::Vector3d(0.1, 1.0, -0.05).normalized();
  m.workpiece_chain[2].direction_parent = Eigen::Vector3d(0.02, -0.03, 1.0).normalized();
  m.workpiece_chain[2].offset_parent_mm = {3.0, -2.0, 70.0};
  m.tool_axis = Eigen::Vector3d(0.01, 0.02, 1.0).normalized();
  const Kinematics kin(m);
  std::mt19937 rng(23);
  for (int t = 0; t < 500; ++t) {
    const AxisVector u = random_pose(m, rng);
    const ToolPose v = nominal_forward(m, u);
    const BackwardSolutions s = kin.backward(v, u);
    bool found = false;
    for (int k = 0; k < s.count; ++k) {
      expect_same_pose(nominal_forward(m, s.u[static_cast<size_t>(k)]), v, "general");
      found = found || (s.u[static_cast<size_t>(k)] - u).cwiseAbs().maxCoeff() < 1e-9;
    }
    EXPECT_TRUE(found);
  }
}

TEST(Backward, ThreeAxisIsLinearAxesForTip) {
  const Machine m = load("hsu-3axis");
  const Kinematics kin(m);
  EXPECT_FALSE(kin.has_rotary_axes());
  std::mt19937 rng(5);
  for (int t = 0; t < 100; ++t) {
    const AxisVector u = random_pose(m, rng);
    const ToolPose v = nominal_forward(m, u);
    const BackwardSolutions s = kin.backward(v, m.home);
    ASSERT_EQ(s.count, 1);
    EXPECT_LT((s.u[0] - u).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((s.u[0] - linear_axes_for_tip(m, m.home, v.tip_mm)).cwiseAbs().maxCoeff(), 1e-9);
  }
  // A tool axis the machine cannot take: no solution.
  EXPECT_EQ(kin.backward(ToolPose{{1, 2, 3}, {1, 0, 0}}, m.home).count, 0);
}

// Section 4.1: at A = 0 (Q along C) C is free; it stays where it was.
TEST(Backward, SingularPositionHoldsTheOuterAxis) {
  for (const char* name : {"lei-hsu-xyzac", "bc-table-table"}) {
    const Machine m = load(name);
    const Kinematics kin(m);
    std::mt19937 rng(9);
    for (int t = 0; t < 50; ++t) {
      AxisVector u = random_pose(m, rng);
      u[3] = 0.0;
      const ToolPose v = nominal_forward(m, u);
      AxisVector prev = random_pose(m, rng);
      const BackwardSolutions s = kin.backward(v, prev);
      ASSERT_EQ(s.count, 1) << name;
      EXPECT_TRUE(s.singular);
      EXPECT_EQ(s.u[0][4], prev[4]);  // C held exactly
      EXPECT_NEAR(s.u[0][3], 0.0, 1e-12);
      expect_same_pose(nominal_forward(m, s.u[0]), v, name);
    }
  }
}

// Just off the singular position (tilts from 1e-9 to 1e-5 rad, above the
// hold threshold) the outer angle is the tool axis's azimuth: the orientation
// comes back to within rounding of the tilt, not to within the tilt itself
// (the |z| = 1 form of subproblem 2 lost every tilt below ~1.5e-8 and gave
// C = 0 mod 360 there).
TEST(Backward, NearTheSingularPositionTheOuterAngleFollowsTheAzimuth) {
  for (const char* name : {"lei-hsu-xyzac", "bc-table-table"}) {
    SCOPED_TRACE(name);
    const Machine m = load(name);
    const Kinematics kin(m);
    const Eigen::Vector3d w1 = kin.outer_axis_w();
    const Eigen::Vector3d e1 = w1.unitOrthogonal(), e2 = w1.cross(e1);
    for (double tilt : {1e-9, 3e-9, 1e-8, 1e-7, 1e-6, 1e-5}) {
      for (double azimuth_deg : {10.0, 45.0, 100.0, 200.0, 300.0}) {
        const double az = azimuth_deg * kDeg;
        const Eigen::Vector3d Q =
            (std::cos(tilt) * w1 + std::sin(tilt) * (std::cos(az) * e1 + std::sin(az) * e2))
                .normalized();
        AxisVector prev = m.home;
        bool singular = true;
        const AxisVector u = kin.backward_selected(ToolPose{{10, 20, 30}, Q}, prev, &singular);
        EXPECT_FALSE(singular) << tilt;
        const ToolPose back = nominal_forward(m, u);
        // The orientation: within a few ulps of Q, a hundredth of the tilt
        // or better.
        EXPECT_LT((back.axis - Q).norm(), std::max(1e-15, 0.01 * tilt))
            << "tilt " << tilt << " azimuth " << azimuth_deg;
        EXPECT_LT((back.tip_mm - Eigen::Vector3d(10, 20, 30)).norm(), 1e-9);
      }
    }
  }
}

TEST(Backward, UnlimitedCIsUnwrappedNextToThePreviousValue) {
  const Machine m = load("lei-hsu-xyzac");
  const Kinematics kin(m);
  const ToolPose v = nominal_forward(m, pose({10, 20, 30, -40, 10}, m));
  for (double prev_c : {725.0, -1000.0, 190.0, 3.0}) {
    const BackwardSolutions s = kin.backward(v, pose({0, 0, 0, -40, prev_c}, m));
    ASSERT_EQ(s.count, 1);  // +40 deg is outside the A travel
    EXPECT_LE(std::abs(s.u[0][4] - prev_c * kDeg), M_PI);
    EXPECT_NEAR(std::remainder(s.u[0][4] - 10 * kDeg, 2 * M_PI), 0.0, 1e-12);
  }
}

TEST(Backward, TravelLimitsDropSolutions) {
  const Machine m = load("lei-hsu-xyzac");
  const Kinematics kin(m);
  // A = -60 deg, C = 40 deg: the mirror solution A = +60 lies outside -100..30.
  const ToolPose v = eq10_15(5, 6, 7, -60 * kDeg, 40 * kDeg);
  const BackwardSolutions s = kin.backward(v, m.home);
  ASSERT_EQ(s.count, 1);
  EXPECT_NEAR(s.u[0][3], -60 * kDeg, 1e-12);
  EXPECT_NEAR(s.u[0][4], 40 * kDeg, 1e-12);
  // Tool axis pointing down: A = 180 deg, out of reach.
  EXPECT_EQ(kin.backward(ToolPose{{0, 0, 0}, {0, 0, -1}}, m.home).count, 0);
  const Kinematics bc(load("bc-table-table"));
  // B = 115 deg needed, travel -110..110.
  EXPECT_EQ(bc.backward(ToolPose{{0, 0, 0}, {std::sin(115 * kDeg), 0, std::cos(115 * kDeg)}},
                        bc.machine().home)
                .count,
            0);
  // A non-unit tool axis is refused.
  EXPECT_THROW(kin.backward(ToolPose{{0, 0, 0}, {0, 0, 1.1}}, m.home), std::invalid_argument);
}

TEST(Backward, SelectionPrefersTheLeastRotaryTravel) {
  const Machine m = load("lei-hsu-xyzac");
  const Kinematics kin(m);
  const ToolPose v = eq10_15(5, 6, 7, 20 * kDeg, 30 * kDeg);  // A = +-20 both reachable
  {
    const AxisVector prev = pose({0, 0, 0, 15, 30}, m);
    const BackwardSolutions s = kin.backward(v, prev);
    ASSERT_EQ(s.count, 2);
    const AxisVector& sel = s.u[static_cast<size_t>(kin.select(s, prev))];
    EXPECT_NEAR(sel[3], 20 * kDeg, 1e-12);
    EXPECT_NEAR(sel[4], 30 * kDeg, 1e-12);
  }
  {
    const AxisVector prev = pose({0, 0, 0, -15, 200}, m);
    const AxisVector sel = kin.backward_selected(v, prev);
    EXPECT_NEAR(sel[3], -20 * kDeg, 1e-12);
    EXPECT_NEAR(sel[4], 210 * kDeg, 1e-12);
  }
}

// The real-time path places only what it needs and picks what select() picks.
TEST(Backward, SelectedEqualsBackwardThenSelect) {
  for (const char* name : {"lei-hsu-xyzac", "bc-table-table", "hsu-3axis"}) {
    Machine m = load(name);
    // The samples' mirror solutions stay within their symmetric X and Y
    // travel; an asymmetric X travel exercises the in-travel rule.
    m.limits[0].max = 0.2 * m.limits[0].max;
    const Kinematics kin(m);
    std::mt19937 rng(61);
    int outside = 0;
    for (int t = 0; t < 2000; ++t) {
      const ToolPose v = nominal_forward(m, random_pose(m, rng));
      const AxisVector prev = random_pose(m, rng);
      const BackwardSolutions s = kin.backward(v, prev);
      const int k = kin.select(s, prev);
      ASSERT_GE(k, 0);
      const AxisVector sel = kin.backward_selected(v, prev);
      EXPECT_EQ((sel - s.u[static_cast<size_t>(k)]).cwiseAbs().maxCoeff(), 0.0) << name;
      for (int j = 0; j < s.count; ++j) {
        bool in = true;
        for (int i = 0; i < m.axis_count(); ++i) {
          const AxisLimits& L = m.limits[static_cast<size_t>(i)];
          in = in && (L.unlimited || (s.u[static_cast<size_t>(j)][i] >= L.min - 1e-9 &&
                                      s.u[static_cast<size_t>(j)][i] <= L.max + 1e-9));
        }
        outside += !in;
      }
    }
    if (m.has_rotary_axes()) {
      EXPECT_GT(outside, 100) << name;  // the travel rule was exercised
    }
  }
}

TEST(Kinematics, RejectsMachinesItCannotInvert) {
  const std::string four_axis = R"({"format": "volmap-machine/1", "name": "four",
    "axes": {"X": {"type": "linear", "direction": [1,0,0], "travel_mm": [0,100]},
             "Y": {"type": "linear", "direction": [0,1,0], "travel_mm": [0,100]},
             "Z": {"type": "linear", "direction": [0,0,1], "travel_mm": [0,100]},
             "C": {"type": "rotary", "direction": [0,0,1], "travel_deg": null}},
    "workpiece_chain": [{"axis": "C"}], "tool_chain": [{"axis": "X"}, {"axis": "Y"}, {"axis": "Z"}],
    "tool": {"length_mm": 0}})";
  std::istringstream in(four_axis);
  EXPECT_THROW(Kinematics(read_machine_json(in, "four.json")), std::invalid_argument);
  Machine m = load("lei-hsu-xyzac");
  m.workpiece_chain[2].direction_parent = Eigen::Vector3d::UnitZ();  // A parallel to C
  EXPECT_THROW(Kinematics{m}, std::invalid_argument);
}

}  // namespace
}  // namespace volmap
