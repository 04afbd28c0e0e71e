// The HTM error model: exact against first order, nominal transformation
// against Lei & Hsu eqs. (10)-(15), hand-derived single-error cases, the
// kinematic-parameter-independent conversion.
#include "core/model/error_model.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>

#include "core/kinematics/kinematics.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "core/model/sensitivity.h"
#include "tests/support/samples.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

constexpr double kDeg = M_PI / 180.0;

Machine lei_hsu() {
  return load_machine_json(test::source_path("samples/machines/lei-hsu-xyzac.json"));
}
Machine hsu3() { return load_machine_json(test::source_path("samples/machines/hsu-3axis.json")); }

using test::random_pose;

// A random error set: every component error of every axis a smooth random
// curve (5 knots over the travel, or a closed 0..360 degree table for an
// unlimited rotary axis), and random location errors; amplitudes `scale`
// times realistic (20 um, 20 urad).
ErrorSet random_errors(const Machine& m, double scale, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  ErrorSet e;
  e.file = "<random>";
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisName a = m.axis_order[static_cast<size_t>(i)];
    const AxisLimits& L = m.limits[static_cast<size_t>(i)];
    AxisErrors ax;
    ax.axis = a;
    const int knots = 7;
    const double lo = L.unlimited ? 0.0 : L.min;
    const double hi = L.unlimited ? 2 * M_PI : L.max;
    for (int k = 0; k < knots; ++k) ax.plus.position.push_back(lo + (hi - lo) * k / (knots - 1));
    std::vector<std::vector<double>> y(kComponentCount);
    for (int c = 0; c < kComponentCount; ++c) {
      for (int k = 0; k < knots; ++k)
        y[static_cast<size_t>(c)].push_back(scale * n(rng) * (c < 3 ? 20e-3 : 20e-6));
      if (L.unlimited) y[static_cast<size_t>(c)].back() = y[static_cast<size_t>(c)].front();
      ax.present[static_cast<size_t>(c)] = true;
    }
    ax.plus.periodic = L.unlimited;
    ax.plus.value.resize(knots);
    ax.plus.slope.resize(knots);
    for (int c = 0; c < kComponentCount; ++c) {
      const std::vector<double> s = pchip_slopes(ax.plus.position, y[static_cast<size_t>(c)]);
      for (int k = 0; k < knots; ++k) {
        ax.plus.value[static_cast<size_t>(k)][static_cast<size_t>(c)] =
            y[static_cast<size_t>(c)][static_cast<size_t>(k)];
        ax.plus.slope[static_cast<size_t>(k)][static_cast<size_t>(c)] = s[static_cast<size_t>(k)];
      }
    }
    ax.plus.source = "<random>";
    e.axis[static_cast<size_t>(a)] = ax;
  }
  for (const std::string& name : model_error_names(m)) {
    const ErrorName en = *parse_error_name(name);
    if (!en.location) continue;
    e.location[name] = scale * n(rng) * (is_angular(en.component) ? 50e-6 : 30e-3);
  }
  return e;
}

double norm6(const PoseError& d) { return std::sqrt(d.dP_mm.squaredNorm() + d.dQ.squaredNorm()); }

// Lei & Hsu eqs. (10)-(15), typed from the paper (offsets Z3 and the
// workpiece offsets Xw0, Yw0, Zw0 of the sample machine).
ToolPose lei_hsu_eq10_15(const AxisVector& u, double Z3, double Xw0, double Yw0, double Zw0) {
  const double xm = u[0], ym = u[1], zm = u[2], a = u[3], c = u[4];
  ToolPose v;
  v.tip_mm.x() =
      zm * std::sin(c) * std::sin(a) - ym * std::sin(c) * std::cos(a) - xm * std::cos(c) - Xw0;
  v.tip_mm.y() =
      zm * std::cos(c) * std::sin(a) - ym * std::cos(c) * std::cos(a) + xm * std::sin(c) - Yw0;
  v.tip_mm.z() = zm * std::cos(a) + ym * std::sin(a) - Z3 - Zw0;
  v.axis = {std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)};
  return v;
}

TEST(NominalForward, LeiHsuEquations10To15HoldForTheSample) {
  const Machine m = lei_hsu();
  std::mt19937 rng(7);
  for (int t = 0; t < 500; ++t) {
    const AxisVector u = random_pose(m, rng);
    const ToolPose v = nominal_forward(m, u);
    const ToolPose p = lei_hsu_eq10_15(u, 50.0, 0.0, 0.0, 60.0);
    EXPECT_NEAR((v.tip_mm - p.tip_mm).norm(), 0.0, 1e-9);
    EXPECT_NEAR((v.axis - p.axis).norm(), 0.0, 1e-12);
  }
}

TEST(NominalForward, WorkpieceOffsetsEnterAsInEq10To12) {
  Machine m = lei_hsu();
  m.workpiece_origin_mm = {12.5, -8.0, 33.0};
  std::mt19937 rng(8);
  for (int t = 0; t < 100; ++t) {
    const AxisVector u = random_pose(m, rng);
    const ToolPose p = lei_hsu_eq10_15(u, 50.0, 12.5, -8.0, 33.0);
    EXPECT_NEAR((nominal_forward(m, u).tip_mm - p.tip_mm).norm(), 0.0, 1e-9);
  }
}

TEST(ErrorModel, ZeroErrorsGiveTheNominalPoseExactly) {
  for (const Machine& m : {hsu3(), lei_hsu()}) {
    ErrorSet none;
    for (Formulation f : {Formulation::kDependent, Formulation::kIndependent}) {
      const ErrorModel model(m, none, {f, OutsidePolicy::kError});
      std::mt19937 rng(3);
      for (int t = 0; t < 50; ++t) {
        const AxisVector u = random_pose(m, rng);
        EXPECT_EQ(norm6(model.exact(u)), 0.0);
        EXPECT_EQ(norm6(model.first_order(u)), 0.0);
      }
    }
  }
}

// The two forms differ by terms of second order in the errors: scaling every
// error by s scales the difference by s^2 (and the errors themselves by s).
TEST(ErrorModel, ExactAndFirstOrderAgreeToSecondOrder) {
  for (const Machine& m : {hsu3(), lei_hsu()}) {
    for (Formulation f : {Formulation::kDependent, Formulation::kIndependent}) {
      std::mt19937 rng(42);
      for (int trial = 0; trial < 20; ++trial) {
        const unsigned seed = static_cast<unsigned>(rng());
        const AxisVector u = random_pose(m, rng);
        double diff[2], size[2];
        const double scales[2] = {1.0, 0.1};
        for (int k = 0; k < 2; ++k) {
          std::mt19937 erng(seed);
          const ErrorModel model(m, random_errors(m, scales[k], erng), {f, OutsidePolicy::kError});
          const PoseError a = model.exact(u), b = model.first_order(u);
          diff[k] = std::sqrt((a.dP_mm - b.dP_mm).squaredNorm() + (a.dQ - b.dQ).squaredNorm());
          size[k] = norm6(a);
        }
        // Realistic errors (tens of um, tens of urad, levers of 500 mm):
        // products of two errors stay below 0.1 um.
        EXPECT_LT(diff[0], 1e-4) << m.name;
        EXPECT_GT(size[0], 1e-4);
        // Quadratic scaling: diff(s/10) = diff(s)/100 (to rounding).
        EXPECT_NEAR(diff[1], diff[0] / 100.0, 0.02 * diff[0] / 100.0 + 1e-15) << m.name;
        EXPECT_NEAR(size[1], size[0] / 10.0, 0.01 * size[0]) << m.name;
      }
    }
  }
}

// Hand derivation on the Hsu machine, dependent form: a constant pitch EBX of
// the X carriage tilts everything below it; the tool tip sits
// (Xz, Yz, Zz + z + Zh - Lt) = (0, -180, 250 + z - 200 - 100) from the X
// carriage, so dx = EBX * (z - 50), dz = -EBX * 0 and di = EBX.
TEST(ErrorModel, SinglePitchErrorByHand) {
  const Machine m = hsu3();
  std::istringstream csv("X,EBX\n0,10\n500,10\n");
  const ErrorModel model(m, read_errors_csv(csv, "pitch.csv"),
                         {Formulation::kDependent, OutsidePolicy::kError});
  AxisVector u(3);
  u << 200, 100, 250;
  const PoseError d = model.exact(u);
  const double ebx = 10e-6;
  EXPECT_NEAR(d.dP_mm.x(), std::sin(ebx) * (250 - 50), 1e-12);
  EXPECT_NEAR(d.dP_mm.y(), 0.0, 1e-12);
  EXPECT_NEAR(d.dP_mm.z(), -(1 - std::cos(ebx)) * (250 - 50), 1e-12);
  EXPECT_NEAR(d.dQ.x(), std::sin(ebx), 1e-15);
  // Independent form: X was measured at the tool tip with Z at 0, so only the
  // Z travel since then is a lever: dx = EBX * z.
  const ErrorModel indep(m, model.errors(), {Formulation::kIndependent, OutsidePolicy::kError});
  EXPECT_NEAR(indep.exact(u).dP_mm.x(), std::sin(ebx) * 250, 1e-12);
}

// Hsu section III.B: a translational error measured at the tool tip holds the
// Abbe term of the measurement pose, EXY' = EXY + Lz EBY + ... (eq. 23-25).
// Feeding the dependent model the true errors and the independent model the
// measured ones must give the same machine.
TEST(ErrorModel, IndependentFormEqualsDependentWithMeasuredTranslations) {
  const Machine m = hsu3();
  // Y pitch and yaw, constant; measured at X = 500, Z = 0 (machine file).
  const double eby = 12e-6, ecy = -7e-6;
  // Tool tip relative to the Y carriage at the measurement pose:
  // (Xx + 500 + Xz, Yx + Yz, Zx + 0 + Zz + Zh - Lt) = (500, -180, 70).
  const Eigen::Vector3d r(500, -180, 70);
  const Eigen::Vector3d eps(0, eby, ecy);
  const Eigen::Vector3d abbe = small_rotation_exact(eps) * r - r;  // exact eq. 17-19 form
  std::istringstream dep_csv(fmt::format(
      "Y,EXY,EYY,EZY,EBY,ECY\n0,0,0,0,{0},{1}\n400,0,0,0,{0},{1}\n", eby * 1e6, ecy * 1e6));
  std::istringstream ind_csv(
      fmt::format("Y,EXY,EYY,EZY,EBY,ECY\n0,{2},{3},{4},{0},{1}\n400,{2},{3},{4},{0},{1}\n",
                  eby * 1e6, ecy * 1e6, abbe.x() * 1e3, abbe.y() * 1e3, abbe.z() * 1e3));
  const ErrorModel dep(m, read_errors_csv(dep_csv, "dep.csv"),
                       {Formulation::kDependent, OutsidePolicy::kError});
  const ErrorModel ind(m, read_errors_csv(ind_csv, "ind.csv"),
                       {Formulation::kIndependent, OutsidePolicy::kError});
  std::mt19937 rng(5);
  for (int t = 0; t < 100; ++t) {
    const AxisVector u = random_pose(m, rng);
    EXPECT_NEAR((dep.exact(u).dP_mm - ind.exact(u).dP_mm).norm(), 0.0, 1e-12);
    // First order: equal up to the second-order part of the exact Abbe term,
    // |eps|^2 |r| / 2 < 1e-7 mm.
    EXPECT_NEAR((dep.first_order(u).dP_mm - ind.first_order(u).dP_mm).norm(), 0.0, 1e-7);
  }
}

// The gains are the derivative of the exact model with respect to each
// error: a central difference of exact() with one error set to +-h.
TEST(Sensitivity, GainsAreTheDerivativeOfTheExactModel) {
  for (const Machine& m : {hsu3(), lei_hsu()}) {
    for (Formulation f : {Formulation::kDependent, Formulation::kIndependent}) {
      std::mt19937 rng(11);
      for (int t = 0; t < 5; ++t) {
        const AxisVector u = random_pose(m, rng);
        for (const ErrorGain& g : error_gains(m, f, u)) {
          const ErrorName n = *parse_error_name(g.name);
          const double h = n.location || is_angular(n.component) ? 1e-5 : 1e-3;
          PoseError d[2];
          for (int s = 0; s < 2; ++s) {
            const double v = (s == 0 ? h : -h);
            ErrorSet e;
            if (n.location) {
              e.location[g.name] = v;
            } else {
              AxisErrors ax;
              ax.axis = n.axis;
              ax.plus.position = {-1e6};
              ax.plus.value.assign(1, {});
              ax.plus.slope.assign(1, {});
              ax.plus.value[0][static_cast<size_t>(n.component)] = v;
              ax.present[static_cast<size_t>(n.component)] = true;
              ax.plus.source = "<fd>";
              e.axis[static_cast<size_t>(n.axis)] = ax;
            }
            d[s] = ErrorModel(m, e, {f, OutsidePolicy::kClamp}).exact(u);
          }
          const Eigen::Vector3d dP = (d[0].dP_mm - d[1].dP_mm) / (2 * h);
          const Eigen::Vector3d dQ = (d[0].dQ - d[1].dQ) / (2 * h);
          EXPECT_NEAR((dP - g.dP).norm(), 0.0, 1e-6 * (1 + g.dP.norm())) << m.name << " " << g.name;
          EXPECT_NEAR((dQ - g.dQ).norm(), 0.0, 1e-8) << m.name << " " << g.name;
        }
      }
    }
  }
}

TEST(Sensitivity, FiveAxisRotaryLocationErrorByHand) {
  // C axis offset EX0C moves the C line (not the part) by +EX0C in X of the A
  // frame; at A = 0, C = 0 the part moves with it, so the tool tip, relative
  // to the part, moves by -EX0C in workpiece X.
  const Machine m = lei_hsu();
  AxisVector u(5);
  u << 10, 20, 30, 0, 0;
  for (const ErrorGain& g : error_gains(m, Formulation::kDependent, u)) {
    if (g.name == "EX0C") {
      EXPECT_NEAR(g.dP.x(), -1.0, 1e-12);
      EXPECT_NEAR(g.dP.y(), 0.0, 1e-12);
    }
    if (g.name == "ECC") {  // C positioning error: rotates the part about C
      // tool tip in the C frame at u: (-10, -20, 30 - 50) -> dP = -e_z x r
      EXPECT_NEAR(g.dP.x(), -20.0, 1e-9);
      EXPECT_NEAR(g.dP.y(), 10.0, 1e-9);
    }
  }
}

TEST(ErrorModel, OutsideTheTableIsAnErrorByDefault) {
  const Machine m = hsu3();
  std::istringstream csv("X,EXX\n100,1\n200,2\n");
  const ErrorSet e = read_errors_csv(csv, "short.csv");
  const ErrorModel strict(m, e);
  AxisVector u(3);
  u << 300, 0, 0;
  EXPECT_THROW(strict.exact(u), std::out_of_range);
  const ErrorModel clamp(m, e, {Formulation::kIndependent, OutsidePolicy::kClamp});
  EXPECT_NEAR(clamp.exact(u).dP_mm.x(), 2e-3, 1e-12);
  EXPECT_GE(clamp.clamped_count(), 1u);
}

TEST(ErrorModel, ErrorsForAnAxisTheMachineLacksAreRefused) {
  std::istringstream csv("A,EAA\n0,1\n10,2\n");
  EXPECT_THROW(ErrorModel(hsu3(), read_errors_csv(csv, "a.csv")), std::invalid_argument);
}

TEST(ErrorModel, SampleErrorsLoadAndGiveRealisticMagnitudes) {
  for (const char* name : {"hsu-3axis", "lei-hsu-xyzac"}) {
    const Machine m =
        load_machine_json(test::source_path(std::string("samples/machines/") + name + ".json"));
    const ErrorModel model(
        m, load_errors_csv(test::source_path(std::string("samples/errors/") + name + ".csv")));
    std::mt19937 rng(1);
    double worst = 0;
    for (int t = 0; t < 200; ++t)
      worst = std::max(worst, model.exact(random_pose(m, rng)).dP_mm.norm());
    // A mid-size machine: tens of micrometres, never millimetres.
    EXPECT_GT(worst, 0.01) << name;
    EXPECT_LT(worst, 0.3) << name;
  }
}

}  // namespace
}  // namespace volmap

namespace volmap {
namespace {
TEST(Kinematics, LinearAxesForTipReachTheTip) {
  const Machine m = load_machine_json(test::source_path("samples/machines/lei-hsu-xyzac.json"));
  std::mt19937 rng(9);
  for (int t = 0; t < 100; ++t) {
    const AxisVector u = random_pose(m, rng);
    const Eigen::Vector3d tip = nominal_forward(m, u).tip_mm;
    AxisVector guess = u;
    guess[0] = guess[1] = guess[2] = 0.0;
    const AxisVector got = linear_axes_for_tip(m, guess, tip);
    EXPECT_NEAR((got - u).norm(), 0.0, 1e-9);
  }
}
}  // namespace
}  // namespace volmap

namespace volmap {
namespace {

// The post-processor's three-axis evaluator is exact()'s arithmetic on the
// tool tip alone: the same numbers to the bit, on both sides of the chain
// and for every approach direction.
TEST(ErrorModel, TipErrorLinearIsExactToTheBit) {
  // A bed-type machine: X and Y carry the workpiece, Z the spindle; the
  // location errors give every joint a rotated location frame.
  std::istringstream bed(R"({
    "format": "volmap-machine/1", "name": "bed-3axis", "structure": "[w X' Y' b Z t]",
    "axes": {
      "X": {"type": "linear", "direction": [1, 0, 0], "travel_mm": [0, 500]},
      "Y": {"type": "linear", "direction": [0, 1, 0], "travel_mm": [0, 400]},
      "Z": {"type": "linear", "direction": [0, 0, 1], "travel_mm": [0, 300]}},
    "workpiece_chain": [{"axis": "Y", "offset_mm": [0, 0, 50]}, {"axis": "X", "offset_mm": [0, 0, 80]}],
    "tool_chain": [{"axis": "Z", "offset_mm": [0, 0, 600]}],
    "spindle_offset_mm": [0, 0, -150], "tool": {"length_mm": 120, "axis": [0, 0, 1]},
    "workpiece_origin_mm": [0, 0, 30],
    "measured_at": {"X": {"Y": 200, "Z": 100}, "Y": {"X": 250, "Z": 100}, "Z": {"X": 250, "Y": 200}}})");
  std::mt19937 rng(7);
  const Machine bed_machine = read_machine_json(bed, "<bed>");
  ErrorSet bed_errors =
      random_errors(bed_machine, 30.0, rng);  // 0.6 mm, 0.6 mrad: second order shows
  for (const char* n : {"EA0X", "EB0Y", "EC0Z", "EA0Z", "EC0X"}) bed_errors.location[n] = 2e-4;
  struct Case {
    Machine machine;
    ErrorSet errors;
  };
  const Case cases[] = {
      {hsu3(),
       load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv"))},  // bidirectional
      {bed_machine, bed_errors}};
  for (const Case& k : cases) {
    SCOPED_TRACE(k.machine.name);
    const ErrorModel model(k.machine, k.errors);
    ASSERT_TRUE(model.all_joints_linear());
    std::uniform_real_distribution<double> f(0.0, 1.0);
    std::uniform_int_distribution<int> die(-1, 1), coin(0, 2);
    double u[3] = {10, 10, 10};
    ApproachDirections dir{};
    for (int trial = 0; trial < 3000; ++trial) {
      // Each axis moves, or stays, or turns round in place.
      for (int a = 0; a < 3; ++a) {
        const int what = coin(rng);
        if (what == 0)
          u[a] = k.machine.limits[static_cast<size_t>(a)].min +
                 f(rng) * (k.machine.limits[static_cast<size_t>(a)].max -
                           k.machine.limits[static_cast<size_t>(a)].min);
        if (what != 1) dir[static_cast<size_t>(a)] = static_cast<std::int8_t>(die(rng));
      }
      AxisVector uv(3);
      uv << u[0], u[1], u[2];
      const Eigen::Vector3d want = model.exact(uv, dir).dP_mm;
      const Eigen::Vector3d got = model.tip_error_linear(u, dir);
      for (int i = 0; i < 3; ++i) {
        std::uint64_t g, w;
        std::memcpy(&g, &got[i], 8);
        std::memcpy(&w, &want[i], 8);
        ASSERT_EQ(g, w) << "trial " << trial << " coordinate " << i << ": " << got[i] << " vs "
                        << want[i];
      }
    }
  }
  // A machine with a rotary joint is not for it.
  EXPECT_FALSE(ErrorModel(lei_hsu(), ErrorSet{}).all_joints_linear());
}

}  // namespace
}  // namespace volmap

namespace volmap {
namespace {

// Bit patterns equal, or both NaN (a NaN's sign and payload are not
// arithmetic: the compiler may swap the operands of a commutative operation).
bool same_bits(double a, double b) {
  if (std::isnan(a) && std::isnan(b)) return true;
  std::uint64_t x, y;
  std::memcpy(&x, &a, 8);
  std::memcpy(&y, &b, 8);
  return x == y;
}

// tip_error_linear against exact() at one u: the same bits, the same
// exception, the same clamped count (in *clamped_out, or in clamped_count()
// without it).
void expect_tip_error_linear_is_exact(const ErrorModel& model, const double* u,
                                      const ApproachDirections& dir) {
  AxisVector uv(3);
  uv << u[0], u[1], u[2];
  const auto where = [&] {
    return fmt::format("u = ({}, {}, {}) dir = ({}, {}, {})", u[0], u[1], u[2], dir[0], dir[1],
                       dir[2]);
  };
  Eigen::Vector3d want = Eigen::Vector3d::Zero(), got = Eigen::Vector3d::Zero();
  std::string want_error, got_error;
  const std::uint64_t c0 = model.clamped_count();
  try {
    want = model.exact(uv, dir).dP_mm;
  } catch (const std::out_of_range& e) {
    want_error = e.what();
  }
  const std::uint64_t c1 = model.clamped_count();
  std::uint64_t clamped = 0;
  try {
    got = model.tip_error_linear(u, dir, &clamped);
  } catch (const std::out_of_range& e) {
    got_error = e.what();
  }
  ASSERT_EQ(got_error, want_error) << where();
  EXPECT_EQ(model.clamped_count(), c1) << where();  // counted in `clamped` instead
  EXPECT_EQ(clamped, c1 - c0) << where();
  if (!want_error.empty()) return;
  for (int i = 0; i < 3; ++i)
    ASSERT_TRUE(same_bits(got[i], want[i]))
        << where() << " coordinate " << i << ": " << got[i] << " vs " << want[i];
  // Without clamped_out the count goes to the model, as exact()'s does.
  const Eigen::Vector3d again = model.tip_error_linear(u, dir);
  EXPECT_EQ(model.clamped_count(), c1 + clamped) << where();
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(same_bits(again[i], want[i])) << where();
}

// The second table of every axis: the first one's values and slopes scaled,
// so that dir = -1, 0, +1 give three different answers.
void make_bidirectional(ErrorSet& e, double scale) {
  for (auto& ax : e.axis) {
    if (!ax) continue;
    ax->minus = ax->plus;
    for (auto& row : ax->minus.value)
      for (double& x : row) x *= scale;
    for (auto& row : ax->minus.slope)
      for (double& x : row) x *= scale;
  }
}

// Edge positions of axis a: the table knots of both directions, the travel
// ends, +-0, the smallest subnormals, outside the tables, +-inf and NaN.
std::vector<double> edge_positions(const ErrorSet& e, const Machine& m, int a) {
  std::vector<double> out = {0.0,
                             -0.0,
                             5e-324,
                             -5e-324,
                             std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::quiet_NaN()};
  const AxisLimits& L = m.limits[static_cast<size_t>(a)];
  for (double x : {L.min, L.max, L.min - 7.5, L.max + 7.5, 0.5 * (L.min + L.max)}) out.push_back(x);
  if (const AxisErrors* ax = e.errors_of(m.axis_order[static_cast<size_t>(a)])) {
    for (const AxisErrorTable* t : {&ax->plus, &ax->minus})
      for (double x : t->position) {
        out.push_back(x);
        out.push_back(std::nextafter(x, -1e300));
        out.push_back(std::nextafter(x, 1e300));
      }
  }
  return out;
}

// Bit for bit on every kind of machine and error set: both formulations,
// both outside policies, every approach direction, positions at and beside
// the table knots, signed zeros, outside the tables, non-finite.
TEST(ErrorModel, TipErrorLinearIsExactToTheBitAtTheEdges) {
  std::mt19937 rng(2024);
  struct Case {
    std::string name;
    Machine machine;
    ErrorSet errors;
  };
  std::vector<Case> cases;
  // 1. The sample machine and its measured (bidirectional) errors.
  cases.push_back(
      {"hsu sample", hsu3(), load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv"))});
  // 2. Workpiece chain of one axis, tool chain of two; non-uniform knots
  //    (binary search), rotated location frames on both sides.
  {
    std::istringstream js(R"({
      "format": "volmap-machine/1", "name": "split-3axis",
      "axes": {
        "X": {"type": "linear", "direction": [1, 0, 0], "travel_mm": [-250, 250]},
        "Y": {"type": "linear", "direction": [0, 1, 0], "travel_mm": [0, 400]},
        "Z": {"type": "linear", "direction": [0, 0, 1], "travel_mm": [-300, 0]}},
      "workpiece_chain": [{"axis": "Y", "offset_mm": [0, 0, 40]}],
      "tool_chain": [{"axis": "X", "offset_mm": [0, 0, 700]}, {"axis": "Z", "offset_mm": [10, -20, 150]}],
      "spindle_offset_mm": [0, 0, -90], "tool": {"length_mm": 75, "axis": [0, 0, 1]},
      "workpiece_origin_mm": [5, -3, 25],
      "measured_at": {"X": {"Y": 200, "Z": -100}, "Y": {"X": 0, "Z": -100}, "Z": {"X": 0, "Y": 200}}})");
    const Machine m = read_machine_json(js, "<split>");
    ErrorSet e = random_errors(m, 10.0, rng);
    make_bidirectional(e, -0.7);
    for (auto& ax : e.axis)
      if (ax) {
        std::vector<double>& x = ax->plus.position;
        for (size_t k = 1; k + 1 < x.size(); ++k) x[k] += (k % 2 ? 3.25 : -1.5);
        ax->minus.position = x;
      }
    for (const char* n : {"EA0X", "EB0Y", "EC0Z", "EB0X", "EA0Y", "EX0Z", "EY0Y"})
      e.location[n] = 1.5e-4;
    cases.push_back({"split", m, e});
  }
  // 3. One axis without error tables (its joint is the identity), one
  //    unidirectional, one bidirectional.
  {
    const Machine m = hsu3();
    ErrorSet e = random_errors(m, 5.0, rng);
    e.axis[static_cast<size_t>(AxisName::Y)].reset();
    auto& z = *e.axis[static_cast<size_t>(AxisName::Z)];
    z.minus = z.plus;
    for (auto& row : z.minus.value) row[3] += 1e-5;
    cases.push_back({"no Y tables", m, e});
  }
  // 4. Signed zeros everywhere: no offsets, the spindle at -0 (the tip
  //    starts as (-0, -0, -0)), no tool, all-zero error tables on X, none on
  //    Y, zero angles with nonzero translations on Z (rotations with entries
  //    1 and +-0); and the same machine without any error table (identity
  //    joints only).
  {
    std::istringstream js(R"({
      "format": "volmap-machine/1", "name": "zero-3axis",
      "axes": {
        "X": {"type": "linear", "direction": [1, 0, 0], "travel_mm": [-100, 100]},
        "Y": {"type": "linear", "direction": [0, 1, 0], "travel_mm": [-100, 100]},
        "Z": {"type": "linear", "direction": [0, 0, 1], "travel_mm": [-100, 100]}},
      "workpiece_chain": [{"axis": "X", "offset_mm": [-0.0, -0.0, -0.0]}],
      "tool_chain": [{"axis": "Y", "offset_mm": [-0.0, -0.0, -0.0]}, {"axis": "Z", "offset_mm": [0, 0, -0.0]}],
      "spindle_offset_mm": [-0.0, -0.0, -0.0], "tool": {"length_mm": 0, "axis": [0, 0, 1]},
      "workpiece_origin_mm": [0, -0.0, 0],
      "measured_at": {"X": {"Y": 0, "Z": 0}, "Y": {"X": 0, "Z": 0}, "Z": {"X": 0, "Y": 0}}})");
    const Machine m = read_machine_json(js, "<zero>");
    ErrorSet e = random_errors(m, 1.0, rng);
    e.location.clear();
    for (auto& row : e.axis[static_cast<size_t>(AxisName::X)]->plus.value) row.fill(0.0);
    for (auto& row : e.axis[static_cast<size_t>(AxisName::X)]->plus.slope) row.fill(0.0);
    e.axis[static_cast<size_t>(AxisName::Y)].reset();
    for (auto& row : e.axis[static_cast<size_t>(AxisName::Z)]->plus.value)
      row[3] = row[4] = row[5] = 0.0;
    for (auto& row : e.axis[static_cast<size_t>(AxisName::Z)]->plus.slope)
      row[3] = row[4] = row[5] = 0.0;
    make_bidirectional(e, -1.0);
    cases.push_back({"zeros", m, e});
    // Location translations of -0: t_parent_loc = offset + delta stays -0.
    ErrorSet minus_zero;
    for (const char* n : {"EX0X", "EY0X", "EZ0X", "EX0Y", "EY0Y", "EZ0Y", "EX0Z", "EY0Z", "EZ0Z"})
      minus_zero.location[n] = -0.0;
    cases.push_back({"zeros, -0 location errors only", m, minus_zero});
    cases.push_back({"zeros, no errors", m, ErrorSet{}});
  }
  // 5. Large angles (small_sincos's other ranges) on the bed machine of the
  //    test above.
  {
    const Machine m = hsu3();
    ErrorSet e = random_errors(m, 300.0, rng);  // 6 mrad: past the 1e-3 series
    make_bidirectional(e, 1.7);                 // 10 mrad: past the 1e-2 series
    cases.push_back({"large angles", m, e});
  }

  for (const Case& k : cases) {
    for (Formulation f : {Formulation::kIndependent, Formulation::kDependent}) {
      for (OutsidePolicy p : {OutsidePolicy::kError, OutsidePolicy::kClamp}) {
        SCOPED_TRACE(fmt::format("{}, {}, {}", k.name,
                                 f == Formulation::kIndependent ? "independent" : "dependent",
                                 p == OutsidePolicy::kError ? "error" : "clamp"));
        const ErrorModel model(k.machine, k.errors, {f, p});
        ASSERT_TRUE(model.all_joints_linear());
        std::vector<double> edges[3];
        for (int a = 0; a < 3; ++a) edges[a] = edge_positions(k.errors, k.machine, a);
        std::uniform_real_distribution<double> unit(0.0, 1.0);
        for (int trial = 0; trial < 300; ++trial) {
          double u[3];
          for (int a = 0; a < 3; ++a) {
            const AxisLimits& L = k.machine.limits[static_cast<size_t>(a)];
            if (trial % 3 == 0) {
              u[a] = L.min + unit(rng) * (L.max - L.min);
            } else {
              std::uniform_int_distribution<size_t> pick(0, edges[a].size() - 1);
              u[a] = edges[a][pick(rng)];
            }
          }
          // Every approach direction.
          for (int d = 0; d < 27; ++d) {
            const ApproachDirections dir{static_cast<std::int8_t>(d % 3 - 1),
                                         static_cast<std::int8_t>(d / 3 % 3 - 1),
                                         static_cast<std::int8_t>(d / 9 - 1),
                                         0,
                                         0,
                                         0};
            expect_tip_error_linear_is_exact(model, u, dir);
            if (::testing::Test::HasFatalFailure()) return;
          }
        }
        // Outside the tables: refused (kError) or clamped and counted once
        // per axis (kClamp), as exact() does.
        const AxisLimits& X = k.machine.limits[0];
        const double outside[3] = {X.max + 50, k.machine.limits[1].min - 50,
                                   k.machine.limits[2].max + 50};
        for (int d = 0; d < 27; ++d) {
          const ApproachDirections dir{static_cast<std::int8_t>(d % 3 - 1),
                                       static_cast<std::int8_t>(d / 3 % 3 - 1),
                                       static_cast<std::int8_t>(d / 9 - 1),
                                       0,
                                       0,
                                       0};
          expect_tip_error_linear_is_exact(model, outside, dir);
        }
        if (p == OutsidePolicy::kClamp && k.errors.errors_of(AxisName::X) &&
            k.errors.errors_of(AxisName::Z)) {
          std::uint64_t clamped = 0;
          model.tip_error_linear(outside, ApproachDirections{}, &clamped);
          EXPECT_EQ(clamped, k.errors.errors_of(AxisName::Y) ? 3u : 2u);
        }
      }
    }
  }
}

}  // namespace
}  // namespace volmap
