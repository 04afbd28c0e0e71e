// A real client: LinuxCNC's interpreter (rs274, Debian's linuxcnc-uspace)
// reads every program volmap post writes, and its canonical moves agree
// with the predicted correction: every commanded point of the output, moved
// by the machine's error (the model), lands within tolerance of the input's
// path as LinuxCNC itself interprets the input (lines, arcs, helices).
//
// rs274 missing: the test is skipped on a developer machine, and fails when
// VOLMAP_REQUIRE_RS274 is set (CI sets it and installs linuxcnc-uspace).
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <sstream>
#include <tuple>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "gcode/nc_path.h"
#include "postproc/three_axis/corrector.h"
#include "tests/postproc/linuxcnc_canon.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/rs274.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

// Arcs kept as arcs: rs274 reads as many arcs as volmap's interpreter
// reads in out (the blocks that state G2/G3 and those that rely on it).
void expect_rs274_reads_the_written_arcs(const std::string& out, const Canon& after) {
  int written = 0, read = 0;
  std::istringstream lines(test::file_bytes(out));
  nc::ProgramSetup setup;
  nc::Interpreter interp(setup, out);
  nc::BlockEffect fx;
  int number = 0;
  for (std::string l; std::getline(lines, l);) {
    interp.execute(nc::lex_block(l, ++number, out), fx);
    written += fx.has_motion && fx.motion.kind == nc::MotionKind::kArc ? 1 : 0;
  }
  for (const nc::Motion& mo : after.feeds) read += mo.kind == nc::MotionKind::kArc ? 1 : 0;
  EXPECT_GT(written, 5);
  EXPECT_EQ(read, written) << "rs274's arcs are the ones volmap wrote";
}

struct Case {
  const char* program;
  const char* extra_args;
  const char* machine;  // sample name (machine and errors)
  double wo[3];         // work offset, mm
  bool arcs = false;    // count the arcs rs274 reads against ours
};

TEST(LinuxCnc, Rs274AcceptsPostedProgramsAndTheirMovesAgreeWithTheModel) {
  require_rs274();
  const std::string nc = "/usr/share/linuxcnc/ncfiles/";
  const std::string tbl = "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/simpockets.tbl";
  // hole-circle.ngc: polar coordinates and a G91 drill cycle repeated round a
  // circle (L6), in inches. plasmatest.ngc: a 594 x 311 mm plasma program
  // that never commands Z, on the 1000 x 600 mm gantry sample; rs274 starts
  // at program Z 0, and so does the post (--initial-position).
  const Case cases[] = {
      {"tort.ngc", "--linearize-arcs", "hsu-3axis", {250, 200, 100}},
      {"arcspiral.ngc", "--linearize-arcs", "hsu-3axis", {250, 200, 100}},
      {"3dtest.ngc", "", "hsu-3axis", {250, 200, 100}},
      {"cds.ngc", "--tool-table", "hsu-3axis", {250, 200, 100}},
      {"hole-circle.ngc", "", "hsu-3axis", {250, 200, 100}},
      {"plasmatest.ngc", "--initial-position 0,0,0", "gantry-3axis", {100, 100, 100}},
      // volmap's own: every polar and canned-cycle rule
      // (G90/G91, L repeats, polar holes, restated cycles,
      // the initial G99) in one program each.
      {"tests/data/linuxcnc/polar.ngc", "", "hsu-3axis", {250, 200, 100}},
      {"tests/data/linuxcnc/cycles.ngc", "", "hsu-3axis", {250, 200, 100}},
      // G52 local offsets of up to 120 mm: the points are where rs274's
      // offsets put them, so a misread offset moves the error they meet.
      {"tests/data/linuxcnc/local-offsets.ngc", "", "hsu-3axis", {250, 200, 100}},
      // Arcs kept as arcs (the default): rs274 reads them, its arcs are
      // ours.
      {"tests/data/linuxcnc/arcs.ngc", "", "hsu-3axis", {150, 100, 200}, true},
      {"arcspiral.ngc", "", "hsu-3axis", {250, 200, 100}, true},
      {"tort.ngc", "", "hsu-3axis", {250, 200, 100}, true}};
  const fs::path dir = test::fresh_dir("linuxcnc");
  for (const Case& k : cases) {
    SCOPED_TRACE(k.program);
    const std::string machine =
        test::source_path(std::string("samples/machines/") + k.machine + ".json");
    const std::string errors =
        test::source_path(std::string("samples/errors/") + k.machine + ".csv");
    const Machine m = load_machine_json(machine);
    const ErrorSet e = load_errors_csv(errors);
    const Eigen::Vector3d wo(k.wo[0], k.wo[1], k.wo[2]);
    const std::string program = k.program;
    const std::string in =
        program.rfind("tests/", 0) == 0 ? test::source_path(program) : nc + program;
    ASSERT_TRUE(fs::exists(in)) << in;
    const std::string out = (dir / ("post-" + fs::path(program).filename().string())).string();
    std::string args = k.extra_args;
    const bool uses_tools = args == "--tool-table";
    if (uses_tools) args += " " + tbl;
    const std::string cmd = test::volmap_binary() + " post --machine " + machine + " --errors " +
                            errors +
                            fmt::format(" --work-offset {},{},{} ", k.wo[0], k.wo[1], k.wo[2]) +
                            args + " " + in + " -o " + out;
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const Canon before = canonical(in, uses_tools ? tbl : "");
    const Canon after = canonical(out, uses_tools ? tbl : "");
    ASSERT_TRUE(before.ok && after.ok) << after.errors;
    if (k.arcs) expect_rs274_reads_the_written_arcs(out, after);
    EXPECT_TRUE(after.errors.empty()) << after.errors;
    ASSERT_FALSE(before.feeds.empty());
    // Nominal path in machine coordinates.
    std::vector<nc::Motion> nominal = before.feeds;
    for (nc::Motion& mo : nominal) {
      mo.start_mm += wo;
      mo.end_mm += wo;
      mo.center_mm += wo;
    }
    // Tool lengths: cds.ngc uses G43 H1 (1.0 in in the sim table? the
    // controlled point is the tip either way); the lever changes with the
    // tool, so the check uses the same tool as the post.
    const post::Corrector c(m, e, m.tool_length_mm, OutsidePolicy::kError);
    if (uses_tools) continue;  // tool-length levers: covered by post_test; here rs274 acceptance
    const double before_um = worst_deviation_um(before, nominal, c, wo),
                 after_um = worst_deviation_um(after, nominal, c, wo);
    EXPECT_GT(before_um, 10.0);
    // 1 um tolerance, plus the rounding of volmap's numbers (<= 0.22 um),
    // plus rs274's own: it prints 4 decimals of the program's unit (0.1 um
    // in mm, 2.5 um in inch: up to 2.2 um in space).
    const double rs274_rounding_um = 0.5e-4 * after.unit_mm * 1e3 * std::sqrt(3.0);
    EXPECT_LT(after_um, 1.25 + rs274_rounding_um);
    std::printf(
        "%s: commanded points off the nominal path, as rs274 reads them: before %.2f um, after "
        "%.3f um\n",
        k.program, before_um, after_um);
  }
}

// Tool length offsets as LinuxCNC applies them: a .tbl Z (or G43.1's Z) is
// how much longer the tool is than the one of offset zero, and a change of
// offset moves the controlled point, not the axes (the current Z jumps by
// minus the change), so moves that do not restate Z (G91 here) start from
// there. volmap's interpreter, and the post's output run through rs274,
// agree with rs274 on the input to its printed 4 decimals (plus the
// correction, some micrometres, for the output). (The standalone rs274
// does not jump when M6 and G43 share a block: after a tool change it
// takes its last programmed point as where it stands, where a running
// LinuxCNC asks the axes; volmap applies the change of offset either way.)
TEST(LinuxCnc, ToolLengthOffsetsMoveTheControlledPointAsRs274Does) {
  require_rs274();
  const fs::path dir = test::fresh_dir("tlo");
  const auto [tbl_inch, tbl_mm] = tool_tables(dir, {1.0, -0.5});
  const std::string program =
      "G21 G90 G17 F100\nG0 X0 Y0 Z50\nG43 H1\nG91 G1 Z-5\nT2 M6\nG43 H2\nG1 X2 Z-5\nG49\nG1 Z-5\n"
      "G43.1 Z10\nG1 Y3 Z-5\nG90 G1 X10 Z0\nG10 L1 P1 Z20\nG43 H1\nG91 G1 Z-5\nG90\nM2\n";
  const std::string in = (dir / "tlo.ngc").string(), out = (dir / "tlo-post.ngc").string();
  std::ofstream(in, std::ios::binary) << program;
  const Canon rs = canonical(in, tbl_inch);
  ASSERT_TRUE(rs.ok) << rs.errors;
  // By hand: 50 - 25.4 - 5 = 19.6; + 25.4 + 12.7 - 5 = 52.7; - 12.7 - 5 =
  // 35; - 10 - 5 = 20; then Z0; G10 L1 makes tool 1's offset 20 mm (the one
  // in effect, G43.1's 10, stays), G43 H1 applies it: 0 - (20 - 10) - 5.
  const double want[] = {19.6, 52.7, 35.0, 20.0, 0.0, -15.0};
  ASSERT_EQ(rs.feeds.size(), 6u);
  for (size_t k = 0; k < 6; ++k)
    EXPECT_NEAR(rs.feeds[k].end_mm.z(), want[k], 1e-4) << "rs274, feed " << k;
  // volmap's interpreter, work offset zero.
  nc::ProgramSetup setup;
  nc::read_tool_table(tbl_mm, setup);
  nc::Interpreter interp(setup, "tlo.ngc");
  nc::BlockEffect fx;
  std::istringstream lines(program);
  std::string line;
  std::vector<double> feeds_z;
  for (int n = 1; std::getline(lines, line); ++n) {
    interp.execute(nc::lex_block(line, n, "tlo.ngc"), fx);
    if (fx.has_motion && fx.motion.kind == nc::MotionKind::kLinear)
      feeds_z.push_back(fx.motion.end_mm.z());
  }
  ASSERT_EQ(feeds_z.size(), 6u);
  for (size_t k = 0; k < 6; ++k) EXPECT_NEAR(feeds_z[k], want[k], 1e-9) << "volmap, feed " << k;
  // The post of it, run by rs274: the same points, moved by the correction.
  const std::string cmd = hsu_post_command("--work-offset 250,200,150 --tool-table " + tbl_mm +
                                           " " + in + " -o " + out);
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Canon posted = canonical(out, tbl_inch);
  ASSERT_TRUE(posted.ok) << posted.errors;
  // The output reaches every feed end of the input, in order, within the
  // correction (the take-up steps of lost motion, a few micrometres from
  // where an offset change left the controlled point, come between).
  size_t next = 0;
  for (const nc::Motion& m : rs.feeds) {
    while (next < posted.points.size() &&
           !(posted.points[next].second && (posted.points[next].first - m.end_mm).norm() < 0.05))
      ++next;
    EXPECT_LT(next, posted.points.size()) << "the output never reaches " << m.end_mm.transpose();
    ++next;
  }
}

// Limits LinuxCNC sets, on both sides of each, run through rs274 and volmap
// post: the radii of an I J K arc may differ by 0.02 sqrt 2 mm (0.002 sqrt 2
// inch), or by more if that is at most 0.1 % of the radius; an R arc may
// fall short of half its chord by 0.00005 inch; G86 needs the spindle
// turning, the taps G84 and G74 turning their way.
TEST(LinuxCnc, ArcAndCycleLimitsAreLinuxCncs) {
  require_rs274();
  const struct {
    const char* block;
    bool accepted;
  } cases[] = {
      {"G2 X20.028 Y0 I10 J0", true},       // 0.028 mm apart
      {"G2 X20.0284 Y0 I10 J0", false},     // 0.0284 mm, 0.28 %
      {"G2 X200.05 Y0 I100 J0", true},      // 0.05 mm but 0.05 %
      {"G2 X20.04 Y0 I10 J0", false},       // 0.04 mm, 0.4 % (volmap took up to 0.05 mm)
      {"G2 X10 Y0 R4.999", true},           // 0.001 mm short
      {"G2 X10 Y0 R4.998", false},          // 0.002 mm short
      {"G20 G2 X1.0028 Y0 I0.5 J0", true},  // 0.0028 inch
      {"G20 G2 X1.0029 Y0 I0.5 J0", false},
      {"G86 X5 Y5 Z-3 R2 P0.5", false},  // spindle stopped
      {"M3 S1000\nG86 X5 Y5 Z-3 R2 P0.5", true},
      {"G84 X5 Y5 Z-3 R2", false},                // spindle stopped
      {"M3 S1000\nG84 X5 Y5 Z-3 R2 P0.2", true},  // P: the dwell at the bottom
      {"M4 S1000\nG84 X5 Y5 Z-3 R2", false},      // a right-hand tap turning left
      {"M4 S1000\nG74 X5 Y5 Z-3 R2", true},
      {"M3 S1000\nG74 X5 Y5 Z-3 R2", false},
      {"M3 S1000\nG84 X5 Y5 Z-3 R2 L2", true},
      {"M4 S1000\nG74 X5 Y5 Z-3 R2 L2", false},  // LinuxCNC's L check leaves G74 out
      {"M3 S1000\nG84 X5 Y5 Z-3 R2 Q1", false},
      {"M3 S1000\nG84 X5 Y5 Z-3 R2\nM5\nX8", false},  // stopped before the next hole
  };
  const fs::path dir = test::fresh_dir("limits");
  const std::string in = (dir / "limit.ngc").string(), out = (dir / "limit-post.ngc").string();
  for (const auto& k : cases) {
    SCOPED_TRACE(k.block);
    std::ofstream(in, std::ios::binary) << "G21 G90 G17 F200\nG0 X0 Y0 Z5\n" << k.block << "\nM2\n";
    EXPECT_EQ(canonical(in, "").ok, k.accepted) << "rs274";
    const std::string cmd =
        hsu_post_command("--work-offset 250,200,100 " + in + " -o " + out + " 2>/dev/null");
    EXPECT_EQ(std::system(cmd.c_str()) == 0, k.accepted) << "volmap post";
  }
}

// --expand-cycles writes G73 and G83 out as LinuxCNC makes them: rs274
// runs the posted moves through the pecks of the input, one for one (G83
// out to R and back down to 0.254 mm or 0.010 in above the level reached,
// G73 up by that much; levels by repeated subtraction of Q in program
// units, so a bottom a whole number of pecks below R, in mm and in inch,
// gets no extra peck), G98 and G99, a restated cycle keeping its Q, L
// repeats under G91. A loose tolerance keeps every feed one piece; points
// less than 0.01 mm from the one before (a lost-motion take-up step, the
// traverse to where the tool already is) count once on both sides.
TEST(LinuxCnc, ExpandedPeckCyclesAreRs274sMoves) {
  require_rs274();
  const std::string program =
      "G21 G90 G17 G94\nF100\nG0 X10 Y10 Z20\n"
      "G98 G83 X10 Y10 Z-3 R2 Q1\n"  // a bottom three pecks below R
      "X20 Z-2.5\n"                  // restated: Q 1 kept
      "G99 G73 X30 Y10 Z-3.1 R2 Q1.2\n"
      "G80\nG0 Z20\n"
      "G91 G98 G83 X5 Y0 Z-4 R-18 Q1.5 L3\n"  // R at 2, bottom at -2, three holes in a row
      "G90 G80\nG20\nG0 Z1\n"
      "G98 G83 X1 Y1 Z-0.1 R0.1 Q0.04\n"  // inch: 0.1 - 5 x 0.04 by repeated subtraction
      "G73 X1.2 Y1 Z-0.1 R0.1 Q0.05\n"
      "G80\nG21\nG0 Z20\nM2\n";
  const fs::path dir = test::fresh_dir("pecks");
  const std::string in = (dir / "pecks.ngc").string(), out = (dir / "pecks-post.ngc").string();
  std::ofstream(in, std::ios::binary) << program;
  const std::string cmd = hsu_post_command(
      "--work-offset 150,100,200 --expand-cycles --tolerance-um 50 " + in + " -o " + out);
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const std::string written = test::file_bytes(out);
  EXPECT_EQ(written.find("G83"), std::string::npos);
  EXPECT_EQ(written.find("G73"), std::string::npos);
  const Canon input = canonical(in, ""), posted = canonical(out, "");
  ASSERT_TRUE(input.ok) << input.errors;
  ASSERT_TRUE(posted.ok) << posted.errors;
  auto distinct = [](const Canon& c) {
    std::vector<std::pair<Eigen::Vector3d, bool>> v;
    for (const auto& p : c.points)
      if (v.empty() || (p.first - v.back().first).norm() >= 0.01) v.push_back(p);
    return v;
  };
  const auto want = distinct(input), got = distinct(posted);
  // The feeds rs274 makes of the input (pecks and the last feed to the
  // bottom): levels 1 0 -1 -2 and -3; 1 0 -1 -2 and -2.5; 0.8 -0.4 -1.6
  // -2.8 and -3.1; three holes of 0.5 -1 and -2; in inch 0.06 0.02 -0.02
  // -0.06 and -0.1; 0.05 0 -0.05 and -0.1.
  int feeds = 0;
  for (const auto& p : want) feeds += p.second ? 1 : 0;
  EXPECT_EQ(feeds, 5 + 5 + 5 + 3 * 3 + 5 + 4);
  ASSERT_EQ(got.size(), want.size()) << written;
  for (size_t k = 0; k < want.size(); ++k) {
    EXPECT_EQ(got[k].second, want[k].second)
        << "move " << k << (want[k].second ? " is a feed" : " is a traverse");
    EXPECT_LT((got[k].first - want[k].first).cwiseAbs().maxCoeff(), 0.05)
        << "move " << k << ": " << got[k].first.transpose() << " vs " << want[k].first.transpose();
  }
}

}  // namespace
}  // namespace volmap

namespace volmap {
namespace {

// The offsets rs274 prints (SET_G5X_OFFSET, SET_G92_OFFSET), in order.
std::vector<std::vector<double>> offsets_of(const std::string& canon_file) {
  std::ifstream f(canon_file);
  std::vector<std::vector<double>> out;
  for (std::string l; std::getline(f, l);) {
    if (l.find("SET_G5X_OFFSET(") == std::string::npos &&
        l.find("SET_G92_OFFSET(") == std::string::npos)
      continue;
    std::vector<double> v;
    std::stringstream ss(l.substr(l.find('(') + 1));
    for (std::string tok; std::getline(ss, tok, ',');)
      v.push_back(std::strtod(tok.c_str(), nullptr));
    out.push_back(v);
  }
  return out;
}

// G92 and G10 L20 set offsets from where the controller stands, which the
// correction moves off the nominal point: the post moves their values by
// as much, so that rs274, running the output, sets the same offsets as it
// does running the input (to its printed 4 decimals, plus the output's).
TEST(LinuxCnc, OffsetsSetFromThePositionAreTheNominalOnes) {
  require_rs274();
  const fs::path dir = test::fresh_dir("linuxcnc_offsets");
  const std::string in = test::source_path("tests/data/linuxcnc/offsets.ngc");
  const std::string out = (dir / "offsets.ngc").string();
  const std::string cmd =
      hsu_post_command("--work-offset 0,0,0 --initial-position 0,0,0 --clamp " + in + " -o " + out);
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const std::string canon_in = (dir / "in.canon").string(),
                    canon_out = (dir / "out.canon").string();
  ASSERT_EQ(std::system(test::rs274_command("-g " + in + " " + canon_in + " >/dev/null").c_str()),
            0);
  ASSERT_EQ(
      std::system(test::rs274_command("-g " + out + " " + canon_out + " >/dev/null 2>&1").c_str()),
      0);
  const auto before = offsets_of(canon_in), after = offsets_of(canon_out);
  ASSERT_EQ(before.size(), after.size());
  ASSERT_GE(before.size(), 8u);
  for (size_t k = 0; k < before.size(); ++k) {
    ASSERT_EQ(before[k].size(), after[k].size());
    for (size_t a = 0; a < before[k].size(); ++a)
      EXPECT_NEAR(after[k][a], before[k][a], 1.6e-4) << k;
  }
  // The G92 and G10 L20 lines themselves did change.
  const std::string text = test::file_bytes(out);
  EXPECT_EQ(text.find("G92 X0 Y0\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("G10 L20 P2 X0\n"), std::string::npos) << text;
}

}  // namespace
}  // namespace volmap
