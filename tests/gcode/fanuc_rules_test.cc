// The Fanuc / Haas dialect's rules (gcode/fanuc_rules.cc, gcode/flatten/
// fanuc_macro.cc), each expected value worked out by hand from Fanuc's
// Series 0i-MF operator's manual (B-64604EN): decimal point programming,
// G04, canned cycles (group 09, K repeats, G98/G99), G28's reference
// position, G53, GOTO's search, the custom macro statements and what is
// refused because it depends on the control's parameters.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/common/input_error.h"
#include "gcode/nc_interpreter.h"
#include "gcode/program_reader.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/nc_read.h"

namespace volmap {
namespace {

using Reading = test::NcReading;

Reading run(const std::string& program, nc::Dialect dialect = nc::Dialect::kFanuc,
            nc::ProgramSetup setup = {}, std::vector<std::string> path = {}) {
  setup.dialect = dialect;
  std::istringstream in(program);
  return test::read_nc(in, "f.nc", setup, std::move(path));
}

std::string error_of(const std::string& program, nc::Dialect d = nc::Dialect::kFanuc,
                     nc::ProgramSetup setup = {}) {
  try {
    run(program, d, setup);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

bool has(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(FanucRules, AnAddressWithoutADecimalPointIsRefusedUnlessZero) {
  // "X10" is 10 least input increments (0.010 mm, IS-B) without 3401#0.
  const std::string e = error_of("G90 G00 X0 Y0 Z10.\nG01 X10 F100.\n");
  EXPECT_TRUE(has(e, "f.nc:2:5: X has no decimal point")) << e;
  EXPECT_TRUE(has(e, "3401#0")) << e;
  const Reading r = run("G90 G00 X0 Y0 Z10.\nG01 X10. F100\n");
  EXPECT_DOUBLE_EQ(r.moves.back().motion.end_mm.x(), 10.0);
  // LinuxCNC: X10 is 10 mm.
  EXPECT_DOUBLE_EQ(run("G90 G00 X0 Y0 Z10\nG01 X10 F100\n", nc::Dialect::kLinuxCnc)
                       .moves.back()
                       .motion.end_mm.x(),
                   10.0);
}

TEST(FanucRules, ASemicolonEndsTheBlock) {
  EXPECT_EQ(run("G90 G00 X1. Y2. Z3. ;\n").state.position_mm, Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(has(error_of("G90 G00 X1. Y2. Z3. ; FIRST POINT\n"), "f.nc:1:21: ';' with text"));
  EXPECT_TRUE(has(error_of("G90 G00 X1. Y2. Z3. (A;B)\n"), "no error"));
}

TEST(FanucRules, G04TakesItsTimeFromXOrP) {
  const Reading r = run("G90 G00 X1. Y2. Z3.\nG04 X1.5\nG04 P500\nG04 X2.\n");
  ASSERT_EQ(r.moves.size(), 1u);
  EXPECT_EQ(r.state.position_mm, Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(has(error_of("G04 X1. P5\n"), "both X and P"));
  EXPECT_TRUE(has(error_of("G04 X2\n"), "0.002 s"));
  EXPECT_TRUE(has(error_of("G04\n"), "X (seconds) or P (milliseconds)"));
}

TEST(FanucRules, G80EndsTheCycleAndTheGroup01MotionGoesOn) {
  const std::string cycle = "G98 G81 X5. Y5. Z-2. R1. F100.\nG80\nX20. Y20.\n";
  // Rapid before the cycle: the move after G80 is a rapid, from the
  // initial level (G98: Z10) to X20 Y20.
  Reading r = run("G90 G00 X0. Y0. Z10.\n" + cycle);
  ASSERT_EQ(r.moves.size(), 3u);
  EXPECT_EQ(r.moves[2].motion.kind, nc::MotionKind::kRapid);
  EXPECT_EQ(r.moves[2].motion.end_mm, Eigen::Vector3d(20, 20, 10));
  // Feed before it: a feed move.
  r = run("G90 G00 X0. Y0. Z10.\nG01 X0. F50.\n" + cycle);
  EXPECT_EQ(r.moves.back().motion.kind, nc::MotionKind::kLinear);
  // LinuxCNC: G80 is a motion mode of its own; the axis words are refused.
  EXPECT_TRUE(has(error_of("G90 G00 X0 Y0 Z10\nG98 G81 X5 Y5 Z-2 R1 F100\nG80\nX20 Y20\n",
                           nc::Dialect::kLinuxCnc),
                  "G80 active"));
}

TEST(FanucRules, KRepeatsACycleAndTheReturnLevelMustBeGiven) {
  // G91: R counts from the initial level (10 - 8 = 2), Z from R (2 - 5 =
  // -3); K3 drills at X10, X20, X30.
  const Reading r = run("G90 G00 X0. Y0. Z10.\nG91 G98 G81 X10. Y0. Z-5. R-8. K3 F100.\n");
  const nc::BlockEffect& fx = r.moves.back();
  EXPECT_EQ(fx.motion.end_mm, Eigen::Vector3d(10, 0, -3));
  ASSERT_EQ(fx.more_holes.size(), 2u);
  EXPECT_DOUBLE_EQ(fx.more_holes[0].end_mm.x(), 20.0);
  EXPECT_DOUBLE_EQ(fx.more_holes[1].end_mm.x(), 30.0);
  EXPECT_TRUE(
      has(error_of("G90 G00 X0. Y0. Z10.\nG98 G81 X1. Y0. Z-5. R1. K0 F100.\n"), "drills no hole"));
  EXPECT_TRUE(
      has(error_of("G90 G00 X0. Y0. Z10.\nG98 G81 X1. Y0. Z-5. R1. K2 L2 F100.\n"), "K and L"));
  EXPECT_TRUE(
      has(error_of("G90 G00 X0. Y0. Z10.\nG81 X1. Y0. Z-5. R1. F100.\n"), "before any G98 or G99"));
}

TEST(FanucRules, G28GoesToTheMachineZeroThroughTheNamedAxesOnly) {
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(100, 100, 100);
  // G91 G28 Z0.: straight up from where the tool is to machine Z0.
  const Reading r = run("G90 G00 X10. Y20. Z30.\nG91 G28 Z0.\n", nc::Dialect::kFanuc, s);
  EXPECT_EQ(r.state.position_mm, Eigen::Vector3d(110, 120, 0));
  EXPECT_TRUE(has(error_of("G90 G00 X10. Y20. Z30.\nG28\n"), "only the axes the block names"));
  // LinuxCNC needs the stored position (a parameter file).
  EXPECT_TRUE(has(error_of("G90 G00 X10 Y20 Z30\nG91 G28 Z0\n", nc::Dialect::kLinuxCnc), "G28"));
}

TEST(FanucRules, G10AddsUnderG91AndWhatDiffersIsRefused) {
  // G10 L2 P1 X5. then, under G91, X5. again: G54 X is 10 (LinuxCNC: 5).
  const std::string p = "G90 G10 L2 P1 X5. Y0 Z0\nG91 G10 L2 P1 X5.\nG90 G54 G00 X0 Y0 Z0\n";
  EXPECT_DOUBLE_EQ(run(p).state.position_mm.x(), 10.0);
  EXPECT_DOUBLE_EQ(run("G90 G10 L2 P1 X5 Y0 Z0\nG91 G10 L2 P1 X5\nG90 G54 G00 X0 Y0 Z0\n",
                       nc::Dialect::kLinuxCnc)
                       .state.position_mm.x(),
                   5.0);
  EXPECT_TRUE(has(error_of("G10 L20 P1 X0\n"), "G54.1"));
  EXPECT_TRUE(has(error_of("G10 L2 P0 X0\n"), "external work offset"));
  EXPECT_TRUE(has(error_of("G90 G00 X0 Y0 Z0\nG92.2\n"), "LinuxCNC's"));
  EXPECT_TRUE(has(error_of("G91 G52 X1.\n"), "under G90"));
  EXPECT_TRUE(has(error_of("G90 G00 X0 Y0 Z0\nG52 X1.\nG92 X0\n"), "G52 and G92"));
}

TEST(FanucRules, G53PositionsAtRapidTraverse) {
  const Reading r = run("G90 G01 X0. Y0. Z0. F100.\nG53 Z-10.\nX5.\n");
  ASSERT_EQ(r.moves.size(), 3u);
  EXPECT_EQ(r.moves[1].motion.kind, nc::MotionKind::kRapid);
  EXPECT_EQ(r.moves[2].motion.kind, nc::MotionKind::kLinear);  // G01 stays
  EXPECT_TRUE(has(error_of("G90 G00 X0. Y0. Z0.\nG53 G01 Z-10. F100.\n"), "beside G53"));
}

TEST(FanucRules, GotoSearchesForwardFirstThenFromTheStart) {
  // From `GOTO 10` the search finds the N10 after it, not the one before.
  const Reading r =
      run("O0001\n#1 = 0\nN10 G90 G00 X1. Y0. Z0.\n#1 = #1 + 1\nIF [#1 GT 1] GOTO 20\nGOTO 10\n"
          "N10 G00 X2.\nN20 G00 X3.\nM30\n");
  ASSERT_EQ(r.moves.size(), 3u);
  EXPECT_DOUBLE_EQ(r.moves[0].motion.end_mm.x(), 1.0);
  EXPECT_DOUBLE_EQ(r.moves[1].motion.end_mm.x(), 2.0);
  EXPECT_DOUBLE_EQ(r.moves[2].motion.end_mm.x(), 3.0);
  // Backward: the loop runs.
  const Reading back =
      run("O0001\n#1 = 0\nN5 #1 = #1 + 1\nG90 G00 X#1 Y0. Z0.\nIF [#1 LT 3] GOTO 5\nM30\n");
  EXPECT_EQ(back.moves.size(), 3u);
  EXPECT_TRUE(has(error_of("O0001\nGOTO 7\nM30\n"), "no block N7"));
}

TEST(FanucRules, LoopsEndAtTheirEndAndAJumpIntoOneIsRefused) {
  EXPECT_TRUE(has(error_of("O0001\nGOTO 5\nWHILE [1 EQ 1] DO1\nN5 G00 X1. Y0. Z0.\nEND1\nM30\n"),
                  "END1 without its WHILE"));
  EXPECT_TRUE(has(error_of("O0001\nWHILE [1 EQ 2] DO1\nM30\n"), "DO1 without END1"));
  EXPECT_TRUE(has(error_of("O0001\nWHILE [1 EQ 1] DO4\nEND4\n"), "1, 2 or 3"));
  // A jump out of a loop leaves it.
  const Reading r =
      run("O0001\n#1 = 0\nWHILE [#1 LT 10] DO1\n#1 = #1 + 1\nIF [#1 EQ 2] GOTO 9\nEND1\n"
          "N9 G90 G00 X#1 Y0. Z0.\nM30\n");
  ASSERT_EQ(r.moves.size(), 1u);
  EXPECT_DOUBLE_EQ(r.moves[0].motion.end_mm.x(), 2.0);
}

TEST(FanucRules, VariablesAsTheManualDefinesThem) {
  // Assignments take effect at once; `#1 = 5` then `#2 = #1 * 2` in the
  // next block is 10. A constant without a point is a whole number.
  Reading r = run("O0001\n#1 = 5\n#2 = #1 * 2 + 1\nG90 G00 X#2 Y0. Z0.\n");
  EXPECT_DOUBLE_EQ(r.moves[0].motion.end_mm.x(), 11.0);
  // Precedence: * / before + -; brackets as written.
  r = run("O0001\n#1 = 2 + 3 * 4\n#2 = [2 + 3] * 4\nG90 G00 X#1 Y#2 Z0.\n");
  EXPECT_EQ(r.moves[0].motion.end_mm, Eigen::Vector3d(14, 20, 0));
  // A vacant variable in an address leaves the address out.
  r = run("O0001\nG90 G00 X1. Y2. Z3.\nG00 X#1 Y5.\n");
  EXPECT_EQ(r.moves.back().motion.end_mm, Eigen::Vector3d(1, 5, 3));
  // #500-#999 are the control's: from a parameter file, or refused.
  EXPECT_TRUE(has(error_of("O0001\nG90 G00 X#500 Y0. Z0.\n"), "#500 is read before"));
  nc::ProgramSetup s;
  s.parameters[500] = 4.5;
  r = run("O0001\nG90 G00 X#500 Y0. Z0.\n", nc::Dialect::kFanuc, s);
  EXPECT_DOUBLE_EQ(r.moves[0].motion.end_mm.x(), 4.5);
  EXPECT_TRUE(has(error_of("O0001\nG90 G00 X#4001 Y0. Z0.\n"), "system variable"));
  EXPECT_TRUE(has(error_of("O0001\n#3000 = 12 (TOOL BROKEN)\n"),
                  "#3000 = 12: the program raises a macro alarm"));
  EXPECT_TRUE(has(error_of("O0001\n#1 = 1 #2 = 2\n"), "holds one"));
  EXPECT_TRUE(has(error_of("O0001\nG00 X#1 #2 = 2\n"), "put it on a line of its own"));
  EXPECT_TRUE(has(error_of("O0001\n#<x> = 1\n"), "LinuxCNC's"));
}

TEST(FanucRules, WhatDependsOnTheControlsParametersIsRefused) {
  // ATAN and ASIN below zero: 0-360 or -180-180 by parameter 6004#0.
  EXPECT_DOUBLE_EQ(run("O1\n#1 = ATAN[1.]/[-1.]\nG90 G00 X#1 Y0. Z0.\n").moves[0].motion.end_mm.x(),
                   135.0);
  EXPECT_TRUE(has(error_of("O1\n#1 = ATAN[-1.]/[-1.]\n"), "-135 or 225"));
  EXPECT_TRUE(has(error_of("O1\n#1 = ASIN[-0.5]\n"), "6004#0"));
  // ROUND in an address rounds to the least input increment.
  EXPECT_TRUE(has(error_of("O1\nG90 G00 X[ROUND[1.4]] Y0. Z0.\n"), "least input increment"));
  // AND binds like *: mixed with a comparison it reads otherwise than in
  // LinuxCNC.
  EXPECT_TRUE(has(error_of("O1\n#1 = 1\nIF [#1 EQ 1 AND #1 EQ 1] GOTO 5\nN5 M30\n"), "bracket"));
  EXPECT_TRUE(
      has(error_of("O1\n#1 = 1\nIF [[#1 EQ 1] AND [#1 EQ 2]] GOTO 5\nN5 M30\n"), "no error"));
  EXPECT_TRUE(has(error_of("O1\n#1 = 6 AND 3\n"), "bits"));
  EXPECT_TRUE(has(error_of("O1\n#1 = 2 ** 3\n"), "LinuxCNC's power"));
  // Too close to call: 0.00001 apart.
  EXPECT_TRUE(has(error_of("O1\n#1 = 0.00001\nIF [#1 EQ 0] GOTO 5\nN5 M30\n"), "closer than"));
}

TEST(FanucRules, SubprogramCallsFindTheirProgramNumber) {
  // P30010: O0010 three times (0i); a file with O30010 calls that one
  // once (8-digit program numbers); with both, refused.
  const std::string sub = "G91 G00 X1.\nG90\nM99\n";
  Reading r = run("O0001\nG90 G00 X0. Y0. Z0.\nM98 P30010\nM30\nO0010\n" + sub);
  EXPECT_DOUBLE_EQ(r.state.position_mm.x(), 3.0);
  r = run("O0001\nG90 G00 X0. Y0. Z0.\nM98 P30010\nM30\nO30010\n" + sub);
  EXPECT_DOUBLE_EQ(r.state.position_mm.x(), 1.0);
  EXPECT_TRUE(
      has(error_of("O0001\nG90 G00 X0. Y0. Z0.\nM98 P30010\nM30\nO30010\n" + sub + "O0010\n" + sub),
          "renumber one"));
  // A :0010 program number is a label too.
  r = run("O0001\nG90 G00 X0. Y0. Z0.\nM98 P10 L2\nM30\n:0010\n" + sub);
  EXPECT_DOUBLE_EQ(r.state.position_mm.x(), 2.0);
  EXPECT_TRUE(has(error_of("O0001\nG65 P9000 X1\nM30\nO9000\nM99\n"), "decimal point"));
  // A macro stored as a program of its own: O9200.nc on the subroutine
  // path (its arguments X Y are #24 #25 there).
  const std::filesystem::path dir = test::fresh_dir("fanuc_macro_file");
  std::ofstream(dir / "O9200.nc") << "%\nO9200 (MOVE TO X Y)\nG90 G00 X#24 Y#25\nM99\n%\n";
  r = run("O0001\nG90 G00 X0. Y0. Z0.\nG65 P9200 X4. Y5.\nM30\n", nc::Dialect::kFanuc, {},
          {dir.string()});
  EXPECT_EQ(r.state.position_mm, Eigen::Vector3d(4, 5, 0));
  EXPECT_TRUE(has(error_of("O0001\nG65 P9300 X4.\nM30\n"), "no file O9300"));
  EXPECT_TRUE(has(error_of("O0001\nG66 P9000 X1.\nM30\n"), "modal macro"));
}

// From the review of session 22: H is modal, the power-on motion mode is a
// parameter, G10 under G91 adds to the control's offset, G65's words.
TEST(FanucRules, WhatTheControlKeepsModalIsGivenOrRefused) {
  nc::ProgramSetup s;
  s.tool_length_mm[1] = 10.0;
  EXPECT_TRUE(
      has(error_of("G90 G00 X0 Y0 Z50.\nG43 Z50.\n", nc::Dialect::kFanuc, s), "G43 without H"));
  EXPECT_TRUE(has(error_of("G90 G00 X0 Y0 Z50.\nG43 H1 Z50.\nH2\n", nc::Dialect::kFanuc, s),
                  "H without G43"));
  EXPECT_TRUE(has(error_of("G90 G17\nX0 Y0 Z5. F100.\n"), "parameter 3402#0"));
  EXPECT_TRUE(has(error_of("G91 G10 L2 P2 X10.\n"), "has not set"));
  EXPECT_DOUBLE_EQ(run("G90 G10 L2 P2 X1. Y0 Z0\nG91 G10 L2 P2 X10.\nG90 G55 G00 X0 Y0 Z0\n")
                       .state.position_mm.x(),
                   11.0);
  EXPECT_TRUE(has(error_of("O0001\nX1. G65 P9000\nM30\nO9000\nM99\n"), "before G65"));
  EXPECT_TRUE(has(error_of("O0001\nG65 P9000 K1. J2.\nM30\nO9000\nM99\n"), "I J K"));
  // An evaluated M, T or H is a whole number without a point.
  EXPECT_EQ(run("O0001\n#1 = 3\nM#1\n").out, "O0001\nM3\n");
  EXPECT_TRUE(has(error_of("O0001\n#1 = 3.5\nT#1\n"), "whole number"));
  // ';' after a statement ends it.
  EXPECT_EQ(run("O0001\n#1 = 5.;\nG90 G00 X#1 Y0 Z0;\n").state.position_mm.x(), 5.0);
}

TEST(FanucRules, AutoReadsAProgramNumberAtTheHeadAsFanuc) {
  EXPECT_EQ(run("%\n:0097\nG90 G00 X0 Y0 Z0\n", nc::Dialect::kAuto).report.dialect.dialect,
            nc::Dialect::kFanuc);
  EXPECT_EQ(run("\xEF\xBB\xBF%\n(TITLE)\nO1000 (PART)\nM30\n%\n", nc::Dialect::kAuto)
                .report.dialect.dialect,
            nc::Dialect::kFanuc);
  EXPECT_EQ(run("o100 sub\no100 endsub\nM30\n", nc::Dialect::kAuto).report.dialect.dialect,
            nc::Dialect::kLinuxCnc);
  EXPECT_EQ(run("G90 G00 X10 Y0 Z0\n", nc::Dialect::kAuto).report.dialect.dialect,
            nc::Dialect::kLinuxCnc);
  // ';' lines: comments for LinuxCNC, empty blocks for Fanuc; not a block.
  EXPECT_EQ(nc::detect_dialect("; TITLE\nO1000\n", 1).dialect, nc::Dialect::kFanuc);
  EXPECT_EQ(nc::detect_dialect("O1000 ;\nG00 X10 Y10 Z5\n", 1).dialect, nc::Dialect::kFanuc);
  const nc::DialectChoice c = nc::detect_dialect("(HEAD)\n\nO0123 (X)\n", 1);
  EXPECT_EQ(c.line, 3);
  EXPECT_EQ(c.reason, "program number O0123 at line 3");
}

}  // namespace
}  // namespace volmap
