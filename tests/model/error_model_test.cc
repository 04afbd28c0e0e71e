// The HTM error model: exact against first order, nominal transformation
// against Lei & Hsu eqs. (10)-(15), hand-derived single-error cases, the
// kinematic-parameter-independent conversion.
#include "core/model/error_model.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>

#include "core/kinematics/kinematics.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "core/model/sensitivity.h"
#include "tests/model/error_model_fixtures.h"
#include "tests/support/samples.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

using test::hsu3;
using test::lei_hsu;
using test::random_errors;
using test::random_pose;

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
  // C axis offset EX0C moves the C line by +EX0C in X of the A frame.
  // Link errors move the C frame, and the part with it: at A = 0, C = 0 the
  // tool tip, relative to the part, moves by -EX0C in workpiece X.
  // ISO 230-1: the part turns about the displaced line, so at C = 0 nothing
  // moves; at C = 90 deg a part point p goes to c + R (p - c) instead of R p,
  // moved by (I - R) c = (1, -1) per unit of c = (1, 0) in the A frame; the
  // tool relative to the part: (-1, 1), in workpiece axes (turned by C)
  // R^T (-1, 1) = (1, 1).
  const Machine m = lei_hsu();
  AxisVector u(5);
  u << 10, 20, 30, 0, 0;
  auto ex0c = [&](LocationConvention c) {
    for (const ErrorGain& g : error_gains(m, Formulation::kDependent, u, c))
      if (g.name == "EX0C") return g.dP;
    return Eigen::Vector3d(Eigen::Vector3d::Constant(NAN));
  };
  EXPECT_NEAR((ex0c(LocationConvention::kLink) - Eigen::Vector3d(-1, 0, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR(ex0c(LocationConvention::kIso230).norm(), 0, 1e-12);
  u[4] = M_PI / 2;
  EXPECT_NEAR((ex0c(LocationConvention::kIso230) - Eigen::Vector3d(1, 1, 0)).norm(), 0, 1e-12);
  u[4] = 0;
  for (const ErrorGain& g : error_gains(m, Formulation::kDependent, u)) {
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
