// Replays the fuzzers' inputs in the ordinary test suite (and so under the
// sanitizers of .ci/run's second pass): every seed of tests/fuzz/corpus/<target>/
// and every input a fuzzer found, tests/fuzz/regressions/<target>/ (one file
// per bug, named after it). What each target does is tests/fuzz/harness.h:
// a reader may refuse an input with InputError, nothing else.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "tests/fuzz/harness.h"
#include "tests/support/cli_in_source.h"

namespace volmap::test {
namespace {

namespace fs = std::filesystem;

const std::map<std::string, std::function<void(std::string_view)>>& targets() {
  static const std::map<std::string, std::function<void(std::string_view)>> t = {
      {"nc_reader_fuzz", fuzz::nc_reader},
      {"nc_flatten_fuzz", fuzz::nc_flatten},
      {"nc_fanuc_fuzz", fuzz::nc_fanuc},
      {"post_fuzz", fuzz::post},
      {"recordings_csv_fuzz", fuzz::recordings_csv},
      {"errors_csv_fuzz", fuzz::errors_csv},
      {"machine_json_fuzz", fuzz::machine_json},
      {"apt_reader_fuzz", fuzz::apt_reader}};
  return t;
}

struct Input {
  std::string target, path;  ///< path relative to tests/fuzz
};

std::vector<Input> inputs(const std::string& kind) {
  std::vector<Input> out;
  for (const auto& [target, run] : targets()) {
    const fs::path d = fs::path(source_path("tests/fuzz")) / kind / target;
    if (!fs::is_directory(d)) continue;
    for (const fs::directory_entry& e : fs::directory_iterator(d))
      if (e.is_regular_file())
        out.push_back({target, kind + "/" + target + "/" + e.path().filename().string()});
  }
  std::sort(out.begin(), out.end(), [](const Input& a, const Input& b) { return a.path < b.path; });
  return out;
}

void replay(const std::vector<Input>& list) {
  for (const Input& in : list) {
    SCOPED_TRACE(in.path);
    const std::string bytes = file_bytes(source_path("tests/fuzz/" + in.path));
    EXPECT_NO_THROW(targets().at(in.target)(bytes));
  }
}

TEST(FuzzRegressions, EveryFoundInputIsHandled) {
  const std::vector<Input> list = inputs("regressions");
  EXPECT_FALSE(list.empty());
  replay(list);
}

TEST(FuzzRegressions, EverySeedIsHandled) {
  const std::vector<Input> list = inputs("corpus");
  for (const auto& entry : targets()) {
    const std::string& target = entry.first;
    EXPECT_TRUE(
        std::any_of(list.begin(), list.end(), [&](const Input& i) { return i.target == target; }))
        << target << " has no seed";
  }
  replay(list);
}

// The bugs the NC reader fuzzer found, by their message: numbers too large
// for an int are refused on their line, never cast (undefined behaviour).
TEST(FuzzRegressions, HugeIntegerWordsAreRefusedOnTheirLine) {
  for (const char* name : {"g_code_overflows_int.ngc", "t_word_overflows_int.ngc",
                           "h_word_overflows_int.ngc", "p_turns_overflow_int.ngc"}) {
    const std::string text =
        file_bytes(source_path(std::string("tests/fuzz/regressions/nc_reader_fuzz/") + name));
    nc::Interpreter interp(nc::ProgramSetup{}, name);
    nc::BlockEffect fx;
    std::istringstream in(text);
    std::string line;
    int number = 0;
    int refused_at = 0;
    try {
      while (std::getline(in, line)) interp.execute(nc::lex_block(line, ++number, name), fx);
    } catch (const InputError& e) {
      refused_at = e.line();
    }
    EXPECT_EQ(refused_at, 2) << name;
  }
}

// Found by nc_reader_fuzz: the work offsets of G54-G59.3 that neither
// --work-offset nor a .var file sets were uninitialised memory (Eigen
// vectors are not zeroed by default); they are zero, as in LinuxCNC.
TEST(FuzzRegressions, UnsetWorkOffsetsAreZero) {
  const nc::ProgramSetup setup;
  for (const Eigen::Vector3d& o : setup.work_offset_mm) EXPECT_EQ(o, Eigen::Vector3d::Zero());
  nc::Interpreter interp(setup, "p.ngc");
  nc::BlockEffect fx;
  interp.execute(nc::lex_block("G59.3 G0 X1 Y2 Z3", 1, "p.ngc"), fx);
  EXPECT_EQ(interp.state().position_mm, Eigen::Vector3d(1, 2, 3));
}

}  // namespace
}  // namespace volmap::test
