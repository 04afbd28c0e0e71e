// The post-processor in two and three threads (PostOptions::threads): the
// reading thread runs the writer's solution ahead to make the evaluations of
// the error field, and the writer takes them only where point and directions
// are bit for bit the ones it asks for. Whatever the reader gets wrong, the
// output, the report and the errors must be the one-thread ones, byte for
// byte: checked here on the samples, on LinuxCNC's programs and on programs
// built to throw the reader out of step (arcs, G91, canned cycles, tool
// changes, lost-motion steps, bad lines).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "core/errors_csv.h"
#include "core/input_error.h"
#include "core/machine_json.h"
#include "postproc/corrector.h"
#include "postproc/post_program.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

Machine hsu() { return load_machine_json(test::source_path("samples/machines/hsu-3axis.json")); }
ErrorSet hsu_errors() { return load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv")); }

std::string read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

struct Posted {
  std::string out;
  std::string error;  ///< what() of the exception, if any
  post::PostReport report;
};

Posted run(const std::string& program, int threads, const nc::ProgramSetup& setup,
        OutsidePolicy outside = OutsidePolicy::kError) {
  static const Machine machine = hsu();
  static const ErrorSet errors = hsu_errors();
  std::istringstream in(program);
  std::ostringstream out;
  post::PostOptions o;
  o.threads = threads;
  o.outside = outside;
  Posted r;
  try {
    r.report = post::post_program(in, "prog.ngc", out, machine, errors, setup, o);
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  r.out = out.str();
  return r;
}

nc::ProgramSetup setup_with_tools() {
  nc::ProgramSetup s;
  s.work_offset_mm[0] = Eigen::Vector3d(250, 200, 100);
  s.work_offset_mm[1] = Eigen::Vector3d(300, 150, 120);
  s.tool_length_mm[1] = 100.0;
  s.tool_length_mm[2] = 150.0;
  return s;
}

// The same bytes, report and error in one, two and three threads; returns
// the two-thread run.
Posted expect_same(const std::string& name, const std::string& program, const nc::ProgramSetup& setup,
                OutsidePolicy outside = OutsidePolicy::kError) {
  SCOPED_TRACE(name);
  const Posted one = run(program, 1, setup, outside);
  Posted two;
  for (int threads : {2, 3}) {
    const Posted many = run(program, threads, setup, outside);
    EXPECT_EQ(many.error, one.error) << threads << " threads";
    EXPECT_TRUE(many.out == one.out) << threads << " threads: the output differs";
    EXPECT_EQ(many.report.lines, one.report.lines);
    EXPECT_EQ(many.report.lines_changed, one.report.lines_changed);
    EXPECT_EQ(many.report.lines_added, one.report.lines_added);
    EXPECT_EQ(many.report.points_corrected, one.report.points_corrected);
    EXPECT_EQ(many.report.max_correction_mm, one.report.max_correction_mm);
    if (threads == 2) two = many;
  }
  return two;
}

// A raster of straight moves over a wavy surface (the benchmark's program,
// bench/post_vs_rs274.sh), rows in both directions: every row end reverses X,
// with lost motion (the sample errors are bidirectional).
std::string raster(int rows, int per_row, bool end = true) {
  std::string p = "%\nG21 G90 G17 G40 G49 G80\nG0 Z10\nG0 X0 Y0\nG1 Z-2 F2000\n";
  for (int r = 0; r < rows; ++r)
    for (int i = 0; i <= per_row; ++i) {
      const double x = r % 2 == 0 ? i * 0.5 : per_row * 0.5 - i * 0.5, y = r * 0.1;
      p += fmt::format("X{:.4f} Y{:.4f} Z{:.4f}\n", x, y, -5 + 3 * std::sin(x / 20) * std::cos(y / 15));
    }
  return end ? p + "G0 Z10\nM2\n%\n" : p;
}

// The writer takes an evaluation made ahead only for the same point and
// directions, bit for bit, each once, in order; the evaluations made ahead
// are the writer's own (command_ahead solves as command_for does).
TEST(PostThreads, AnEvaluationMadeAheadIsTakenOnlyForTheSamePointAndDirections) {
  const Machine m = hsu();
  const ErrorSet e = hsu_errors();
  const post::Corrector c(m, e, m.tool_length_mm, OutsidePolicy::kError);
  const post::Corrector direct(m, e, m.tool_length_mm, OutsidePolicy::kError);
  const Eigen::Vector3d x1(300, 200, 150), x2(std::nextafter(300.0, 400.0), 200, 150);
  const ApproachDirections plus{1, 1, 1}, minus{-1, -1, -1};
  std::vector<post::Evaluation> made;
  EXPECT_EQ(c.error_ahead(x1, plus, made), direct.error_at(x1, plus));
  ASSERT_EQ(made.size(), 1u);
  made[0].e_mm = Eigen::Vector3d(1, 2, 3);  // marked: taken where it shows
  post::EvaluationMemo memo{made.data(), made.data() + made.size()};
  c.use_memo(&memo);
  EXPECT_EQ(c.error_at(x2, plus), direct.error_at(x2, plus));    // one ulp away
  EXPECT_EQ(c.error_at(x1, minus), direct.error_at(x1, minus));  // other directions
  EXPECT_EQ(memo.hits, 0u);
  EXPECT_EQ(memo.misses, 2u);
  EXPECT_EQ(c.error_at(x1, plus), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(memo.hits, 1u);
  EXPECT_EQ(c.error_at(x1, plus), direct.error_at(x1, plus));  // once only
  c.use_memo(nullptr);
  // Solving ahead: the same command to the bit, warm or cold.
  made.clear();
  const Eigen::Vector3d nominal(310.5, 205.25, 140.125), nearby(0.012, -0.004, 0.009);
  EXPECT_EQ(c.command_ahead(nominal, plus, nullptr, 1e-12, made), direct.command_for(nominal, plus));
  EXPECT_GE(made.size(), 2u);
  EXPECT_EQ(c.command_ahead(nominal, minus, &nearby, 1e-9, made),
            direct.command_for(nominal, minus, nearby, 1e-9));
}

TEST(PostThreads, StraightMovesAreEvaluatedAheadAndTheOutputIsTheSame) {
  const Posted r = expect_same("raster", raster(40, 200), setup_with_tools());
  ASSERT_TRUE(r.error.empty()) << r.error;
  // The reader stays in step with the writer through every reversal (lost
  // motion): the writer takes every move's solution and evaluates nothing.
  EXPECT_GT(r.report.lines_solved_ahead, 8000u);
  EXPECT_EQ(r.report.evaluations_not_ahead, 0u);
}

TEST(PostThreads, WhatTheReaderDoesNotFollowChangesNothing) {
  const nc::ProgramSetup s = setup_with_tools();
  // Arcs, G91, canned cycles (the reader stops following), a tool change
  // (it starts again), inch, G53, G93, polar words, block delete, CRLF and
  // a last line without its newline.
  const std::string program =
      "G21 G90 G17 G40 G49 G80 F800\nG0 X0 Y0 Z10\nG1 Z-1\nX20 Y5\nG2 X30 Y15 I10 J0\nG1 X40 Y10\n"
      "G91 G1 X1.5 Y-0.5\nX1.5 Y0.5\nG90 G0 Z5\nG81 X10 Y10 Z-3 R2\nX20\nG80\n"
      "T2 M6 G43 H2\nG0 X5 Y5 Z8\nG1 Z-2\nX50 Y20 Z-3\nX10 Y40\n/G1 X12 Y42\nG20 G1 X0.5 Y1.5\nG21\n"
      "G55 G0 X1 Y1 Z5\nG1 X30 Y2 Z-1\nG53 G0 Z150\nG54 G0 X0 Y0 Z10\nG93 G1 X5 Y5 Z0 F10\nG94 F800\n"
      "G1 @20 ^30\nG1 X0 Y0\r\nX10 Y0\r\nX10 Y10";
  const Posted r = expect_same("mixed", program, s);
  ASSERT_TRUE(r.error.empty()) << r.error;
  EXPECT_GT(r.report.lines_solved_ahead, 0u);
}

TEST(PostThreads, AnErrorStopsAtTheSameLineWithTheSameOutput) {
  const nc::ProgramSetup s = setup_with_tools();
  const std::string good = raster(4, 200, false);
  // A line the interpreter refuses, far enough in that batches went ahead.
  const Posted bad_line = expect_same("refused line", good + "G1 X1 Q\n" + good, s);
  EXPECT_NE(bad_line.error.find("prog.ngc:"), std::string::npos) << bad_line.error;
  // A move that leaves the error tables (refused under kError, clamped
  // under kClamp).
  const std::string outside = good + "G1 X5000 Y0 Z0\n" + good;
  const Posted refused = expect_same("leaves the tables", outside, s);
  EXPECT_NE(refused.error.find("leaves the error tables"), std::string::npos) << refused.error;
  const Posted clamped = expect_same("clamped", outside, s, OutsidePolicy::kClamp);
  EXPECT_TRUE(clamped.error.empty()) << clamped.error;
}

TEST(PostThreads, SamplesAndLinuxCncProgramsGiveTheSameBytes) {
  std::vector<std::string> paths;
  for (const auto& e : std::filesystem::directory_iterator(test::source_path("samples/programs")))
    if (e.path().extension() == ".ngc") paths.push_back(e.path().string());
  const std::filesystem::path ncfiles("/usr/share/linuxcnc/ncfiles");
  if (std::filesystem::exists(ncfiles))
    for (const auto& e : std::filesystem::directory_iterator(ncfiles))
      if (e.path().extension() == ".ngc") paths.push_back(e.path().string());
  std::sort(paths.begin(), paths.end());
  int posted = 0;
  for (const std::string& path : paths) {
    const Posted r = expect_same(path, read_file(path), setup_with_tools());
    if (r.error.empty()) ++posted;
  }
  EXPECT_GE(posted, 2);  // the samples at least; LinuxCNC's where installed
}

}  // namespace
}  // namespace volmap
