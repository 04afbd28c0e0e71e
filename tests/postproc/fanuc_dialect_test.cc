// The Fanuc / Haas dialect (docs/post.md, "Dialects"). rs274 cannot read a
// Fanuc program, so each macro program of tests/data/fanuc has beside it
// its translation into LinuxCNC's language, written by hand from Fanuc's
// Series 0i-MF operator's manual (B-64604EN, "Custom macro"), with the
// values the manual's rules give where the two languages differ (FIX and
// FUP of negatives, vacant variables): volmap's reading of the Fanuc
// program must reach the points rs274 reaches running the translation.
// Then each is posted with the sample machine's errors and verified.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "gcode/nc_interpreter.h"
#include "gcode/program_reader.h"
#include "postproc/three_axis/post_program.h"
#include "postproc/verify/verify.h"
#include "tests/postproc/linuxcnc_canon.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/cli_run.h"
#include "tests/support/nc_read.h"
#include "tests/support/samples.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

const fs::path kDir = test::source_path("tests/data/fanuc");
const char* const kPrograms[] = {"bolt-circle-goto", "while-do-nested", "g65-macro-arguments",
                                 "m98-count-in-p", "functions-vacant"};

// Consecutive equal points once (rs274 prints a move that goes nowhere,
// volmap's interpreter hands it out too; neither changes the path).
std::vector<Eigen::Vector3d> distinct(const std::vector<Eigen::Vector3d>& p) {
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& x : p)
    if (out.empty() || (out.back() - x).norm() > 1e-4) out.push_back(x);
  return out;
}

// The end of every motion as volmap reads the program (its dialect
// detected), program coordinates.
std::vector<Eigen::Vector3d> volmap_points(const fs::path& program) {
  std::ifstream in(program, std::ios::binary);
  const test::NcReading r = test::read_nc(in, program.string(), {}, {kDir.string()});
  EXPECT_EQ(r.report.dialect.dialect, nc::Dialect::kFanuc);
  std::vector<Eigen::Vector3d> ends;
  for (const nc::BlockEffect& fx : r.moves) ends.push_back(fx.motion.end_mm);
  return ends;
}

TEST(FanucDialect, MacroProgramsReachWhatRs274ReachesRunningTheirTranslations) {
  require_rs274();
  for (const char* name : kPrograms) {
    SCOPED_TRACE(name);
    const Canon c = canonical((kDir / (std::string(name) + ".ngc")).string(), "");
    ASSERT_TRUE(c.ok && c.errors.empty()) << c.errors;
    std::vector<Eigen::Vector3d> expected;
    for (const auto& [point, feed] : c.points) expected.push_back(point);
    expected = distinct(expected);
    const std::vector<Eigen::Vector3d> got =
        distinct(volmap_points(kDir / (std::string(name) + ".nc")));
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t k = 0; k < got.size(); ++k)
      EXPECT_LT((got[k] - expected[k]).norm(), 1.5e-4)
          << "point " << k << ": " << got[k].transpose() << " vs " << expected[k].transpose();
  }
}

TEST(FanucDialect, MacroProgramsArePostedFlatAndVerifyWithinTolerance) {
  const Machine m = test::sample_machine("hsu-3axis");
  const ErrorSet e = test::sample_errors("hsu-3axis");
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(100, 100, 100);
  for (const char* name : kPrograms) {
    SCOPED_TRACE(name);
    const std::string program = test::file_bytes(kDir / (std::string(name) + ".nc"));
    std::istringstream in(program);
    std::ostringstream out;
    post::PostOptions o;
    o.subroutine_path = {kDir.string()};
    const post::PostReport r = post::post_program(in, name, out, m, e, s, o);
    EXPECT_EQ(r.read.dialect.dialect, nc::Dialect::kFanuc);
    EXPECT_GT(r.read.flattened_from, 0);
    // Flat: no macro statement, no call left; every number written with
    // its point.
    const std::string posted = out.str();
    std::string words;  // without the comments
    for (std::size_t k = 0, depth = 0; k < posted.size(); ++k) {
      depth += posted[k] == '(';
      if (depth == 0) words += posted[k];
      depth -= depth > 0 && posted[k] == ')';
    }
    for (const char* gone : {"#", "GOTO", "WHILE", "M98", "G65", "M99"})
      EXPECT_EQ(words.find(gone), std::string::npos) << gone << " in\n" << posted;
    std::istringstream nominal(program), compensated(posted);
    const post::VerifyResult v =
        post::verify_programs(nominal, name, compensated, "posted.nc", m, e, s, {});
    EXPECT_GT(v.before.max_um, 5.0);
    EXPECT_LT(v.after.max_um, 1.0) << "worst at line " << v.after.worst_line << "\n" << posted;
  }
}

// A correction that lands on a whole number: "X10" on a Fanuc control is
// 0.010 mm (without parameter 3401#0), so the post writes "X10.".
TEST(FanucDialect, ANumberThePostWritesKeepsItsDecimalPoint) {
  std::istringstream csv("X,EXX,EYX,EZX\n0,500,0,0\n500,500,0,0\n");  // X 0.5 mm long
  const ErrorSet e = read_errors_csv(csv, "const.csv");
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(100, 100, 100);
  auto posted = [&](nc::Dialect d) {
    s.dialect = d;
    std::istringstream in("O0001\nG21 G90\nG00 X10.5 Y20. Z30.\nG01 X20.5 F100.\nM30\n");
    std::ostringstream out;
    post::post_program(in, "c.nc", out, test::sample_machine("hsu-3axis"), e, s, {});
    return out.str();
  };
  EXPECT_EQ(posted(nc::Dialect::kAuto),
            "O0001\nG21 G90\nG00 X10. Y20. Z30.\nG01 X20. F100.\nM30\n");
  EXPECT_EQ(posted(nc::Dialect::kLinuxCnc),
            "O0001\nG21 G90\nG00 X10 Y20. Z30.\nG01 X20 F100.\nM30\n");
}

// K repeats come out as one block per hole, like L: a K left in the first
// block would drill its repeats again (the review of session 22 found it).
TEST(FanucDialect, KRepeatsAreWrittenOutAsLRepeatsAre) {
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(100, 100, 100);
  std::istringstream in(
      "O1000\nG90 G17 G21 G99\nG00 X0. Y0. Z5.\nG91 G81 X10. Y0. Z-3. R-2. K3 F100.\nG80\nM30\n");
  std::ostringstream out;
  post::post_program(in, "k.nc", out, test::sample_machine("hsu-3axis"),
                     test::sample_errors("hsu-3axis"), s, {});
  const std::string posted = out.str();
  EXPECT_EQ(posted.find('K'), std::string::npos) << posted;
  std::istringstream again(posted);
  const test::NcReading r = test::read_nc(again, "posted.nc", s);
  int holes = 0;
  for (const nc::BlockEffect& fx : r.moves)
    holes +=
        fx.motion.kind == nc::MotionKind::kCycle ? 1 + static_cast<int>(fx.more_holes.size()) : 0;
  EXPECT_EQ(holes, 3) << posted;
}

// A Fanuc number as CAM posts write it: "-.27", "12.", "173.913".
std::string fanuc_number(double v) {
  std::string t = fmt::format("{:.3f}", v);
  while (t.back() == '0') t.pop_back();
  if (t.rfind("0.", 0) == 0) t.erase(0, 1);
  if (t.rfind("-0.", 0) == 0) t.erase(1, 1);
  return t == "-." || t == "." ? "0." : t;
}

// Issue 35's crash (`volmap: basic_string::_M_create`, exit 1): a Fanuc
// program whose output passes the post's 64 KiB buffer. The buffer was
// flushed inside a line that changed, and the decimal-point pass then
// read the line's output from where it began (a size that wrapped).
TEST(FanucDialect, AProgramLongerThanTheOutputBufferIsPosted) {
  std::string program = "%\nO0042 (ARCS)\nN10 G90 G17 G21 G40 G80\nN20 G00 X-20. Y-30. Z5.\n";
  program += "N30 G01 Z-1. F100.\n";
  int n = 40;
  double x = -20.0;
  for (int row = 0; row < 60; ++row) {
    const double y = -30.0 + row, dir = row % 2 ? -1.0 : 1.0;
    for (int k = 0; k < 37; ++k, n += 10) {
      x += dir * 1.08;  // half circles of radius .54, "I.54 J0" or "I-.54 J0"
      program += fmt::format("N{} G0{} X{} Y{} I{} J0 F173.913\n", n, k % 2 ? 2 : 3,
                             fanuc_number(x), fanuc_number(y), fanuc_number(dir * .54));
    }
    program += fmt::format("N{} G01 Y{}\n", n, fanuc_number(y + 1));
    n += 10;
  }
  program += fmt::format("N{} G00 Z5.\nN{} M30\n%\n", n, n + 10);
  ASSERT_GT(program.size(), std::size_t{1} << 16);
  const Machine m = test::sample_machine("hsu-3axis");
  const ErrorSet e = test::sample_errors("hsu-3axis");
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(250, 200, 100);
  s.dialect = nc::Dialect::kFanuc;
  auto posted = [&](std::size_t recorded) {
    std::istringstream in(program);
    std::ostringstream out;
    post::PostOptions o;
    o.max_recorded_changes = recorded;
    const post::PostReport r = post::post_program(in, "arcs.nc", out, m, e, s, o);
    EXPECT_GT(r.lines_changed, r.lines / 2);
    return out.str();
  };
  std::string plain;
  ASSERT_NO_THROW(plain = posted(0));
  // The same bytes as when every line is recorded for --report (that kept
  // each line's output in the buffer and never crashed).
  EXPECT_EQ(plain, posted(100000));
  std::istringstream nominal(program), compensated(plain);
  const post::VerifyResult v =
      post::verify_programs(nominal, "arcs.nc", compensated, "posted.nc", m, e, s, {});
  EXPECT_GT(v.before.max_um, 5.0);
  EXPECT_LT(v.after.max_um, 1.0) << "worst at line " << v.after.worst_line;
}

TEST(FanucDialect, TheChoiceIsSaidOnStderrAndCanBeGiven) {
  const std::string machine = test::source_path("samples/machines/hsu-3axis.json");
  const std::string errors = test::source_path("samples/errors/hsu-3axis.csv");
  const fs::path dir = test::fresh_dir("fanuc_cli");
  const std::string fanuc = (dir / "f.nc").string(), out = (dir / "o.nc").string();
  std::ofstream(fanuc) << "%\nO0010 (PART)\nG90 G21 G00 X10. Y10. Z10.\nG01 X20. F100.\nM30\n%\n";
  const std::string base = "post --machine " + machine + " --errors " + errors +
                           " --work-offset 100,100,100 " + fanuc + " -o " + out;
  test::CliResult r = test::run_volmap(base);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("read as Fanuc/Haas (--dialect auto: program number O0010 at line 2)"),
            std::string::npos)
      << r.err;
  // Given, it is not detected (and not said).
  r = test::run_volmap(base + " --dialect fanuc");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err.find("--dialect auto"), std::string::npos) << r.err;
  // LinuxCNC reads the same program: O0010 is a label there.
  r = test::run_volmap(base + " --dialect linuxcnc");
  EXPECT_EQ(r.status, 0) << r.err;
  // A LinuxCNC program: said so, with the way to the other.
  const std::string ngc = (dir / "l.ngc").string();
  std::ofstream(ngc) << "G90 G21 G00 X10 Y10 Z10\nG01 X20 F100\nM30\n";
  r = test::run_volmap("post --machine " + machine + " --errors " + errors +
                       " --work-offset 100,100,100 " + ngc + " -o " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("read as LinuxCNC (--dialect auto: no Fanuc program number"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("give --dialect fanuc"), std::string::npos);
  r = test::run_volmap(base + " --dialect iso");
  EXPECT_NE(r.status, 0);
}

}  // namespace
}  // namespace volmap
