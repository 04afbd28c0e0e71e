// J_v_u = dF_f,n/du (core/jacobian.h, Lei & Hsu eq. 5): against central
// finite differences of nominal_forward on every sample and a tilted,
// offset machine; and for X'Y'ZA'C' against the paper's inverse-Jacobian
// formulas, eqs. (18)-(22) and the singular cases 1 and 2, eqs. (23)-(31),
// typed from the paper. The printed eqs. (19) and (23)-(31) are wrong
// (errata E-LH4 to E-LH6, docs/errata.md): each test checks that the derived
// formula inverts the Jacobian and that the printed one does not.
#include "core/kinematics/jacobian.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "core/model/machine_json.h"
#include "tests/support/samples.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

constexpr double kDeg = M_PI / 180.0;

Machine load(const std::string& name) { return test::sample_machine(name); }

using test::random_pose;

using Vector6d = Eigen::Matrix<double, 6, 1>;
Vector6d stack(const ToolPose& v) {
  Vector6d x;
  x << v.tip_mm, v.axis;
  return x;
}

// Central difference of nominal_forward along direction du (step h).
Vector6d directional_fd(const Machine& m, const AxisVector& u, const AxisVector& du, double h) {
  return (stack(nominal_forward(m, u + h * du)) - stack(nominal_forward(m, u - h * du))) / (2 * h);
}

void check_against_fd(const Machine& m, unsigned seed) {
  std::mt19937 rng(seed);
  for (int t = 0; t < 200; ++t) {
    const AxisVector u = random_pose(m, rng);
    PoseJacobian J;
    const ToolPose v = nominal_forward_jacobian(m, u, J);
    const ToolPose v0 = nominal_forward(m, u);
    EXPECT_LT((v.tip_mm - v0.tip_mm).norm(), 1e-10);
    EXPECT_LT((v.axis - v0.axis).norm(), 1e-14);
    ASSERT_EQ(J.cols(), m.axis_count());
    for (int i = 0; i < m.axis_count(); ++i) {
      const AxisVector e = AxisVector::Unit(m.axis_count(), i);
      const Vector6d fd = directional_fd(m, u, e, 1e-5);
      // Truncation h^2/6 |F'''| (levers <= ~1000 mm) and rounding 1e-13/h.
      EXPECT_LT((J.col(i) - fd).head<3>().norm(), 1e-6) << m.name << " axis " << i;
      EXPECT_LT((J.col(i) - fd).tail<3>().norm(), 1e-9) << m.name << " axis " << i;
    }
  }
}

TEST(Jacobian, MatchesFiniteDifferencesOnTheSamples) {
  check_against_fd(load("hsu-3axis"), 1);
  check_against_fd(load("lei-hsu-xyzac"), 2);
  check_against_fd(load("bc-table-table"), 3);
}

TEST(Jacobian, MatchesFiniteDifferencesOnAGeneralMachine) {
  // Rotary axes in both chains, tilted, with offsets; a tilted tool.
  Machine m = load("bc-table-table");
  m.workpiece_chain[1].direction_parent = Eigen::Vector3d(0.1, 1.0, -0.05).normalized();
  m.workpiece_chain[2].offset_parent_mm = {3.0, -2.0, 70.0};
  m.tool_chain[1].direction_parent = Eigen::Vector3d(0.01, -0.02, 1.0).normalized();
  m.tool_axis = Eigen::Vector3d(0.01, 0.02, 1.0).normalized();
  check_against_fd(m, 4);
  // Move C to the tool chain (a table-head machine).
  Machine th = load("bc-table-table");
  Joint c = th.workpiece_chain.back();
  th.workpiece_chain.pop_back();
  c.offset_parent_mm = {5.0, 0.0, -30.0};
  c.direction_parent = Eigen::Vector3d(0.0, 0.2, 1.0).normalized();
  th.tool_chain.push_back(c);
  check_against_fd(th, 5);
}

// ---- Lei & Hsu eqs. (18)-(31), X'Y'ZA'C' ----

struct Dv {
  double dx, dy, dz, di, dj, dk;
};
struct Du {
  double dxm, dym, dzm, da, dc;
};

// Eqs. (18)-(22) as printed. x, y, z: the axis positions x_m, y_m, z_m.
Du printed_18_22(const Dv& d, double x, double y, double z, double a, double c) {
  const double Sa = std::sin(a), Ca = std::cos(a), Sc = std::sin(c), Cc = std::cos(c);
  Du u;
  u.dxm = (-d.dx * Cc * Sa + d.dy * Sc * Sa + d.di * Cc * Sa * z - d.di * Cc * Ca * y -
           d.dj * Sc * Sa * z + d.dj * Sc * Ca * y) /
          Sa;  // (18)
  u.dym = (-d.dx * Sc * Ca * Ca - d.dy * Cc * Ca * Ca + d.dz * Ca * Sa + d.di * Sa * Sa * Sc * z +
           d.di * Cc * Sa * Ca * Ca * x - d.dj * Sc * Sa * Ca * Ca * x + d.dj * Cc * Sa * Sa * z) /
          Ca;  // (19)
  u.dzm = (d.dx * Sa * Sc * Ca + d.dy * Cc * Sa * Ca + d.dz * Ca * Ca - d.di * Sc * y -
           d.di * Cc * Ca * x + d.dj * Sc * Ca * x - d.dj * Cc * y) /
          Ca;                           // (20)
  u.da = (d.di * Sc + d.dj * Cc) / Ca;  // (21)
  u.dc = (d.di * Cc - d.dj * Sc) / Sa;  // (22)
  return u;
}

// Eq. (19) derived (erratum E-LH4): the rotary terms of the printed
// equation carry an extra factor sin^2(A).
double derived_19(const Dv& d, double x, double z, double a, double c) {
  const double Sa = std::sin(a), Ca = std::cos(a), Sc = std::sin(c), Cc = std::cos(c);
  return -d.dx * Sc * Ca - d.dy * Cc * Ca + d.dz * Sa + z * (d.di * Sc + d.dj * Cc) / Ca +
         x * Ca * (d.di * Cc - d.dj * Sc) / Sa;
}

Dv to_dv(const Vector6d& x) { return {x[0], x[1], x[2], x[3], x[4], x[5]}; }

TEST(LeiHsuInverseJacobian, Eqs18To22AsPrintedExcept19) {
  const Machine m = load("lei-hsu-xyzac");
  std::mt19937 rng(31);
  std::normal_distribution<double> n(0.0, 1.0);
  int checked = 0;
  for (int t = 0; t < 300; ++t) {
    AxisVector u = random_pose(m, rng);
    if (std::abs(std::sin(u[3])) < 0.1 || std::abs(std::cos(u[3])) < 0.1) continue;
    AxisVector du(5);
    du << n(rng) * 0.01, n(rng) * 0.01, n(rng) * 0.01, n(rng) * 1e-4, n(rng) * 1e-4;
    // dv = J du by finite differences of the forward transformation (not the
    // analytic J: independent of the code under test).
    const Dv d = to_dv(directional_fd(m, u, du, 1e-3));
    const Du p = printed_18_22(d, u[0], u[1], u[2], u[3], u[4]);
    const double tol_mm = 1e-8, tol_rad = 1e-10;
    EXPECT_NEAR(p.dxm, du[0], tol_mm);
    EXPECT_NEAR(p.dzm, du[2], tol_mm);
    EXPECT_NEAR(p.da, du[3], tol_rad);
    EXPECT_NEAR(p.dc, du[4], tol_rad);
    EXPECT_NEAR(derived_19(d, u[0], u[2], u[3], u[4]), du[1], tol_mm);
    // The printed (19) is off by far more than the tolerance.
    EXPECT_GT(std::abs(p.dym - du[1]), 1e-6) << "printed eq. 19 at u = " << u.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

// The analytic J inverts to the derived eqs. (18)-(22) (here J is the code
// under test and the paper's formulas are the reference).
TEST(LeiHsuInverseJacobian, AnalyticJacobianInvertsLikeTheDerivedEquations) {
  const Machine m = load("lei-hsu-xyzac");
  std::mt19937 rng(32);
  for (int t = 0; t < 100; ++t) {
    const AxisVector u = random_pose(m, rng);
    if (std::abs(std::sin(u[3])) < 0.1 || std::abs(std::cos(u[3])) < 0.1) continue;
    const PoseJacobian J = nominal_jacobian(m, u);
    // Columns of J^-1 (rows dx, dy, dz, di, dj) via the paper's formulas.
    const Eigen::Matrix<double, 5, 5> J5 = J.topRows<5>();
    const Eigen::Matrix<double, 5, 5> Jinv = J5.inverse();
    for (int r = 0; r < 5; ++r) {
      Dv d{0, 0, 0, 0, 0, 0};
      (&d.dx)[r] = 1.0;
      Du p = printed_18_22(d, u[0], u[1], u[2], u[3], u[4]);
      p.dym = derived_19(d, u[0], u[2], u[3], u[4]);
      const Eigen::Matrix<double, 5, 1> col(p.dxm, p.dym, p.dzm, p.da, p.dc);
      EXPECT_LT((Jinv.col(r) - col).norm(), 1e-9 * (1 + col.norm()));
    }
  }
}

// Case 1, A = 0 (section 4.1): C correction suppressed. Derived: the A axis
// takes the orientation error along the direction it tilts the tool,
// (sin C, cos C, 0); the linear axes the position error including A's lever.
//   dx_m = -Cc dx + Sc dy,  dy_m = -Sc dx - Cc dy + z_m da,
//   dz_m = dz - y_m da,     da = Sc di + Cc dj.
TEST(LeiHsuInverseJacobian, SingularCase1) {
  const Machine m = load("lei-hsu-xyzac");
  std::mt19937 rng(33);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int t = 0; t < 100; ++t) {
    AxisVector u = random_pose(m, rng);
    u[3] = 0.0;
    const double x = u[0], y = u[1], z = u[2], c = u[4], Sc = std::sin(c), Cc = std::cos(c);
    AxisVector du(5);
    du << n(rng) * 0.01, n(rng) * 0.01, n(rng) * 0.01, n(rng) * 1e-4, 0.0;  // no C
    const Dv d = to_dv(directional_fd(m, u, du, 1e-3));
    const double da = Sc * d.di + Cc * d.dj;
    EXPECT_NEAR(da, du[3], 1e-10);
    EXPECT_NEAR(-Cc * d.dx + Sc * d.dy, du[0], 1e-8);
    EXPECT_NEAR(-Sc * d.dx - Cc * d.dy + z * da, du[1], 1e-8);
    EXPECT_NEAR(d.dz - y * da, du[2], 1e-8);
    // Printed eqs. (23)-(26).
    const double p23 = -Cc * d.dx + Sc * d.dy - y * d.dj;
    const double p24 = -Sc * d.dx - Cc * d.dy + x * d.dj;
    const double p25 = d.dz;
    const double p26 = d.di;
    const double wrong = std::abs(p23 - du[0]) + std::abs(p24 - du[1]) + std::abs(p25 - du[2]) +
                         std::abs(p26 - du[3]);
    EXPECT_GT(wrong, 1e-6);
    // What the printed equations do get right: a pure translation.
    AxisVector dl = du;
    dl[3] = 0.0;
    const Dv e = to_dv(directional_fd(m, u, dl, 1e-3));
    EXPECT_NEAR(-Cc * e.dx + Sc * e.dy - y * e.dj, dl[0], 1e-8);
    EXPECT_NEAR(-Sc * e.dx - Cc * e.dy + x * e.dj, dl[1], 1e-8);
    EXPECT_NEAR(e.dz, dl[2], 1e-8);
  }
}

// Case 2, A = 90 deg (section 4.2): k = 0, so di and dj do not see A
// (dQ/dA = (0, 0, -1)); the A correction comes from dk. Derived:
//   dc = Cc di - Sc dj,  da = -dk,
//   dx_m = -Cc dx + Sc dy + z_m dc,  dy_m = dz + z_m da,
//   dz_m = Sc dx + Cc dy - y_m da - x_m dc.
TEST(LeiHsuInverseJacobian, SingularCase2) {
  const Machine m = load("lei-hsu-xyzac");
  std::mt19937 rng(34);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int t = 0; t < 100; ++t) {
    AxisVector u = random_pose(m, rng);
    u[3] = 90 * kDeg;  // the paper's case (outside the sample's A travel; J does not care)
    const double x = u[0], y = u[1], z = u[2], c = u[4], Sc = std::sin(c), Cc = std::cos(c);
    AxisVector du(5);
    du << n(rng) * 0.01, n(rng) * 0.01, n(rng) * 0.01, n(rng) * 1e-4, n(rng) * 1e-4;
    const Dv d = to_dv(directional_fd(m, u, du, 1e-3));
    const double dc = Cc * d.di - Sc * d.dj, da = -d.dk;
    EXPECT_NEAR(dc, du[4], 1e-10);
    EXPECT_NEAR(da, du[3], 1e-10);
    EXPECT_NEAR(-Cc * d.dx + Sc * d.dy + z * dc, du[0], 1e-8);
    EXPECT_NEAR(d.dz + z * da, du[1], 1e-8);
    EXPECT_NEAR(Sc * d.dx + Cc * d.dy - y * da - x * dc, du[2], 1e-8);
    // Printed eqs. (27)-(31).
    const double p27 = -Cc * d.dx + Sc * d.dy + z * d.dj;
    const double p28 = d.dz;
    const double p29 = Sc * d.dx + Cc * d.dy - x * d.dj;
    const double p30 = d.di, p31 = d.dj;
    EXPECT_GT(std::abs(p30 - du[3]), 1e-9);  // di does not depend on dA at all here
    const double wrong = std::abs(p27 - du[0]) + std::abs(p28 - du[1]) + std::abs(p29 - du[2]) +
                         std::abs(p31 - du[4]);
    EXPECT_GT(wrong, 1e-6);
    // A pure translation they do get right.
    AxisVector dl = du;
    dl[3] = dl[4] = 0.0;
    const Dv e = to_dv(directional_fd(m, u, dl, 1e-3));
    EXPECT_NEAR(-Cc * e.dx + Sc * e.dy + z * e.dj, dl[0], 1e-8);
    EXPECT_NEAR(e.dz, dl[1], 1e-8);
    EXPECT_NEAR(Sc * e.dx + Cc * e.dy - x * e.dj, dl[2], 1e-8);
  }
}

}  // namespace
}  // namespace volmap
