// The NC reader and the three-axis post-processor: byte-for-byte identity
// on a zero-error machine, the correction against the model solved by
// hand, refusals of unsupported constructs with file:line, and the modes
// (inch, incremental, work offsets, tool length, canned cycles).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "core/common/input_error.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "gcode/nc_writer.h"
#include "maps/tables/table_builder.h"
#include "postproc/three_axis/corrector.h"
#include "postproc/three_axis/post_program.h"
#include "postproc/verify/verify.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

Machine hsu() { return load_machine_json(test::source_path("samples/machines/hsu-3axis.json")); }
ErrorSet hsu_errors() { return load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv")); }

nc::ProgramSetup offset_setup(double x, double y, double z) {
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(x, y, z);
  return s;
}

std::string post(const std::string& program, const ErrorSet& errors, const nc::ProgramSetup& setup,
                 double tol_um = 1.0) {
  std::istringstream in(program);
  std::ostringstream out;
  post::PostOptions o;
  o.tolerance_mm = tol_um * 1e-3;
  post::post_program(in, "prog.ngc", out, hsu(), errors, setup, o);
  return out.str();
}

std::string read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

const char* kLinuxCncPrograms[] = {"tort.ngc", "arcspiral.ngc",   "3dtest.ngc",
                                   "cds.ngc",  "hole-circle.ngc", "plasmatest.ngc"};
const char* kNcFiles = "/usr/share/linuxcnc/ncfiles/";

TEST(NcBlock, KeepsSpansAndScalesCodes) {
  const nc::Block b = nc::lex_block("N10 g1 x 1 0.5 Y-2 (comment) G38.2 ; rest", 3, "f.ngc");
  ASSERT_EQ(b.words.size(), 5u);
  EXPECT_EQ(b.words[1].code10, 10);
  EXPECT_DOUBLE_EQ(b.words[2].value, 10.5);  // spaces inside a number
  EXPECT_EQ(b.text.substr(b.words[2].begin, b.words[2].end - b.words[2].begin), "x 1 0.5");
  EXPECT_EQ(b.words[4].code10, 382);
  EXPECT_EQ(b.comment, "comment");
}

// Every number the lexer reads equals the correctly rounded value of its
// digits (std::from_chars), with its decimals and span, whatever follows it
// (the fast path for CAM's plain numbers and the general one agree).
TEST(NcBlock, NumbersReadAsTheirCorrectlyRoundedValue) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> len(0, 8), digit(0, 9), pick(0, 6);
  const char* tails[] = {"", " ", " Y1", "Y1", "(c)", " ;x", "\t"};
  for (int trial = 0; trial < 20000; ++trial) {
    std::string num = pick(rng) == 0 ? "-" : pick(rng) == 0 ? "+" : "";
    const int int_digits = len(rng), frac_digits = len(rng) % 7;
    for (int k = 0; k < int_digits; ++k) num += static_cast<char>('0' + digit(rng));
    const bool point = frac_digits > 0 || pick(rng) == 0;
    if (point) num += '.';
    for (int k = 0; k < frac_digits; ++k) num += static_cast<char>('0' + digit(rng));
    if (int_digits + frac_digits == 0) num += '7';
    const std::string text = "X" + num + tails[trial % 7];
    const nc::Block b = nc::lex_block(text, 1, "n.ngc");
    ASSERT_GE(b.words.size(), 1u) << text;
    const nc::Word& w = b.words[0];
    double want = 0;
    const char* first = num.data() + (num[0] == '+' ? 1 : 0);
    std::from_chars(first, num.data() + num.size(), want);
    EXPECT_EQ(w.value, want) << text;
    EXPECT_EQ(std::signbit(w.value), num[0] == '-') << text;
    EXPECT_EQ(w.end, 1 + num.size()) << text;
    const size_t dot = num.find('.');
    EXPECT_EQ(w.decimals, dot == std::string::npos ? 0 : static_cast<int>(num.size() - dot - 1))
        << text;
  }
  // Spaces inside a number join its parts (RS274NGC); a second point ends it.
  EXPECT_EQ(nc::lex_block("X 1 2.5 Y3", 1, "n.ngc").words[0].value, 12.5);
  EXPECT_EQ(nc::lex_block("X1 .5", 1, "n.ngc").words[0].value, 1.5);
  EXPECT_THROW(nc::lex_block("X1.2.3", 1, "n.ngc"), InputError);
}

TEST(NcBlock, RefusesWhatItDoesNotRead) {
  const std::pair<const char*, const char*> cases[] = {
      {"o100 sub", "O-word"},
      {"G1 X#1", "# parameters"},
      {"G1 X[1+2]", "expressions"},
      {"G1 X", "has no number"},
      {"G1 Y - ", "has no number"},
      {"G1 (open", "not closed"},
      {"G0 X1 $2", "unexpected character"},
  };
  for (const auto& [text, words] : cases) {
    try {
      nc::lex_block(text, 7, "p.ngc");
      ADD_FAILURE() << text;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("p.ngc:7:", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  }
}

TEST(NcInterpreter, RefusesUnsupportedAndInvalidBlocks) {
  const std::pair<const char*, const char*> cases[] = {
      {"G41 D1", "cutter radius compensation"},
      {"G0 G1 X1", "same modal group"},
      {"G28", "stored positions"},
      {"G92 X0", "G92"},
      {"G38.2 Z-5", "probing"},
      {"M98 P100", "subroutine"},
      {"G0 A10", "axis word A"},
      {"X1 X2", "twice"},
      {"G1 X1 Y1 Z1", "no feed rate"},
      {"G0 X0 Y0 Z0\nF100 G2 X10 Y0 I3 J0", "radius to end of arc"},
      {"F100 G1 X5", "unknown position"},
      {"G0 X0 Y0 Z0\nG43 H7", "tool table"},
      {"G0 X0 Y0 Z0\nG91 G1 @5 F10", "indeterminate"},
      {"G0 X0 Y0 Z0\nG1 X1 @2 F10", "polar"},
      {"G0 X1 Y1 Z0\nF10 G81 X2 Y2 Z-1 R1 L2.5", "L (repeats)"},
      {"G0 X1 Y1 Z0\nF10 G81 X2 Y2 Z2 R1", "above the R plane"},
      {"G91 F10 G1 X1 Y1 Z1", "unknown position"},
      // rs274: "Negative or zero q value used" (a starting block, and one
      // that goes on with the cycle).
      {"G0 X1 Y1 Z5\nF10 G83 X2 Y2 Z-1 R1 Q0", "Q must be positive"},
      {"G0 X1 Y1 Z5\nF10 G73 X2 Y2 Z-1 R1 Q0.5\nX3 Q-0.2", "Q must be positive"},
      // Words no code of the block uses (rs274: "I word with no G2, G3 ...
      // to use it", "R word with no g code that uses it", ...).
      {"G0 X1 Y1 Z5 I2", "I word with no G2 or G3"},
      {"G0 X1 Y1 Z5\nF10 G1 X2 K1", "K word with no G2 or G3"},
      {"G0 X1 Y1 Z5\nG91 Z-4 R-4", "R word with no G2, G3 or canned cycle"},
      {"G0 X1 Y1 Z5\nX2 P0.3", "P word with no"},
      {"G0 X1 Y1 Z5\nX2 Q1", "Q word with no G64, G73 or G83"},
      {"G0 X1 Y1 Z5\nF10 G1 X2 L3", "L word with no canned cycle"},
      {"G0 X1 Y1 Z5\nG2", "neither axis words nor a centre"},
      // rs274: "K word given for arc in xy plane", "Mixed radius ijk format".
      {"G0 X0 Y0 Z5\nF10 G2 X10 Y0 I5 J0 K1", "K word given for an arc in the XY (G17) plane"},
      {"G0 X0 Y0 Z5\nF10 G18 G2 X10 Z5 I5 K0 J1", "J word given for an arc in the XZ (G18) plane"},
      {"G0 X0 Y0 Z5\nF10 G2 X10 Y0 R5 K1", "both R and I/J/K"},
  };
  for (const auto& [text, words] : cases) {
    try {
      post(text, hsu_errors(), offset_setup(100, 100, 100));
      ADD_FAILURE() << text;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("prog.ngc:", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << text << " -> " << e.what();
    }
  }
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

TEST(NcWriter, FormatsDeterministically) {
  EXPECT_EQ(nc::format_number(12.5, 4), "12.5");
  EXPECT_EQ(nc::format_number(3.0, 4), "3");
  EXPECT_EQ(nc::format_number(-0.00001, 4), "0");
  EXPECT_EQ(nc::format_number(-1.23456, 4), "-1.2346");
}

// Property: a machine without errors gets its program back byte for byte,
// for the bundled real programs and odd formatting (CRLF, no final newline).
TEST(Post, ZeroErrorMachineReturnsTheInputByteForByte) {
  const ErrorSet none;
  std::vector<std::string> programs = {
      "%\r\nG21 G90\r\nG0 X0 Y0 Z5\r\ng1 f100 x10 y 2\r\nG2 X20 Y2 I5 J0\r\n%",
      "G20\nG0X0Y0Z1\nG91 G1 F5 X.5\nG90\nM2\n",
  };
  for (const char* name : kLinuxCncPrograms)
    if (std::filesystem::exists(std::string(kNcFiles) + name))
      programs.push_back(read_file(std::string(kNcFiles) + name));
  for (const std::string& p : programs) {
    nc::ProgramSetup s = offset_setup(250, 200, 100);
    s.tool_length_mm[1] = 10.0;
    s.initial_position_mm = Eigen::Vector3d(250, 200, 100);  // plasmatest.ngc never commands Z
    EXPECT_EQ(post(p, none, s), p);
  }
}

// The correction solves x_cmd + e(x_cmd) = x_nom: with a constant error the
// command is the nominal point minus the error, exactly.
TEST(Post, ConstantErrorIsSubtracted) {
  std::istringstream csv("X,EXX,EYX,EZX\n0,5,-3,2\n500,5,-3,2\n");
  const ErrorSet e = read_errors_csv(csv, "const.csv");
  const std::string out = post("G21 G90\nG0 X10 Y20 Z30\n", e, offset_setup(100, 100, 100));
  EXPECT_EQ(out, "G21 G90\nG0 X9.995 Y20.003 Z29.998\n");
}

// A linear error field: the command solves x + k x = p exactly
// (x = p / (1 + k)); the fixed point must find it, not the first-order
// guess p - k p.
TEST(Post, ExactSolutionNotFirstOrder) {
  std::istringstream csv("X,EXX\n0,0\n500,2000\n");  // k = 4e-3 (exaggerated on purpose)
  const ErrorSet e = read_errors_csv(csv, "scale.csv");
  const std::string out = post("G21\nG0 X400 Y0 Z0\n", e, offset_setup(0, 0, 0));
  // x = 400 / 1.004 = 398.406375; first order would give 398.4.
  EXPECT_NE(out.find("X398.4064"), std::string::npos) << out;
}

TEST(Post, InchIncrementalAndKeptWords) {
  std::istringstream csv("X,EXX\n0,25.4\n500,25.4\n");  // 25.4 um = 0.001 inch
  const ErrorSet e = read_errors_csv(csv, "inch.csv");
  const std::string out = post("G20 G90\nN5 G0 X1 Y1 Z1 (to start)\nG91\nN7 g0 x2 M8\n", e,
                               offset_setup(100, 100, 100));
  // Absolute: X1 -> 0.999; incremental after a corrected point: 2 stays 2
  // (both ends carry the same correction), so the line is unchanged.
  EXPECT_EQ(out, "G20 G90\nN5 G0 X0.999 Y1 Z1 (to start)\nG91\nN7 g0 x2 M8\n");
}

TEST(Post, ToolLengthChangesTheLever) {
  // A pitch of the Z carriage (EBZ): the tool tip moves by EBZ times the
  // tool length (Hsu Table II: EBZ has no position gain at the gauge line
  // of the measured tool, the longer tool adds its extra length).
  std::istringstream csv("Z,EBZ\n0,100\n300,100\n");
  const ErrorSet e = read_errors_csv(csv, "ebz.csv");
  nc::ProgramSetup s = offset_setup(100, 100, 100);
  s.tool_length_mm[2] = 50.0;  // offset: 50 mm longer than the machine's 100 mm probe
  const std::string out = post("G21\nG0 X0 Y0 Z0\nT2 M6 G43 H2\nG0 X1 Y0 Z0\n", e, s);
  // Independent form: measured with the 100 mm tool, the 150 mm one has a
  // 50 mm longer lever below the pivot: dx = -EBZ * 50 mm = -5 um.
  EXPECT_NE(out.find("G0 X1.005 Y0 Z0"), std::string::npos) << out;
}

TEST(Post, CannedCycleHolePositionAndDepth) {
  std::istringstream csv("X,EXX\n0,10\n500,10\n\nZ,EZZ\n0,-20\n300,-20\n");
  const ErrorSet e = read_errors_csv(csv, "cycle.csv");
  const std::string out = post("G21 G90 G98\nG0 X0 Y0 Z10\nF100 G81 X5 Y5 Z-2 R2\nX15\nG80\n", e,
                               offset_setup(100, 100, 100));
  EXPECT_EQ(out,
            "G21 G90 G98\nG0 X-0.01 Y0 Z10.02\nF100 G81 X4.99 Y5 Z-1.98 R2.02\nX14.99 Z-1.98 "
            "R2.02\nG80\n");
}

TEST(Post, StopCodeWithASegmentedMoveIsRefused) {
  try {
    post("G21\nG0 X0 Y0 Z0\nF100 G2 X10 Y0 I5 J0 M0\n", hsu_errors(), offset_setup(100, 100, 100));
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stop code"), std::string::npos);
  }
}

// The path between points: verify (the model sampled densely) finds the
// compensated program within tolerance where the nominal one is not.
TEST(Post, SegmentedPathStaysWithinToleranceOnRealPrograms) {
  for (const char* name : {"tort.ngc", "arcspiral.ngc", "3dtest.ngc"}) {
    const std::string path = std::string(kNcFiles) + name;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "LinuxCNC programs not installed";
    const std::string in = read_file(path);
    const nc::ProgramSetup s = offset_setup(250, 200, 100);
    for (double tol_um : {1.0, 5.0}) {
      const std::string out = post(in, hsu_errors(), s, tol_um);
      std::istringstream a(in), b(out);
      const post::VerifyResult r =
          post::verify_programs(a, name, b, "out.ngc", hsu(), hsu_errors(), s, {});
      EXPECT_GT(r.before.max_um, 15.0) << name;
      // Tolerance plus the rounding of the written numbers (4 decimals in
      // mm, 5 in inch: at most 0.22 um in space).
      EXPECT_LT(r.after.max_um, tol_um + 0.25) << name << " tol " << tol_um;
    }
  }
}

TEST(Post, DeterministicOutput) {
  const std::string p = "G21\nG0 X0 Y0 Z5\nF200 G1 X100 Y50 Z0\nG3 X120 Y70 R20\n";
  EXPECT_EQ(post(p, hsu_errors(), offset_setup(100, 100, 100)),
            post(p, hsu_errors(), offset_setup(100, 100, 100)));
}

// Under G91 each written increment is rounded to the output's decimals; the
// next increment must start from where the controller really is, or the
// roundings add up along the program (a random walk: some micrometres after
// thousands of moves). The real machine (verify, reading the numbers as
// written) stays within the tolerance to the end.
TEST(PostIncremental, RoundingsOfIncrementsDoNotAddUp) {
  std::string program = "G21 G90 G17\nG0 X20 Y20 Z50\nG91 G1 F500\n";
  for (int k = 0; k < 3000; ++k) {
    const int row = k / 100, col = k % 100;
    const double dx = (row % 2 == 0 ? 1 : -1) * 1.1;  // a zig-zag of 1.1 mm steps
    program += fmt::format("X{:.4f} Y{:.4f}\n", col == 99 ? 0.0 : dx, col == 99 ? 1.3 : 0.0);
  }
  program += "G90\nM2\n";
  const nc::ProgramSetup s = offset_setup(100, 50, 100);
  const std::string out = post(program, hsu_errors(), s);
  std::istringstream a(program), b(out);
  const post::VerifyResult r =
      post::verify_programs(a, "inc.ngc", b, "out.ngc", hsu(), hsu_errors(), s, {});
  EXPECT_GT(r.before.max_um, 5.0);
  EXPECT_LE(r.after.max_um, 1.0 + 0.09) << "worst at line " << r.after.worst_line;
}

// Under G93 (inverse time) every piece carries its F: the pieces of a block
// share its time, and a lost-motion take-up step (no nominal path) takes the
// time of its own length at the block's speed, not an absurd F.
TEST(PostInverseTime, PiecesShareTheBlocksTimeAndStepsGetASensibleFeed) {
  const std::string program =
      "G21 G90 G17\nG0 X10 Y10 Z10\nG93 G1 X100 Y10 Z10 F2\nX20 Y12 F2\nX110 F1\nG94\nM2\n";
  const std::string out = post(program, hsu_errors(), offset_setup(150, 100, 100));
  double minutes_in = 0.5 + 0.5 + 1.0, minutes_out = 0.0;
  int steps = 0;
  std::istringstream lines(out);
  std::string l;
  bool g93 = false;
  while (std::getline(lines, l)) {
    if (l.find("G93") != std::string::npos) g93 = true;
    if (l.find("G94") != std::string::npos) g93 = false;
    const size_t f = l.find('F');
    if (!g93 || f == std::string::npos) continue;
    const double F = std::strtod(l.c_str() + f + 1, nullptr);
    ASSERT_GT(F, 0.0) << l;
    EXPECT_LT(F, 1e6) << l;  // 3 um at 180 mm/min: F 6e4
    if (F > 100) ++steps;
    minutes_out += 1.0 / F;
  }
  EXPECT_GE(steps, 1);  // the reversals of X at lines 4 and 5
  EXPECT_NEAR(minutes_out, minutes_in, 1e-3);
}

// The drilling cycles of pocket.ngc on the sample machine (X with 3 um of
// lost motion): between holes X does not move nominally but its command
// creeps; the approach takes up the play in the creep's direction, so the
// hole is where the command says (without it the play was half taken up:
// 3.1 um). --expand-cycles writes the cycles out as moves, the feed into
// each hole segmented within tolerance like any feed move.
TEST(PostCycles, HolesApproachedWithThePlayTakenUpAndExpandedCyclesKeepTheTolerance) {
  const std::string program = read_file(test::source_path("samples/programs/pocket.ngc"));
  const nc::ProgramSetup s = offset_setup(250, 200, 100);
  for (const bool expand : {false, true}) {
    SCOPED_TRACE(expand ? "--expand-cycles" : "cycles kept");
    std::istringstream in(program);
    std::ostringstream out;
    post::PostOptions o;
    o.expand_cycles = expand;
    post::post_program(in, "pocket.ngc", out, hsu(), hsu_errors(), s, o);
    EXPECT_EQ(out.str().find("G81") == std::string::npos, expand);
    std::istringstream a(program), b(out.str());
    const post::VerifyResult r =
        post::verify_programs(a, "pocket.ngc", b, "out.ngc", hsu(), hsu_errors(), s, {});
    EXPECT_GT(r.before.max_um, 20.0);
    EXPECT_LE(r.after.max_um, 1.0 + 0.09) << "worst at line " << r.after.worst_line;
  }
  // Pecking cycles are written out too (their moves against rs274's:
  // LinuxCnc.ExpandedPeckCyclesAreRs274sMoves), within the tolerance.
  {
    const std::string pecks =
        "G21 G90\nG0 X10 Y10 Z10\nG98 G83 X20 Y20 Z-5 R2 Q1 F100\nG99 G73 X30 Z-4 R2 Q0.7\nG80\n";
    std::istringstream in(pecks);
    std::ostringstream out;
    post::PostOptions o;
    o.expand_cycles = true;
    post::post_program(in, "peck.ngc", out, hsu(), hsu_errors(), s, o);
    std::istringstream a(pecks), b(out.str());
    const post::VerifyResult r =
        post::verify_programs(a, "peck.ngc", b, "out.ngc", hsu(), hsu_errors(), s, {});
    EXPECT_GT(r.before.max_um, 20.0);
    EXPECT_LE(r.after.max_um, 1.0 + 0.09) << "worst at line " << r.after.worst_line;
  }
  // A hole of more pecks than --expand-cycles writes: refused at its line.
  {
    std::istringstream in("G21 G90\nG0 X10 Y10 Z10\nG83 X20 Y20 Z-5 R2 Q0.0005 F100\n");
    std::ostringstream out;
    post::PostOptions o;
    o.expand_cycles = true;
    try {
      post::post_program(in, "peck.ngc", out, hsu(), hsu_errors(), s, o);
      ADD_FAILURE() << "14 000 pecks were written";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("peck.ngc:3"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("10000 pecks"), std::string::npos) << e.what();
    }
  }
  // Spindle-stop cycles are not written out.
  post::PostOptions o;
  o.expand_cycles = true;
  std::istringstream in("G21 G90\nM3 S1000\nG0 X10 Y10 Z10\nG86 X20 Y20 Z-5 R2 P0.5 F100\n");
  std::ostringstream out;
  EXPECT_THROW(
      post::post_program(in, "bore.ngc", out, hsu(), hsu_errors(), offset_setup(100, 100, 100), o),
      InputError);
}

// Arcs kept as arcs (--keep-arcs): arcs in every plane, G91, G90.1, R
// form, helices, an inch arc, a full circle, arcs over several quadrants.
// Each becomes arcs cut at its quadrant points (no axis turns round inside
// one; take-up steps between them), with corrected ends and centres, the
// arc's G code stated; the real machine runs the whole within the
// tolerance. Where an arc cannot be kept the output is the linearised one,
// byte for byte (keep_arc puts back what it tried).
// tests/data/linuxcnc/arcs.ngc: its 11 arc blocks become 16 arcs.
std::string arc_program() { return read_file(test::source_path("tests/data/linuxcnc/arcs.ngc")); }

int arc_blocks(const std::string& program) {
  int n = 0;
  std::istringstream in(program);
  for (std::string line; std::getline(in, line);) {
    const nc::Block b = nc::lex_block(line, 1, "x.ngc");
    for (const nc::Word& w : b.words)
      n += w.letter == 'G' && (w.code10 == 20 || w.code10 == 30) ? 1 : 0;
  }
  return n;
}

TEST(PostArcs, KeptWhereTheFieldAllowsWithinTheTolerance) {
  const nc::ProgramSetup s = offset_setup(150, 100, 200);
  for (double tol_um : {1.0, 5.0}) {
    SCOPED_TRACE(tol_um);
    const std::string program = arc_program();
    std::istringstream in(program);
    std::ostringstream out;
    post::PostOptions o;
    o.tolerance_mm = tol_um * 1e-3;
    o.keep_arcs = true;
    post::post_program(in, "arcs.ngc", out, hsu(), hsu_errors(), s, o);
    EXPECT_EQ(arc_blocks(out.str()), 16) << out.str();
    std::istringstream a(program), b(out.str());
    const post::VerifyResult r =
        post::verify_programs(a, "arcs.ngc", b, "out.ngc", hsu(), hsu_errors(), s, {});
    EXPECT_GT(r.before.max_um, 20.0);
    EXPECT_LT(r.after.max_um, tol_um + 0.25) << "worst at line " << r.after.worst_line;
  }
  // LinuxCNC's programs: arcspiral's 2 mm arcs and tort's helices in three
  // planes.
  for (const char* name : {"arcspiral.ngc", "tort.ngc"}) {
    const std::string path = std::string(kNcFiles) + name;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "LinuxCNC programs not installed";
    const std::string program = read_file(path);
    const nc::ProgramSetup s2 = offset_setup(250, 200, 100);
    post::PostOptions o;
    o.keep_arcs = true;
    std::istringstream in(program);
    std::ostringstream kept;
    post::post_program(in, name, kept, hsu(), hsu_errors(), s2, o);
    const std::string lines = post(program, hsu_errors(), s2);
    std::istringstream a(program), b(kept.str());
    const post::VerifyResult r =
        post::verify_programs(a, name, b, "out.ngc", hsu(), hsu_errors(), s2, {});
    EXPECT_LT(r.after.max_um, 1.25) << name << " worst at line " << r.after.worst_line;
    EXPECT_GT(arc_blocks(kept.str()), 5) << name;
    EXPECT_LT(kept.str().size(), lines.size()) << name;
    if (std::string(name) == "arcspiral.ngc") {
      EXPECT_LT(kept.str().size() * 4, lines.size());
    }
  }
}

TEST(PostArcs, WhereNoneIsKeptTheOutputIsTheLinearisedOne) {
  // A quarter of a 150 mm circle over which the error field is not affine
  // enough (tried, put back), and a half circle under inverse time (G93),
  // which would take two arcs, each needing its own F.
  const std::string program =
      "G21 G90 G17 F300\nG0 X0 Y0 Z5\nG1 Z-1\nG1 X50\nG2 X200 Y150 I150 J0\nG1 X210\n"
      "G93 G3 X230 Y150 I10 J0 F30\nG94 G1 X240 F300\nM2\n";
  const nc::ProgramSetup s = offset_setup(150, 100, 200);
  std::string outs[2];
  post::PostReport reports[2];
  for (int k = 0; k < 2; ++k) {
    std::istringstream in(program);
    std::ostringstream out;
    post::PostOptions o;
    o.keep_arcs = k == 1;
    reports[k] = post::post_program(in, "circles.ngc", out, hsu(), hsu_errors(), s, o);
    outs[k] = out.str();
  }
  EXPECT_EQ(outs[1], outs[0]);
  EXPECT_EQ(reports[1].points_corrected, reports[0].points_corrected);
  EXPECT_EQ(reports[1].max_correction_mm, reports[0].max_correction_mm);
  EXPECT_EQ(arc_blocks(outs[1]), 0);
}

// post --table (cli.md): the table's interpolated tool-tip error stands for
// the model. Checked against the model itself: the real machine simulated
// from the errors runs the table-posted program within the tolerance plus
// the table's own interpolation error (check_table against the model).
TEST(PostTable, ATablePostedProgramRunsWithinToleranceOnTheModelMachine) {
  const Machine m = hsu();
  const ErrorSet e = hsu_errors();
  const ErrorModel model(m, e);
  maps::VolumetricTable table = maps::build_table(model, {10.0, 10.0, 10.0});
  const double table_um = maps::check_table(model, table).max_dv_um;
  ASSERT_LT(table_um, 0.5);  // the 10 mm grid holds the sample's smooth errors
  const std::string program = read_file(test::source_path("samples/programs/pocket.ngc"));
  const nc::ProgramSetup s = offset_setup(250, 200, 100);
  std::istringstream in(program);
  std::ostringstream out;
  post::post_program(in, "pocket.ngc", out, m, table, s, post::PostOptions{});
  std::istringstream a(program), b(out.str());
  const post::VerifyResult r = post::verify_programs(a, "pocket.ngc", b, "out.ngc", m, e, s, {});
  // Posting from the errors: within 1 um on the feed moves; the drill
  // cycle's feed-in is corrected at the hole bottom only (docs/post.md), its
  // deviation on the way down is the largest.
  const post::VerifyResult direct = [&] {
    std::istringstream n(program), c(post(program, e, s));
    return post::verify_programs(n, "pocket.ngc", c, "direct.ngc", m, e, s, {});
  }();
  EXPECT_GT(r.before.max_um, 10.0);
  // From the table: the same to within the table's error and the rounding
  // to 4 decimals (0.05 um a coordinate).
  EXPECT_LE(r.after.max_um, direct.after.max_um + table_um + 0.09)
      << "table error " << table_um << " um";
  EXPECT_NEAR(r.after.rms_um, direct.after.rms_um, table_um + 0.05);
  // The plain-line shortcut from a table too: the general path's bytes, on
  // pocket.ngc and on a raster of plain lines; and --keep-arcs, which has no
  // bounds of a table's field, linearises (the same output as without it).
  std::string raster = "G21 G90 G17 F800\nG0 X0 Y0 Z5\nG1 Z-1\n";
  for (int k = 0; k < 400; ++k)
    raster +=
        fmt::format("X{:.4f} Y{:.4f} Z{:.4f}\n", (k % 40) * 2.5 * ((k / 40) % 2 ? -1 : 1) + 50,
                    (k / 40) * 0.7, -1 - 0.3 * std::sin(k * 0.1));
  for (const std::string& text : {program, raster}) {
    std::string outs[3];
    for (int k = 0; k < 3; ++k) {
      post::PostOptions o;
      o.shortcuts = k != 1;
      o.keep_arcs = k == 2;
      std::istringstream i(text);
      std::ostringstream os;
      post::post_program(i, "t.ngc", os, m, table, s, o);
      outs[k] = os.str();
    }
    EXPECT_EQ(outs[0], outs[1]);
    EXPECT_EQ(outs[2], outs[0]);
  }
}

TEST(PostTable, AnotherToolOrAnotherMachineIsRefused) {
  const Machine m = hsu();
  const ErrorModel model(m, hsu_errors());
  const maps::VolumetricTable table = maps::build_table(model, {50.0, 50.0, 50.0});
  nc::ProgramSetup s = offset_setup(250, 200, 100);
  s.tool_length_mm[1] = 0.0;   // offset zero: the machine file's tool, fine
  s.tool_length_mm[2] = 30.0;  // another one: its errors are not in the table
  auto run = [&](const std::string& program, const Machine& machine) {
    std::istringstream in(program);
    std::ostringstream out;
    post::post_program(in, "p.ngc", out, machine, table, s, post::PostOptions{});
    return out.str();
  };
  EXPECT_NO_THROW(run("G21 G90\nG0 X0 Y0 Z0\nG43 H1\nG1 X10 F100\n", m));
  try {
    run("G21 G90\nG0 X0 Y0 Z0\nG43 H2\nG1 X10 F100\n", m);
    FAIL() << "a 130 mm tool was posted from a table of the 100 mm tool";
  } catch (const InputError& err) {
    EXPECT_EQ(err.line(), 3);  // the G43 line
    EXPECT_NE(std::string(err.what()).find("post with --errors"), std::string::npos) << err.what();
  }
  Machine other = m;
  other.name = "another-machine";
  EXPECT_THROW(run("G0 X0 Y0 Z0\n", other), std::invalid_argument);
}

}  // namespace
}  // namespace volmap
