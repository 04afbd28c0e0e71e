// The samples of LinuxCNC's own five-axis machines against LinuxCNC's
// kinematics for them. The A-B dual-rotary table
// (samples/machines/xyzab-tdr.json) against xyzab_tdr_kins (its TCP
// inverse, src/hal/components/xyzab_tdr_kins.comp, typed in here with the
// sim config's defaults: rotation point (-50, -50, -100), x-offset -20,
// z-offset -10, tool offset 30): the joints LinuxCNC commands for a
// programmed tool tip are the axis positions whose nominal forward
// transformation puts the tip there; backward finds them among its
// solutions; at the singular position (tool axis along A's line) A is held.
// And the sample's errors give a correction that reaches the nominal pose.
// The head-head bridge mill (samples/machines/bridgemill-bc-head.json)
// against 5axiskins (src/emc/kinematics/5axiskins.c, pivot-length 250, W 0):
// the same, with C held where the tool axis is vertical (B = 0).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/kinematics/correction.h"
#include "core/kinematics/kinematics.h"
#include "core/model/error_model.h"
#include "tests/support/samples.h"

namespace volmap {
namespace {

using Eigen::Vector3d;

constexpr double kDeg = M_PI / 180.0;

// xyzab_tdr_kins.comp, kinematicsInverse, switchkins type 1 (TCP): joints
// from the programmed tip `p` (G54 at the A table's face centre: LinuxCNC's
// pos = p + rotation point + offsets + tool offset) and A, B in degrees.
Vector3d linuxcnc_joints(const Vector3d& p, double a_deg, double b_deg) {
  const double x_rot = -50, y_rot = -50, z_rot = -100, dx = -20, dz = -10, dt = 30;
  const Vector3d pos = p + Vector3d(x_rot + dx, y_rot, z_rot + dz + dt);
  const double sa = std::sin(a_deg * kDeg), ca = std::cos(a_deg * kDeg);
  const double sb = std::sin(b_deg * kDeg), cb = std::cos(b_deg * kDeg);
  const double qx = pos.x() - x_rot - dx, qy = pos.y() - y_rot, qz = pos.z() - z_rot - dz - dt;
  return {cb * qx + sa * sb * qy - ca * sb * qz + cb * dx - sb * dz + x_rot,
          ca * qy + sa * qz + y_rot,
          sb * qx - sa * cb * qy + ca * cb * qz + sb * dx + cb * dz + z_rot + dt};
}

AxisVector axes(const Vector3d& xyz, double a_deg, double b_deg) {
  AxisVector u(5);
  u << xyz.x(), xyz.y(), xyz.z(), a_deg * kDeg, b_deg * kDeg;
  return u;
}

TEST(XyzabTdr, ForwardIsLinuxCncsKinematics) {
  const Machine m = test::sample_machine("xyzab-tdr");
  const Kinematics kin(m);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-40, 40), a(-180, 180), b(-120, 120);
  for (int t = 0; t < 500; ++t) {
    const Vector3d p(pos(rng), pos(rng), pos(rng) + 40);
    const double a_deg = a(rng), b_deg = b(rng);
    const AxisVector u = axes(linuxcnc_joints(p, a_deg, b_deg), a_deg, b_deg);
    const ToolPose v = nominal_forward(m, u);
    EXPECT_LT((v.tip_mm - p).norm(), 1e-9) << u.transpose();
    // The tool axis: machine +Z seen from the part, which A (about -X)
    // and B (about -Y) turned: Rx(a) Ry(b) z.
    const Vector3d want = Eigen::AngleAxisd(a_deg * kDeg, Vector3d::UnitX()) *
                          (Eigen::AngleAxisd(b_deg * kDeg, Vector3d::UnitY()) * Vector3d::UnitZ());
    EXPECT_LT((v.axis - want).norm(), 1e-12);
    // Backward finds LinuxCNC's joints among its solutions (A modulo 360).
    const BackwardSolutions s = kin.backward(v, u);
    bool found = false;
    for (int k = 0; k < s.count; ++k)
      found = found || (s.u[static_cast<size_t>(k)] - u).cwiseAbs().maxCoeff() < 1e-9;
    EXPECT_TRUE(found) << u.transpose();
  }
}

TEST(XyzabTdr, SingularPositionHoldsA) {
  // The tool axis along A's line (B = 90 degrees): A cannot turn it; the
  // previous A is kept and the pose is reached.
  const Machine m = test::sample_machine("xyzab-tdr");
  const Kinematics kin(m);
  const ToolPose v{Vector3d(5, -3, 20), Vector3d::UnitX()};
  for (double a_prev : {-30.0, 0.0, 37.0, 200.0}) {
    bool singular = false;
    const AxisVector u = kin.backward_selected(v, axes(Vector3d::Zero(), a_prev, 80), &singular);
    EXPECT_TRUE(singular);
    EXPECT_NEAR(u[3], a_prev * kDeg, 1e-12);
    const ToolPose got = nominal_forward(m, u);
    EXPECT_LT((got.tip_mm - v.tip_mm).norm(), 1e-9);
    EXPECT_LT((got.axis - v.axis).norm(), 1e-12);
  }
}

TEST(XyzabTdr, SampleErrorsCorrectedToTheNominalPose) {
  // The sample's errors move the tool tens of um; the one-step correction
  // of eq. 6 brings it back within a small fraction of a um.
  const Machine m = test::sample_machine("xyzab-tdr");
  const ErrorSet e = test::sample_errors("xyzab-tdr");
  const ErrorModel model(m, e);
  const Kinematics kin(m);
  const CorrectionSolver solver(model);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> pos(-40, 40), tilt(-60, 60), turn(0, 360);
  double worst_before = 0, worst_after = 0;
  for (int t = 0; t < 200; ++t) {
    const double a_deg = turn(rng), b_deg = tilt(rng);
    const AxisVector u = axes(
        linuxcnc_joints(Vector3d(pos(rng), pos(rng), pos(rng) + 40), a_deg, b_deg), a_deg, b_deg);
    const ToolPose nominal = nominal_forward(m, u);
    worst_before = std::max(worst_before, (model.actual(u).tip_mm - nominal.tip_mm).norm());
    const AxisVector c = u + solver.correct(u).du;
    worst_after = std::max(worst_after, (model.actual(c).tip_mm - nominal.tip_mm).norm());
  }
  EXPECT_GT(worst_before, 0.010);
  EXPECT_LT(worst_after, 0.2e-3);
}

// 5axiskins.c, kinematicsForward: the tip from the joints (X Y Z B C,
// degrees): joints + (0, 0, pivot) + s2r(pivot, C, 180 - B).
Vector3d linuxcnc_5axis_tip(const Vector3d& xyz, double b_deg, double c_deg) {
  const double pivot = 250, t = c_deg * kDeg, p = (180.0 - b_deg) * kDeg;
  return xyz + Vector3d(pivot * std::sin(p) * std::cos(t), pivot * std::sin(p) * std::sin(t),
                        pivot + pivot * std::cos(p));
}

TEST(BridgemillHead, ForwardIsLinuxCncs5axiskins) {
  const Machine m = test::sample_machine("bridgemill-bc-head");
  const Kinematics kin(m);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> pos(-300, 300), b(-110, 110), c(-180, 180);
  for (int t = 0; t < 500; ++t) {
    const Vector3d xyz(pos(rng), pos(rng), pos(rng) / 3 - 100);
    const double b_deg = b(rng), c_deg = c(rng);
    AxisVector u(5);  // X Y Z B C
    u << xyz.x(), xyz.y(), xyz.z(), b_deg * kDeg, c_deg * kDeg;
    const ToolPose v = nominal_forward(m, u);
    EXPECT_LT((v.tip_mm - linuxcnc_5axis_tip(xyz, b_deg, c_deg)).norm(), 1e-9) << u.transpose();
    // The tool axis points from the tip to the pivot: -s2r / pivot.
    const Vector3d want(-std::sin(b_deg * kDeg) * std::cos(c_deg * kDeg),
                        -std::sin(b_deg * kDeg) * std::sin(c_deg * kDeg), std::cos(b_deg * kDeg));
    EXPECT_LT((v.axis - want).norm(), 1e-12);
    const BackwardSolutions s = kin.backward(v, u);
    bool found = false;
    for (int k = 0; k < s.count; ++k)
      found = found || (s.u[static_cast<size_t>(k)] - u).cwiseAbs().maxCoeff() < 1e-9;
    EXPECT_TRUE(found) << u.transpose();
  }
}

TEST(BridgemillHead, VerticalToolHoldsC) {
  const Machine m = test::sample_machine("bridgemill-bc-head");
  const Kinematics kin(m);
  const ToolPose v{Vector3d(40, -25, 10), Vector3d::UnitZ()};
  for (double c_prev : {-90.0, 0.0, 33.0, 400.0}) {
    AxisVector prev(5);
    prev << 0, 0, 0, 10 * kDeg, c_prev * kDeg;
    bool singular = false;
    const AxisVector u = kin.backward_selected(v, prev, &singular);
    EXPECT_TRUE(singular);
    EXPECT_NEAR(u[4], c_prev * kDeg, 1e-12);
    EXPECT_NEAR(u[3], 0.0, 1e-12);
    EXPECT_LT((nominal_forward(m, u).tip_mm - v.tip_mm).norm(), 1e-9);
  }
}

TEST(BridgemillHead, SampleErrorsCorrectedToTheNominalPose) {
  const Machine m = test::sample_machine("bridgemill-bc-head");
  const ErrorModel model(m, test::sample_errors("bridgemill-bc-head"));
  const CorrectionSolver solver(model);
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> pos(-300, 300), b(-60, 60), c(0, 360);
  double worst_before = 0, worst_after = 0;
  for (int t = 0; t < 200; ++t) {
    AxisVector u(5);
    u << pos(rng), pos(rng), pos(rng) / 3 - 100, b(rng) * kDeg, c(rng) * kDeg;
    const ToolPose nominal = nominal_forward(m, u);
    worst_before = std::max(worst_before, (model.actual(u).tip_mm - nominal.tip_mm).norm());
    const AxisVector cmd = u + solver.correct(u).du;
    worst_after = std::max(worst_after, (model.actual(cmd).tip_mm - nominal.tip_mm).norm());
  }
  EXPECT_GT(worst_before, 0.010);
  EXPECT_LT(worst_after, 0.2e-3);
}

}  // namespace
}  // namespace volmap
