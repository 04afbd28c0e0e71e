// `volmap kinematics` as scripts call it (shared/spec/cli.md): forward and
// backward against Lei & Hsu eqs. (10)-(15), all solutions, the three-axis
// and B-C table-table samples, the correction with --errors, the errors.
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/kinematics/lei_hsu_poses.h"
#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

using test_kinematics::eq10_15;
using test_kinematics::kDeg;
using test_kinematics::load;
using test_kinematics::pose;

using Result = test::CliResult;

Result run(const std::string& args) { return test::run_volmap(args); }

std::string fmt_pose(const ToolPose& v) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", v.tip_mm.x(), v.tip_mm.y(),
                v.tip_mm.z(), v.axis.x(), v.axis.y(), v.axis.z());
  return buf;
}

std::string machine_arg(const std::string& name) {
  return "kinematics --machine " + test::source_path("samples/machines/" + name + ".json");
}

TEST(Cli, KinematicsForwardJsonIsEqs10To15) {
  const Result r = run(machine_arg("lei-hsu-xyzac") + " --forward 10,20,30,-30,40 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  const ToolPose p = eq10_15(10, 20, 30, -30 * kDeg, 40 * kDeg);
  ASSERT_EQ(doc["tip_mm"].size(), 3u);
  ASSERT_EQ(doc["axis"].size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(doc["tip_mm"][k].get<double>(), p.tip_mm[k], 1e-9);
    EXPECT_NEAR(doc["axis"][k].get<double>(), p.axis[k], 1e-12);
  }
}

TEST(Cli, KinematicsBackwardJsonListsAllSolutions) {
  const ToolPose v = eq10_15(10, 20, 30, -20 * kDeg, 40 * kDeg);
  const std::string arg = fmt_pose(v);
  const Result r = run(machine_arg("lei-hsu-xyzac") + " --backward " + arg + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc["solutions"].size(), 2u);
  bool found = false;
  for (const auto& s : doc["solutions"]) {
    for (const char* k : {"X", "Y", "Z", "A", "C"}) EXPECT_TRUE(s.contains(k));
    if (std::abs(s["A"].get<double>() + 20) < 1e-9) {
      found = true;
      EXPECT_NEAR(s["X"].get<double>(), 10, 1e-9);
      EXPECT_NEAR(s["Y"].get<double>(), 20, 1e-9);
      EXPECT_NEAR(s["Z"].get<double>(), 30, 1e-9);
      EXPECT_NEAR(s["C"].get<double>(), 40, 1e-9);
    } else {
      EXPECT_NEAR(s["A"].get<double>(), 20, 1e-9);
    }
  }
  EXPECT_TRUE(found);
}

TEST(Cli, KinematicsBackwardThreeAxisAndBCTableTable) {
  const Result r3 = run(machine_arg("hsu-3axis") + " --backward 12.5,-30,40 --json");
  ASSERT_EQ(r3.status, 0) << r3.err;
  const auto d3 = nlohmann::json::parse(r3.out);
  ASSERT_EQ(d3["solutions"].size(), 1u);
  const Machine m = load("hsu-3axis");
  const AxisVector u =
      pose({d3["solutions"][0]["X"].get<double>(), d3["solutions"][0]["Y"].get<double>(),
            d3["solutions"][0]["Z"].get<double>()},
           m);
  EXPECT_LT((nominal_forward(m, u).tip_mm - Eigen::Vector3d(12.5, -30, 40)).norm(), 1e-9);

  const Machine bc = load("bc-table-table");
  const ToolPose v = nominal_forward(bc, pose({100, -50, 120, 35, 250}, bc));
  const Result r = run(machine_arg("bc-table-table") + " --backward " + fmt_pose(v) +
                       " --previous 0,0,0,30,250 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc["solutions"].size(), 2u);
  const auto& sel = doc["solutions"][doc["selected"].get<int>()];
  EXPECT_NEAR(sel["B"].get<double>(), 35, 1e-9);
  EXPECT_NEAR(sel["C"].get<double>(), 250, 1e-9);
  EXPECT_NEAR(sel["X"].get<double>(), 100, 1e-9);
}

TEST(Cli, KinematicsHumanTextAndHelp) {
  const Result f = run(machine_arg("lei-hsu-xyzac") + " --forward 10,20,30,-30,40");
  ASSERT_EQ(f.status, 0) << f.err;
  EXPECT_NE(f.out.find("tip"), std::string::npos);
  EXPECT_NE(f.out.find("axis"), std::string::npos);
  EXPECT_EQ(f.out.find('{'), std::string::npos);  // not JSON
  const Result h = run("kinematics --help");
  EXPECT_EQ(h.status, 0);
  std::string out = h.out;
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  const size_t ex = out.rfind("Example:");
  ASSERT_NE(ex, std::string::npos);
  EXPECT_EQ(out.find('\n', out.find('\n', ex) + 1), std::string::npos);  // the example ends it
  EXPECT_NE(out.find("volmap kinematics", ex), std::string::npos);
}

TEST(Cli, KinematicsWithErrorsPrintsTheCorrection) {
  const Result r = run(machine_arg("lei-hsu-xyzac") + " --forward 10,20,30,-30,40 --errors " +
                       test::source_path("samples/errors/lei-hsu-xyzac.csv") + " --iterate --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["tip_mm"].size(), 3u);  // the contract keys stay
  const auto& c = doc["correction"];
  for (const char* k : {"X_um", "Y_um", "Z_um", "A_urad", "C_urad"})
    EXPECT_TRUE(c["du"].contains(k));
  EXPECT_LT(c["residual_um"].get<double>(), 1e-6);
  EXPECT_EQ(c["method"], "iterated");
}

// A tool axis tilted 30 degrees: the solution has A at the machine's
// limit (-100..30 deg) up to rounding (the backward transformation gives
// 30.000000000000004), which is inside the travel: selected and corrected,
// not refused (issue 23).
TEST(Cli, KinematicsAtATravelLimitUpToRoundingIsInside) {
  const Result r =
      run(machine_arg("lei-hsu-xyzac") + " --backward 10,20,30,0.5,0,0.8660254037844386 --errors " +
          test::source_path("samples/errors/lei-hsu-xyzac.csv") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  const int selected = doc["selected"];
  const double a_deg = doc["solutions"][selected]["A"];
  EXPECT_NEAR(a_deg, 30.0, 1e-12);
  EXPECT_TRUE(doc["correction"]["corrected"].contains("A"));
}

TEST(Cli, KinematicsErrorsAreOneLineWithStatus1Or2) {
  auto one_line = [](const Result& r) {
    EXPECT_FALSE(r.err.empty());
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  };
  const std::string m = machine_arg("lei-hsu-xyzac");
  // Option values that do not parse or do not fit the machine: usage (2).
  for (const std::string& usage : {m + " --forward 10,20,x,0,0", m + " --forward 10,20,30,0",
                                   m + " --forward 10,20,30,60,0"}) {  // A outside -100..30
    const Result r = run(usage);
    EXPECT_EQ(r.status, 2) << usage;
    one_line(r);
  }
  for (const std::string& bad :
       {m + " --backward 0,0,0,0,0,2",   // not a unit vector
        m + " --backward 0,0,0,0,0,-1",  // unreachable
        m + " --backward 1,2,3",
        std::string("kinematics --machine /nonexistent.json --forward 0,0,0,0,0")}) {
    const Result r = run(bad);
    EXPECT_EQ(r.status, 1) << bad;
    one_line(r);
  }
  for (const std::string& usage :
       {m, m + " --forward 0,0,0,0,0 --backward 0,0,0,0,0,1",
        std::string("kinematics --forward 0,0,0,0,0"), m + " --forward 0,0,0,0,0 --iterate"}) {
    const Result r = run(usage);
    EXPECT_EQ(r.status, 2) << usage;
    one_line(r);
  }
}

}  // namespace
}  // namespace volmap
