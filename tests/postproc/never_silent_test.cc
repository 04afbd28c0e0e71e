// Issue 35's classes of silently wrong output, each as rs274 (LinuxCNC's
// interpreter) judges it: the tape frame read as LinuxCNC reads it (no
// leader, '%' only where it opens or closes the program), programs that
// move nothing refused, and G91 polar increments taken from where the
// controller really stands (the corrected position), not the nominal one.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "core/common/input_error.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "postproc/three_axis/corrector.h"
#include "postproc/three_axis/post_program.h"
#include "tests/postproc/linuxcnc_canon.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

Machine hsu() { return load_machine_json(test::source_path("samples/machines/hsu-3axis.json")); }
const ErrorSet& hsu_errors() {
  static const ErrorSet e = load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv"));
  return e;
}

nc::ProgramSetup placed(nc::Dialect dialect = nc::Dialect::kAuto) {
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(250, 200, 100);
  s.dialect = dialect;
  return s;
}

std::string post(const std::string& program, nc::Dialect dialect = nc::Dialect::kAuto) {
  std::istringstream in(program);
  std::ostringstream out;
  post::PostOptions o;
  o.tolerance_mm = 1e-3;
  post::post_program(in, "prog.ngc", out, hsu(), hsu_errors(), placed(dialect), o);
  return out.str();
}

// The refusal's message ("" if the program posts), with its line.
std::string refusal(const std::string& program, int* line = nullptr,
                    nc::Dialect dialect = nc::Dialect::kAuto) {
  try {
    post(program, dialect);
  } catch (const InputError& e) {
    if (line) *line = e.line();
    return e.what();
  }
  return "";
}

// rs274's verdict on a program text: its canonical calls, and what it
// printed (errors go to its standard output, beside the calls' file).
struct Verdict {
  Canon canon;
  std::string said;
};
Verdict rs274_on(const std::string& text, const std::string& name) {
  static const fs::path dir = test::fresh_dir("never_silent");
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  const std::string log = path + ".said";
  const std::string cmd =
      test::rs274_command("-g " + path + " " + path + ".canon") + " >" + log + " 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()) >= 0, true);
  std::ifstream f(log);
  std::stringstream ss;
  ss << f.rdbuf();
  return {canonical(path, ""), ss.str()};
}

// The feeds of a run in machine coordinates (rs274 prints program ones).
std::vector<nc::Motion> placed_feeds(const Canon& c) {
  std::vector<nc::Motion> out = c.feeds;
  const Eigen::Vector3d wo = placed().work_offset_mm[0];
  for (nc::Motion& m : out) {
    m.start_mm += wo;
    m.end_mm += wo;
    m.center_mm += wo;
  }
  return out;
}

// Class 1: no opening '%', a '%' line at the end. rs274 refuses it where no
// M2/M30 ends the program before; volmap took everything before it as
// tape leader and wrote the program back uncorrected.
TEST(NeverSilent, PercentAfterTheProgramBeganIsRefusedAsRs274RefusesIt) {
  const std::string p = "G21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\nG1 Y20\n%\n";
  int line = 0;
  EXPECT_NE(refusal(p, &line).find("'%' after the program began"), std::string::npos);
  EXPECT_EQ(line, 5);
  // With M2 before it, rs274 stops at M2 and never reads the '%': posted,
  // every move corrected.
  const std::string ended = "G21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\nG1 Y20\nM2\n%\n";
  EXPECT_EQ(refusal(ended), "");
  EXPECT_NE(post(ended), ended);
  require_rs274();
  EXPECT_NE(rs274_on(p, "class1.ngc").said.find("Bad character '%' used"), std::string::npos);
  EXPECT_EQ(rs274_on(ended, "class1-ended.ngc").said.find("used"), std::string::npos);
}

// Class 4: text before the opening '%' (a version-control conflict
// marker). rs274 reads it as a block and refuses it; volmap took it as
// tape leader and posted the program after it.
TEST(NeverSilent, TextBeforeTheOpeningPercentIsRefusedInLinuxCnc) {
  const std::string p = "<<<<<<< HEAD\n%\nG21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\nM2\n%\n";
  int line = 0;
  EXPECT_NE(refusal(p, &line), "");
  EXPECT_EQ(line, 1);
  // A comment before it: run by rs274, then the '%' refused.
  const std::string commented = "(leader)\n%\nG21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\nM2\n%\n";
  EXPECT_NE(refusal(commented, &line).find("'%' after the program began"), std::string::npos);
  EXPECT_EQ(line, 2);
  // Blank lines before it are no text: rs274 opens the program there.
  const std::string blank = "\n  \n%\nG21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\n%\n";
  EXPECT_EQ(refusal(blank), "");
  // A Fanuc tape's leader is skipped by the control (label skip): kept.
  const std::string fanuc = "LEADER\n%\nO1000\nG21 G90\nG0 X10. Y10. Z10.\nG1 X20. F100.\nM30\n%\n";
  EXPECT_EQ(refusal(fanuc, nullptr, nc::Dialect::kFanuc), "");
  require_rs274();
  EXPECT_NE(rs274_on(p, "class4.ngc").said.find("Bad character '<' used"), std::string::npos);
  EXPECT_NE(rs274_on(commented, "class4-comment.ngc").said.find("Bad character '%' used"),
            std::string::npos);
  EXPECT_EQ(rs274_on(blank, "class4-blank.ngc").said.find("used"), std::string::npos);
}

// LinuxCNC's other '%' rules: text after it, and a program opened by '%'
// that neither closes nor ends.
TEST(NeverSilent, PercentLinesFollowLinuxCncsRules) {
  const std::string after = "% (start)\nG21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\n%\n";
  int line = 0;
  EXPECT_NE(refusal(after, &line).find("'%' with text after it"), std::string::npos);
  EXPECT_EQ(line, 1);
  const std::string open = "%\nG21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\n";
  EXPECT_NE(refusal(open, &line).find("without a closing '%'"), std::string::npos);
  EXPECT_EQ(refusal(open + "M2\n"), "");
  // Also where the program is flattened (parameters).
  const std::string flat_open = "%\nG21 G90\n#1=20\nG0 X10 Y10 Z10\nG1 X#1 F100\n";
  EXPECT_NE(refusal(flat_open).find("without a closing '%'"), std::string::npos);
  const std::string flat_mid = "G21 G90\n#1=20\nG0 X10 Y10 Z10\nG1 X#1 F100\n%\n";
  EXPECT_NE(refusal(flat_mid, &line).find("'%' after the program began"), std::string::npos);
  EXPECT_EQ(line, 5);
  require_rs274();
  EXPECT_NE(rs274_on(after, "after.ngc").said.find("Bad character '%' used"), std::string::npos);
  EXPECT_NE(rs274_on(open, "open.ngc").said.find("File ended with no percent sign"),
            std::string::npos);
  EXPECT_NE(rs274_on(flat_mid, "flat-mid.ngc").said.find("Bad character '%' used"),
            std::string::npos);
}

// Item 3: a program that moves nothing is refused with what was read.
TEST(NeverSilent, ProgramsThatMoveNothingAreRefused) {
  EXPECT_NE(refusal("").find("the file is empty"), std::string::npos);
  EXPECT_NE(refusal("(only a comment)\nM3 S1000\nM5\nM2\n").find("4 lines read"),
            std::string::npos);
  // A Fanuc tape whose program is all leader (no opening '%'): the control
  // skips it whole.
  const std::string msg =
      refusal("O1000\nG21 G90\nG0 X10. Y10. Z10.\nM30\n%\n", nullptr, nc::Dialect::kFanuc);
  EXPECT_NE(msg.find("4 of them tape leader before the '%' on line 5"), std::string::npos) << msg;
}

// Class 2: G91 polar increments (LinuxCNC: @ adds to the radius of where
// the controller stands, ^ to its angle). The controller stands at the
// corrected point, so an increment left as written turns the correction
// already made by its angle; the post must take each line's end from its
// own output. Judged by rs274: every commanded point of the output, moved
// by the machine's errors, on the nominal path.
void expect_polar_program_within_tolerance(const std::string& program, const std::string& name,
                                           double allowed_um) {
  const std::string out = post(program);
  EXPECT_NE(out, program);
  require_rs274();
  const Verdict nominal = rs274_on(program, name + ".ngc");
  const Verdict written = rs274_on(out, name + "-out.ngc");
  ASSERT_TRUE(nominal.canon.ok && nominal.canon.errors.empty()) << nominal.said;
  ASSERT_TRUE(written.canon.ok && written.canon.errors.empty()) << written.said;
  ASSERT_GE(written.canon.feeds.size(), nominal.canon.feeds.size());
  const post::Corrector c(hsu(), hsu_errors(), hsu().tool_length_mm, OutsidePolicy::kError);
  EXPECT_LE(
      worst_deviation_um(written.canon, placed_feeds(nominal.canon), c, placed().work_offset_mm[0]),
      allowed_um);
}

TEST(NeverSilent, G91PolarIncrementsAreTakenFromWhereTheControllerStands) {
  // mm: a spiral of 300 small polar steps around the program origin.
  std::string mm = "G21 G90 G17\nG0 X40 Y0 Z5\nG1 Z0 F300\nG91\n";
  for (int k = 0; k < 300; ++k) mm += "G1 @-0.05 ^4.5\n";
  mm += "G90\nG0 Z5\nM2\n";
  // (rs274 prints 4 decimals: 0.05 um in mm.)
  expect_polar_program_within_tolerance(mm, "polar-mm", 1.0 + 0.06);
  // inch, as in the issue: G91 G1 @-.0025 ^4.5, a few hundred times.
  std::string inch = "G20 G90 G17\nG0 X1.5 Y0 Z.2\nG1 Z0 F12\n";
  for (int k = 0; k < 250; ++k) inch += "G91 G1 @-.0025 ^4.5\n";
  inch += "G90 G0 Z.2\nM2\n";
  // (rs274 prints 4 decimals: each of X and Y up to 1.27 um off in inch,
  // in the nominal run and in the output's: 2 sqrt(2) 1.27 um = 3.6 um.
  // Before the fix: 18.9 um.)
  expect_polar_program_within_tolerance(inch, "polar-inch", 1.0 + 3.6);
  // G90 with one polar word: the other is the standing point's own.
  std::string one = "G21 G90 G17\nG0 X40 Y0 Z5\nG1 Z0 F300\n";
  for (int k = 1; k <= 60; ++k) one += fmt::format("G1 ^{}\n", 6 * k);
  one += "G0 Z5\nM2\n";
  expect_polar_program_within_tolerance(one, "polar-angle-only", 1.0 + 0.06);
}

// Found by the speed work: after a G40 exit move, a plain line took the
// shortcut with the "compensated move" state left on, and was refused as
// under cutter compensation; the same line with G1 in front posted.
TEST(NeverSilent, APlainLineAfterG40IsNoCompensatedMove) {
  const std::string p =
      "%\nG21 G90 G17 G94\nG0 X20 Y0 Z110\nG1 Z98 F800\nG1 X25\nG41.1 D0.2 X30 Y0\n"
      "G1 X40 Y5\nG40 G1 X50 Y0\nX49.99 Y0.3\nM2\n%\n";
  EXPECT_EQ(refusal(p), "");
  std::string g1 = p;
  g1.replace(g1.find("X49.99"), 0, "G1 ");
  EXPECT_EQ(refusal(g1), "");
}

}  // namespace
}  // namespace volmap
