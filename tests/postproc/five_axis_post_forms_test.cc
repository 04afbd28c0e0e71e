// The five-axis post-processor (postproc/five_axis_post.h): the three input
// forms give the same machine program, inch and incremental programs the
// same positions; the input form detected; refusals with file:line; lines
// without moves pass unchanged; the pose path allocates nothing; the
// writer's numbers.
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
#include "postproc/five_axis/five_axis_post.h"
#include "postproc/five_axis/five_axis_transform.h"
#include "postproc/five_axis/five_axis_verify.h"
#include "tests/postproc/five_axis_closed_form.h"
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

// The five-axis reader runs on the three-axis post's interpreter, so it
// reads the modal rules as LinuxCNC does (each checked with rs274 -g): a
// lone G94 sets the feed rate to zero ("Cannot do g1 with zero feed
// rate"), G80 leaves no motion mode for axis words that follow, an M code
// LinuxCNC does not know is refused, and a G17 arc takes no K.
TEST(FiveAxisPost, ModalRulesAreTheInterpretersAsLinuxCncs) {
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  auto refusal = [&](const std::string& p) -> std::string {
    std::string text;
    try {
      run_post(p, m, ErrorSet{}, post::FiveAxisPostOptions{}, text);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  const std::string start = "G21 G90 G94 G17\nG0 X0 Y0 Z10 A0 C0\n";
  EXPECT_NE(refusal(start + "G1 X1 F100\nG94\nG1 X2\n").find("test.ngc:5: G1 with no feed rate"),
            std::string::npos);
  EXPECT_EQ(refusal(start + "G1 X1 F100\nG94 F200 G1 X2\n"), "");
  EXPECT_NE(refusal(start + "G1 X1 F100\nG80\nX2\n").find("G80 active"), std::string::npos);
  EXPECT_NE(refusal(start + "M250\n").find("M code is not supported"), std::string::npos);
  EXPECT_NE(refusal(start + "G2 X2 Y0 I1 J0 K0 F100\n").find("K word given for an arc"),
            std::string::npos);
  EXPECT_EQ(refusal("M428\n" + start + "G1 X1 F100\nM429\n"), "");  // stripped, not interpreted
  // Before M428 the axis words are machine axes (LinuxCNC's identity
  // kinematics), not the tool tip.
  EXPECT_NE(refusal(start + "M428\nG1 X1 F100\nM429\n").find("test.ngc:2:1: a move outside"),
            std::string::npos);
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
