// The NC interpreter: LinuxCNC's polar coordinates, the common block's
// short path against the general steps, incremental canned cycles and the
// cycle rules as rs274 reads them.
#include "gcode/nc_interpreter.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <string>

#include "core/common/input_error.h"
#include "gcode/nc_block.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

nc::ProgramSetup offset_setup(double x, double y, double z) {
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(x, y, z);
  return s;
}

// LinuxCNC's polar coordinates (interp_find.cc, find_ends), by hand:
// G90 @10 ^30 is (10 cos 30, 10 sin 30) = (8.660254, 5); a lone ^90 keeps
// the radius 10: (0, 10); G91 @5 adds to the radius: (0, 15); G91 ^-90
// turns by -90 degrees: (15, 0). Work offset (100, 100, 100) mm.
TEST(NcInterpreter, PolarCoordinatesAsLinuxCncReadsThem) {
  nc::Interpreter in(offset_setup(100, 100, 100), "p.ngc");
  nc::BlockEffect fx;
  const char* lines[] = {"G21 G90 G17", "G0 X0 Y0 Z0", "G1 @10 ^30 F100",
                         "G1 ^90",      "G91 G1 @5",   "G1 ^-90"};
  const Eigen::Vector3d want[] = {{0, 0, 0},       {100, 100, 100}, {108.660254037844386, 105, 100},
                                  {100, 110, 100}, {100, 115, 100}, {115, 100, 100}};
  for (int k = 0; k < 6; ++k) {
    in.execute(nc::lex_block(lines[k], k + 1, "p.ngc"), fx);
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(in.state().position_mm[a], want[k][a], 1e-12) << lines[k];
  }
}

// The interpreter's short way for the common block (X Y Z and F only)
// leaves the same state and effect as the general steps, errors included:
// the same blocks with an N word (which changes nothing) take the general
// steps.
TEST(NcInterpreter, CommonBlockAsTheGeneralSteps) {
  std::mt19937 rng(3);
  for (int run = 0; run < 40; ++run) {
    nc::ProgramSetup setup = offset_setup(100, 50, 20);
    if (run % 3 == 0) setup.initial_position_mm = Eigen::Vector3d(1, 2, 3);
    nc::Interpreter plain(setup, "p.ngc"), general(setup, "p.ngc");
    std::uniform_real_distribution<double> u(-50, 50);
    for (int k = 0; k < 60; ++k) {
      std::string words;
      const int pick = static_cast<int>(rng() % 16);
      if (pick == 0) {
        words = rng() % 2 ? "G90" : "G91";
      } else if (pick == 1) {
        words = rng() % 2 ? "G0" : "G1";
      } else if (pick == 2) {
        words = rng() % 2 ? "G20" : "G21";
      } else {
        for (char L : {'X', 'Y', 'Z'})
          if (rng() % 2) words += fmt::format("{}{:.3f} ", L, u(rng));
        if (rng() % 4 == 0)
          words += fmt::format("F{:.1f}", rng() % 5 == 0 ? -1.0 : 100.0 * (rng() % 3));
        if (words.empty()) words = "X1";
      }
      std::string err_plain, err_general;
      nc::BlockEffect fx_plain, fx_general;
      try {
        plain.execute(nc::lex_block(words, k + 1, "p.ngc"), fx_plain);
      } catch (const InputError& e) {
        err_plain = e.what();
      }
      try {
        general.execute(nc::lex_block("N1 " + words, k + 1, "p.ngc"), fx_general);
      } catch (const InputError& e) {
        err_general = e.what();
      }
      // The same message; a column counts the N word's three characters more.
      auto message = [](const std::string& m) {
        return m.substr(m.find(' ') == std::string::npos ? 0 : m.find(' '));
      };
      ASSERT_EQ(message(err_plain), message(err_general)) << words;
      const nc::State &a = plain.state(), &b = general.state();
      ASSERT_EQ(a.position_mm, b.position_mm) << words;
      ASSERT_EQ(a.axis_known, b.axis_known) << words;
      ASSERT_EQ(a.position_known, b.position_known) << words;
      ASSERT_EQ(a.feed, b.feed) << words;
      ASSERT_EQ(a.cycle_il_known, b.cycle_il_known) << words;
      ASSERT_EQ(a.motion, b.motion) << words;
      if (!err_plain.empty()) continue;
      ASSERT_EQ(fx_plain.has_motion, fx_general.has_motion) << words;
      ASSERT_EQ(fx_plain.motion_code, fx_general.motion_code) << words;
      ASSERT_EQ(fx_plain.g53, fx_general.g53) << words;
      ASSERT_EQ(fx_plain.stop_code, fx_general.stop_code) << words;
      ASSERT_EQ(fx_plain.more_holes.size(), fx_general.more_holes.size()) << words;
      const nc::Motion &p = fx_plain.motion, &q = fx_general.motion;
      ASSERT_EQ(p.kind, q.kind) << words;
      ASSERT_EQ(p.start_mm, q.start_mm) << words;
      ASSERT_EQ(p.end_mm, q.end_mm) << words;
      ASSERT_EQ(p.center_mm, q.center_mm) << words;
      ASSERT_EQ(p.feed, q.feed) << words;
      ASSERT_EQ(p.r_mm, q.r_mm) << words;
      ASSERT_EQ(p.clear_mm, q.clear_mm) << words;
      ASSERT_EQ(p.plane, q.plane) << words;
    }
  }
}

// hole-circle.ngc's cycle, by hand: from (1.5, 0, 0) in, G91 G81 R.1 Z-.5
// ^60 L6: R is 0.1 in above the start level, the bottom 0.5 in below R
// (-0.4 in), the tool returns to R (G99, LinuxCNC's initial mode; G98 too,
// the start being below R); each
// repeat turns the hole 60 degrees about the origin on the 1.5 in circle.
TEST(NcInterpreter, IncrementalCannedCycleRepeatsRoundACircle) {
  nc::Interpreter in(offset_setup(100, 100, 100), "p.ngc");
  nc::BlockEffect fx;
  for (const char* l : {"G20 G17 G90", "G0 X1.5 Y0 Z0"})
    in.execute(nc::lex_block(l, 1, "p.ngc"), fx);
  in.execute(nc::lex_block("G91 G81 R.1 Z-.5 ^60 L6 F10", 3, "p.ngc"), fx);
  ASSERT_TRUE(fx.has_motion);
  ASSERT_EQ(fx.more_holes.size(), 5u);
  const double r_in = 1.5, deg = M_PI / 180;
  for (int k = 0; k < 6; ++k) {
    const nc::Motion& h = k == 0 ? fx.motion : fx.more_holes[static_cast<size_t>(k - 1)];
    EXPECT_EQ(h.kind, nc::MotionKind::kCycle);
    EXPECT_NEAR(h.end_mm.x(), 100 + 25.4 * r_in * std::cos(60 * (k + 1) * deg), 1e-9) << k;
    EXPECT_NEAR(h.end_mm.y(), 100 + 25.4 * r_in * std::sin(60 * (k + 1) * deg), 1e-9) << k;
    EXPECT_NEAR(h.end_mm.z(), 100 - 0.4 * 25.4, 1e-9);
    EXPECT_NEAR(h.r_mm, 100 + 0.1 * 25.4, 1e-9);
    EXPECT_NEAR(h.clear_mm, 100 + 0.1 * 25.4, 1e-9);
    if (k > 0) {  // from over the hole before, at the clearance level
      const nc::Motion& prev = k == 1 ? fx.motion : fx.more_holes[static_cast<size_t>(k - 2)];
      EXPECT_EQ(h.start_mm, Eigen::Vector3d(prev.end_mm.x(), prev.end_mm.y(), prev.clear_mm));
    }
  }
  EXPECT_NEAR(in.state().position_mm.x(), 100 + 25.4 * 1.5,
              1e-9);  // the sixth hole, at 360 degrees
  EXPECT_NEAR(in.state().position_mm.z(), 100 + 0.1 * 25.4, 1e-9);
  // Under G90, L repeats drill the same hole.
  in.execute(nc::lex_block("G90 G81 X1 Y1 Z-.2 R.1 L3", 4, "p.ngc"), fx);
  ASSERT_EQ(fx.more_holes.size(), 2u);
  EXPECT_EQ(fx.more_holes[1].end_mm, fx.motion.end_mm);
}

// The rest of the cycle rules, by hand (mm, work offset (100, 100, 100)),
// each checked against rs274 (tests/data/linuxcnc/cycles.ngc):
// - no G98/G99: LinuxCNC starts in G99, so from Z 20 a G81 R5 hole returns
//   to R (105), not to the initial level (120);
// - a G81 restated while G81 is modal needs no Z or R: bottom 98, R 105;
// - G91 G81 X5 Y-2 L3 from over (6, 6) at R: R 5 above the initial level
//   (which is Z 20 where the run began: 100 + 20 + 5 = 125), Z -2 below R
//   (123), holes at (11, 4), (16, 2), (21, 0);
// - G98 in G91 with R -10 below the initial level: R 110, bottom 107, and
//   the tool returns to the initial level 120.
TEST(NcInterpreter, CannedCycleRulesAsRs274ReadsThem) {
  nc::Interpreter in(offset_setup(100, 100, 100), "p.ngc");
  nc::BlockEffect fx;
  auto run = [&](const char* l) { in.execute(nc::lex_block(l, 1, "p.ngc"), fx); };
  run("G21 G17 G90");
  run("G0 X10 Y10 Z20");
  run("G81 X5 Y5 R5 Z-2 F100");
  EXPECT_NEAR(fx.motion.clear_mm, 105, 1e-12);
  EXPECT_NEAR(in.state().position_mm.z(), 105, 1e-12);
  run("G81 X6 Y6");
  EXPECT_EQ(fx.motion.end_mm, Eigen::Vector3d(106, 106, 98));
  EXPECT_NEAR(fx.motion.r_mm, 105, 1e-12);
  run("G91 X5 Y-2 R5 Z-2 L3");
  ASSERT_EQ(fx.more_holes.size(), 2u);
  EXPECT_EQ(fx.motion.end_mm, Eigen::Vector3d(111, 104, 123));
  EXPECT_EQ(fx.more_holes[0].end_mm, Eigen::Vector3d(116, 102, 123));
  EXPECT_EQ(fx.more_holes[1].end_mm, Eigen::Vector3d(121, 100, 123));
  EXPECT_NEAR(fx.motion.r_mm, 125, 1e-12);
  run("G98 X0 R-10 Z-3");
  EXPECT_NEAR(fx.motion.r_mm, 110, 1e-12);
  EXPECT_NEAR(fx.motion.end_mm.z(), 107, 1e-12);
  EXPECT_NEAR(in.state().position_mm.z(), 120, 1e-12);
  // A different cycle needs its words again (LinuxCNC: motion mode changes).
  EXPECT_THROW(run("G82 X1"), InputError);
}

// Polar words and the plane: LinuxCNC looks at the plane in effect before
// the block, so `G18 @..` from G17 is read (as X Y: @10 ^90 is (0, 10)),
// while any polar word under G18/G19, even in a block that selects G17, is
// refused.
TEST(NcInterpreter, PolarWordsNeedG17BeforeTheBlock) {
  nc::Interpreter in(offset_setup(0, 0, 0), "p.ngc");
  nc::BlockEffect fx;
  auto run = [&](const char* l) { in.execute(nc::lex_block(l, 1, "p.ngc"), fx); };
  run("G21 G17 G90");
  run("G0 X1 Y1 Z5");
  run("G18 G0 @10 ^90");
  EXPECT_NEAR(in.state().position_mm.x(), 0, 1e-12);
  EXPECT_NEAR(in.state().position_mm.y(), 10, 1e-12);
  EXPECT_THROW(run("G17 G0 @10 ^0"), InputError);
  EXPECT_THROW(run("G0 ^45"), InputError);
}

}  // namespace
}  // namespace volmap

namespace volmap {
namespace {

// rs274 (LinuxCNC 2.9) reads G80 beside another motion code as that code
// alone, in either order; the other code stays modal. Its canonical calls
// for this program: the hole at (1,1), then traverses to X5, a feed to X7,
// the hole again, traverses to Y3, X9 (G0 still modal), X11. (rs274 also
// emits a zero-length traverse for `G0 G80` without axis words, which
// moves nothing; volmap's interpreter has no motion there.)
TEST(NcInterpreter, G80BesideAnotherMotionCodeIsThatCode) {
  nc::Interpreter in(nc::ProgramSetup{}, "g80.ngc");
  nc::BlockEffect fx;
  const char* lines[] = {"G21 G90 G17",
                         "G0 X0 Y0 Z5",
                         "G81 X1 Y1 Z-1 R1 F100",
                         "G0 X5 G80",
                         "G80 G1 X7 F100",
                         "G81 X1 Y1 Z-1 R1",
                         "G80 G0 Y3",
                         "X9",
                         "G0 G80",
                         "X11"};
  std::vector<std::pair<nc::MotionKind, double>> got;
  for (int k = 0; k < 10; ++k) {
    in.execute(nc::lex_block(lines[k], k + 1, "g80.ngc"), fx);
    if (fx.has_motion) got.emplace_back(fx.motion.kind, fx.motion.end_mm.x());
  }
  using K = nc::MotionKind;
  const std::vector<std::pair<nc::MotionKind, double>> want = {
      {K::kRapid, 0}, {K::kCycle, 1}, {K::kRapid, 5}, {K::kLinear, 7},
      {K::kCycle, 1}, {K::kRapid, 1}, {K::kRapid, 9}, {K::kRapid, 11}};
  EXPECT_EQ(got, want);
  EXPECT_THROW(in.execute(nc::lex_block("G0 G1 X1", 11, "g80.ngc"), fx), InputError);
}

}  // namespace
}  // namespace volmap

namespace volmap {
namespace {

// G28 as rs274 runs it (LinuxCNC 2.9, homes 0, a tool 1 inch long): its
// canonical traverses for this program end at (1,2,3), (1,2,3), (1,2,-1)
// after G28 Z2 (through Z2 to Z home, the tip a tool length below it),
// (5,2,-1), (0,2,-1) after G91 G28 X0 (X only), and (0,0,-1) after G28
// (every axis), in inches.
TEST(NcInterpreter, G28ReturnsAsRs274Does) {
  nc::ProgramSetup setup;
  setup.tool_length_mm[1] = 25.4;
  for (int a = 0; a < 6; ++a) setup.parameters[5161 + a] = 0.0;
  nc::Interpreter in(setup, "g28.ngc");
  nc::BlockEffect fx;
  const char* lines[] = {"G20 G90 G17", "G0 X1 Y2 Z3", "T1 M6",      "G43 H1", "G0 X1 Y2 Z3",
                         "G28 Z2",      "G0 X5",       "G91 G28 X0", "G90",    "G28"};
  std::vector<Eigen::Vector3d> ends;
  for (int k = 0; k < 10; ++k) {
    in.execute(nc::lex_block(lines[k], k + 1, "g28.ngc"), fx);
    if (fx.has_motion) ends.push_back(fx.motion.end_mm / 25.4);
  }
  const std::vector<Eigen::Vector3d> want = {{1, 2, 3},  {1, 2, 3},  {1, 2, -1},
                                             {5, 2, -1}, {0, 2, -1}, {0, 0, -1}};
  ASSERT_EQ(ends.size(), want.size());
  for (size_t k = 0; k < want.size(); ++k) EXPECT_TRUE(ends[k].isApprox(want[k], 1e-12)) << k;
  // Without the stored position (no parameter file), G28 is refused.
  nc::Interpreter bare(nc::ProgramSetup{}, "g28.ngc");
  try {
    bare.execute(nc::lex_block("G28", 1, "g28.ngc"), fx);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("#5161"), std::string::npos) << e.what();
  }
  // G28.1 stores where the axes stand (the tip plus the tool length).
  in.execute(nc::lex_block("G0 X1 Y1 Z1", 11, "g28.ngc"), fx);
  in.execute(nc::lex_block("G28.1", 12, "g28.ngc"), fx);
  in.execute(nc::lex_block("G0 X3 Y3 Z3", 13, "g28.ngc"), fx);
  in.execute(nc::lex_block("G28", 14, "g28.ngc"), fx);
  EXPECT_TRUE((fx.motion.end_mm / 25.4).isApprox(Eigen::Vector3d(1, 1, 1), 1e-12));
}

// M61 sets the tool number without a change: rs274 then applies, for a G43
// without H, the length of the tool the last M6 loaded (T1 here, not T2),
// a machine that of M61's tool. Refused until H names the tool or an M6
// loads one; G43 H2 after M61 applies tool 2's length, as rs274 does.
TEST(NcInterpreter, G43WithoutHAfterM61IsRefusedAndHNamesTheTool) {
  nc::ProgramSetup setup;
  setup.tool_length_mm[1] = 50.0;
  setup.tool_length_mm[2] = 120.5;
  nc::Interpreter in(setup, "m61.ngc");
  nc::BlockEffect fx;
  int line = 0;
  for (const char* l : {"G21 G90 G17", "T1 M6", "G43", "M61 Q2"})
    in.execute(nc::lex_block(l, ++line, "m61.ngc"), fx);
  EXPECT_EQ(in.state().tool_length_mm, 50.0);
  try {
    in.execute(nc::lex_block("G43", ++line, "m61.ngc"), fx);
    ADD_FAILURE() << "G43 without H after M61 read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("m61.ngc:5:1: G43 without H after M61"), std::string::npos)
        << e.what();
  }
  nc::Interpreter again(setup, "m61.ngc");
  line = 0;
  for (const char* l : {"G21 G90 G17", "M61 Q2", "G43 H2"})
    again.execute(nc::lex_block(l, ++line, "m61.ngc"), fx);
  EXPECT_EQ(again.state().tool_length_mm, 120.5);
  again.execute(nc::lex_block("T1 M6", ++line, "m61.ngc"), fx);  // an M6 clears it
  again.execute(nc::lex_block("G43", ++line, "m61.ngc"), fx);
  EXPECT_EQ(again.state().tool_length_mm, 50.0);
}

// M61 is in LinuxCNC's modal group 6 with M6: rs274 reads `M61 Q2 M64 P1`
// and refuses `M6 M61 Q1` ("Two m codes used from same modal group").
TEST(NcInterpreter, M61SharesItsModalGroupWithM6) {
  nc::Interpreter in(nc::ProgramSetup{}, "m61.ngc");
  nc::BlockEffect fx;
  in.execute(nc::lex_block("M61 Q2 M64 P1", 1, "m61.ngc"), fx);
  EXPECT_THROW(in.execute(nc::lex_block("M6 M61 Q1", 2, "m61.ngc"), fx), InputError);
}

}  // namespace
}  // namespace volmap

namespace volmap {
namespace {

// G10 L2, G10 L20, G92 and G92.1-G92.3 as rs274 runs
// tests/data/linuxcnc/offsets.ngc: it prints G54 = (5, 1, 0) after G10 L2,
// G55 X = 6 after G10 L20 at machine X 6, G92 = (3, -1, 0) after G92 X0 Y0
// at machine (8, 0, 0) in G54, and every G0 X1 Y1 at program (1, 1): so the
// machine points are (6, 2, 1), (8, 0, 0), (9, 1, 0), (6, 2, 0) after G92.2,
// (9, 1, 0) after G92.3 and (6, 2, 0) after G92.1.
TEST(NcInterpreter, OffsetsAsRs274SetsThem) {
  nc::Interpreter in(nc::ProgramSetup{}, "offsets.ngc");
  nc::BlockEffect fx;
  std::ifstream f(test::source_path("tests/data/linuxcnc/offsets.ngc"));
  std::vector<Eigen::Vector3d> ends;
  std::string line;
  for (int n = 1; std::getline(f, line); ++n) {
    in.execute(nc::lex_block(line, n, "offsets.ngc"), fx);
    if (fx.has_motion) ends.push_back(fx.motion.end_mm);
  }
  const std::vector<Eigen::Vector3d> want = {{0, 0, 0}, {6, 2, 1}, {8, 0, 0}, {9, 1, 0},
                                             {6, 2, 0}, {9, 1, 0}, {6, 2, 0}};
  ASSERT_EQ(ends.size(), want.size());
  for (size_t k = 0; k < want.size(); ++k) EXPECT_TRUE(ends[k].isApprox(want[k], 1e-12)) << k;
  nc::Interpreter fresh(nc::ProgramSetup{}, "o.ngc");
  EXPECT_THROW(fresh.execute(nc::lex_block("G10 L1 P1 Z5", 1, "o.ngc"), fx), InputError);
  EXPECT_THROW(fresh.execute(nc::lex_block("G10 L2 P1 R30", 1, "o.ngc"), fx), InputError);
  EXPECT_THROW(fresh.execute(nc::lex_block("G92 X0", 1, "o.ngc"), fx), InputError);  // X unknown
}

}  // namespace
}  // namespace volmap
