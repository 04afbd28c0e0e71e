// The five-axis post-processor (postproc/five_axis_post.h) on synthetic
// programs, against independent derivations:
//  - zero errors: every programmed pose becomes the closed-form backward
//    transformation of the X'Y'ZA'C' machine, derived from Lei & Hsu
//    eqs. (10)-(15) here (not volmap's Kinematics), with the selection
//    policy re-implemented here (within travel, least rotary motion, C
//    nearest the previous C, C held at A = 0);
//  - C continuity: C never moves by 180 degrees or more between consecutive
//    written positions, also through the singular position;
//  - with the sample errors: every written pose, run through the error
//    model, lies on the nominal path within the tolerances; verify agrees;
//  - feeds: inverse time keeps the programmed time of every move;
//  - the three input forms give the same machine program.
#include "postproc/five_axis/five_axis_post.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/common/input_error.h"
#include "core/model/error_model.h"
#include "gcode/nc_block.h"
#include "gcode/nc_path.h"
#include "gcode/nc_writer.h"
#include "maps/tables/table_builder.h"
#include "postproc/five_axis/five_axis_input.h"
#include "postproc/five_axis/five_axis_transform.h"
#include "postproc/five_axis/five_axis_verify.h"
#include "tests/postproc/five_axis_closed_form.h"
#include "tests/support/samples.h"

namespace volmap {
namespace {

TEST(FiveAxisPost, ZeroErrorsWriteTheClosedFormBackwardTransformation) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const Offsets off;
  // Poses in sequence (rapids: one written position each, no pieces).
  const std::vector<ToolPose> poses = random_poses(off, 300, 11);
  post::FiveAxisPostOptions o;
  std::string text;
  run_post(vector_program(poses, /*rapid=*/true), m, ErrorSet{}, o, text);
  const std::vector<OutLine> ends = group_ends(parse_output(text));
  ASSERT_EQ(ends.size(), poses.size());
  Axes prev{0, 0, 0, 0, 0};
  for (size_t i = 0; i < poses.size(); ++i) {
    // The input carries 6 and 9 decimals: the closed form of what was read.
    ToolPose v;
    v.tip_mm = Vector3d(std::round(poses[i].tip_mm.x() * 1e6) / 1e6,
                        std::round(poses[i].tip_mm.y() * 1e6) / 1e6,
                        std::round(poses[i].tip_mm.z() * 1e6) / 1e6);
    v.axis = Vector3d(std::round(poses[i].axis.x() * 1e9) / 1e9,
                      std::round(poses[i].axis.y() * 1e9) / 1e9,
                      std::round(poses[i].axis.z() * 1e9) / 1e9)
                 .normalized();
    const Axes want = closed_form_backward(off, v, prev);
    const Axes& got = ends[i].u;
    // Written with 4 decimals (mm) and 5 (degrees): within half a unit.
    EXPECT_NEAR(got.x, want.x, 0.5e-4 + 1e-9) << "pose " << i;
    EXPECT_NEAR(got.y, want.y, 0.5e-4 + 1e-9) << "pose " << i;
    EXPECT_NEAR(got.z, want.z, 0.5e-4 + 1e-9) << "pose " << i;
    EXPECT_NEAR(got.a, want.a, 0.5e-5 * kDeg + 1e-12) << "pose " << i;
    EXPECT_NEAR(got.c, want.c, 0.5e-5 * kDeg + 1e-12) << "pose " << i;
    prev = want;
  }
}

TEST(FiveAxisPost, ZeroErrorsTcpProgramKeepsTheAnglesAndPlacesTheTipExactly) {
  Machine m = test::sample_machine("lei-hsu-xyzac");
  m.workpiece_origin_mm = Vector3d(12, -7, 100);  // --part-origin
  Offsets off;
  off.Xw0 = 12;
  off.Yw0 = -7;
  off.Zw0 = 100;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> p(-40, 40), a(-60, 20), c(-720, 720);
  std::string prog = "G21 G90\n";
  struct Pt {
    Vector3d tip;
    double a, c;
  };
  std::vector<Pt> pts;
  for (int i = 0; i < 200; ++i) {
    Pt t{Vector3d(std::round(p(rng) * 1e3) / 1e3, std::round(p(rng) * 1e3) / 1e3,
                  std::round(p(rng) * 1e3) / 1e3),
         std::round(a(rng) * 1e3) / 1e3, std::round(c(rng) * 1e3) / 1e3};
    pts.push_back(t);
    prog += fmt::format("N{} G0 X{:.3f} Y{:.3f} Z{:.3f} A{:.3f} C{:.3f}\n", (i + 1) * 10, t.tip.x(),
                        t.tip.y(), t.tip.z(), t.a, t.c);
  }
  std::string text;
  run_post(prog, m, ErrorSet{}, post::FiveAxisPostOptions{}, text);
  const std::vector<OutLine> ends = group_ends(parse_output(text));
  ASSERT_EQ(ends.size(), pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    const Vector3d l = linear_closed_form(off, pts[i].tip, pts[i].a * kDeg, pts[i].c * kDeg);
    EXPECT_NEAR(ends[i].u.x, l.x(), 0.5e-4 + 1e-9);
    EXPECT_NEAR(ends[i].u.y, l.y(), 0.5e-4 + 1e-9);
    EXPECT_NEAR(ends[i].u.z, l.z(), 0.5e-4 + 1e-9);
    EXPECT_NEAR(ends[i].u.a / kDeg, pts[i].a, 1e-9);
    // C (unlimited) as programmed up to whole turns: a rapid takes the
    // equivalent angle within half a turn of where C is.
    EXPECT_NEAR(std::remainder(ends[i].u.c / kDeg - pts[i].c, 360.0), 0.0, 1e-9);
    if (i > 0) {
      EXPECT_LT(std::abs(ends[i].u.c - ends[i - 1].u.c) / kDeg, 180.0 + 1e-9);
    }
  }
}

// Every other supported machine type: the B-C table-table sample. Zero
// errors: each programmed pose is the nominal forward transformation of
// the written axes (round trip, within rounding). With location errors of
// B and C: the actual tool tip at every written position lies on the
// nominal path within the tolerance plus rounding.
TEST(FiveAxisPost, BcTableTableRoundTripAndCorrection) {
  const Machine m = test::sample_machine("bc-table-table");
  ErrorSet e;
  e.location = {{"EX0C", 0.02},  {"EY0C", -0.015}, {"EA0C", 40e-6}, {"EB0C", -30e-6},
                {"EX0B", 0.025}, {"EZ0B", -0.01},  {"EA0B", 25e-6}, {"EC0B", 50e-6}};
  std::vector<ToolPose> path;
  for (int i = 0; i <= 60; ++i) {
    const double t = i * 0.05, tilt = (5 + 40.0 * i / 60) * kDeg;
    path.push_back({Vector3d(30 * std::cos(t), 30 * std::sin(t), 10 + 0.2 * i),
                    Vector3d(std::sin(tilt) * std::cos(2 * t), std::sin(tilt) * std::sin(2 * t),
                             std::cos(tilt))});
  }
  const std::string prog = vector_program(path);
  std::string text;
  run_post(prog, m, ErrorSet{}, post::FiveAxisPostOptions{}, text);
  // Output words X Y Z B C: parse them here (parse_output knows A C only).
  auto positions = [&](const std::string& t) {
    std::vector<std::pair<bool, AxisVector>> out;  // (numbered, u)
    std::istringstream in(t);
    std::string l;
    int n = 0;
    while (std::getline(in, l)) {
      const nc::Block b = nc::lex_block(l, ++n, "out");
      AxisVector u = AxisVector::Zero(5);
      bool move = false, numbered = false;
      for (const nc::Word& w : b.words) {
        if (w.letter == 'N') numbered = true;
        const char* at = std::strchr("XYZBC", w.letter);
        if (w.letter != 0 && at) {
          const int k = static_cast<int>(at - "XYZBC");
          u[k] = k < 3 ? w.value : w.value * kDeg;
          move = true;
        }
      }
      if (move) out.push_back({numbered, u});
    }
    return out;
  };
  std::vector<AxisVector> ends;
  for (const auto& [numbered, u] : positions(text)) {
    if (numbered)
      ends.push_back(u);
    else
      ends.back() = u;
  }
  ASSERT_EQ(ends.size(), path.size());
  for (size_t i = 0; i < path.size(); ++i) {
    const ToolPose v = nominal_forward(m, ends[i]);
    EXPECT_LT((v.tip_mm - path[i].tip_mm).norm(), std::sqrt(3.0) * 0.5e-4 + 2 * 0.5e-5 * kDeg * 400)
        << i;
    EXPECT_LT((v.axis - path[i].axis).norm(), 2 * 0.5e-5 * kDeg + 1e-8) << i;
  }
  // With errors.
  post::FiveAxisPostOptions o;
  run_post(prog, m, e, o, text);
  ErrorModel model(m, e);
  const double rounding_mm = std::sqrt(3.0) * 0.5e-4 + 2 * 0.5e-5 * kDeg * 400;
  size_t group = 0;
  for (const auto& [numbered, u] : positions(text)) {
    if (numbered) ++group;
    if (group < 2) continue;  // the first line is a rapid
    nc::Motion seg;
    seg.start_mm = path[group - 2].tip_mm;
    seg.end_mm = path[group - 1].tip_mm;
    EXPECT_LT(nc::distance_to_path(seg, model.actual(u).tip_mm), o.tolerance_mm + rounding_mm)
        << group;
  }
}

// --table: the errors from a five-axis volumetric table (volmap map). The
// written positions, run through the model itself, put the tool on the
// nominal path within the tolerance plus the table's own interpolation
// error (check_table) and rounding.
TEST(FiveAxisPost, TableInputCorrectsWithinItsInterpolationError) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const ErrorSet e = test::sample_errors("lei-hsu-xyzac");
  const ErrorModel model(m, e);
  maps::BuildOptions bo;
  bo.threads = 1;
  maps::VolumetricTable table = maps::build_table(model, {100, 100, 100, 10 * kDeg, 20 * kDeg}, bo);
  table.checked_with = maps::Interpolation::kCubic;
  maps::CheckOptions co;
  co.method = maps::Interpolation::kCubic;
  co.random_points = 2000;
  co.threads = 1;
  co.check_correction = false;
  const double table_um = maps::check_table(model, table, co).max_dv_um;
  const Offsets off;
  const std::vector<ToolPose> ends = {eq10_15(off, 40, -30, 120, -35 * kDeg, 20 * kDeg),
                                      eq10_15(off, -60, 50, 150, -50 * kDeg, 75 * kDeg)};
  std::vector<ToolPose> path;
  for (int i = 0; i <= 20; ++i) {
    const double s = i / 20.0;
    path.push_back({ends[0].tip_mm + s * (ends[1].tip_mm - ends[0].tip_mm),
                    post::slerp_axis(ends[0].axis, ends[1].axis, s)});
  }
  post::FiveAxisPostOptions o;
  std::istringstream in(vector_program(path));
  std::ostringstream out;
  post::post_five_axis(in, "test.ngc", out, m, table, o);
  const std::vector<OutLine> lines = parse_output(out.str());
  const std::vector<OutLine> got = group_ends(lines);
  ASSERT_EQ(got.size(), path.size());
  const double rounding_mm = std::sqrt(3.0) * 0.5e-4 + 2 * 0.5e-5 * kDeg * 400;
  for (size_t i = 0; i < path.size(); ++i) {
    AxisVector u(5);
    u << got[i].u.x, got[i].u.y, got[i].u.z, got[i].u.a, got[i].u.c;
    // One step on interpolated dv: the table's error plus the one-step
    // residual (0.15 um) plus rounding.
    EXPECT_LT((model.actual(u).tip_mm - path[i].tip_mm).norm(),
              1e-3 * table_um + 0.15e-3 + rounding_mm)
        << i;
  }
  std::printf("table interpolation error %.3f um (cubic, 100 mm / 10 deg / 20 deg)\n", table_um);
}

// A tool axis that circles the vertical on a narrow cone (C turns fast),
// crosses the vertical (singular: C held), and sweeps back: with feed
// moves (segmented) and the sample errors, no written C step reaches 180
// degrees (in fact the segmentation keeps it below 90).
TEST(FiveAxisPost, CNeverJumpsHalfATurn) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const ErrorSet e = test::sample_errors("lei-hsu-xyzac");
  std::vector<ToolPose> poses;
  for (int i = 0; i <= 120; ++i) {
    const double t = i * 7.0 * kDeg, tilt = (i % 40 == 20) ? 0.0 : 4.0 * kDeg;
    ToolPose v;
    v.tip_mm = Vector3d(20 * std::cos(t / 3), 20 * std::sin(t / 3), 10);
    v.axis = Vector3d(std::sin(tilt) * std::cos(t), std::sin(tilt) * std::sin(t), std::cos(tilt));
    poses.push_back(v);
  }
  // Through the vertical along a great circle: (sin 10, 0, cos 10) -> (-sin 10, 0, cos 10).
  for (int i = 0; i <= 20; ++i) {
    const double tilt = (10.0 - i) * kDeg;
    poses.push_back({Vector3d(5.0 * i, 0, 0), Vector3d(std::sin(tilt), 0, std::cos(tilt))});
  }
  for (const ErrorSet& errors : {ErrorSet{}, e}) {
    std::string text;
    const post::FiveAxisPostReport r =
        run_post(vector_program(poses), m, errors, post::FiveAxisPostOptions{}, text);
    EXPECT_GT(r.singular_poses, 0u);
    EXPECT_LT(r.max_rotary_step_rad, M_PI / 2);
    // Leaving the singular position C turns to the new azimuth with the tip
    // held on the path (20 mm off the C axis): no gouge.
    if (!errors.location.empty() || errors.errors_of(AxisName::X)) {
      std::istringstream nominal(vector_program(poses)), compensated(text);
      const post::FiveAxisVerifyResult v = post::verify_five_axis(
          nominal, "in", compensated, "out", m, errors, post::FiveAxisVerifyOptions{});
      EXPECT_LT(v.after.max_um, 1.0 + 1e3 * (std::sqrt(3.0) * 0.5e-4 + 2 * 0.5e-5 * kDeg * 400));
    }
    const std::vector<OutLine> out = parse_output(text);
    double prev_c = 0;
    bool first = true;
    for (const OutLine& o : out) {
      if (!o.move) continue;
      if (!first) {
        EXPECT_LT(std::abs(o.u.c - prev_c), M_PI);
      }
      prev_c = o.u.c;
      first = false;
    }
  }
}

// Near the singular position the post's correction (damped C, iterated) is
// the damped solution of eq. 4: the tip exact, the gradient of
// |dQ_left|^2 + lambda^2 dC^2 zero, |dC| within |dQ| / (2 lambda), and
// continuous down to A = 0. The plain chord-Newton iteration converged
// towards the undamped solution instead (dC = -dQ_perp / sin A, 75 mrad at
// A = 0.07 deg for the 134 urad that only C can turn at C = -603 deg, the
// pose i = 100 above), unconverged after 20 iterations, and C's correction
// then jumped to 0 at the singular threshold: more than 65536 pieces.
TEST(FiveAxisPost, CorrectionNearTheSingularPositionIsDampedAndContinuous) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const ErrorModel model(m, test::sample_errors("lei-hsu-xyzac"));
  CorrectionOptions o;
  o.outer_damping = post::kPostOuterDamping;
  o.iterate_below_sin = post::kPostIterateBelowSin;
  const CorrectionSolver solver(model, o);
  const post::FiveAxisTransform tf(m, test::sample_errors("lei-hsu-xyzac"), OutsidePolicy::kError,
                                   o);
  const double lambda = post::kPostOuterDamping;
  double prev_dc = 0;
  for (int k = 0; k <= 400; ++k) {
    const double a = (0.4 - 0.001 * k) * kDeg;
    SCOPED_TRACE(a / kDeg);
    AxisVector q = AxisVector::Zero(5);
    q[3] = a;
    q[4] = -603 * kDeg;
    const AxisVector u = tf.axes_for_angles(q, Vector3d(-11.943172, -16.042464, 10));
    PoseJacobian J;
    const ToolPose v = nominal_forward_jacobian(m, u, J);
    const CorrectionResult r = solver.correct(u);
    EXPECT_LT(r.iterations, CorrectionOptions::kNearSingularIterations);
    const ToolPose act = model.actual(u + r.du);
    EXPECT_LT((act.tip_mm - v.tip_mm).norm(), 1e-9);
    Eigen::Matrix<double, 3, 2> G;
    G.col(0) = J.block<3, 1>(3, 4);
    G.col(1) = J.block<3, 1>(3, 3);
    const Eigen::Vector2d grad =
        G.transpose() * (act.axis - v.axis) + Eigen::Vector2d(lambda * lambda * r.du[4], 0.0);
    EXPECT_LT(grad.norm(), 1e-11);
    EXPECT_LE(std::abs(r.du[4]), (model.actual(u).axis - v.axis).norm() / (2 * lambda) * 1.01);
    // Lipschitz in sin A with constant |dQ| / lambda^2 (the damped dC =
    // sin A dQ_perp / (sin^2 A + lambda^2)); 0.001 deg of A: < 0.1 mrad.
    if (k > 0) {
      EXPECT_LT(std::abs(r.du[4] - prev_dc),
                1.1 * (model.actual(u).axis - v.axis).norm() * 0.001 * kDeg / (lambda * lambda));
    }
    prev_dc = r.du[4];
  }
  EXPECT_LT(std::abs(prev_dc), 1e-12);  // at A = 0 C's correction vanishes
}

// With the sample errors: every written position, run through the model,
// puts the tool on the nominal path (tip within the tolerance plus the
// rounding of the written numbers), and each programmed end point within
// the one-step residual (0.15 um, docs/kinematics.md) plus rounding.
TEST(FiveAxisPost, CorrectedPositionsPutTheToolOnTheNominalPath) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const ErrorSet e = test::sample_errors("lei-hsu-xyzac");
  ErrorModel model(m, e);
  const Offsets off;
  const std::vector<ToolPose> poses = {eq10_15(off, 40, -30, 120, -35 * kDeg, 20 * kDeg),
                                       eq10_15(off, -60, 50, 150, -50 * kDeg, 75 * kDeg)};
  // A smooth path between two random poses: 40 points.
  std::vector<ToolPose> path;
  for (int i = 0; i <= 40; ++i) {
    const double s = i / 40.0;
    path.push_back({poses[0].tip_mm + s * (poses[1].tip_mm - poses[0].tip_mm),
                    post::slerp_axis(poses[0].axis, poses[1].axis, s)});
  }
  post::FiveAxisPostOptions o;
  std::string text;
  const post::FiveAxisPostReport r = run_post(vector_program(path), m, e, o, text);
  EXPECT_GT(r.lines_added, 0u);
  const std::vector<OutLine> out = parse_output(text);
  const std::vector<OutLine> ends = group_ends(out);
  ASSERT_EQ(ends.size(), path.size());
  auto actual = [&](const Axes& u) {
    AxisVector x(5);
    x << u.x, u.y, u.z, u.a, u.c;
    return model.actual(x);
  };
  // Rounding: 0.5e-4 mm per linear axis; 0.5e-5 deg per rotary axis times a
  // lever below 400 mm.
  const double rounding_mm = std::sqrt(3.0) * 0.5e-4 + 2 * 0.5e-5 * kDeg * 400;
  for (size_t i = 0; i < path.size(); ++i) {
    const ToolPose a = actual(ends[i].u);
    EXPECT_LT((a.tip_mm - path[i].tip_mm).norm(), 0.15e-3 + rounding_mm) << i;
    EXPECT_LT(std::atan2(a.axis.cross(path[i].axis).norm(), a.axis.dot(path[i].axis)),
              0.1e-6 + 2 * 0.5e-5 * kDeg)
        << i;
  }
  nc::Motion seg;
  seg.start_mm = path.front().tip_mm;
  seg.end_mm = path.back().tip_mm;
  for (const OutLine& l : out)
    if (l.move) {
      EXPECT_LT(nc::distance_to_path(seg, actual(l.u).tip_mm), o.tolerance_mm + rounding_mm);
    }
  // verify: densely sampled, before and after.
  std::istringstream nominal(vector_program(path)), compensated(text);
  post::FiveAxisVerifyOptions vo;
  const post::FiveAxisVerifyResult v =
      post::verify_five_axis(nominal, "in", compensated, "out", m, e, vo);
  EXPECT_GT(v.before.max_um, 10.0);
  EXPECT_LT(v.after.max_um, 1e3 * (o.tolerance_mm + rounding_mm));
  EXPECT_GT(v.before.max_urad, 10.0);
  EXPECT_LT(v.after.max_urad, 1e6 * o.angle_tolerance_rad);
}

// G93 output: the pieces of a move take its programmed time. G94 input:
// the time is the nominal tip path length over F.
TEST(FiveAxisPost, InverseTimeKeepsTheProgrammedTime) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const ErrorSet e = test::sample_errors("lei-hsu-xyzac");
  const std::string prog =
      "G21 G90 G94\nN10 G0 X0 Y0 Z20 A0 C0\nN20 G1 X30 Y10 Z15 A-30 C40 F600\nN30 G93 G1 X-20 Y5 "
      "Z15 A-45 C90 F4\nM30\n";
  std::string text;
  run_post(prog, m, e, post::FiveAxisPostOptions{}, text);
  const std::vector<OutLine> out = parse_output(text);
  double t20 = 0, t30 = 0;
  int group = 0;
  for (const OutLine& l : out) {
    if (l.numbered) group = l.n;
    if (!l.move || group < 20) continue;
    ASSERT_GT(l.f, 0);
    (group == 20 ? t20 : t30) += 1.0 / l.f;
  }
  const double L = std::sqrt(30.0 * 30 + 10 * 10 + 5 * 5);
  EXPECT_NEAR(t20, L / 600.0, 1e-6 * L / 600 + 1e-7 * 20);
  EXPECT_NEAR(t30, 1.0 / 4.0, 1e-6);
  EXPECT_NE(text.find("G93"), std::string::npos);

  // Per minute (G94): F over each piece's machine X Y Z length gives the
  // same times.
  post::FiveAxisPostOptions pm;
  pm.feed = post::FeedOutput::kPerMinute;
  run_post(prog, m, e, pm, text);
  EXPECT_EQ(text.find("G93"), std::string::npos);
  const std::vector<OutLine> out2 = parse_output(text);
  t20 = t30 = 0;
  group = 0;
  Axes prev{};
  for (const OutLine& l : out2) {
    if (l.numbered) group = l.n;
    if (l.move && group >= 20) {
      const double len = std::sqrt(std::pow(l.u.x - prev.x, 2) + std::pow(l.u.y - prev.y, 2) +
                                   std::pow(l.u.z - prev.z, 2));
      (group == 20 ? t20 : t30) += len / l.f;
    }
    if (l.move) prev = l.u;
  }
  // Lengths from the written (rounded) numbers: 1e-4 relative.
  EXPECT_NEAR(t20, L / 600.0, 1e-3 * L / 600);
  EXPECT_NEAR(t30, 1.0 / 4.0, 1e-3);
}

}  // namespace
}  // namespace volmap
