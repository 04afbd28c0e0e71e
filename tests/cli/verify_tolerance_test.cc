// cli.md, verify: with --tolerance-um T, exit status 3 and one line on
// stderr when the compensated program's actual path leaves T; without it, a
// warning on stderr whenever the compensated program deviates more than the
// nominal one (a verify given another placement than its post, issue 23).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace volmap::test {
namespace {

const std::string kThree = " --machine " + source_path("samples/machines/hsu-3axis.json") +
                           " --errors " + source_path("samples/errors/hsu-3axis.csv");
const std::string kFive = " --machine " + source_path("samples/machines/lei-hsu-xyzac.json") +
                          " --errors " + source_path("samples/errors/lei-hsu-xyzac.csv");

int lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

TEST(VerifyTolerance, ExitThreeWithOneLineWhenThePathLeavesIt) {
  const std::string nominal = source_path("samples/programs/pocket.ngc");
  const std::string out = ::testing::TempDir() + "verify_tolerance_pocket.ngc";
  ASSERT_EQ(
      run_volmap("post" + kThree + " --work-offset 250,200,100 " + nominal + " -o " + out).status,
      0);
  const std::string verify = "verify" + kThree + " --work-offset 250,200,100 --nominal " + nominal +
                             " --program " + out + " --json";
  const CliResult held = run_volmap(verify + " --tolerance-um 1");
  EXPECT_EQ(held.status, 0) << held.err;
  EXPECT_EQ(held.err, "");
  const CliResult left = run_volmap(verify + " --tolerance-um 0.0001");
  EXPECT_EQ(left.status, 3) << left.err;
  EXPECT_EQ(lines(left.err), 1) << left.err;
  EXPECT_NE(left.err.find("leaves the tolerance"), std::string::npos) << left.err;
  EXPECT_NE(left.out.find("\"after\""), std::string::npos);  // the result is still written
  EXPECT_EQ(run_volmap(verify + " --tolerance-um 0").status, 2);
  EXPECT_EQ(run_volmap(verify + " --tolerance-um nan").status, 2);
}

// The case: a five-axis program verified with another part origin
// than its post placed it at.
TEST(VerifyTolerance, AWarningWhenAfterIsWorseThanBefore) {
  const std::string cone = source_path("samples/programs/cone-vector.ngc");
  const std::string out5 = ::testing::TempDir() + "verify_tolerance_cone.ngc";
  ASSERT_EQ(run_volmap("post" + kFive + " " + cone + " -o " + out5).status, 0);
  const CliResult same = run_volmap("verify" + kFive + " --nominal " + cone + " --program " + out5);
  EXPECT_EQ(same.status, 0) << same.err;
  EXPECT_EQ(same.err, "");
  const CliResult moved = run_volmap("verify" + kFive + " --part-origin 30,0,0 --nominal " + cone +
                                     " --program " + out5);
  EXPECT_EQ(moved.status, 0) << moved.err;
  EXPECT_NE(moved.err.find("--part-origin"), std::string::npos) << moved.err;
}

}  // namespace
}  // namespace volmap::test
