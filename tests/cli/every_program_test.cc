// Every NC program under tests/ (the real corpus, the Fanuc and flattener
// data, the bad-input catalogue, the fuzz seeds and regressions, anything
// with a program's extension) posted with each dialect forced and detected
// (issue 35: every exception that reaches main is a bug). Each run must end
// in exit 0 with an output, or in a refusal: exit 1, nothing written, and a
// last stderr line "volmap: FILE:LINE[:COLUMN]: ..." that is not an internal
// error. Never a crash, a timeout, another exit status or a message without
// its place. Runs from the repository folder (messages carry the relative
// path), two posts at a time. Not run under the sanitizers (.ci/run,
// CMakePresets.json: about 2 100 posts; the fuzzers cover the same code).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/cli_in_source.h"
#include "tests/support/test_paths.h"

namespace volmap::test {
namespace {

namespace fs = std::filesystem;

// Program files by extension, relative to the repository ("tests/...").
std::vector<std::string> programs() {
  static const std::set<std::string> kExtensions = {
      ".ngc", ".nc", ".tap", ".gcode", ".txt", ".cnc", ".mpf", ".apt", ".cls", ".clsf", ".eia"};
  std::vector<std::string> out;
  const fs::path root = source_path("");
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(root / "tests")) {
    if (!e.is_regular_file() || e.path().filename() == "CMakeLists.txt") continue;
    std::string ext = e.path().extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (kExtensions.count(ext)) out.push_back(fs::relative(e.path(), root).string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

struct Run {
  std::string args;  ///< everything but the program and -o
  std::string program;
};

// What is wrong with one post ("" when it is posted or refused at a line).
// `dir`: the job's own folder, which must hold nothing else afterwards (no
// temporary file left).
std::string check(const Run& run, const fs::path& dir) {
  const fs::path out = dir / "out.nc", err = dir / "err.txt";
  fs::remove(out);
  const std::string cmd = "cd '" + source_path("") + "' && timeout 60 '" + volmap_binary() +
                          "' post " + run.args + " '" + run.program + "' -o '" + out.string() +
                          "' </dev/null >/dev/null 2>'" + err.string() + "'";
  const int st = std::system(cmd.c_str());
  const int status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  std::string text = file_bytes(err);
  while (!text.empty() && text.back() == '\n') text.pop_back();
  const std::string last =
      text.substr(text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1);
  static const std::regex kAtLine(R"(^volmap: [^ ]+:[0-9]+(:[0-9]+)?: .*)");
  const std::string what = "post " + run.args + " " + run.program + ": ";
  for (const fs::directory_entry& e : fs::directory_iterator(dir))
    if (e.path() != out && e.path() != err) return what + "left " + e.path().string();
  if (status == 0) return fs::exists(out) ? "" : what + "exit 0 and no output";
  if (status != 1) return what + "exit " + std::to_string(status) + ": " + last;
  if (fs::exists(out)) return what + "refused, yet wrote its output: " + last;
  if (last.find("internal error") != std::string::npos) return what + last;
  if (!std::regex_match(last, kAtLine)) return what + "refused without file:line: " + last;
  return "";
}

// Every program with each of `dialects`, `args` before them; two at a time.
void post_every_program(const std::string& name, const std::string& args,
                        const std::vector<std::string>& dialects) {
  std::vector<Run> runs;
  for (const std::string& p : programs())
    for (const std::string& d : dialects) runs.push_back({args + " --dialect " + d, p});
  ASSERT_GT(runs.size(), 400u);  // the corpus is there
  const fs::path dir = fresh_dir("every_program_" + name);
  std::atomic<std::size_t> next{0};
  std::mutex m;
  std::vector<std::string> failures;
  auto worker = [&](int job) {
    const fs::path own = dir / std::to_string(job);
    fs::create_directories(own);
    for (std::size_t k; (k = next++) < runs.size();) {
      std::string f = check(runs[k], own);
      if (f.empty()) continue;
      std::lock_guard<std::mutex> lock(m);
      failures.push_back(std::move(f));
    }
  };
  std::thread a(worker, 0), b(worker, 1);
  a.join();
  b.join();
  std::sort(failures.begin(), failures.end());
  for (const std::string& f : failures) ADD_FAILURE() << f;
}

const char kThreeAxis[] =
    "--machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
    "--work-offset 250,200,100 --tool-table tests/bad/tool.tbl";

TEST(EveryProgram, ThreeAxisPostsOrRefusesAtALine) {
  post_every_program("3", kThreeAxis, {"auto", "linuxcnc", "fanuc"});
}

// From a known start and holding the error tables' end values, more of
// each program is posted before a refusal (or all of it).
TEST(EveryProgram, ThreeAxisFromAKnownStartPostsOrRefusesAtALine) {
  post_every_program("3s", std::string(kThreeAxis) + " --initial-position 0,0,50 --clamp",
                     {"auto", "linuxcnc", "fanuc"});
}

// The five-axis post (TCP, tool-vector and APT inputs); `--dialect fanuc`
// is a usage error there (docs/post.md), so auto and linuxcnc.
TEST(EveryProgram, FiveAxisPostsOrRefusesAtALine) {
  post_every_program(
      "5",
      "--machine samples/machines/lei-hsu-xyzac.json --errors samples/errors/lei-hsu-xyzac.csv",
      {"auto", "linuxcnc"});
}

}  // namespace
}  // namespace volmap::test
