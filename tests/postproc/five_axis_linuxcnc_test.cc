// Real five-axis programs: LinuxCNC's TCP demos for its X'Y'ZA'C' table
// machine (impeller-7bl-xyzac.ngc, boat-xyzac.ngc, shipped with
// linuxcnc-uspace's documentation), posted with the sample machine and its
// errors by `volmap post`:
//  - rs274 (LinuxCNC's interpreter) accepts every output without an error;
//  - every feed point rs274 reads from the output is a position volmap
//    wrote, and that position, run through the error model, puts the tool
//    tip on the program's nominal path (read independently of the post:
//    its straight moves and arcs in workpiece coordinates) within the
//    tolerance plus rounding;
//  - `volmap verify` shows the deviation before (tens of um) and after
//    (below the tolerance) along the whole path.
// Programs or rs274 missing: skipped, unless VOLMAP_REQUIRE_RS274 is set.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/model/error_model.h"
#include "gcode/nc_block.h"
#include "gcode/nc_path.h"
#include "postproc/five_axis/five_axis_input.h"
#include "tests/postproc/five_axis_canon.h"
#include "tests/support/cli_run.h"
#include "tests/support/rs274.h"
#include "tests/support/samples.h"

namespace volmap {
namespace {

namespace fs = std::filesystem;
using test::canonical_feeds;
using test::have_rs274;
using test::Pose5;
using test::worst_tip_distance_mm;
using test::written_feeds;

const char* kDemos =
    "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/vismach/5axis/table-rotary-tilting/"
    "demos/";

// The program (uncompressed into the test's temporary folder when only a
// .gz is installed); empty when missing.
std::string demo(const std::string& name) {
  const std::string plain = std::string(kDemos) + name;
  if (fs::exists(plain)) return plain;
  if (fs::exists(plain + ".gz")) {
    const std::string out = ::testing::TempDir() + name;
    if (std::system(("gzip -dc " + plain + ".gz > " + out).c_str()) == 0) return out;
  }
  return "";
}

// The nominal feed moves of the input, in workpiece coordinates.
std::vector<nc::Motion> nominal_feeds(const std::string& program, const Machine& m) {
  std::ifstream f(program);
  post::FiveAxisReader reader(f, program, m, post::InputForm::kTcp, post::InitialPose{});
  std::vector<nc::Motion> out;
  post::FiveAxisLine l;
  while (reader.next(l))
    if (l.has_move && !l.move.rapid) out.push_back(l.move.tip);
  return out;
}

// The output commands machine axes: the input's TCP switches are gone.
void expect_no_tcp_switches(const std::string& out) {
  std::ifstream f(out);
  std::stringstream ss;
  ss << f.rdbuf();
  EXPECT_EQ(ss.str().find("M428"), std::string::npos);
  EXPECT_EQ(ss.str().find("M429"), std::string::npos);
}

// C never jumps by 180 degrees or more between consecutive lines, rapids
// included (the demos' own G0 C0 after C-399.8 is taken a whole turn
// off: the same pose).
void expect_c_never_jumps_half_a_turn(const std::string& out) {
  std::ifstream f(out);
  std::string line;
  int n = 0, moves = 0;
  double c_prev = 0;
  bool have = false;
  while (std::getline(f, line)) {
    const nc::Block b = nc::lex_block(line, ++n, out);
    if (const nc::Word* w = b.find('C')) {
      if (have) {
        EXPECT_LT(std::abs(w->value - c_prev), 180.0) << out << ":" << n << ": " << line;
      }
      c_prev = w->value;
      have = true;
      ++moves;
    }
  }
  EXPECT_GT(moves, 100);
}

class RealFiveAxisProgram : public ::testing::TestWithParam<const char*> {};

TEST_P(RealFiveAxisProgram, PostedRs274AcceptsAndTheToolFollowsTheNominalPath) {
  const std::string in = demo(GetParam());
  const bool required = std::getenv("VOLMAP_REQUIRE_RS274") != nullptr;
  if (in.empty()) {
    if (required) FAIL() << "LinuxCNC's demo " << GetParam() << " is missing (linuxcnc-uspace)";
    GTEST_SKIP() << GetParam() << " not installed (apt-get install linuxcnc-uspace)";
  }
  const std::string machine = test::source_path("samples/machines/lei-hsu-xyzac.json");
  const std::string errors = test::source_path("samples/errors/lei-hsu-xyzac.csv");
  const std::string out = ::testing::TempDir() + "volmap5_" + std::string(GetParam());
  fs::remove(out);
  const test::CliResult post = test::run_volmap("post --machine " + machine + " --errors " +
                                                errors + " " + in + " -o " + out);
  ASSERT_EQ(post.status, 0) << post.err;

  // Independent of rs274: the input's TCP switches are gone.
  expect_no_tcp_switches(out);

  // C never jumps by 180 degrees or more between consecutive lines, rapids
  // included.
  expect_c_never_jumps_half_a_turn(out);

  // verify: before and after along the whole path.
  const test::CliResult v = test::run_volmap("verify --machine " + machine + " --errors " + errors +
                                             " --nominal " + in + " --program " + out + " --json");
  ASSERT_EQ(v.status, 0) << v.err;
  const nlohmann::json j = nlohmann::json::parse(v.out);
  std::printf(
      "%s: before max %.3f um rms %.3f um, axis max %.2f urad; after max %.3f um rms %.3f um, axis "
      "max %.2f urad\n",
      GetParam(), j["before"]["max_um"].get<double>(), j["before"]["rms_um"].get<double>(),
      j["before"]["max_urad"].get<double>(), j["after"]["max_um"].get<double>(),
      j["after"]["rms_um"].get<double>(), j["after"]["max_urad"].get<double>());
  EXPECT_GT(j["before"]["max_um"].get<double>(), 20.0);
  EXPECT_LT(j["after"]["max_um"].get<double>(), 1.0);
  EXPECT_LT(j["after"]["max_urad"].get<double>(), j["before"]["max_urad"].get<double>());

  if (!have_rs274()) {
    if (required) FAIL() << "rs274 (linuxcnc-uspace) is required but missing";
    GTEST_SKIP() << "rs274 not installed (apt-get install linuxcnc-uspace)";
  }
  const std::string canon = out + ".canon";
  const std::string cmd =
      test::rs274_command("-g " + out + " " + canon) + " >" + canon + ".log 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::string rs_errors;
  const std::vector<Pose5> feeds = canonical_feeds(canon, rs_errors);
  EXPECT_TRUE(rs_errors.empty()) << rs_errors;

  // Every canonical feed point is the next position volmap wrote.
  const std::vector<Pose5> written = written_feeds(out);
  ASSERT_EQ(feeds.size(), written.size());
  for (size_t i = 0; i < feeds.size(); ++i) {
    ASSERT_NEAR(feeds[i].x, written[i].x, 0.6e-4) << i;
    ASSERT_NEAR(feeds[i].y, written[i].y, 0.6e-4) << i;
    ASSERT_NEAR(feeds[i].z, written[i].z, 0.6e-4) << i;
    ASSERT_NEAR(feeds[i].a, written[i].a, 0.6e-4) << i;
    ASSERT_NEAR(feeds[i].c, written[i].c, 0.6e-4) << i;
  }

  // rs274's feed points on the real machine: on the nominal path.
  const Machine m = test::sample_machine("lei-hsu-xyzac");
  const ErrorModel model(m, test::sample_errors("lei-hsu-xyzac"));
  const std::vector<nc::Motion> path = nominal_feeds(in, m);
  ASSERT_FALSE(path.empty());
  // rs274 prints 4 decimals (mm and degrees): 0.5e-4 mm per linear axis,
  // 0.5e-4 deg per rotary axis times a lever below 300 mm.
  const double slack_mm = std::sqrt(3.0) * 0.5e-4 + 2 * 0.5e-4 * M_PI / 180 * 300;
  const double worst = worst_tip_distance_mm(feeds, path, model, slack_mm);
  std::printf("%s: %zu feed points read by rs274, worst tip distance to the nominal path %.3f um\n",
              GetParam(), feeds.size(), worst * 1e3);
  EXPECT_LT(worst, 1e-3 + slack_mm);
}

// The other input forms: an APT/CLDATA file and a Siemens-style tool-vector
// program, posted for the sample machine; rs274 reads every output, and its
// feed points are the positions volmap wrote.
TEST(FiveAxisRs274, AptAndToolVectorOutputsAreAccepted) {
  if (!have_rs274()) {
    if (std::getenv("VOLMAP_REQUIRE_RS274"))
      FAIL() << "rs274 (linuxcnc-uspace) is required but missing";
    GTEST_SKIP() << "rs274 not installed (apt-get install linuxcnc-uspace)";
  }
  std::string apt =
      "PARTNO/RS274 "
      "CHECK\nMULTAX\nUNITS/MM\nSPINDL/1200,CLW\nRAPID\nGOTO/20,0,40,0,0,1\nFEDRAT/MMPM,800\n";
  std::string vec = "G21 G90 G94\nG0 X20 Y0 Z40 A3=0 B3=0 C3=1\n";
  for (int i = 1; i <= 72; ++i) {
    const double t = i * 5 * M_PI / 180, tilt = 25 * M_PI / 180;
    const double x = 20 * std::cos(t), y = 20 * std::sin(t), z = 10 + i * 0.1;
    const double ti = std::sin(tilt) * std::cos(t), tj = std::sin(tilt) * std::sin(t),
                 tk = std::cos(tilt);
    char line[200];
    std::snprintf(line, sizeof line, "GOTO/%.4f,%.4f,%.4f,%.7f,%.7f,%.7f\n", x, y, z, ti, tj, tk);
    apt += line;
    std::snprintf(line, sizeof line, "G1 X%.4f Y%.4f Z%.4f A3=%.7f B3=%.7f C3=%.7f F800\n", x, y, z,
                  ti, tj, tk);
    vec += line;
  }
  apt += "SPINDL/OFF\nFINI\n";
  vec += "M30\n";
  const std::string machine = test::source_path("samples/machines/lei-hsu-xyzac.json");
  const std::string errors = test::source_path("samples/errors/lei-hsu-xyzac.csv");
  for (const auto& [name, text] :
       {std::pair<std::string, std::string>{"cone.apt", apt}, {"cone.mpf", vec}}) {
    const std::string in = ::testing::TempDir() + "volmap5_" + name, out = in + ".ngc";
    std::ofstream(in) << text;
    fs::remove(out);
    const test::CliResult post = test::run_volmap("post --machine " + machine + " --errors " +
                                                  errors + " " + in + " -o " + out);
    ASSERT_EQ(post.status, 0) << post.err;
    const std::string canon = out + ".canon";
    ASSERT_EQ(
        std::system(
            (test::rs274_command("-g " + out + " " + canon) + " >" + canon + ".log 2>&1").c_str()),
        0);
    std::string rs_errors;
    const std::vector<Pose5> feeds = canonical_feeds(canon, rs_errors);
    EXPECT_TRUE(rs_errors.empty()) << name << ": " << rs_errors;
    const std::vector<Pose5> written = written_feeds(out);
    ASSERT_EQ(feeds.size(), written.size()) << name;
    EXPECT_GE(feeds.size(), 72u) << name;
    for (size_t i = 0; i < feeds.size(); ++i) {
      EXPECT_NEAR(feeds[i].x, written[i].x, 0.6e-4) << name << " " << i;
      EXPECT_NEAR(feeds[i].c, written[i].c, 0.6e-4) << name << " " << i;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(LinuxCncDemos, RealFiveAxisProgram,
                         ::testing::Values("impeller-7bl-xyzac.ngc", "boat-xyzac.ngc"),
                         [](const ::testing::TestParamInfo<const char*>& i) {
                           return std::string(i.param).substr(0, std::string(i.param).find('-'));
                         });

}  // namespace
}  // namespace volmap
