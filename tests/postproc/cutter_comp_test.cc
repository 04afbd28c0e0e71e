// Cutter radius compensation kept (G41/G42): LinuxCNC's interpreter (rs274)
// computes the tool centre path of the input and of volmap's output; every
// commanded tool-centre point of the output, moved by the machine's error,
// lands within the tolerance of the input's tool-centre path. And what
// rs274 refuses under compensation, volmap refuses too.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "postproc/three_axis/corrector.h"
#include "tests/postproc/linuxcnc_canon.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

const fs::path& dir() {
  static const fs::path d = test::fresh_dir("cutter_comp");
  return d;
}

// Tools 1 (1/8 in, the real program's), 2 (10 mm) and 3 (-4 mm: the side swapped), in inches for
// rs274 and in mm for volmap.
std::pair<std::string, std::string> diameter_tables() {
  const std::string inch = (dir() / "d-inch.tbl").string(), mm = (dir() / "d-mm.tbl").string();
  std::ofstream fi(inch), fm(mm);
  int tool = 0;
  for (double d : {3.175, 10.0, -4.0}) {
    ++tool;
    fi << fmt::format("T{0} P{0} D{1:.9f} Z0 ;\n", tool, d / 25.4);
    fm << fmt::format("T{0} P{0} D{1} Z0 ;\n", tool, d);
  }
  fi << "T4 P4 D0.1 Z0 Q2 ; a lathe tool\n";
  fm << "T4 P4 D2.54 Z0 Q2 ; a lathe tool\n";
  return {inch, mm};
}

std::string write_program(const std::string& name, const std::string& text) {
  const std::string path = (dir() / name).string();
  std::ofstream(path) << text;
  return path;
}

// The options every run here shares: the sample machine at work offset
// 100,100,100 with `errors` (default: the sample's) and the mm tool table.
std::string sample_options(const std::string& mm_table, const std::string& errors = "") {
  return fmt::format("--machine {} --errors {} --work-offset 100,100,100 --tool-table {}",
                     test::source_path("samples/machines/hsu-3axis.json"),
                     errors.empty() ? test::source_path("samples/errors/hsu-3axis.csv") : errors,
                     mm_table);
}

struct Kept {
  const char* name;
  const char* text;
};

// Programs as shops write them: a pocket (inside corners, an arc), an
// outside profile (corners gone round on arcs, a convex arc), G41.1/G42.1
// with the diameter in the block, a negative diameter, a long side the
// post cuts into pieces, a Z move under compensation and an exit in Z.
const Kept kKept[] = {
    {"pocket-g41.ngc",
     "G21 G17 G90 G40 G49\nT1 M6\nG0 X-10 Y-10 Z5\nG1 Z-1 F300\nG41 D1 G1 X0 Y0\nG1 X50\n"
     "G3 X60 Y10 R10\nG1 Y40\nX0\nY0\nG40 G1 X-10 Y-10\nG0 Z5\nM2\n"},
    {"profile-g41-outside.ngc",
     "G21 G90\nT2 M6\nG0 X-20 Y-20 Z5\nG1 Z-2 F400\nG41 D2 X0 Y-5\nY40\nG2 X30 Y70 R30\n"
     "G1 X80\nY0\nX-5\nG40 X-20 Y-20\nG0 Z5\nM30\n"},
    {"profile-g42-1.ngc",
     "G21 G90\nG0 X100 Y-20 Z5\nG1 Z-1 F250\nG42.1 D8 X100 Y0\nX150\nG3 X170 Y20 I0 J20\n"
     "G1 Y60\nX100\nY0\nG40 G0 Z5\nG0 X100 Y-20\nM2\n"},
    {"negative-diameter.ngc",
     "G21 G90\nT3 M6\nG0 X-10 Y0 Z3\nG1 Z-1 F200\nG42 D3 X0 Y0\nX40 Y5\nX60 Y30\nG1 Z-1.5\n"
     "X20 Y50\nG0 Z2\nX0 Y0\nG1 Z-1\nX10 Y-5\nG40 X-10 Y0\nG0 Z3\nM2\n"},
    {"g10-l1-radius.ngc",
     "G21 G90\nG10 L1 P2 R2.5 Z0\nT2 M6\nG0 X-10 Y-10 Z3\nG1 Z-1 F300\nG41 D2 X0 Y0\n"
     "X30\nG2 X40 Y-10 R10\nG1 X60\nG40 X70 Y-20\nG0 Z3\nM2\n"},
    {"long-sides.ngc",
     "G21 G90\nT1 M6\nG0 X0 Y-10 Z5\nG1 Z0 F500\nG41 D1 X0 Y0\nX250 Y3\nY180\nX0 Y176\nY0\n"
     "G40 G1 X0 Y-10\nM2\n"},
};

TEST(CutterCompensation, KeptCompensationPutsTheToolCentreWithinToleranceAsRs274Offsets) {
  require_rs274();
  const auto [inch, mm] = diameter_tables();
  const std::string machine = test::source_path("samples/machines/hsu-3axis.json");
  const Machine m = load_machine_json(machine);
  const std::string errors = errors_without_lost_motion(dir());
  const ErrorSet e = load_errors_csv(errors);
  const post::Corrector c(m, e, m.tool_length_mm, OutsidePolicy::kError);
  const Eigen::Vector3d wo(100, 100, 100);
  constexpr double kToleranceUm = 40;
  std::vector<Kept> programs(std::begin(kKept), std::end(kKept));
  // A real program: Ed Nisley's door latch cam (tests/data/real, SOURCES.md),
  // G42 D1 with Z steps under compensation, O-word loops (written flat).
  const std::string nisley =
      test::source_path("tests/data/real/nc/linuxcnc-nisley-door-latch-cam.ngc");
  programs.push_back({"nisley", nullptr});
  for (const Kept& k : programs) {
    SCOPED_TRACE(k.name);
    const std::string in = k.text ? write_program(k.name, k.text) : nisley;
    const std::string out = (dir() / (std::string("post-") + k.name)).string();
    const std::string cmd =
        test::volmap_binary() + fmt::format(" post {} --tolerance-um {} {} -o {} 2>{}.log",
                                            sample_options(mm, errors), kToleranceUm, in, out, out);
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd << "\n" << test::file_bytes(out + ".log");
    // The codes are kept, and stderr says so with the bound.
    EXPECT_NE(test::file_bytes(out + ".log").find("cutter compensation (G41/G42) kept over"),
              std::string::npos);
    // The codes are kept: the controller offsets the corrected contour.
    const std::string written = test::file_bytes(out);
    EXPECT_NE(written.find("G4"), std::string::npos);
    const Canon before = canonical(in, inch), after = canonical(out, inch);
    ASSERT_TRUE(before.ok) << before.errors;
    ASSERT_TRUE(after.ok) << after.errors;
    std::vector<nc::Motion> nominal = before.feeds;
    for (nc::Motion& mo : nominal) {
      mo.start_mm += wo;
      mo.end_mm += wo;
      mo.center_mm += wo;
    }
    const double before_um = worst_deviation_um(before, nominal, c, wo);
    const double after_um = worst_deviation_um(after, nominal, c, wo);
    EXPECT_GT(before_um, 10.0);  // the errors matter
    // rs274 prints 4 decimals (0.05 um each way, in space 0.09 um).
    EXPECT_LT(after_um, kToleranceUm + 0.1);
    std::printf("%s: tool centre off the nominal one: before %.2f um, after %.2f um\n", k.name,
                before_um, after_um);
    // verify reads both, measures the programmed contours and says so.
    const test::CliResult v =
        test::run_volmap(fmt::format("verify {} --nominal {} --program {} --tolerance-um {} --json",
                                     sample_options(mm, errors), in, out, kToleranceUm));
    EXPECT_EQ(v.status, 0) << v.err;
    EXPECT_NE(v.err.find("keep cutter compensation"), std::string::npos) << v.err;
    const nlohmann::json doc = nlohmann::json::parse(v.out);
    EXPECT_GT(doc.at("cutter_compensation_radius_mm").get<double>(), 1.58);
  }
}

TEST(CutterCompensation, AZeroErrorMachineGetsTheProgramBackByteForByte) {
  const auto [inch, mm] = diameter_tables();
  const std::string zero = write_program("zero.csv", "# machine: hsu-3axis\n");
  for (const Kept& k : kKept) {
    const std::string in = write_program(k.name, k.text);
    const std::string out = (dir() / (std::string("zero-") + k.name)).string();
    const test::CliResult r =
        test::run_volmap(fmt::format("post {} {} -o {}", sample_options(mm, zero), in, out));
    ASSERT_EQ(r.status, 0) << k.name << ": " << r.err;
    EXPECT_EQ(test::file_bytes(out), k.text) << k.name;
  }
}

struct Refused {
  const char* body;     ///< after a setup that loads tool 1 and stands at X-10 Y-10 Z-1
  bool rs274_refuses;   ///< LinuxCNC's interpreter refuses it too
  const char* message;  ///< in volmap's message
};

const Refused kRefused[] = {
    {"G41 D1 X-9 Y-9\nX10\nG40 X-20\n", true, "entry move is not greater than the tool radius"},
    {"G41 D1 G1 Z-2\nX10 Y10\nG40 X-20\n", true, "entry move is not greater than the tool radius"},
    {"G41 D1 X0 Y0\nG42 D1 X10\nG40 X-20\n", true, "cutter compensation is on already"},
    {"G1 X0 D1\n", true, "D word with no G41"},
    {"G41 D1.5 X0 Y0\nG40 X-20\n", true, "whole number"},
    {"G41 D7 X0 Y0\nG40 X-20\n", true, "tool 7"},
    {"G41 D1 X0 Y0\nG81 X10 Y10 Z-3 R1\nG80\nG40 X-20\n", true, "a canned cycle"},
    {"G41 D1 X0 Y0\nG28\nG40 X-20\n", true, "G28/G30"},
    {"G41 D1 X0 Y0\nT2 M6\nG40 X-20\n", true, "a tool change (M6)"},
    {"G41 D1 X0 Y0\nG55\nG40 X-20\n", true, "coordinate system"},
    {"G41 D1 X0 Y0\nG43 H1\nG40 X-20\n", true, "tool length offset"},
    {"G41 D1 X0 Y0\nG18\nG40 X-20\n", true, "a change of plane"},
    {"G41 D1 X0 Y0\nX10\nG40\nG2 X20 Y0 R5\n", true, "must be straight"},
    {"G41 D1 X0 Y0\nX10\nG3 X11.5 Y1.5 R1.5\nG40 X-20\n", true, "not less than arc radius"},
    {"G41 D1 X0 Y0\nG92 X0\nG40 X-20\n", true, "a change of offsets"},
    {"G41 D1 X0 Y0\nX10\nG40\nG42 D1\nG2 X20 Y-10 J-10\nG40 G1 X40\n", true, "must be straight"},
    {"G41 D1 X0 Y0\nX10\nG40\nG81 X20 Y0 Z-3 R1\nG80\nG2 X30 Y-10 J-10\n", true,
     "must be straight"},
    {"M3 S500\nG41 D1 X0 Y0\nX10\nG33.1 Z-5 K1\nG40 X-20\n", true,
     "G33.1 while cutter compensation is on"},
    {"G41 D4 X0 Y0\nG40 X-20\n", true, "lathe tool"},
    {"G41 D1 X0 Y0\nX10\nY3\nX0\nG40 X-20\n", true, "cannot be reached by the tool"},
    // volmap's own: M70-M73 (their restore is not followed), a tap as the
    // exit (LinuxCNC taps across from the offset point), an arc as the
    // entry on a machine with errors (its construction is not bounded).
    {"M70\nG41 D1 X0 Y0\nX10\nG40 X-20\nM72\n", false, "M70-M73"},
    {"M3 S500\nG41 D1 X0 Y0\nX10\nG40\nG33.1 X10 Y0 Z-5 K1\nG1 X-20\n", false,
     "a rigid tap (G33.1) as the move after G40"},
    {"G41 D1 G2 X10 Y-20 R15\nG40 G1 X-20\n", false, "an arc as the entry move"},
    // A side that leaves the 1/8 in cutter 0.1 um to spare: the correction
    // could make LinuxCNC refuse the output.
    {"G41 D1 X0 Y0\nX10\nY3.1751\nX0\nG40 X-20\n", false, "to spare"},
    // volmap's own: another plane, and a program whose kept compensation
    // would leave the tolerance (1 um here, default).
    {"G18\nG41 D1 X0 Z0\nG40 X-20\n", false, "XY plane (G17) only"},
};

TEST(CutterCompensation, WhatRs274RefusesUnderCompensationVolmapRefusesWithFileLine) {
  require_rs274();
  const auto [inch, mm] = diameter_tables();
  int n = 0;
  for (const Refused& k : kRefused) {
    SCOPED_TRACE(k.body);
    const std::string name = fmt::format("refused-{}.ngc", ++n);
    const std::string in = write_program(
        name, std::string("G21 G17 G90\nT1 M6\nG0 X-10 Y-10 Z5\nG1 Z-1 F300\n") + k.body + "M2\n");
    const std::string out = (dir() / ("out-" + name)).string();
    const test::CliResult r = test::run_volmap(
        fmt::format("post {} --tolerance-um 40 {} -o {}", sample_options(mm), in, out));
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find(name + ":"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(k.message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
    const Canon run = canonical(in, inch);
    EXPECT_EQ(!run.ok, k.rs274_refuses) << run.errors;
  }
}

TEST(CutterCompensation, ABoundAboveAQuarterOfTheToleranceIsRefusedWithItsNumbers) {
  const auto [inch, mm] = diameter_tables();
  const std::string in = write_program("bound.ngc", kKept[0].text);
  const std::string out = (dir() / "bound-out.ngc").string();
  const test::CliResult r =
      test::run_volmap(fmt::format("post {} {} -o {}", sample_options(mm), in, out));
  EXPECT_EQ(r.status, 1);
  // The entry (line 5): radius 1.5875 mm, g = 2 (LinuxCNC ends it at the
  // end's offset square to the move), and the sample's slope bound.
  const Machine m = load_machine_json(test::source_path("samples/machines/hsu-3axis.json"));
  const ErrorSet e = load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv"));
  const post::Corrector c(m, e, m.tool_length_mm, OutsidePolicy::kError);
  const double radius = 3.175 / 2;
  const double bound_um = 2 * radius * c.lipschitz_bound() * 1e3;
  EXPECT_NE(r.err.find("bound.ngc:5: the entry move of cutter compensation"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(fmt::format("up to {:.3g} µm off", bound_um)), std::string::npos) << r.err;
  EXPECT_NE(
      r.err.find(fmt::format("--tolerance-um {:g} or more", std::ceil(bound_um * 4 * 100) / 100)),
      std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// #5403 and #5410 are the loaded tool's table Z and diameter, whatever G43
// applies (rs274 printed 0.5 and 0.1 for T1 of an inch table after
// `G43 H2`); G10 L1 changes them; before any M6 they are the machine's.
TEST(CutterCompensation, ToolTableParametersAreTheLoadedToolsRow) {
  const auto [inch, mm] = diameter_tables();  // T1: D 3.175 Z0; T2: D 10 Z0
  const std::string in =
      write_program("params.ngc",
                    "G21 G90\nT1 M6\nG0 X#5403 Y#5410 Z10\nG43 H2\nG0 X#5410\nG10 L1 P1 Z4 R2\n"
                    "G0 X#5403 Y#5410\nM2\n");
  const std::string out = (dir() / "params-out.ngc").string();
  const std::string args = "post " + sample_options(mm) + " ";
  const test::CliResult r = test::run_volmap(args + in + " -o " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  // Written flat: the values, moved by the correction (some µm).
  std::istringstream lines(test::file_bytes(out));
  std::vector<std::pair<double, double>> xy;
  for (std::string l; std::getline(lines, l);)
    if (l.rfind("G0 X", 0) == 0)
      xy.emplace_back(std::strtod(l.c_str() + 4, nullptr),
                      l.find('Y') == std::string::npos
                          ? 0.0
                          : std::strtod(l.c_str() + l.find('Y') + 1, nullptr));
  ASSERT_EQ(xy.size(), 3u) << test::file_bytes(out);
  EXPECT_NEAR(xy[0].first, 0.0, 0.05);
  EXPECT_NEAR(xy[0].second, 3.175, 0.05);
  EXPECT_NEAR(xy[1].first, 3.175, 0.05);
  EXPECT_NEAR(xy[2].first, 4.0, 0.05);
  EXPECT_NEAR(xy[2].second, 4.0, 0.05);
  const std::string early = write_program("params-early.ngc", "G21 G90\nG0 X#5403 Y0 Z10\nM2\n");
  const test::CliResult e = test::run_volmap(args + early + " -o " + out + "-early");
  EXPECT_EQ(e.status, 1);
  EXPECT_NE(e.err.find("params-early.ngc:2"), std::string::npos) << e.err;
  EXPECT_NE(e.err.find("#5403 before any M6"), std::string::npos) << e.err;
}

// verify compares programmed contours: a compensated program whose G41/G42
// or tool differs from the nominal one's is refused, not measured.
TEST(CutterCompensation, VerifyRefusesProgramsWhoseCompensationDiffers) {
  const auto [inch, mm] = diameter_tables();
  const std::string in = write_program("verify-in.ngc", kKept[0].text);
  std::string edited = kKept[0].text;
  edited.replace(edited.find("G41 D1"), 6, "G42 D1");
  const std::string other = write_program("verify-other.ngc", edited);
  const test::CliResult v = test::run_volmap(
      fmt::format("verify {} --nominal {} --program {}", sample_options(mm), in, other));
  EXPECT_EQ(v.status, 1);
  EXPECT_NE(v.err.find("verify-other.ngc:5: cutter compensation G42 with radius 1.5875 mm (line "
                       "5) differs from the nominal program's (G41 with radius 1.5875 mm"),
            std::string::npos)
      << v.err;
}

TEST(CutterCompensation, LostMotionTakenUpUnderCompensationIsRefused) {
  // The sample's X reverses with play: at the arc after Y40 (line 7) the
  // post would write a take-up step, a corner for the controller.
  const auto [inch, mm] = diameter_tables();
  const std::string in = write_program("play.ngc", kKept[1].text);
  const std::string out = (dir() / "play-out.ngc").string();
  const test::CliResult r = test::run_volmap(
      fmt::format("post {} --tolerance-um 40 {} -o {}", sample_options(mm), in, out));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("play.ngc:7: an axis with lost motion turns round here under cutter "
                       "compensation"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace volmap
