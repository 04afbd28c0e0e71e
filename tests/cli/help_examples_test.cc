// Every example in the commands' --help runs as printed, from a folder whose
// samples/ is the repository's, in the order of `volmap --help`: map writes
// the table export reads, post the programs verify checks (with the same
// machine, errors and placement), simulate the recordings identify fits.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/cli_in_source.h"
#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace volmap::test {
namespace {

// The command lines after "Example:" in a help text, each without its
// leading "volmap"; a line ending in '\' continues on the next.
std::vector<std::string> examples(const std::string& help) {
  std::vector<std::string> out;
  const size_t at = help.find("Example:\n");
  if (at == std::string::npos) return out;
  std::istringstream in(help.substr(at));
  bool continued = false;
  for (std::string line; std::getline(in, line);) {
    const size_t text = line.find_first_not_of(' ');
    if (text == std::string::npos) continue;
    std::string part = line.substr(text);
    const bool more = !part.empty() && part.back() == '\\';
    if (more) part.pop_back();
    if (continued)
      out.back() += " " + part;
    else if (part.rfind("volmap ", 0) == 0)
      out.push_back(part.substr(7));
    continued = more && (continued || part.rfind("volmap ", 0) == 0);
  }
  return out;
}

TEST(HelpExamples, EveryExampleRunsAsPrinted) {
  const std::filesystem::path dir = fresh_dir("help_examples");
  std::filesystem::create_directory_symlink(source_path("samples"), dir / "samples");
  const std::string top = run_volmap("--help").out;
  const std::regex command(R"(\n  ([a-z]+) {2,})");
  int run = 0;
  for (std::sregex_iterator c(top.begin(), top.end(), command), end; c != end; ++c) {
    const std::string name = (*c)[1];
    const std::vector<std::string> list = examples(run_volmap(name + " --help").out);
    EXPECT_FALSE(list.empty()) << name << " --help has no example";
    for (const std::string& args : list) {
      ASSERT_EQ(args.rfind(name + " ", 0), 0u) << "an example of " << name << ": " << args;
      const std::string log = (dir / ("example" + std::to_string(++run) + ".log")).string();
      const int status = std::system(
          ("cd " + dir.string() + " && " + volmap_binary() + " " + args + " >" + log + " 2>&1")
              .c_str());
      std::ifstream in(log);
      const std::string said((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
      EXPECT_EQ(status, 0) << "volmap " << args << "\n" << said;
    }
  }
  EXPECT_GE(run, 14);
}

}  // namespace
}  // namespace volmap::test
