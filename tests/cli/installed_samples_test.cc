// An installed volmap takes samples/... inputs from <prefix>/share/volmap
// when they are not in the current folder, and never redirects an output
// (cli/installed_samples.h).
#include "cli/installed_samples.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support/cli_in_source.h"

namespace volmap::cli {
namespace {

namespace fs = std::filesystem;

TEST(InstalledSamples, MissingSampleInputsComeFromTheInstalledFolder) {
  const fs::path dir = test::fresh_dir("installed_samples");
  const fs::path share = dir / "share" / "volmap" / "samples";
  fs::create_directories(share / "machines");
  std::ofstream(share / "machines" / "m.json") << "{}";
  fs::create_directories(dir / "work" / "samples" / "machines");
  std::ofstream(dir / "work" / "samples" / "machines" / "here.json") << "{}";
  const fs::path old = fs::current_path();
  fs::current_path(dir / "work");
  std::vector<std::string> notes;
  const std::vector<std::string> out = with_installed_samples(
      {"volmap", "map", "--machine", "samples/machines/m.json", "--errors=samples/machines/m.json",
       "samples/machines/here.json", "samples/machines/none.json", "-o", "samples/machines/m.json",
       "--report=samples/machines/m.json"},
      share.string(), &notes);
  fs::current_path(old);
  const std::string installed = (share / "machines" / "m.json").string();
  EXPECT_EQ(out[3], installed);                     // an input not here: installed
  EXPECT_EQ(out[4], "--errors=" + installed);       // also as --opt=value
  EXPECT_EQ(out[5], "samples/machines/here.json");  // present here: kept
  EXPECT_EQ(out[6], "samples/machines/none.json");  // nowhere: kept (its error names it)
  EXPECT_EQ(out[8], "samples/machines/m.json");     // an output: never redirected
  EXPECT_EQ(out[9], "--report=samples/machines/m.json");
  ASSERT_EQ(notes.size(), 2u);
  EXPECT_NE(notes[0].find("using the installed sample " + installed), std::string::npos);
  // Not installed (no share/ folder): nothing changes.
  EXPECT_EQ(with_installed_samples({"volmap", "samples/machines/m.json"}, "", nullptr)[1],
            "samples/machines/m.json");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace volmap::cli
