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
#include "tests/support/cli_in_source.h"
#include "tests/support/rs274.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

namespace fs = std::filesystem;

bool have_rs274() { return std::system("command -v rs274 >/dev/null 2>&1") == 0; }

void require_rs274() {
  if (have_rs274()) return;
  if (std::getenv("VOLMAP_REQUIRE_RS274"))
    FAIL() << "rs274 (linuxcnc-uspace) is required but missing";
  GTEST_SKIP() << "rs274 not installed (apt-get install linuxcnc-uspace)";
}

struct Canon {
  double unit_mm = 1.0;           ///< rs274 prints 4 decimals in the program's unit
  std::vector<nc::Motion> feeds;  // nominal path, program units -> mm
  std::vector<std::pair<Eigen::Vector3d, bool>> points;  // every commanded end point, feed?
  bool ok = true;
  std::string errors;
};

// Runs rs274 on a program and reads its canonical calls.
Canon canonical(const std::string& program, const std::string& tool_table) {
  // Written under this test run's temporary folder, never beside the program
  // (LinuxCNC's own programs are in a system folder other runs share).
  static const fs::path dir = test::fresh_dir("canon");
  static int count = 0;
  const std::string out =
      (dir / (std::to_string(++count) + "-" + fs::path(program).filename().string() + ".canon"))
          .string();
  const std::string cmd = "cd " + fs::path(program).parent_path().string() + " && " +
                          test::rs274_command((tool_table.empty() ? "" : "-t " + tool_table + " ") +
                                              "-g " + program + " " + out) +
                          " >" + out + ".log 2>&1";
  Canon c;
  c.ok = std::system(cmd.c_str()) == 0;
  std::ifstream f(out);
  std::string line;
  double unit = 1.0;
  int plane = 0;
  Eigen::Vector3d pos = Eigen::Vector3d::Zero();
  auto numbers = [](const std::string& l) {
    std::vector<double> v;
    const size_t open = l.find('('), close = l.rfind(')');
    std::stringstream ss(l.substr(open + 1, close - open - 1));
    std::string tok;
    while (std::getline(ss, tok, ',')) v.push_back(std::strtod(tok.c_str(), nullptr));
    return v;
  };
  while (std::getline(f, line)) {
    if (line.find("USE_LENGTH_UNITS(CANON_UNITS_INCHES)") != std::string::npos)
      unit = c.unit_mm = 25.4;
    if (line.find("USE_LENGTH_UNITS(CANON_UNITS_MM)") != std::string::npos) unit = 1.0;
    if (line.find("SELECT_PLANE(CANON_PLANE_XY)") != std::string::npos) plane = 0;
    if (line.find("SELECT_PLANE(CANON_PLANE_XZ)") != std::string::npos) plane = 1;
    if (line.find("SELECT_PLANE(CANON_PLANE_YZ)") != std::string::npos) plane = 2;
    if (line.find("rror") != std::string::npos) c.errors += line + "\n";
    const bool traverse = line.find("STRAIGHT_TRAVERSE(") != std::string::npos;
    const bool feed = line.find("STRAIGHT_FEED(") != std::string::npos;
    if (traverse || feed) {
      const std::vector<double> v = numbers(line);
      const Eigen::Vector3d p(v[0] * unit, v[1] * unit, v[2] * unit);
      if (feed) {
        nc::Motion m;
        m.kind = nc::MotionKind::kLinear;
        m.start_mm = pos;
        m.end_mm = p;
        c.feeds.push_back(m);
      }
      c.points.push_back({p, feed});
      pos = p;
    }
    if (line.find("ARC_FEED(") != std::string::npos) {
      // ARC_FEED(first_end, second_end, first_centre, second_centre,
      //          rotation, axis_end, a, b, c); XY: first X; XZ (G18): first
      // Z, second X; YZ (G19): first Y, second Z.
      const std::vector<double> v = numbers(line);
      static constexpr int kFirst[3] = {0, 2, 1}, kSecond[3] = {1, 0, 2}, kAxis[3] = {2, 1, 0};
      nc::Motion m;
      m.kind = nc::MotionKind::kArc;
      m.start_mm = pos;
      m.end_mm[kFirst[plane]] = v[0] * unit;
      m.end_mm[kSecond[plane]] = v[1] * unit;
      m.end_mm[kAxis[plane]] = v[5] * unit;
      m.center_mm = pos;
      m.center_mm[kFirst[plane]] = v[2] * unit;
      m.center_mm[kSecond[plane]] = v[3] * unit;
      const int rotation = static_cast<int>(v[4]);
      m.clockwise = rotation < 0;
      m.extra_turns = std::abs(rotation) - 1;
      // volmap's planes: 0 XY (I J), 1 ZX (K I), 2 YZ (J K).
      m.plane = plane;
      c.feeds.push_back(m);
      // The commanded end of an arc; its interior is the controller's.
      c.points.push_back({m.end_mm, true});
      pos = m.end_mm;
    }
  }
  return c;
}

// `volmap post` on the sample three-axis machine with its errors, args after
// (work offset, input, -o output, ...), for std::system.
std::string hsu_post_command(const std::string& args) {
  return test::volmap_binary() + " post --machine " +
         test::source_path("samples/machines/hsu-3axis.json") + " --errors " +
         test::source_path("samples/errors/hsu-3axis.csv") + " " + args;
}

// The same tool table twice, for rs274 (which reads it in inches) and for
// volmap (mm): {inch file, mm file}, tools numbered from 1 with the offsets
// given in inches.
std::pair<std::string, std::string> tool_tables(const fs::path& dir,
                                                std::initializer_list<double> offsets_inch) {
  const std::string inch = (dir / "inch.tbl").string(), mm = (dir / "mm.tbl").string();
  std::ofstream fi(inch), fm(mm);
  int tool = 0;
  for (double z : offsets_inch) {
    ++tool;
    fi << fmt::format("T{0} P{0} Z{1} ;\n", tool, z);
    fm << fmt::format("T{0} P{0} Z{1} ;\n", tool, z * 25.4);
  }
  return {inch, mm};
}

struct Case {
  const char* program;
  const char* extra_args;
  const char* machine;  // sample name (machine and errors)
  double wo[3];         // work offset, mm
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
      {"tort.ngc", "", "hsu-3axis", {250, 200, 100}},
      {"arcspiral.ngc", "", "hsu-3axis", {250, 200, 100}},
      {"3dtest.ngc", "", "hsu-3axis", {250, 200, 100}},
      {"cds.ngc", "--tool-table", "hsu-3axis", {250, 200, 100}},
      {"hole-circle.ngc", "", "hsu-3axis", {250, 200, 100}},
      {"plasmatest.ngc", "--initial-position 0,0,0", "gantry-3axis", {100, 100, 100}},
      // volmap's own: every polar and canned-cycle rule
      // (G90/G91, L repeats, polar holes, restated cycles,
      // the initial G99) in one program each.
      {"tests/data/linuxcnc/polar.ngc", "", "hsu-3axis", {250, 200, 100}},
      {"tests/data/linuxcnc/cycles.ngc", "", "hsu-3axis", {250, 200, 100}},
      // Arcs kept as arcs: rs274 reads them, its arcs are ours.
      {"tests/data/linuxcnc/arcs.ngc", "--keep-arcs", "hsu-3axis", {150, 100, 200}},
      {"arcspiral.ngc", "--keep-arcs", "hsu-3axis", {250, 200, 100}},
      {"tort.ngc", "--keep-arcs", "hsu-3axis", {250, 200, 100}}};
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
    if (args == "--keep-arcs") {
      int written = 0, read = 0;
      std::istringstream lines(test::file_bytes(out));
      for (std::string l; std::getline(lines, l);)
        for (const nc::Word& w : nc::lex_block(l, 1, out).words)
          written += w.letter == 'G' && (w.code10 == 20 || w.code10 == 30) ? 1 : 0;
      for (const nc::Motion& mo : after.feeds) read += mo.kind == nc::MotionKind::kArc ? 1 : 0;
      EXPECT_GT(written, 5);
      EXPECT_EQ(read, written) << "rs274's arcs are the ones volmap wrote";
    }
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
    auto worst = [&](const Canon& run) {
      Eigen::Vector3d h = Eigen::Vector3d::Zero(), prev = Eigen::Vector3d::Zero();
      bool first = true;
      size_t cursor = 0;
      double max_um = 0;
      for (const auto& [p_prog, feed] : run.points) {
        const Eigen::Vector3d p = p_prog + wo;
        for (int a = 0; a < 3 && !first; ++a) {
          const double step = p[a] - prev[a];
          if (step == 0 || !c.bidirectional(a)) continue;
          const double w = c.play_width_mm(a, p);
          h[a] = w < 1e-9 ? (step > 0 ? 1 : -1) : std::clamp(h[a] + 2 * step / w, -1.0, 1.0);
        }
        first = false;
        prev = p;
        if (!feed) continue;
        const Eigen::Vector3d actual = p + c.error_with_play(p, h);
        double best = 1e9;
        size_t best_i = cursor;
        for (size_t i = cursor > 3 ? cursor - 3 : 0; i < std::min(nominal.size(), cursor + 6);
             ++i) {
          const double d = nc::distance_to_path(nominal[i], actual);
          if (d < best) {
            best = d;
            best_i = i;
          }
        }
        cursor = best_i;
        max_um = std::max(max_um, best * 1e3);
      }
      return max_um;
    };
    if (uses_tools) continue;  // tool-length levers: covered by post_test; here rs274 acceptance
    const double before_um = worst(before), after_um = worst(after);
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
      "G43.1 Z10\nG1 Y3 Z-5\nG90 G1 X10 Z0\nM2\n";
  const std::string in = (dir / "tlo.ngc").string(), out = (dir / "tlo-post.ngc").string();
  std::ofstream(in, std::ios::binary) << program;
  const Canon rs = canonical(in, tbl_inch);
  ASSERT_TRUE(rs.ok) << rs.errors;
  // By hand: 50 - 25.4 - 5 = 19.6; + 25.4 + 12.7 - 5 = 52.7; - 12.7 - 5 =
  // 35; - 10 - 5 = 20; then Z0.
  const double want[] = {19.6, 52.7, 35.0, 20.0, 0.0};
  ASSERT_EQ(rs.feeds.size(), 5u);
  for (size_t k = 0; k < 5; ++k)
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
  ASSERT_EQ(feeds_z.size(), 5u);
  for (size_t k = 0; k < 5; ++k) EXPECT_NEAR(feeds_z[k], want[k], 1e-9) << "volmap, feed " << k;
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
// turning.
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

// Random programs of the words volmap reads, as a fuzzer writes them (any
// order, words no code uses, arcs with stray centres, cycles without their
// words, zero and negative P Q L): volmap post refuses every program rs274
// refuses, with file:line, accepts those rs274 accepts except where it
// says a construct is not supported (or is a post-processing policy: a
// stop code beside a feed move), and rs274 accepts every program volmap
// writes. Found and fixed with it: words no code uses, K in a G17 arc, R
// with I J K, a lone G2, a peck depth Q of zero or less.
TEST(LinuxCnc, RandomProgramsAreAcceptedAndRefusedAsRs274Does) {
  require_rs274();
  const std::string tbl = "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/simpockets.tbl";
  const fs::path dir = test::fresh_dir("random");
  std::mt19937 rng(20261201);
  const auto chance = [&](double p) {
    return std::uniform_real_distribution<double>(0, 1)(rng) < p;
  };
  const auto pick = [&](std::initializer_list<const char*> v) {
    return std::string(v.begin()[std::uniform_int_distribution<size_t>(0, v.size() - 1)(rng)]);
  };
  const auto number = [&](double lo, double hi) {
    const int decimals = std::uniform_int_distribution<int>(0, 3)(rng);
    return fmt::format("{:.{}f}", std::uniform_real_distribution<double>(lo, hi)(rng), decimals);
  };
  double wild = 1.0;  // a program of stray words, or (0.1) one of mostly plain moves
  const auto block = [&] {
    std::vector<std::string> words;
    if (chance(0.35))
      words.push_back(pick({"G0", "G1", "G2", "G3", "G2", "G3", "G81", "G82", "G83", "G73", "G85",
                            "G89", "G80", "G86", "G1", "G0"}));
    if (chance(0.15 * wild))
      words.push_back(pick({"G90", "G91",    "G20", "G21", "G17",     "G18",   "G19",
                            "G98", "G99",    "G93", "G94", "G90.1",   "G91.1", "G54",
                            "G55", "G43 H1", "G49", "G53", "G4 P0.5", "G61",   "G64"}));
    for (const char* L : {"X", "Y", "Z"})
      if (chance(0.5)) words.push_back(L + number(-20, 20));
    if (chance(0.05 * wild)) words.push_back(pick({"@", "^"}) + number(-20, 20));
    for (const char* L : {"I", "J", "K", "R"})
      if (chance(0.25 * wild)) words.push_back(L + number(-10, 10));
    for (const auto& [L, lo, hi] :
         {std::tuple{"Q", -2.0, 5.0}, {"P", -1.0, 3.0}, {"L", -1.0, 4.0}, {"F", -10.0, 500.0}})
      if (chance(0.06 * wild)) words.push_back(L + number(lo, hi));
    if (chance(0.03 * wild)) words.push_back(pick({"M3 S1000", "M5", "M8", "M9", "M0", "M1"}));
    std::shuffle(words.begin(), words.end(), rng);
    std::string b;
    for (const std::string& w : words) b += (b.empty() ? "" : " ") + w;
    return b;
  };
  const std::string in = (dir / "random.ngc").string(), out = (dir / "random-post.ngc").string();
  int both = 0, refused = 0;
  for (int n = 0; n < 300; ++n) {
    wild = chance(0.5) ? 1.0 : 0.1;
    std::string program = "G21 G90 G17 F200\nG0 X0 Y0 Z30\n";
    for (int k = std::uniform_int_distribution<int>(1, 6)(rng); k > 0; --k)
      program += block() + "\n";
    program += "M2\n";
    std::ofstream(in, std::ios::binary) << program;
    const bool rs274_ok = canonical(in, tbl).ok;
    const std::string log = out + ".err";
    const std::string cmd = hsu_post_command("--work-offset 250,200,100 --clamp --tool-table " +
                                             tbl + " " + in + " -o " + out + " 2>" + log);
    fs::remove(out);
    const bool volmap_ok = std::system(cmd.c_str()) == 0;
    const std::string err = test::file_bytes(log);
    SCOPED_TRACE(program + "volmap: " + err);
    if (!rs274_ok) {
      EXPECT_FALSE(volmap_ok) << "rs274 refuses the program, volmap post read it";
      EXPECT_NE(err.find(in + ":"), std::string::npos);
      ++refused;
      continue;
    }
    if (!volmap_ok) {
      const bool by_design = err.find("not supported") != std::string::npos ||
                             err.find("stop code") != std::string::npos;
      EXPECT_TRUE(by_design) << "rs274 reads the program, volmap post refused it";
      continue;
    }
    ++both;
    EXPECT_TRUE(canonical(out, tbl).ok) << "rs274 refuses volmap's output";
  }
  // Both kinds were met many times (the test has teeth both ways).
  EXPECT_GT(both, 30);
  EXPECT_GT(refused, 100);
  std::printf("random programs: %d read by both, %d refused by rs274 (and volmap)\n", both,
              refused);
}

// Random programs that a CAM system could write (lines, arcs with exact
// centres in all three planes, canned cycles, G20/G21, G91, polar moves,
// G43/G49, G93), posted and run by rs274: rs274 and volmap accept the same
// ones, rs274 accepts every output, and the output passes through every
// point the input does (rs274's canonical end points, in order, within
// 0.05 mm: the correction is micrometres). Every other program is posted
// with --keep-arcs, and its output, run on the model by volmap verify,
// keeps the tolerance between the points too.
TEST(LinuxCnc, RandomCamProgramsPostedPassThroughTheSamePoints) {
  require_rs274();
  const fs::path dir = test::fresh_dir("cam");
  const auto [tbl_inch, tbl_mm] = tool_tables(dir, {1.0});
  std::mt19937 rng(20261202);
  const auto uniform = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  const auto chance = [&](double p) { return uniform(0, 1) < p; };
  const auto integer = [&](int lo, int hi) {
    return std::uniform_int_distribution<int>(lo, hi)(rng);
  };
  const auto program = [&] {
    std::string p = "G21 G90 G17 G94 F300\nG0 X10 Y10 Z20\n";
    double x = 10, y = 10, z = 20;  // mm
    bool inch = false, incremental = false;
    int plane = 0;                  // 0 XY, 1 XZ, 2 YZ
    double active_offset_mm = 0.0;  // tool length offset (G43 H1: 25.4 mm)
    for (int n = integer(3, 12); n > 0; --n) {
      const double k = uniform(0, 1), u = inch ? 25.4 : 1.0;
      const auto num = [&](double v) {
        return fmt::format("{:.{}f}", v, integer(0, 2) == 0 ? 1 : 4);
      };
      if (k < 0.25) {
        const double nx = x + uniform(-15, 15), ny = y + uniform(-15, 15), nz = z + uniform(-5, 5);
        if (incremental)
          p += "G1 X" + num((nx - x) / u) + " Y" + num((ny - y) / u) + " Z" + num((nz - z) / u) +
               "\n";
        else
          p += "G1 X" + num(nx / u) + " Y" + num(ny / u) + " Z" + num(nz / u) + "\n";
        x = nx, y = ny, z = nz;
      } else if (k < 0.30 && !incremental) {
        plane = integer(0, 2);
        p += plane == 0 ? "G17\n" : plane == 1 ? "G18\n" : "G19\n";
      } else if (k < 0.45 && !incremental) {
        // In-plane axes (a0, a1) and their centre words, as RS274NGC pairs them.
        static constexpr int kA0[3] = {0, 2, 1}, kA1[3] = {1, 0, 2};
        static constexpr char kW0[3] = {'I', 'K', 'J'}, kW1[3] = {'J', 'I', 'K'};
        double pos[3] = {x, y, z};
        const double r = uniform(2, 15), a0 = uniform(0, 2 * M_PI), sweep = uniform(0.3, 5);
        const double c0 = pos[kA0[plane]] - r * std::cos(a0),
                     c1 = pos[kA1[plane]] - r * std::sin(a0);
        const bool cw = chance(0.5);
        const double a1 = cw ? a0 - sweep : a0 + sweep;
        double end[3] = {x, y, z};
        end[kA0[plane]] = c0 + r * std::cos(a1);
        end[kA1[plane]] = c1 + r * std::sin(a1);
        if (chance(0.3)) end[3 - kA0[plane] - kA1[plane]] += uniform(-3, 3);
        p += fmt::format("{} X{:.4f} Y{:.4f} Z{:.4f} {}{:.4f} {}{:.4f}\n", cw ? "G2" : "G3",
                         end[0] / u, end[1] / u, end[2] / u, kW0[plane], (c0 - pos[kA0[plane]]) / u,
                         kW1[plane], (c1 - pos[kA1[plane]]) / u);
        x = end[0], y = end[1], z = end[2];
      } else if (k < 0.55 && !incremental && plane == 0) {
        static const char* kCycles[] = {"G81", "G82 P0.2", "G83 Q1.5",        "G73 Q0.7",
                                        "G85", "G89 P0.1", "M3 S900 G86 P0.3"};
        const double hz = z - uniform(3, 8), rz = z - uniform(0, 1), nx = x + uniform(-10, 10),
                     ny = y + uniform(-10, 10);
        p +=
            fmt::format("{} {} X{:.4f} Y{:.4f} Z{:.4f} R{:.4f}{}\nG80\nG0 Z{:.4f}\n",
                        chance(0.5) ? "G98" : "G99", kCycles[integer(0, 6)], nx / u, ny / u, hz / u,
                        rz / u, chance(0.2) ? fmt::format(" L{}", integer(2, 3)) : "", z / u);
        x = nx, y = ny;
      } else if (k < 0.62) {
        inch = !inch;
        p += inch ? "G20\n" : "G21\n";
      } else if (k < 0.68) {
        incremental = !incremental;
        p += incremental ? "G91\n" : "G90\n";
      } else if (k < 0.73 && !incremental) {
        x += uniform(-10, 10), y += uniform(-10, 10), z += uniform(0, 5);
        p += fmt::format("G0 X{:.4f} Y{:.4f} Z{:.4f}\n", x / u, y / u, z / u);
      } else if (k < 0.78 && !incremental && plane == 0) {
        const double radius = std::hypot(x, y) + uniform(-3, 3);
        const double angle = std::atan2(y, x) * 180 / M_PI + uniform(-20, 20);
        p += fmt::format("G1 @{:.4f} ^{:.4f}\n", radius / u, angle);
        x = radius * std::cos(angle * M_PI / 180), y = radius * std::sin(angle * M_PI / 180);
      } else if (k < 0.83) {
        static const char* kCodes[] = {"G43 H1", "G49",       "M3 S2000", "M8",
                                       "M9",     "G64 P0.01", "G61",      "G4 P0.2"};
        const std::string code = kCodes[integer(0, 7)];
        p += code + "\n";
        // The controlled point jumps by minus the change of offset (LinuxCNC).
        const double offset_mm = code == "G43 H1" ? 25.4 : code == "G49" ? 0.0 : active_offset_mm;
        z -= offset_mm - active_offset_mm;
        active_offset_mm = offset_mm;
      } else if (k < 0.88 && !incremental) {
        p += fmt::format("G93 G1 X{:.4f} Y{:.4f} F{:.2f}\nG94 F300\n", (x + 3) / u, (y - 2) / u,
                         uniform(5, 50));
        x += 3, y -= 2;
      } else {
        const double nx = x + uniform(-5, 5);
        p += fmt::format("X{:.4f}\n", incremental ? (nx - x) / u : nx / u);
        x = nx;
      }
    }
    return p + "M2\n";
  };
  const std::string in = (dir / "cam.ngc").string(), out = (dir / "cam-post.ngc").string();
  int both = 0, kept_arcs = 0;  // kept_arcs: outputs with arcs in them
  for (int n = 0; n < 150; ++n) {
    const std::string text = program();
    std::ofstream(in, std::ios::binary) << text;
    const Canon input = canonical(in, tbl_inch);
    const std::string log = out + ".err";
    fs::remove(out);
    // Every other program keeps its arcs as arcs (--keep-arcs).
    const std::string keep = n % 2 ? "--keep-arcs " : "";
    const bool volmap_ok =
        std::system(hsu_post_command("--work-offset 250,200,150 --clamp " + keep + "--tool-table " +
                                     tbl_mm + " " + in + " -o " + out + " 2>" + log)
                        .c_str()) == 0;
    const std::string err = test::file_bytes(log);
    SCOPED_TRACE(keep + text + "volmap: " + err);
    EXPECT_EQ(volmap_ok, input.ok);
    if (!input.ok || !volmap_ok) continue;
    ++both;
    const Canon posted = canonical(out, tbl_inch);
    ASSERT_TRUE(posted.ok) << "rs274 refuses volmap's output";
    for (const nc::Motion& mo : posted.feeds)
      if (mo.kind == nc::MotionKind::kArc) {
        ++kept_arcs;
        break;
      }
    size_t next = 0;
    for (const auto& [p, feed] : input.points) {
      while (next < posted.points.size() &&
             (posted.points[next].first - p).cwiseAbs().maxCoeff() >= 0.05)
        ++next;
      ASSERT_LT(next, posted.points.size()) << "the output never passes through " << p.transpose();
      ++next;
    }
    if (keep.empty()) continue;
    // Kept arcs pass through the same end points even when wrong (a full
    // circle instead of a sliver): the machine's path, sampled between the
    // points too, keeps the tolerance (1 um, plus the rounding of inch
    // numbers).
    const test::CliResult r = test::run_volmap_in_source(
        "verify --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
        "--work-offset 250,200,150 --clamp --tool-table " +
        tbl_mm + " --nominal " + in + " --program " + out + " --json");
    ASSERT_EQ(r.status, 0) << r.err;
    const double after_um = nlohmann::json::parse(r.out)["after"]["max_um"].get<double>();
    EXPECT_LT(after_um, 1.5) << r.out;
  }
  EXPECT_GT(both, 100);
  EXPECT_GT(kept_arcs, 20);
  std::printf(
      "random CAM programs: %d of 150 posted (every other with --keep-arcs: %d outputs with arcs "
      "kept) and run "
      "through the same points by rs274\n",
      both, kept_arcs);
}

}  // namespace
}  // namespace volmap
