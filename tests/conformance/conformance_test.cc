// The conformance engine in CI (docs/conformance.md): a fixed budget of
// generated programs (a fixed seed: the same programs every run) judged
// against rs274, and every regression file the engine kept. Both take
// minutes: the sanitizer pass of .ci/run leaves them out (label
// `conformance`, name Conformance.*).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "tests/conformance/engine.h"
#include "tests/conformance/regression.h"

namespace volmap::conformance {
namespace {

namespace fs = std::filesystem;

bool have_rs274() { return std::system("command -v rs274 >/dev/null 2>&1") == 0; }

#define REQUIRE_RS274()                                                        \
  do {                                                                         \
    if (!have_rs274()) {                                                       \
      if (std::getenv("VOLMAP_REQUIRE_RS274")) FAIL() << "rs274 is required";  \
      GTEST_SKIP() << "rs274 not installed (apt-get install linuxcnc-uspace)"; \
    }                                                                          \
  } while (0)

EngineOptions options(const std::string& name) {
  EngineOptions o;
  o.volmap = VOLMAP_BINARY;
  o.source_dir = VOLMAP_SOURCE_DIR;
  o.work_dir = (fs::path(::testing::TempDir()) / ("conformance-" + name)).string();
  fs::remove_all(o.work_dir);
  return o;
}

// The budget: kConformancePrograms programs of seed 35 (about two minutes
// on two busy cores), two workers; each failure class shrunk once, within
// a bounded number of judge runs, and written under the test's temporary
// folder (the runner writes tests/conformance/regressions/).
constexpr int kConformancePrograms = 120;
// The path findings of seed 35 on 2026-12-07 (programs, counted per class):
// the ratchet until they are triaged (docs/conformance.md, "Open findings").
constexpr int kOpenPathFindings = 27;

TEST(Conformance, GeneratedProgramsPostAsRs274RunsThem) {
  REQUIRE_RS274();
  EngineOptions o = options("budget");
  o.seed = 35;
  o.programs = kConformancePrograms;
  o.jobs = 2;
  o.shrink_trials = 60;
  o.regressions_dir = (fs::path(o.work_dir) / "regressions").string();
  const EngineReport r = run_engine(o, std::cout);
  std::ostringstream report;
  print_report(r, report);
  std::cout << report.str();
  EXPECT_EQ(r.programs, kConformancePrograms);
  // The test has teeth: most programs are read by rs274 and posted.
  EXPECT_GT(r.rs274_reads, kConformancePrograms / 2);
  EXPECT_GT(r.posts_judged, kConformancePrograms);
  // What is exact already: every program rs274 and volmap both read or both
  // refuse, volmap never crashes or refuses without file:line, rs274 reads
  // every output, zero errors give the bytes back. The path classes (the
  // actual path off the nominal one: at seed 35, 20 of the 120 programs on
  // 2026-12-07, not yet triaged between the post and the judge, listed in
  // docs/conformance.md) may not grow.
  int path_programs = 0;
  for (const auto& [kind, programs] : r.failure_counts) {
    if (kind.starts_with("the actual path leaves the nominal path") ||
        kind.starts_with("the nominal path is not followed")) {
      path_programs += programs;
      continue;
    }
    ADD_FAILURE() << kind << ": " << programs << " programs\n" << report.str();
  }
  EXPECT_LE(path_programs, kOpenPathFindings) << report.str();
}

TEST(Conformance, RegressionFilesPass) {
  REQUIRE_RS274();
  EngineOptions o = options("regressions");
  Judge judge({o.volmap, o.source_dir, o.work_dir});
  const std::vector<std::string> paths =
      regression_paths((fs::path(VOLMAP_SOURCE_DIR) / "tests/conformance/regressions").string());
  for (const std::string& path : paths) {
    SCOPED_TRACE(path);
    const Regression r = read_regression(path);
    for (const Finding& f : rerun_regression(judge, r))
      ADD_FAILURE() << f.kind << " [" << f.field << "]: " << f.detail << "\n(recorded: " << r.kind
                    << ")";
  }
  std::cout << paths.size() << " regression files\n";
}

// The generator is reproducible: a seed gives the same files.
TEST(Conformance, GeneratorIsSeeded) {
  for (std::uint64_t s : {1ULL, 35ULL, 123456789ULL}) {
    const Program a = generate_program(s), b = generate_program(s);
    EXPECT_EQ(a.main, b.main);
    EXPECT_EQ(a.files, b.files);
  }
  EXPECT_NE(generate_program(1).main, generate_program(2).main);
}

}  // namespace
}  // namespace volmap::conformance
