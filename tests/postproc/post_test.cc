// The three-axis post-processor: byte-for-byte identity on a zero-error
// machine, the correction against the model solved by hand, refusals of
// unsupported constructs with file:line, and the modes (inch, incremental,
// work offsets, tool length, canned cycles). The NC reader and writer on
// their own: tests/gcode/.
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
                 double tol_um = 1.0, const Machine& machine = hsu()) {
  std::istringstream in(program);
  std::ostringstream out;
  post::PostOptions o;
  o.tolerance_mm = tol_um * 1e-3;
  post::post_program(in, "prog.ngc", out, machine, errors, setup, o);
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

TEST(NcInterpreter, RefusesUnsupportedAndInvalidBlocks) {
  const std::pair<const char*, const char*> cases[] = {
      {"G41 D1", "G41/G42 uses tool 1, whose diameter the tool table does not give"},
      {"G41.1", "G41.1/G42.1 needs D"},
      {"G1 X1 D2", "D word with no G41"},
      {"G0 G1 X1", "same modal group"},
      {"G28", "#5161"},
      {"G92 X0", "from where the tool stands"},
      {"G38.2 Z-5", "probing"},
      {"M98 P100", "no O100 line"},
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
      {"G0 X1 Y1 Z5\nG91 Z-4 R-4", "R word with no G2, G3, G10 or canned cycle"},
      {"G0 X1 Y1 Z5\nX2 P0.3", "P word with no"},
      {"G0 X1 Y1 Z5\nX2 Q1", "Q word with no G64, G73 or G83"},
      {"G0 X1 Y1 Z5\nF10 G1 X2 L3", "L word with no G10 or canned cycle"},
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
  // LinuxCNC's demos are larger than the sample's travel in places (the
  // post refuses positions outside it): the same machine, travel widened.
  Machine wide = hsu();
  for (AxisLimits& L : wide.limits) {
    L.min = -2000;
    L.max = 2000;
  }
  for (const std::string& p : programs) {
    nc::ProgramSetup s = offset_setup(250, 200, 100);
    s.tool_length_mm[1] = 10.0;
    s.initial_position_mm = Eigen::Vector3d(250, 200, 100);  // plasmatest.ngc never commands Z
    EXPECT_EQ(post(p, none, s, 1.0, wide), p);
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
    EXPECT_NE(std::string(err.what()).find("post with `errors`"), std::string::npos) << err.what();
  }
  Machine other = m;
  other.name = "another-machine";
  EXPECT_THROW(run("G0 X0 Y0 Z0\n", other), std::invalid_argument);
}

}  // namespace
}  // namespace volmap
