// Determinism (issue 8; STYLE.md 10): the same input gives the same bytes,
// whatever the thread count and however often it runs: map with 1 and 2
// threads (three and five axes, also the automatic spacing and the JSON
// summary apart from its timing), its exports, post and simulate twice.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/support/cli_in_source.h"

namespace volmap::test {
namespace {

namespace fs = std::filesystem;

const char* kHsu =
    "--machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv";
const char* kLei =
    "--machine samples/machines/lei-hsu-xyzac.json --errors samples/errors/lei-hsu-xyzac.csv";

CliResult ok(const std::string& args) {
  const CliResult r = run_volmap_in_source(args);
  EXPECT_EQ(r.status, 0) << args << "\n" << r.err;
  return r;
}

// Every file of folder a has the same bytes in folder b, and b no other.
void expect_same_folder(const fs::path& a, const fs::path& b) {
  size_t n = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(a)) {
    ++n;
    const std::string bytes = file_bytes(e.path());
    EXPECT_FALSE(bytes.empty()) << e.path();
    EXPECT_EQ(bytes, file_bytes(b / e.path().filename())) << e.path().filename();
  }
  size_t m = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(b)) {
    ++m;
    (void)e;
  }
  EXPECT_EQ(n, m);
  EXPECT_GT(n, 0u);
}

nlohmann::json without_timing(nlohmann::json doc) {
  for (const char* k : {"seconds", "build_seconds", "check_seconds", "threads", "output", "table"})
    doc.erase(k);
  return doc;
}

TEST(Determinism, MapIsTheSameWithOneAndTwoThreads) {
  const fs::path d = fresh_dir("determinism_map");
  struct Case {
    std::string name, args;
    std::vector<const char*> formats;
  };
  for (const Case& c :
       {Case{"hsu",
             std::string(kHsu) + " --spacing 25,25,25",
             {"csv", "json", "heidenhain", "fanuc"}},
        Case{"hsu_auto", std::string(kHsu) + " --tolerance-um 2", {"csv", "linuxcnc"}},
        Case{"lei", std::string(kLei) + " --spacing 100,100,100,26,60", {"csv", "json"}}}) {
    const fs::path t1 = d / (c.name + "_1.vmt"), t2 = d / (c.name + "_2.vmt"),
                   t2b = d / (c.name + "_2b.vmt");
    const CliResult r1 = ok("map " + c.args + " --threads 1 --json -o " + t1.string());
    const CliResult r2 = ok("map " + c.args + " --threads 2 --json -o " + t2.string());
    ok("map " + c.args + " --threads 2 -o " + t2b.string());
    const std::string b1 = file_bytes(t1);
    ASSERT_FALSE(b1.empty());
    EXPECT_EQ(b1, file_bytes(t2)) << c.name << ": 1 vs 2 threads";
    EXPECT_EQ(b1, file_bytes(t2b)) << c.name << ": two runs";
    EXPECT_EQ(without_timing(nlohmann::json::parse(r1.out)),
              without_timing(nlohmann::json::parse(r2.out)))
        << c.name;
    for (const char* format : c.formats) {
      const fs::path e1 = d / (c.name + "_1_" + format), e2 = d / (c.name + "_2_" + format);
      ok("export --table " + t1.string() + " --format " + format + " -o " + e1.string());
      ok("export --table " + t2.string() + " --format " + format + " -o " + e2.string());
      expect_same_folder(e1, e2);
    }
  }
  fs::remove_all(d);
}

TEST(Determinism, PostAndSimulateTwice) {
  const fs::path d = fresh_dir("determinism_post");
  for (int k = 0; k < 2; ++k) {
    ok(std::string("post ") + kHsu + " --work-offset 250,200,100 samples/programs/pocket.ngc -o " +
       (d / ("p" + std::to_string(k) + ".ngc")).string());
    const CliResult s = ok(std::string("post ") + kHsu +
                           " --work-offset 250,200,100 - -o - < samples/programs/pocket.ngc");
    std::ofstream(d / ("s" + std::to_string(k) + ".ngc"), std::ios::binary) << s.out;
    ok(std::string("simulate ") + kLei + " --plan samples/plans/probe-ball.json -o " +
       (d / ("r" + std::to_string(k) + ".csv")).string());
  }
  const std::string p0 = file_bytes(d / "p0.ngc");
  ASSERT_FALSE(p0.empty());
  EXPECT_EQ(p0, file_bytes(d / "p1.ngc"));
  EXPECT_EQ(p0, file_bytes(d / "s0.ngc")) << "stdin/stdout differs from files";
  EXPECT_EQ(p0, file_bytes(d / "s1.ngc"));
  EXPECT_NE(p0, file_bytes(source_path("samples/programs/pocket.ngc")));
  const std::string r0 = file_bytes(d / "r0.csv");
  ASSERT_FALSE(r0.empty());
  EXPECT_EQ(r0, file_bytes(d / "r1.csv"));
  fs::remove_all(d);
}

}  // namespace
}  // namespace volmap::test
