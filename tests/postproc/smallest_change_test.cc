// The smallest faithful change (docs/post.md "The smallest change"): a
// machine whose errors are zero, or so small that no correction shows at the
// output's resolution, gets every program back byte for byte — arcs, canned
// cycles with L repeats and polar words, G91 stretches, flattened O-word
// programs, tape frames, the first move from an unknown or a given start,
// tool length offsets, G28 homes. Over every program of the suite: the
// samples, LinuxCNC's shipped programs and the real third-party corpus
// (tests/data/real/nc). A program the post refuses with zero errors is
// refused with the tiny ones too (the same rules, whatever the numbers).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/cli_in_source.h"
#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

namespace fs = std::filesystem;

// The sample's errors file with every error value multiplied by `scale`
// (the position and direction columns kept): 0 gives a file of zeros in
// the sample's shape (bidirectional rows, location errors and all).
std::string scaled_errors(double scale) {
  std::istringstream in(test::file_bytes(test::source_path("samples/errors/hsu-3axis.csv")));
  std::string out;
  std::vector<std::string> header;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') {
      out += line + '\n';
      header.clear();
      continue;
    }
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (header.empty() || !(std::isdigit(static_cast<unsigned char>(line[0])) || line[0] == '-' ||
                            line[0] == '+' || line[0] == '.')) {
      header = cells;  // a header row: X,dir,EXX,... or EC0X,EB0Z,...
      out += line + '\n';
      continue;
    }
    for (std::size_t k = 0; k < cells.size(); ++k) {
      const bool error_column = k < header.size() && header[k].size() > 1 && header[k][0] == 'E';
      if (k > 0) out += ',';
      out += error_column ? fmt::format("{:.9g}", std::stod(cells[k]) * scale) : cells[k];
    }
    out += '\n';
  }
  return out;
}

std::vector<fs::path> programs() {
  std::vector<fs::path> all{test::source_path("samples/programs/pocket.ngc")};
  for (const fs::path& dir : {fs::path(test::source_path("tests/data/real/nc")),
                              fs::path("/usr/share/linuxcnc/ncfiles")}) {
    if (!fs::exists(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir)) {
      const std::string ext = e.path().extension().string();
      if (e.is_regular_file() && (ext == ".ngc" || ext == ".nc" || ext == ".gcode"))
        all.push_back(e.path());
    }
  }
  std::sort(all.begin(), all.end());
  return all;
}

TEST(SmallestChange, ZeroOrInvisibleErrorsGiveEveryProgramBackByteForByte) {
  const fs::path dir = test::fresh_dir("smallest_change");
  const std::string zero = (dir / "zero.csv").string(), tiny = (dir / "tiny.csv").string();
  std::ofstream(zero) << scaled_errors(0.0);
  // A hundred-thousandth of the sample's errors: corrections below a
  // nanometre inside the travel and a few nanometres where a program placed
  // at 250,200,150 reaches metres beyond it (--clamp; angular errors times
  // that lever), below half the output's unit (50 nm in mm, 127 nm in
  // inch). The whole correction runs (segments, arcs, cycles), only to
  // change nothing.
  std::ofstream(tiny) << scaled_errors(1e-5);
  const std::string tools = (dir / "tools.tbl").string(), var = (dir / "homes.var").string();
  {
    std::ofstream t(tools);
    for (int k = 0; k <= 30; ++k) t << fmt::format("T{0} P{0} Z{1} ;\n", k, 0.5 * k);
    std::ofstream v(var);
    for (int a = 0; a < 6; ++a)
      for (int first : {5161, 5181}) v << fmt::format("{} {}\n", first + a, a < 3 ? 100.0 : 0.0);
  }
  const std::string machine = test::source_path("samples/machines/hsu-3axis.json");
  const std::string subs = test::source_path("tests/data/real/nc/subs");
  const std::string setups[] = {
      "--work-offset 250,200,150 --clamp",
      "--work-offset 250,200,150 --clamp --initial-position 0,0,0 --tool-table " + tools +
          " --var-file " + var};
  int posted = 0, refused = 0;
  for (const fs::path& p : programs()) {
    for (const std::string& setup : setups) {
      SCOPED_TRACE(p.string() + " " + setup);
      const std::string input = test::file_bytes(p);
      bool refused_with_zero = false;
      for (const std::string& errors : {zero, tiny}) {
        const test::CliResult r =
            test::run_volmap("post --machine " + machine + " --errors " + errors + " " + setup +
                             " --subroutine-path " + subs + " " + p.string() + " -o -");
        if (errors == zero) {
          refused_with_zero = r.status != 0;
          if (refused_with_zero) {
            ++refused;
            EXPECT_EQ(r.status, 1) << r.err;
            EXPECT_TRUE(r.out.empty());
            continue;
          }
          ++posted;
        }
        ASSERT_EQ(r.status != 0, refused_with_zero) << errors << ": " << r.err;
        if (refused_with_zero) continue;
        EXPECT_TRUE(r.out == input) << errors << ": the output differs from the input";
      }
    }
  }
  // The suite's programs: the sample, 48 real ones, LinuxCNC's when
  // installed (those it cannot post: rotary axes, cutter compensation,
  // probing, lathe cycles...).
  EXPECT_GE(posted, 50) << refused << " refused";
}

}  // namespace
}  // namespace volmap
