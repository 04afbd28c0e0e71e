// The circular test (ISO 230-4) of `volmap simulate` plans: the path, the
// readings, the directions of approach, the time on the path, and the
// radial deviation of effects whose signature on a circle is derived by hand.
#include "core/measure/circular_test.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <numbers>
#include <sstream>

#include "core/measure/effects.h"
#include "core/measure/simulate.h"
#include "core/model/error_model.h"
#include "core/model/gain_evaluator.h"
#include "tests/support/plans.h"
#include "tests/support/samples.h"

namespace volmap {
namespace {

constexpr double kPi = std::numbers::pi;

std::string plan_json(const std::string& extra) {
  return R"({"format": "volmap-plan/1", "tests": [{"type": "circular", "plane": "XY",
      "center": {"X": 250, "Y": 200, "Z": 150}, "radius_mm": 100, "feed_mm_min": 1200,
      "step_deg": 2)" +
         extra + "}]}";
}

TEST(CircularTest, ReadsEveryStepOfBothDirectionsRadially) {
  const Machine m = test::sample_machine("hsu-3axis");
  const Plan plan = test::plan_from_text(plan_json(R"(, "overshoot_deg": 45)"), m);
  ASSERT_EQ(plan.points.size(), 2u * 180u);  // 360 / 2 degrees, ccw then cw; no lead arcs
  for (std::size_t i = 0; i < plan.points.size(); ++i) {
    const PlannedPoint& p = plan.points[i];
    EXPECT_EQ(p.run, i < 180 ? 1 : 2);
    EXPECT_TRUE(p.projection);
    const Eigen::Vector3d v(p.u[0] - 250, p.u[1] - 200, p.u[2] - 150);
    EXPECT_NEAR(v.norm(), 100, 1e-6);
    EXPECT_NEAR(p.beam.dot(v / 100), 1.0, 1e-7);  // the beam is the radial direction
    EXPECT_NEAR(p.feed_mm_min, 1200, 0);
  }
  // Counter-clockwise at 20 deg the velocity is (-sin, cos)(20 deg): X falls, Y rises.
  const PlannedPoint& q = plan.points[10];  // 20 deg, ccw
  EXPECT_EQ(q.dir[0], -1);
  EXPECT_EQ(q.dir[1], +1);
  // Clockwise at 340 deg the velocity is (sin, -cos)(340 deg): both fall.
  const PlannedPoint& w = plan.points[180 + 10];
  EXPECT_EQ(w.dir[0], -1);
  EXPECT_EQ(w.dir[1], -1);
  // Time: each 2 deg chord at 1200 mm/min.
  const double chord_mm = 2 * 100 * std::sin(kPi / 180);
  EXPECT_NEAR(plan.points[11].t_s - plan.points[10].t_s, chord_mm / 1200 * 60, 1e-7);
  // The first reading comes after the 45 deg lead-in arc.
  EXPECT_EQ(plan.points[0].dir[1], +1);
}

TEST(CircularTest, RefusesWhatIsNotACircle) {
  const Machine m = test::sample_machine("hsu-3axis");
  EXPECT_THROW(test::plan_from_text(plan_json(R"(, "plane": "XX")"), m), std::exception);
  EXPECT_THROW(test::plan_from_text(R"({"format": "volmap-plan/1", "tests": [{"type": "circular",
      "radius_mm": 100}]})",
                                    m),
               std::exception);  // no feed
  EXPECT_THROW(test::plan_from_text(plan_json(R"(, "direction": "up")"), m), std::exception);
  // a circle beyond the travel
  EXPECT_THROW(test::plan_from_text(R"({"format": "volmap-plan/1", "tests": [{"type": "circular",
      "center": {"X": 10, "Y": 200, "Z": 150}, "radius_mm": 100, "feed_mm_min": 1000}]})",
                                    m),
               std::exception);
}

TEST(CircularTest, SquarenessAndBacklashHaveTheirHandDerivedSignatures) {
  // A squareness alpha (X moves along X + alpha Y): the radial deviation is
  // alpha x sin(phi) = alpha (x_c + R cos phi) sin phi, the same in both
  // directions. A backlash B of X adds s_X B/2 cos(phi), s_X the sign of
  // X's motion: -sign(sin phi) counter-clockwise, +sign(sin phi) clockwise.
  const Machine m = test::sample_machine("hsu-3axis");
  ErrorSet errors;
  const double alpha = 30e-6;  // rad
  errors.location["EC0X"] = alpha;
  const ErrorModel model(m, errors);
  const Plan plan = test::plan_from_text(plan_json(""), m);
  const GainEvaluator gains(m, Formulation::kIndependent);
  std::istringstream fx(R"({"format": "volmap-effects/1",
      "effects": [{"effect": "reversal", "axis": "X", "value_um": 4}]})");
  const EffectSet effects = read_effects_json(fx, "fx.json", m, gains);
  const Recordings rec = simulate(model, plan, &effects);
  ASSERT_EQ(rec.size(), plan.points.size());
  // Compared up to a centre offset and a radius error (the squareness's
  // pivot, where X = 0 sits, shifts the centre): the difference must be
  // c0 + c1 cos(phi) + c2 sin(phi) to 0.01 um.
  Eigen::MatrixXd A(static_cast<Eigen::Index>(rec.size()), 3);
  Eigen::VectorXd diff(static_cast<Eigen::Index>(rec.size()));
  Eigen::Index used = 0;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const double x = rec.position[0][i] - 250, y = rec.position[1][i] - 200;
    const double phi = std::atan2(y, x);
    if (std::abs(std::sin(phi)) < 0.02) continue;  // at the reversal itself
    const double s_x = (plan.points[i].run == 1 ? -1 : 1) * (std::sin(phi) > 0 ? 1 : -1);
    const double expected_um =
        alpha * rec.position[0][i] * std::sin(phi) * 1000 + s_x * 2.0 * std::cos(phi);
    A.row(used) << 1, std::cos(phi), std::sin(phi);
    diff[used++] = rec.e_along_n_um[i] - expected_um;
  }
  A.conservativeResize(used, 3);
  diff.conservativeResize(used);
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(diff);
  EXPECT_LT((diff - A * c).cwiseAbs().maxCoeff(), 0.01);
  EXPECT_GT(used, 300);
}

TEST(CircularTest, ReversalSpikeAndLateralPlayFollowTheTurnarounds) {
  // A bidirectional X laser run 0..100 mm, two cycles, ex and ey recorded:
  // a spike of 4 um decaying over 20 mm after each reversal of X
  // (-s_X 4 exp(-d / 20), d from the turnaround), and Y shifting 2 um with
  // the direction of X (lateral play: s_X 2 / 2).
  const Machine m = test::sample_machine("hsu-3axis");
  const Plan plan = test::plan_from_text(
      R"({"format": "volmap-plan/1", "tests": [{"type": "laser", "axis": "X", "from": 0,
          "to": 100, "step": 10, "cycles": 2, "at": {"Y": 200, "Z": 150},
          "record": ["ex", "ey"]}]})",
      m);
  const GainEvaluator gains(m, Formulation::kIndependent);
  std::istringstream fx(R"({"format": "volmap-effects/1", "effects": [
      {"effect": "reversal", "axis": "X", "kind": "spike", "value_um": 4, "length_mm": 20},
      {"effect": "reversal", "axis": "Y", "kind": "lateral", "input_axis": "X", "value_um": 2}]})");
  const EffectSet effects = read_effects_json(fx, "fx.json", m, gains);
  const Recordings rec = simulate(ErrorModel(m, ErrorSet{}), plan, &effects);
  ASSERT_EQ(rec.size(), 44u);  // 11 targets, two passes, two cycles
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const double x = rec.position[0][i];
    const int s = plan.points[i].dir[0];
    const bool backward = (i % 22) >= 11;
    // the turnaround: 100 mm before the backward pass, 0 mm before the
    // second cycle's forward pass; none before the first forward pass
    const double d = backward ? 100 - x : (i >= 22 ? x : INFINITY);
    EXPECT_NEAR(rec.e_um[0][i], -s * 4 * std::exp(-d / 20), 1e-6) << i;
    EXPECT_NEAR(rec.e_um[1][i], s * 1.0, 1e-6) << i;
  }
  std::istringstream bad(R"({"format": "volmap-effects/1", "effects": [
      {"effect": "reversal", "axis": "X", "kind": "spike", "value_um": 4}]})");
  EXPECT_THROW(read_effects_json(bad, "fx.json", m, gains), std::exception);  // no length
}

}  // namespace
}  // namespace volmap
