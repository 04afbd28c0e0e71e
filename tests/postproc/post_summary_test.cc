// What the post did, as `volmap post` says it: the summary on stderr, the
// same numbers as one JSON document with --json, and the --report page
// (self-contained, loaded in headless Chromium without a console message).
// The numbers are checked against the files themselves: lines counted in
// the input and the output, changed and added lines found by comparing
// them, arcs counted by reading the output back.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "tests/support/browser.h"
#include "tests/support/cli_in_source.h"
#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

namespace fs = std::filesystem;

long count_lines(const std::string& text) {
  long n = 0;
  for (char ch : text) n += ch == '\n' ? 1 : 0;
  return n + (!text.empty() && text.back() != '\n' ? 1 : 0);
}

// Arc blocks of a program as volmap's interpreter reads them (stated G2/G3
// and modal ones).
long arc_moves(const std::string& text) {
  std::istringstream lines(text);
  nc::ProgramSetup setup;
  nc::Interpreter interp(setup, "out.ngc");
  nc::BlockEffect fx;
  long arcs = 0;
  int number = 0;
  for (std::string l; std::getline(lines, l);) {
    interp.execute(nc::lex_block(l, ++number, "out.ngc"), fx);
    arcs += fx.has_motion && fx.motion.kind == nc::MotionKind::kArc ? 1 : 0;
  }
  return arcs;
}

TEST(PostSummary, JsonStderrAndReportTellWhatThePostDid) {
  const fs::path dir = test::fresh_dir("post_summary");
  const std::string in = test::source_path("samples/programs/pocket.ngc");
  const std::string out = (dir / "pocket-machine.ngc").string();
  const std::string report = (dir / "post.html").string();
  const test::CliResult r = test::run_volmap(
      "post --machine " + test::source_path("samples/machines/hsu-3axis.json") + " --errors " +
      test::source_path("samples/errors/hsu-3axis.csv") + " --work-offset 250,200,100 " + in +
      " -o " + out + " --json --report " + report);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string input = test::file_bytes(in), output = test::file_bytes(out);
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["lines_in"].get<long>(), count_lines(input));
  EXPECT_EQ(j["lines_out"].get<long>(), count_lines(output));
  EXPECT_EQ(j["lines_out"].get<long>(), j["lines_in"].get<long>() + j["lines_added"].get<long>());
  // Changed lines: the input's lines outside the longest common
  // subsequence of input and output lines (an edited line replaces its
  // line; added lines are insertions).
  {
    std::vector<std::string> a, b;
    std::istringstream sa(input), sb(output);
    for (std::string l; std::getline(sa, l);) a.push_back(l);
    for (std::string l; std::getline(sb, l);) b.push_back(l);
    std::vector<std::vector<long>> lcs(a.size() + 1, std::vector<long>(b.size() + 1, 0));
    for (std::size_t i = a.size(); i-- > 0;)
      for (std::size_t k = b.size(); k-- > 0;)
        lcs[i][k] = a[i] == b[k] ? lcs[i + 1][k + 1] + 1 : std::max(lcs[i + 1][k], lcs[i][k + 1]);
    EXPECT_EQ(j["lines_changed"].get<long>(), static_cast<long>(a.size()) - lcs[0][0]);
  }
  const long arcs = j["arcs"]["kept"].get<long>() + j["arcs"]["cut"].get<long>();
  EXPECT_GT(arcs, 0);
  EXPECT_EQ(j["arcs"]["linearized"].get<long>(), 0);
  EXPECT_GE(arc_moves(output), arcs);
  EXPECT_GT(j["max_correction_um"].get<double>(), 10.0);
  EXPECT_LE(j["max_deviation_um"].get<double>(), j["tolerance_um"].get<double>());
  EXPECT_TRUE(j["flattened"].is_null());
  // stderr: the summary line with the same numbers.
  EXPECT_NE(r.err.find("post: " + in + ": " + std::to_string(count_lines(input)) + " lines in, " +
                       std::to_string(count_lines(output)) + " out"),
            std::string::npos)
      << r.err;
  // The page: every changed line as read and as written, and it loads.
  const std::string page = test::file_bytes(report);
  EXPECT_NE(page.find("largest predicted deviation between points"), std::string::npos);
  EXPECT_EQ(page.find("<script"), std::string::npos) << "no script";
  EXPECT_EQ(page.find("http"), std::string::npos) << "no network";
  if (!test::chromium_or_skip()) return;
  test::expect_console_check_sees_errors((dir / "scratch.html").string());
  std::string dom, console;
  test::load_in_chromium(report, dom, console);
  EXPECT_TRUE(console.empty()) << console;
  EXPECT_NE(dom.find("Lines changed"), std::string::npos);
}

TEST(PostSummary, NothingToChangeIsSaidAndJsonNeedsAFileForTheProgram) {
  const fs::path dir = test::fresh_dir("post_summary_zero");
  const std::string zero = (dir / "zero.csv").string();
  std::ofstream(zero) << "# volmap component errors v1\n\nX,EXX\n0,0\n500,0\n";
  const std::string in = test::source_path("samples/programs/pocket.ngc");
  const std::string machine = test::source_path("samples/machines/hsu-3axis.json");
  const test::CliResult r = test::run_volmap("post --machine " + machine + " --errors " + zero +
                                             " --work-offset 250,200,100 " + in + " -o -");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out, test::file_bytes(in));
  EXPECT_NE(r.err.find("none needed a change"), std::string::npos) << r.err;
  const test::CliResult j = test::run_volmap("post --machine " + machine + " --errors " + zero +
                                             " --work-offset 250,200,100 " + in + " -o - --json");
  EXPECT_EQ(j.status, 2) << j.err;
  EXPECT_TRUE(j.out.empty());
}

}  // namespace
}  // namespace volmap
