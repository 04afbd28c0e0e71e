// The interpreter reads five-axis programs (ProgramSetup::rotary_axes,
// tool_axis_words): rotary words as axes in degrees, I J K of straight moves
// as the tool axis; and the feed rate rule of LinuxCNC's convert_feed_mode
// that both posts share (G94 sets the feed rate to zero), checked with rs274.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/common/input_error.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "tests/support/rs274.h"

namespace volmap::nc {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Runs `lines`; returns the message of the first refusal ("" for none).
std::string run(Interpreter& in, const std::vector<std::string>& lines, BlockEffect& fx) {
  int n = 0;
  try {
    for (const std::string& l : lines) in.execute(lex_block(l, ++n, "p.ngc"), fx);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

ProgramSetup five_axis(const std::string& rotary, bool tool_axis_words = false) {
  ProgramSetup s;
  s.rotary_axes = rotary;
  s.tool_axis_words = tool_axis_words;
  s.initial_position_mm = Eigen::Vector3d::Zero();
  return s;
}

// G90: A C as written (degrees); G91: added; no work offset on a rotary
// axis; the tip moves as without them.
TEST(FiveAxisWords, RotaryWordsAreAxesInDegrees) {
  ProgramSetup setup = five_axis("AC");
  setup.work_offset_mm[0] = Eigen::Vector3d(10, 20, 30);
  setup.initial_rotary_rad = {5 * kDeg, 0, 0};
  Interpreter in(setup, "p.ngc");
  BlockEffect fx;
  ASSERT_EQ(run(in, {"G21 G90", "G0 X1 Y2 Z3 C-20"}, fx), "");
  EXPECT_NEAR(in.state().rotary_rad[0], 5 * kDeg, 1e-15);  // A untouched
  EXPECT_NEAR(in.state().rotary_rad[2], -20 * kDeg, 1e-15);
  EXPECT_EQ(in.state().position_mm, Eigen::Vector3d(11, 22, 33));
  ASSERT_EQ(run(in, {"G91 G1 A30 C5 F100"}, fx), "");
  EXPECT_TRUE(fx.has_motion);  // a move of the rotary axes alone
  EXPECT_EQ(fx.motion.start_mm, fx.motion.end_mm);
  EXPECT_NEAR(in.state().rotary_rad[0], 35 * kDeg, 1e-15);
  EXPECT_NEAR(in.state().rotary_rad[2], -15 * kDeg, 1e-15);
  ASSERT_EQ(run(in, {"G90 G2 X1 Y22 I0 J10 A0 F100"}, fx), "");  // with an arc
  EXPECT_EQ(fx.motion.kind, MotionKind::kArc);
  EXPECT_NEAR(in.state().rotary_rad[0], 0.0, 1e-15);
}

TEST(FiveAxisWords, RotaryWordsTheMachineHasNotAreRefused) {
  BlockEffect fx;
  Interpreter three(ProgramSetup{}, "p.ngc");
  EXPECT_NE(run(three, {"G0 X0 Y0 Z0 A1"}, fx).find("three-axis post-processor"),
            std::string::npos);
  Interpreter ac(five_axis("AC"), "p.ngc");
  EXPECT_NE(run(ac, {"G0 B1"}, fx).find("p.ngc:1:4: the machine has no axis B"), std::string::npos);
  EXPECT_NE(run(ac, {"G0 U1"}, fx).find("no axis U"), std::string::npos);
  const std::string cycle = run(ac, {"G0 X0 Y0 Z10", "G81 X1 Y1 Z-1 R2 A10 F100"}, fx);
  EXPECT_NE(cycle.find("rotary axis word A in a canned cycle"), std::string::npos) << cycle;
  EXPECT_NEAR(ac.state().rotary_rad[0], 0.0, 0.0);  // the refused block changed nothing
}

// Tool-vector programs: I J K of G0/G1 give the tool axis, normalised; a
// block of I J K alone turns the tool where it stands; arcs keep I J K as
// centres; without tool_axis_words I J K in a straight move are refused
// (LinuxCNC: unused words).
TEST(FiveAxisWords, IjkOfAStraightMoveIsTheToolAxis) {
  Interpreter in(five_axis("", true), "p.ngc");
  BlockEffect fx;
  ASSERT_EQ(run(in, {"G21 G90", "G1 X1 I0 J3 K4 F100"}, fx), "");
  EXPECT_NEAR(in.state().tool_axis.y(), 0.6, 1e-15);
  EXPECT_NEAR(in.state().tool_axis.z(), 0.8, 1e-15);
  ASSERT_EQ(run(in, {"G1 I1 J0 K0"}, fx), "");
  EXPECT_TRUE(fx.has_motion);
  EXPECT_EQ(fx.motion.start_mm, fx.motion.end_mm);
  EXPECT_EQ(in.state().tool_axis, Eigen::Vector3d::UnitX());
  ASSERT_EQ(run(in, {"G2 X1 Y2 I0 J1"}, fx), "");
  EXPECT_EQ(fx.motion.kind, MotionKind::kArc);
  EXPECT_EQ(in.state().tool_axis, Eigen::Vector3d::UnitX());  // the centre, not an axis
  EXPECT_NE(run(in, {"G1 X2 I0 J0 K0"}, fx).find("the tool axis I J K is zero"), std::string::npos);

  Interpreter plain(five_axis(""), "p.ngc");
  EXPECT_NE(run(plain, {"G1 X1 I0 J0 K1 F100"}, fx).find("I word with no G2 or G3"),
            std::string::npos);
}

// LinuxCNC's convert_feed_mode: G94 (and G95) set the feed rate to zero, F
// in the same block comes after; G93 keeps it. rs274 refuses the G1 after
// a lone G94 ("Cannot do g1 with zero feed rate") and runs the others.
TEST(FiveAxisWords, G94SetsTheFeedRateToZeroAsLinuxCncDoes) {
  const std::vector<std::vector<std::string>> programs = {
      {"G21 G90 F500", "G0 X0 Y0 Z0", "G94", "G1 X10"},
      {"G21 G90 F500", "G0 X0 Y0 Z0", "G94 F300 G1 X10"},
      {"G21 G90 F500", "G0 X0 Y0 Z0", "G93", "G94 G1 X10 F200"},
      {"G21 G90 F500", "G0 X0 Y0 Z0", "G1 X10"}};
  const bool refused[] = {true, false, false, false};
  for (size_t p = 0; p < programs.size(); ++p) {
    Interpreter in(ProgramSetup{}, "p.ngc");
    BlockEffect fx;
    const std::string why = run(in, programs[p], fx);
    EXPECT_EQ(!why.empty(), refused[p]) << p << ": " << why;
    if (refused[p]) {
      EXPECT_NE(why.find("G1 with no feed rate"), std::string::npos) << why;
    }
  }
  if (std::system("command -v rs274 >/dev/null 2>&1") != 0) {
    if (std::getenv("VOLMAP_REQUIRE_RS274")) FAIL() << "rs274 (linuxcnc-uspace) is required";
    GTEST_SKIP() << "rs274 not installed (apt-get install linuxcnc-uspace)";
  }
  const std::filesystem::path dir = test::fresh_dir("g94");
  for (size_t p = 0; p < programs.size(); ++p) {
    const std::string prog = (dir / ("p" + std::to_string(p) + ".ngc")).string();
    std::ofstream(prog) << [&] {
      std::string text;
      for (const std::string& l : programs[p]) text += l + "\n";
      return text + "M2\n";
    }();
    const std::string log = prog + ".log";
    (void)std::system((test::rs274_command("-g " + prog) + " >" + log + " 2>&1").c_str());
    std::ifstream in(log);
    const std::string out((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(out.find("zero feed rate") != std::string::npos, refused[p]) << prog << "\n" << out;
  }
}

}  // namespace
}  // namespace volmap::nc
