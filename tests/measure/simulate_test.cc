// volmap simulate: determinism, noise, the geometric part against a
// hand-derived case, and every effect's injected signal against its formula
// (docs/simulate.md), computed here independently from the recorded columns.
#include "core/measure/simulate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "core/common/input_error.h"
#include "core/measure/effects.h"
#include "core/measure/plan.h"
#include "core/measure/recordings.h"
#include "core/model/errors_csv.h"
#include "core/model/gain_evaluator.h"
#include "core/model/machine_json.h"
#include "tests/support/plans.h"
#include "tests/support/samples.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

Machine machine(const std::string& name) { return test::sample_machine(name); }

ErrorSet errors_from(const std::string& text) { return test::errors_from_text(text); }

Plan plan_from(const std::string& json, const Machine& m) { return test::plan_from_text(json, m); }

EffectSet effects_from(const std::string& json, const Machine& m) {
  std::istringstream in(json);
  const GainEvaluator g(m, Formulation::kIndependent);
  return read_effects_json(in, "fx.json", m, g);
}

std::string csv(const Recordings& r) {
  std::ostringstream out;
  write_recordings_csv(out, r);
  return out.str();
}

/// Recordings of a plan with no geometric errors and the given effects.
Recordings run_effects(const std::string& machine_name, const std::string& plan,
                       const std::string& fx) {
  const Machine m = machine(machine_name);
  const ErrorModel model(m, ErrorSet{});
  const Plan p = plan_from(plan, m);
  const EffectSet e = effects_from(fx, m);
  return simulate(model, p, &e);
}

const std::string kLaserX =
    R"({"seed": 3, "tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 50,
        "cycles": 2, "at": {"Y": 200, "Z": 150}, "dwell_s": 5, "move_s": 2}]})";

TEST(Simulate, SameSeedSameBytesOtherSeedOtherBytes) {
  const Machine m = machine("lei-hsu-xyzac");
  const ErrorModel model(m, load_errors_csv(test::source_path("samples/errors/lei-hsu-xyzac.csv")));
  std::ifstream in(test::source_path("samples/plans/probe-ball.json"));
  std::stringstream text;
  text << in.rdbuf();
  const Plan a = plan_from(text.str(), m);
  const std::string first = csv(simulate(model, a, nullptr));
  EXPECT_EQ(first, csv(simulate(model, a, nullptr)));
  std::string other = text.str();
  other.replace(other.find("\"seed\": 7"), 9, "\"seed\": 8");
  const std::string second = csv(simulate(model, plan_from(other, m), nullptr));
  EXPECT_NE(first, second);
  EXPECT_EQ(first.size() / 100, second.size() / 100);  // same table, other noise
}

TEST(Simulate, NoiseIsStandardNormalTimesSigma) {
  NormalSource n(42);
  double sum = 0, sum2 = 0;
  const int count = 200000;
  for (int k = 0; k < count; ++k) {
    const double z = n.next();
    sum += z;
    sum2 += z * z;
  }
  EXPECT_NEAR(sum / count, 0.0, 5.0 / std::sqrt(count));
  EXPECT_NEAR(sum2 / count, 1.0, 0.01);
  // Through the simulator: zero errors, sigma 0.5.
  const Machine m = machine("hsu-3axis");
  const ErrorModel model(m, ErrorSet{});
  const Recordings r = simulate(model,
                                plan_from(R"({"seed": 9, "noise_um": 0.5, "tests": [{"type": "grid",
      "axes": {"X": {"from": 0, "to": 500, "step": 10}, "Y": {"from": 0, "to": 400, "step": 10}}}]})",
                                          m),
                                nullptr);
  double s2 = 0;
  for (double v : r.e_um[0]) s2 += v * v;
  EXPECT_NEAR(std::sqrt(s2 / static_cast<double>(r.size())), 0.5, 0.02);
}

TEST(Simulate, LaserRunPositionsDirectionsTimeAndRuns) {
  const Machine m = machine("hsu-3axis");
  const Recordings r = simulate(ErrorModel(m, ErrorSet{}), plan_from(kLaserX, m), nullptr);
  ASSERT_EQ(r.size(), 2u * 22u);  // 11 targets, forward and back, two cycles
  EXPECT_EQ(r.position[0][10], 500.0);
  EXPECT_EQ(r.position[0][11], 500.0);  // the end point twice, as in the spec example
  EXPECT_EQ(r.dir[0][10], 1);
  EXPECT_EQ(r.dir[0][11], -1);
  EXPECT_EQ(r.dir[1][5], 1);  // Y keeps the direction of its one move (home 0 -> 200)
  EXPECT_EQ(r.dir[2][5], 1);
  EXPECT_DOUBLE_EQ(r.t_s[0], 7.0);  // move 2 s + dwell 5 s
  EXPECT_DOUBLE_EQ(r.t_s[1], 14.0);
  EXPECT_EQ(r.run_names[static_cast<std::size_t>(r.run[21])], "1");
  EXPECT_EQ(r.run_names[static_cast<std::size_t>(r.run[22])], "2");
  EXPECT_TRUE(r.has_component(0));
  EXPECT_FALSE(r.has_component(1));
}

TEST(Simulate, GeometricPartMatchesHandDerivedCAxisOffset) {
  // Only EX0C = 10 um: the C line is displaced by +10 um in x of the
  // (non-rotating) A frame, c = (10, 0, 0) um.
  //  - ISO 230-1: the part turns by C about the displaced line, a part
  //    point goes to c + R(p - c) instead of R p: it moves by (I - R) c, the
  //    tool relative to it by -(I - R) c; in workpiece coordinates
  //    (R^T = Rz(-C)): R^T c - c, so ex = 10 - 10 cos C, ey = 10 sin C.
  //  - link errors: the part moves with the line, +10 um in base x at
  //    A = 0; the tool relative to it in workpiece coordinates: -R^T c,
  //    ex = -10 cos C, ey = +10 sin C.
  const Machine m = machine("lei-hsu-xyzac");
  for (LocationConvention convention : {LocationConvention::kIso230, LocationConvention::kLink}) {
    ErrorSet e = errors_from("EX0C\n10\n");
    e.convention = convention;
    const ErrorModel model(m, e);
    const Recordings r =
        simulate(model,
                 plan_from(R"({"tests": [{"type": "probe_ball", "center_mm": [40, 10, 30],
      "a_deg": 0, "c_deg": {"from": 0, "to": 330, "step": 30}}]})",
                           m),
                 nullptr);
    ASSERT_EQ(r.size(), 12u);
    const double iso = convention == LocationConvention::kIso230 ? 10.0 : 0.0;
    for (std::size_t i = 0; i < r.size(); ++i) {
      const double c = r.position[5][i];
      EXPECT_NEAR(r.e_um[0][i], iso - 10.0 * std::cos(c), 1e-9);
      EXPECT_NEAR(r.e_um[1][i], 10.0 * std::sin(c), 1e-9);
      EXPECT_NEAR(r.e_um[2][i], 0.0, 1e-9);
    }
  }
}

TEST(SimulateEffects, Reversal) {
  const Recordings r = run_effects(
      "hsu-3axis", kLaserX, R"({"effects": [{"effect": "reversal", "axis": "X", "value_um": 4}]})");
  for (std::size_t i = 0; i < r.size(); ++i) EXPECT_NEAR(r.e_um[0][i], 2.0 * r.dir[0][i], 1e-9);
}

TEST(SimulateEffects, ThermalDriftSettlingOffset) {
  const Recordings r = run_effects(
      "hsu-3axis", kLaserX,
      R"({"effects": [{"effect": "thermal_drift", "axis": "X", "amplitude_um": 6, "tau_s": 60}]})");
  for (std::size_t i = 0; i < r.size(); ++i)
    EXPECT_NEAR(r.e_um[0][i], 6.0 * (1.0 - std::exp(-r.t_s[i] / 60.0)), 1e-6);
}

TEST(SimulateEffects, ThermalDriftRateScale) {
  const Recordings r = run_effects(
      "hsu-3axis", kLaserX,
      R"({"effects": [{"effect": "thermal_drift", "axis": "X", "kind": "scale", "rate_um_per_h": 36,
          "origin_mm": 100, "reference_length_mm": 500}]})");
  for (std::size_t i = 0; i < r.size(); ++i)
    EXPECT_NEAR(r.e_um[0][i], 36.0 * r.t_s[i] / 3600.0 * (r.position[0][i] - 100.0) / 500.0, 1e-6);
}

TEST(SimulateEffects, ThermalDriftAgainstTemperature) {
  const std::string plan =
      R"({"temperature": {"sensor": "x_screw", "start_c": 20, "rise_c": 3, "tau_s": 100},
      "tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 100, "at": {"Y": 0, "Z": 0}}]})";
  const Recordings r = run_effects(
      "hsu-3axis", plan,
      R"({"effects": [{"effect": "thermal_drift", "axis": "X", "um_per_k": 2.5, "sensor": "x_screw", "reference_c": 20}]})");
  ASSERT_EQ(r.temperature_c.size(), 1u);
  EXPECT_EQ(r.temperature_c[0].name, "temp_x_screw_c");
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double T = r.temperature_c[0].values[i];
    EXPECT_NEAR(T, 20.0 + 3.0 * (1.0 - std::exp(-r.t_s[i] / 100.0)), 1e-9);
    EXPECT_NEAR(r.e_um[0][i], 2.5 * (T - 20.0), 1e-6);
  }
}

TEST(SimulateEffects, Cyclic) {
  const std::string plan =
      R"({"tests": [{"type": "laser", "axis": "X", "from": 0, "to": 40, "step": 1.25,
      "at": {"Y": 0, "Z": 0}}]})";
  const Recordings r = run_effects(
      "hsu-3axis", plan,
      R"({"effects": [{"effect": "cyclic", "axis": "X", "period_mm": 10, "amplitude_um": 0.5, "phase_deg": 30}]})");
  for (std::size_t i = 0; i < r.size(); ++i)
    EXPECT_NEAR(r.e_um[0][i], 0.5 * std::sin(2 * kPi * r.position[0][i] / 10.0 + 30 * kDeg), 1e-9);
}

TEST(SimulateEffects, ServoLagAlongMotionTimesFeed) {
  const std::string plan =
      R"({"tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 100,
      "at": {"Y": 0, "Z": 0}, "feed_mm_min": [1000, 4000]}]})";
  const Recordings r =
      run_effects("hsu-3axis", plan,
                  R"({"effects": [{"effect": "servo_lag", "axis": "X", "um_per_m_min": 1.5}]})");
  ASSERT_EQ(r.size(), 24u);
  for (std::size_t i = 0; i < r.size(); ++i)
    EXPECT_NEAR(r.e_um[0][i], -1.5 * r.feed_mm_min[i] / 1000.0 * r.dir[0][i], 1e-9);
  // Time follows the feed: 100 mm at 1000 mm/min = 6 s, plus the 1 s dwell.
  EXPECT_NEAR(r.t_s[2] - r.t_s[1], 7.0, 1e-9);
}

TEST(SimulateEffects, SagQuadraticInAnotherAxis) {
  const std::string plan =
      R"({"tests": [{"type": "grid", "axes": {"X": {"from": 0, "to": 500, "step": 50},
      "Y": 100, "Z": 100}, "record": ["ez"]}]})";
  const Recordings r = run_effects(
      "hsu-3axis", plan,
      R"({"effects": [{"effect": "sag", "axis": "Z", "input_axis": "X", "coefficient": -4e-5, "origin": 250}]})");
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double d = r.position[0][i] - 250.0;
    EXPECT_NEAR(r.e_um[2][i], -4e-5 * d * d, 1e-9);
  }
}

TEST(SimulateEffects, SetupShiftPerRun) {
  const std::string plan =
      R"({"tests": [{"type": "grid", "axes": {"X": [0, 250, 500], "Y": 100, "Z": 100},
      "cycles": 3}]})";
  const Recordings r = run_effects(
      "hsu-3axis", plan,
      R"({"effects": [{"effect": "setup_shift", "per_run_um": [[1, 2, 3], [-4, 5, 0.5]]}]})");
  const double expected[3][3] = {{1, 2, 3}, {-4, 5, 0.5}, {0, 0, 0}};  // run 3: none given
  for (std::size_t i = 0; i < r.size(); ++i) {
    const int run = std::stoi(r.run_names[static_cast<std::size_t>(r.run[i])]);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(r.e_um[static_cast<std::size_t>(c)][i], expected[run - 1][c], 1e-9);
  }
}

// Rotary effects on the X'Y'ZA'C' sample at A = 0. The C joint's frame
// origin lies on the C line at the table face, 60 mm below the workpiece
// origin: o_w = (0, 0, -60). A small rotation eps (base axes; at A = 0 the A
// frame is aligned with the base) of the workpiece about o moves a point p
// by eps x (p - o); the tool relative to the workpiece moves by the
// opposite, seen in workpiece coordinates R_w_b = Rz(C)^T.
Eigen::Vector3d rotated_tool_um(const Eigen::Vector3d& eps_b_urad, const Eigen::Vector3d& p_w,
                                double c) {
  const Eigen::Matrix3d R_w_b =
      Eigen::AngleAxisd(c, Eigen::Vector3d::UnitZ()).toRotationMatrix().transpose();
  const Eigen::Vector3d o_w(0, 0, -60);
  return -(R_w_b * eps_b_urad * 1e-6).cross(p_w - o_w) * 1e3;
}

const std::string kBallC =
    R"({"tests": [{"type": "probe_ball", "center_mm": [40, -25, 30], "a_deg": 0,
    "c_deg": {"from": 0, "to": 350, "step": 10}}]})";

TEST(SimulateEffects, RotaryPositioning) {
  const Recordings r = run_effects(
      "lei-hsu-xyzac", kBallC,
      R"({"effects": [{"effect": "rotary_positioning", "axis": "C", "order": 2, "amplitude_urad": 50, "phase_deg": 10}]})");
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double c = r.position[5][i];
    const double eps = 50.0 * std::sin(2 * c + 10 * kDeg);
    const Eigen::Vector3d e = rotated_tool_um({0, 0, eps}, {40, -25, 30}, c);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.e_um[static_cast<std::size_t>(k)][i], e[k], 1e-6);
  }
}

TEST(SimulateEffects, RotaryWobble) {
  const Recordings r = run_effects(
      "lei-hsu-xyzac", kBallC,
      R"({"effects": [{"effect": "rotary_wobble", "axis": "C", "order": 1, "amplitude_urad": 30}]})");
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double c = r.position[5][i];
    const Eigen::Vector3d e =
        rotated_tool_um({30 * std::cos(c), 30 * std::sin(c), 0}, {40, -25, 30}, c);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.e_um[static_cast<std::size_t>(k)][i], e[k], 1e-6);
  }
}

TEST(Simulate, MachineFrameIsTheWorkpieceDeviationRotatedToTheBase) {
  const Machine m = machine("lei-hsu-xyzac");
  const ErrorModel model(m, load_errors_csv(test::source_path("samples/errors/lei-hsu-xyzac.csv")));
  const std::string plan =
      R"({"tests": [{"type": "probe_ball", "center_mm": [40, 0, 0], "a_deg": [-60, -30],
      "c_deg": [0, 120, 240]}]})";
  const Recordings w = simulate(model, plan_from(plan, m), nullptr);
  std::string machine_plan = plan;
  machine_plan.insert(1, "\"frame\": \"machine\", ");
  const Recordings b = simulate(model, plan_from(machine_plan, m), nullptr);
  EXPECT_EQ(b.frame, RecordingFrame::kMachine);
  for (std::size_t i = 0; i < w.size(); ++i) {
    const double a = w.position[3][i], c = w.position[5][i];
    // Workpiece on C on A: R_b_w = Rx(A) Rz(C) for this machine.
    const Eigen::Matrix3d R_b_w = (Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()) *
                                   Eigen::AngleAxisd(c, Eigen::Vector3d::UnitZ()))
                                      .toRotationMatrix();
    const Eigen::Vector3d e_w(w.e_um[0][i], w.e_um[1][i], w.e_um[2][i]);
    const Eigen::Vector3d e_b = R_b_w * e_w;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(b.e_um[static_cast<std::size_t>(k)][i], e_b[k], 1e-9);
  }
}

TEST(Simulate, ProjectionAlongTheBeam) {
  const Machine m = machine("hsu-3axis");
  const ErrorModel model(m, load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv")));
  const std::string base =
      R"({"tests": [{"type": "grid", "axes": {"X": [0, 250, 500], "Y": [0, 400], "Z": 100})";
  const Recordings v = simulate(model, plan_from(base + "}]}", m), nullptr);
  const Recordings p =
      simulate(model, plan_from(base + R"(, "beam": [0.6, 0, 0.8]}]})", m), nullptr);
  ASSERT_TRUE(p.has_projection());
  for (std::size_t i = 0; i < v.size(); ++i)
    EXPECT_NEAR(p.e_along_n_um[i], 0.6 * v.e_um[0][i] + 0.8 * v.e_um[2][i], 1e-9);
}

TEST(SimulateInput, PointOutsideTravelNamesTheTest) {
  const Machine m = machine("hsu-3axis");
  try {
    (void)plan_from(R"({"tests": [{"type": "grid", "axes": {"X": [0, 600]}}]})", m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("plan.json:/tests/0: planned point X=600"),
              std::string::npos)
        << e.what();
  }
}

TEST(SimulateInput, UnknownEffectAndUnknownKey) {
  const Machine m = machine("hsu-3axis");
  EXPECT_THROW((void)effects_from(R"({"effects": [{"effect": "backlash", "axis": "X"}]})", m),
               InputError);
  try {
    (void)effects_from(R"({"effects": [{"effect": "reversal", "axis": "X", "value": 3}]})", m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fx.json:/effects/0/value: unknown key"),
              std::string::npos)
        << e.what();
  }
  try {
    (void)plan_from("{\"tests\": [\n  {\"type\": \"laser\",}\n]}", m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 2) << e.what();
  }
}

}  // namespace
}  // namespace volmap
