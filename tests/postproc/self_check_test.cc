// The post's self-check (postproc/three_axis/self_check.h) on written
// programs that are wrong in the ways issue 35 found: a program written
// back uncorrected, and G91 polar increments left as written after a
// corrected start (the controller takes them from where it really stands).
// The check reads the written text alone; the expected deviations come
// from the error model at the nominal points, computed here.
#include "postproc/three_axis/self_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "core/common/input_error.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "postproc/three_axis/corrector.h"
#include "postproc/three_axis/post_program.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

const Machine& hsu() {
  static const Machine m = load_machine_json(test::source_path("samples/machines/hsu-3axis.json"));
  return m;
}
// The sample errors without lost motion (X's + direction table only), so
// that the expected deviation is the plain error at a point.
const ErrorSet& errors() {
  static const ErrorSet e = [] {
    ErrorSet s = load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv"));
    for (auto& axis : s.axis)
      if (axis) axis->minus = AxisErrorTable{};  // one table: no direction
    return s;
  }();
  return e;
}

nc::ProgramSetup placed() {
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(250, 200, 100);
  return s;
}

// Runs the check as the post does: each input line's nominal motion, then
// what was "written" for it. Returns the refusal ("" if none) and its line.
std::string check(const std::vector<std::string>& input, const std::vector<std::string>& written,
                  int* line = nullptr) {
  const post::Corrector c(hsu(), errors(), hsu().tool_length_mm, OutsidePolicy::kError);
  nc::Interpreter nominal(placed(), "in.ngc");
  post::SelfCheck sc(nominal, placed(), "in.ngc", 1e-3);
  nc::Block b;
  nc::BlockEffect fx;
  try {
    for (std::size_t k = 0; k < input.size(); ++k) {
      nc::lex_block_into(input[k], static_cast<int>(k + 1), "in.ngc", b);
      nominal.execute(b, fx);
      if (fx.has_motion) sc.nominal(fx.motion, &fx.more_holes);
      sc.written(written[k] + "\n", c, "in.ngc", static_cast<int>(k + 1));
    }
  } catch (const InputError& e) {
    if (line) *line = e.line();
    return e.what();
  }
  return "";
}

std::vector<std::string> polar_program() {
  std::vector<std::string> p = {"G21 G90 G17", "G0 X40 Y0 Z5", "G1 Z0 F300", "G1 X40 Y1", "G91"};
  for (int k = 0; k < 300; ++k) p.push_back("G1 @-0.05 ^4.5");
  return p;
}

// Class 2 on its own: the start corrected, then the polar increments left
// as written. The controller turns the correction it stands at by each
// step's 4.5 degrees, so the error the start corrected (e at 40,1,0: about
// 20 um) soon points the wrong way: refused once it is 1 um off, within
// the first steps, not after 300.
TEST(SelfCheck, CatchesPolarIncrementsTakenFromTheNominalPosition) {
  const post::Corrector c(hsu(), errors(), hsu().tool_length_mm, OutsidePolicy::kError);
  const Eigen::Vector3d wo = placed().work_offset_mm[0];
  const std::vector<std::string> in = polar_program();
  std::vector<std::string> out = in;
  // The corrected start, as the post writes it (program coordinates).
  for (const auto& [k, nominal] :
       {std::pair{1, Eigen::Vector3d(40, 0, 5)}, std::pair{2, Eigen::Vector3d(40, 0, 0)},
        std::pair{3, Eigen::Vector3d(40, 1, 0)}}) {
    const Eigen::Vector3d cmd =
        c.command_for(nominal + wo, ApproachDirections{}, Eigen::Vector3d::Zero()) - wo;
    out[static_cast<std::size_t>(k)] = (k == 1 ? "G0 X" : "G1 X") + std::to_string(cmd.x()) + " Y" +
                                       std::to_string(cmd.y()) + " Z" + std::to_string(cmd.z()) +
                                       (k == 2 ? " F300" : "");
  }
  const double e_um = c.error_at(Eigen::Vector3d(40, 1, 0) + wo, ApproachDirections{}).norm() * 1e3;
  ASSERT_GT(e_um, 10.0);  // a correction that matters
  int line = 0;
  const std::string why = check(in, out, &line);
  EXPECT_NE(why.find("self-check"), std::string::npos) << why;
  // One step turns a correction of e by 4.5 degrees: 2 e sin(2.25 deg) off.
  // 1 um is passed by the first step already for e > 12.7 um.
  EXPECT_GE(line, 6);
  EXPECT_LE(line, 6 + static_cast<int>(1.0 / (2 * e_um * std::sin(2.25 * M_PI / 180))) + 1);
  // The same program written with the increments as X Y from the corrected
  // positions (what the post writes now) passes.
  std::ostringstream written;
  post::PostOptions o;
  std::string text;
  for (const std::string& l : in) text += l + "\n";
  std::istringstream src(text);
  const post::PostReport r =
      post::post_program(src, "in.ngc", written, hsu(), errors(), placed(), o);
  EXPECT_TRUE(r.self_checked);
  EXPECT_GE(r.self_check.points, 300u);
  EXPECT_LE(r.self_check.max_mm, 1e-3);
}

// A program written back uncorrected (class 1: taken as tape leader) is
// off by the error at its points: refused at its second motion line, the
// first the check measures, with the size the model gives there.
TEST(SelfCheck, CatchesAnUncorrectedProgram) {
  const std::vector<std::string> in = {"G21 G90", "G0 X10 Y10 Z10", "G1 X20 F100", "G1 Y20"};
  int line = 0;
  const std::string why = check(in, in, &line);
  EXPECT_EQ(line, 3);
  const post::Corrector c(hsu(), errors(), hsu().tool_length_mm, OutsidePolicy::kError);
  const Eigen::Vector3d wo = placed().work_offset_mm[0];
  // The first point measured: X20 Y10 Z10's end (its interior is nearer).
  const double e_um = c.error_at(Eigen::Vector3d(20, 10, 10) + wo, ApproachDirections{}).norm();
  ASSERT_GT(e_um * 1e3, 1.0);
  EXPECT_NE(why.find("leaves this line's nominal path by"), std::string::npos) << why;
  // And what the post writes for it passes, every point measured.
  std::ostringstream written;
  std::istringstream src("G21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\nG1 Y20\n");
  const post::PostReport r =
      post::post_program(src, "in.ngc", written, hsu(), errors(), placed(), {});
  EXPECT_TRUE(r.self_checked);
  EXPECT_GT(r.self_check.points, 0u);
  EXPECT_LE(r.self_check.max_mm, 1e-3);
}

// Zero errors: no check (the output is the input), and the post says so.
TEST(SelfCheck, AMachineWithoutErrorsIsNotChecked) {
  std::ostringstream written;
  std::istringstream src("G21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\n");
  const post::PostReport r =
      post::post_program(src, "in.ngc", written, hsu(), ErrorSet{}, placed(), {});
  EXPECT_FALSE(r.self_checked);
  EXPECT_EQ(written.str(), "G21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\n");
}

}  // namespace
}  // namespace volmap
