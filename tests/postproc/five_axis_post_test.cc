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
#include "tests/support/samples.h"

// Counts heap allocations through operator new (the per-pose path must make
// none; STYLE.md rule 3).
namespace {
thread_local long g_allocations = 0;
}  // namespace
[[gnu::noinline]] void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace volmap {
namespace {

using Eigen::Vector3d;
constexpr double kDeg = M_PI / 180.0;

// Lei & Hsu eqs. (10)-(15) with the sample's offsets: Z3 = 50 (C table face
// above the A line), (Xw0, Yw0, Zw0) = the workpiece origin in the C frame.
struct Offsets {
  double Z3 = 50, Xw0 = 0, Yw0 = 0, Zw0 = 60;
};
ToolPose eq10_15(const Offsets& o, double xm, double ym, double zm, double a, double c) {
  ToolPose v;
  v.tip_mm.x() =
      zm * std::sin(c) * std::sin(a) - ym * std::sin(c) * std::cos(a) - xm * std::cos(c) - o.Xw0;
  v.tip_mm.y() =
      zm * std::cos(c) * std::sin(a) - ym * std::cos(c) * std::cos(a) + xm * std::sin(c) - o.Yw0;
  v.tip_mm.z() = zm * std::cos(a) + ym * std::sin(a) - o.Z3 - o.Zw0;
  v.axis = {std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)};
  return v;
}
// Linear axes from eqs. (10)-(12) for given angles: their matrix is
// orthogonal, so (x_m, y_m, z_m) = M^T (x + Xw0, y + Yw0, z + Z3 + Zw0).
Vector3d linear_closed_form(const Offsets& o, const Vector3d& tip, double a, double c) {
  const double X = tip.x() + o.Xw0, Y = tip.y() + o.Yw0, Z = tip.z() + o.Z3 + o.Zw0;
  const double sa = std::sin(a), ca = std::cos(a), sc = std::sin(c), cc = std::cos(c);
  return {-cc * X + sc * Y, -sc * ca * X - cc * ca * Y + sa * Z,
          sc * sa * X + cc * sa * Y + ca * Z};
}
// The backward transformation with the policy: A = +-acos(k) within
// -100..30 deg; C = atan2(i, j) (sin A > 0) or atan2(-i, -j) (sin A < 0),
// unwrapped next to the previous C; the least (dA^2 + dC^2); at k = 1 the
// previous C is kept.
struct Axes {
  double x, y, z, a, c;
};
Axes closed_form_backward(const Offsets& o, const ToolPose& v, const Axes& prev) {
  const double k = std::clamp(v.axis.z(), -1.0, 1.0);
  Axes best{};
  double best_d = 1e300;
  bool best_inside = false;
  if (std::hypot(v.axis.x(), v.axis.y()) <= 1e-10) {
    const Vector3d l = linear_closed_form(o, v.tip_mm, 0.0, prev.c);
    return {l.x(), l.y(), l.z(), 0.0, prev.c};
  }
  for (double sign : {1.0, -1.0}) {
    const double a = sign * std::acos(k);
    if (a < -100 * kDeg - 1e-12 || a > 30 * kDeg + 1e-12) continue;
    double c = sign > 0 ? std::atan2(v.axis.x(), v.axis.y()) : std::atan2(-v.axis.x(), -v.axis.y());
    c += 2 * M_PI * std::round((prev.c - c) / (2 * M_PI));
    const double d = (a - prev.a) * (a - prev.a) + (c - prev.c) * (c - prev.c);
    const Vector3d l = linear_closed_form(o, v.tip_mm, a, c);
    // Solutions within the linear travel first (X +-300, Y +-250, Z -50..450).
    const bool inside =
        std::abs(l.x()) <= 300 && std::abs(l.y()) <= 250 && l.z() >= -50 && l.z() <= 450;
    if ((inside && !best_inside) || (inside == best_inside && d < best_d)) {
      best_d = d;
      best_inside = inside;
      best = {l.x(), l.y(), l.z(), a, c};
    }
  }
  EXPECT_LT(best_d, 1e299) << "unreachable test pose";
  return best;
}

struct OutLine {
  bool numbered = false;
  int n = 0;
  bool move = false;
  Axes u{};
  double f = 0;
  bool g93 = false;
};
std::vector<OutLine> parse_output(const std::string& text) {
  std::vector<OutLine> out;
  std::istringstream in(text);
  std::string l;
  int line = 0;
  while (std::getline(in, l)) {
    const nc::Block b = nc::lex_block(l, ++line, "out");
    OutLine o;
    for (const nc::Word& w : b.words) {
      switch (w.letter) {
        case 'N':
          o.numbered = true;
          o.n = static_cast<int>(w.value);
          break;
        case 'X':
          o.u.x = w.value;
          o.move = true;
          break;
        case 'Y':
          o.u.y = w.value;
          break;
        case 'Z':
          o.u.z = w.value;
          break;
        case 'A':
          o.u.a = w.value * kDeg;
          break;
        case 'C':
          o.u.c = w.value * kDeg;
          break;
        case 'F':
          o.f = w.value;
          break;
        case 'G':
          if (w.code10 == 930) o.g93 = true;
          break;
        default:
          break;
      }
    }
    out.push_back(o);
  }
  return out;
}

post::FiveAxisPostReport run_post(const std::string& program, const Machine& m, const ErrorSet& e,
                                  const post::FiveAxisPostOptions& o, std::string& output) {
  std::istringstream in(program);
  std::ostringstream out;
  const post::FiveAxisPostReport r = post::post_five_axis(in, "test.ngc", out, m, e, o);
  output = out.str();
  return r;
}

// Random reachable poses: from random axis positions through eqs. (10)-(15).
std::vector<ToolPose> random_poses(const Offsets& o, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-150, 150), y(-150, 150), z(0, 300), a(-95, 25),
      c(-180, 180);
  std::vector<ToolPose> v;
  for (int i = 0; i < n; ++i)
    v.push_back(eq10_15(o, x(rng), y(rng), z(rng), a(rng) * kDeg, c(rng) * kDeg));
  return v;
}

std::string vector_program(const std::vector<ToolPose>& poses, bool rapid = false) {
  std::string p = "G21 G90 G94\n";
  for (size_t i = 0; i < poses.size(); ++i) {
    const ToolPose& v = poses[i];
    p += fmt::format("N{} {} X{:.6f} Y{:.6f} Z{:.6f} I{:.9f} J{:.9f} K{:.9f}{}\n", (i + 1) * 10,
                     rapid || i == 0 ? "G0" : "G1", v.tip_mm.x(), v.tip_mm.y(), v.tip_mm.z(),
                     v.axis.x(), v.axis.y(), v.axis.z(), rapid || i == 0 ? "" : " F1000");
  }
  p += "M30\n";
  return p;
}

// The written end position of every numbered input line: the last line of
// its group (the line itself and the pieces added after it).
std::vector<OutLine> group_ends(const std::vector<OutLine>& out) {
  std::vector<OutLine> ends;
  for (const OutLine& o : out) {
    if (o.numbered && o.move)
      ends.push_back(o);
    else if (o.move && !ends.empty())
      ends.back() = OutLine{true, ends.back().n, true, o.u, o.f, o.g93};
  }
  return ends;
}

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

// The same path as a TCP-free tool-vector program, a Siemens A3= B3= C3=
// program and an APT CLDATA file: the same machine program.
TEST(FiveAxisPost, InputFormsAgree) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const ErrorSet e = test::sample_errors("lei-hsu-xyzac");
  const std::string vec =
      "G21 G90 G94\nG0 X10 Y0 Z30 I0 J0 K1\nG1 X10 Y5 Z20 I0 J-0.5 K0.8660254 F500\nG1 X0 Y5 Z20 "
      "I0.5 J0 "
      "K0.8660254\nM30\n";
  const std::string siemens =
      "G21 G90 G94\nG0 X10 Y0 Z30 A3=0 B3=0 C3=1\nG1 X10 Y5 Z20 A3=0 B3=-0.5 C3=0.8660254 F500\nG1 "
      "X0 Y5 Z20 "
      "A3=0.5 B3=0 C3=0.8660254\nM30\n";
  const std::string apt =
      "PARTNO/TEST\nMULTAX\nUNITS/MM\nRAPID\nGOTO/10,0,30,0,0,1\nFEDRAT/MMPM,500\nGOTO/10,5,20,$\n "
      " "
      "0,-0.5,0.8660254\nGOTO/0,5,20,0.5,0,0.8660254\nFINI\n";
  auto moves = [&](const std::string& p, post::InputForm expect) {
    std::string text;
    post::FiveAxisPostOptions o;
    const post::FiveAxisPostReport r = run_post(p, m, e, o, text);
    EXPECT_EQ(r.form, expect);
    std::vector<std::string> lines;
    std::istringstream in(text);
    std::string l;
    while (std::getline(in, l)) {
      const size_t x = l.find('X');
      if (x != std::string::npos && l.find('(') == std::string::npos) lines.push_back(l.substr(x));
    }
    return lines;
  };
  const std::vector<std::string> a = moves(vec, post::InputForm::kToolVector);
  EXPECT_GT(a.size(), 3u);
  EXPECT_EQ(moves(siemens, post::InputForm::kToolVector), a);
  EXPECT_EQ(moves(apt, post::InputForm::kApt), a);
}

// Inch and incremental programs of the same path: the same machine
// positions (inch output in inch: 5 decimals), always absolute (G91 becomes
// G90 in the output).
TEST(FiveAxisPost, InchAndIncrementalProgramsGiveTheSamePositions) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const ErrorSet e = test::sample_errors("lei-hsu-xyzac");
  const std::vector<std::array<double, 5>> pts = {
      {0, 0, 20, 0, 0}, {10, 5, 15, -20, 30}, {25.4, -12.7, 10, -35, 75}, {-5, 20, 12, -50, 140}};
  std::string mm = "G21 G90\n", inch = "G20 G90\n", inc = "G21 G90\n";
  for (size_t i = 0; i < pts.size(); ++i) {
    const auto& p = pts[i];
    const char* g = i == 0 ? "G0" : "G1";
    const char* f = i == 0 ? "" : " F400";
    mm += fmt::format("N{} {} X{} Y{} Z{} A{} C{}{}\n", i + 1, g, p[0], p[1], p[2], p[3], p[4], f);
    inch += fmt::format("N{} {} X{:.8f} Y{:.8f} Z{:.8f} A{} C{}{}\n", i + 1, g, p[0] / 25.4,
                        p[1] / 25.4, p[2] / 25.4, p[3], p[4], i == 0 ? "" : " F15.748031");
    if (i == 0) {
      inc += fmt::format("N1 G0 X{} Y{} Z{} A{} C{}\nG91\n", p[0], p[1], p[2], p[3], p[4]);
    } else {
      const auto& q = pts[i - 1];
      inc += fmt::format("N{} G1 X{:.6f} Y{:.6f} Z{:.6f} A{:.6f} C{:.6f} F400\n", i + 1,
                         p[0] - q[0], p[1] - q[1], p[2] - q[2], p[3] - q[3], p[4] - q[4]);
    }
  }
  auto ends = [&](const std::string& prog, double unit) {
    std::string text;
    run_post(prog, m, e, post::FiveAxisPostOptions{}, text);
    EXPECT_EQ(text.find("G91"), std::string::npos) << text;
    std::vector<OutLine> g = group_ends(parse_output(text));
    for (OutLine& o : g) {
      o.u.x *= unit;
      o.u.y *= unit;
      o.u.z *= unit;
    }
    return g;
  };
  const std::vector<OutLine> a = ends(mm, 1.0), b = ends(inch, 25.4), c = ends(inc, 1.0);
  ASSERT_EQ(a.size(), pts.size());
  ASSERT_EQ(b.size(), pts.size());
  ASSERT_EQ(c.size(), pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    for (const OutLine* o : {&b[i], &c[i]}) {
      EXPECT_NEAR(o->u.x, a[i].u.x, 0.5e-4 + 25.4 * 0.5e-5) << i;
      EXPECT_NEAR(o->u.y, a[i].u.y, 0.5e-4 + 25.4 * 0.5e-5) << i;
      EXPECT_NEAR(o->u.z, a[i].u.z, 0.5e-4 + 25.4 * 0.5e-5) << i;
      EXPECT_NEAR(o->u.a, a[i].u.a, 1e-5 * kDeg) << i;
      EXPECT_NEAR(o->u.c, a[i].u.c, 1e-5 * kDeg) << i;
    }
  }
}

TEST(FiveAxisPost, DetectsTheInputForm) {
  using post::detect_input_form;
  using post::InputForm;
  EXPECT_EQ(detect_input_form({"G0 X1 Y2 Z3 A4 C5", "G2 X1 Y2 I3 J4"}), InputForm::kTcp);
  EXPECT_EQ(detect_input_form({"G1 X1 Y2 Z3 I0 J0 K1"}), InputForm::kToolVector);
  EXPECT_EQ(detect_input_form({"N10 G1 X1 A3=0 B3=0 C3=1"}), InputForm::kToolVector);
  EXPECT_EQ(detect_input_form({"PARTNO/X", "GOTO/1,2,3,0,0,1"}), InputForm::kApt);
  EXPECT_EQ(detect_input_form({"G2 X1 Y2 I3 J4", "X5 Y6 I1 J1 (arc, modal)"}), InputForm::kTcp);
}

TEST(FiveAxisPost, RefusesWithFileAndLine) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  auto refuse = [&](const std::string& p, const std::string& what) {
    std::string text;
    try {
      run_post(p, m, ErrorSet{}, post::FiveAxisPostOptions{}, text);
      ADD_FAILURE() << "accepted: " << p;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("test.ngc:"), std::string::npos) << e.what();
    }
  };
  refuse("G0 X0 Y0 Z0 A0 C0\nG43 H1\n", "G43");
  refuse("G0 X0 Y0 Z0 A0 C0\nG55\n", "G54");
  refuse("G0 X0 Y0 Z0 A0 C0\nG1 X10 F100 B5\n", "no axis B");
  refuse("G0 X0 Y0 Z0 A0 C0\nG93 G1 X10\n", "needs F");
  refuse("G0 X0 Y0 Z0 A0 C0\nG2 X10 R5 F100\n", "R-form");
  refuse("G0 X0 Y0 Z0 A0 C0\nG0 X900\n", "travel");
  refuse("#1=5\n", "parameters");
  refuse("G1 X1 Y1 Z1 I0 J0 K0 F100\n", "zero");
}

TEST(FiveAxisPost, LinesWithoutMovesPassUnchanged) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const std::string prog =
      "%\n(a comment)\nS600 M3 ; spindle\nM428 ;TCP:xyzac\nG0 X1 Y2 Z3 A-10 C5\nM5\nM30\n%\n";
  std::string text;
  run_post(prog, m, test::sample_errors("lei-hsu-xyzac"), post::FiveAxisPostOptions{}, text);
  EXPECT_NE(text.find("%\n(a comment)\nS600 M3 ; spindle\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("M428"), std::string::npos) << text;
  EXPECT_NE(text.find("\nM5\nM30\n%\n"), std::string::npos) << text;
}

// Backward transformation, correction and formatting into a reserved
// buffer: no heap allocation per pose.
TEST(FiveAxisPost, PosePathAllocatesNothing) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const post::FiveAxisTransform tf(m, test::sample_errors("lei-hsu-xyzac"), OutsidePolicy::kError);
  const std::vector<ToolPose> poses = random_poses(Offsets{}, 200, 21);
  std::string out;
  out.reserve(1 << 16);
  AxisVector prev = m.home;
  const long before = g_allocations;
  for (const ToolPose& v : poses) {
    const AxisVector u = tf.axes_for_pose(v, prev);
    const AxisVector c = tf.command(u);
    for (int k = 0; k < 5; ++k) post::append_number(out, c[k], 4);
    prev = u;
  }
  EXPECT_EQ(g_allocations - before, 0);
  EXPECT_GT(out.size(), 1000u);
}

TEST(FiveAxisPost, AppendNumberMatchesFormatNumberOffTies) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> d(-1000, 1000);
  for (int i = 0; i < 200000; ++i) {
    const double v = i % 10 == 0 ? d(rng) * 1e-6 : d(rng);
    for (int dec : {0, 3, 4, 5}) {
      const double scaled = std::abs(v) * std::pow(10.0, dec);
      if (std::abs(scaled - std::floor(scaled) - 0.5) < 1e-6) continue;  // a tie: may differ
      std::string s;
      post::append_number(s, v, dec);
      ASSERT_EQ(s, nc::format_number(v, dec)) << v << " " << dec;
    }
  }
}

}  // namespace
}  // namespace volmap
