// volmap explain where there is nothing to find or nothing to decide: the
// null recordings (and other noise draws of them) give no finding;
// confounded designs are reported as such, not guessed.
#include "tests/explain/explain_test_support.h"

namespace volmap {
namespace {

using namespace explain_testing;

// ------------------------------------------------- no effect, confounding --

TEST(ExplainNull, ThreeAxisLaserRunGivesNoFinding) {
  const json res = run_explain("samples/recordings/null.csv", kM3);
  EXPECT_TRUE(res.at("findings").empty()) << res.at("findings").dump(1);
  EXPECT_TRUE(res.at("confounded").empty());
  EXPECT_TRUE(res.at("mismatch").empty()) << res.at("mismatch").dump(1);
  EXPECT_DOUBLE_EQ(res.at("final").at("rms_um").get<double>(),
                   res.at("baseline").at("rms_um").get<double>());
}

TEST(ExplainNull, FiveAxisProbeBallGivesNoFindingInBothModes) {
  const json fitted = run_explain("samples/recordings/null-5axis.csv", kM5);
  EXPECT_TRUE(fitted.at("findings").empty()) << fitted.at("findings").dump(1);
  const json fixed = run_explain("samples/recordings/null-5axis.csv", kM5,
                                 "samples/recordings/geometry-5axis.csv");
  EXPECT_TRUE(fixed.at("findings").empty()) << fixed.at("findings").dump(1);
}

/// The null plan of a sample with another noise seed, simulated in memory.
Recordings reseeded_null(const Machine& m, const std::string& plan_name,
                         const std::string& geometry, int seed) {
  json plan = json::parse(slurp(test::source_path("samples/recordings/" + plan_name)));
  plan["seed"] = seed;
  const ErrorModel model(m, load_errors_csv(test::source_path(geometry)));
  Recordings rec = simulate(model, test::plan_from_text(plan.dump(), m), nullptr);
  rec.file = plan_name + " seed " + std::to_string(seed);
  return rec;
}

TEST(ExplainNull, NoFalseFindingOverOtherNoiseSeeds) {
  // Six more noise draws of each null recording (fitted baseline): any
  // finding is a false discovery.
  const Machine m3 = load_machine_json(test::source_path(kM3));
  const Machine m5 = load_machine_json(test::source_path(kM5));
  for (int seed = 1001; seed <= 1006; ++seed) {
    const ExplainResult r3 = explain(
        m3, reseeded_null(m3, "null.plan.json", "samples/recordings/geometry-3axis.csv", seed), {});
    EXPECT_TRUE(r3.findings.empty())
        << "3-axis seed " << seed << ": " << r3.findings.front().effect;
    const ExplainResult r5 = explain(
        m5,
        reseeded_null(m5, "null-5axis.plan.json", "samples/recordings/geometry-5axis.csv", seed),
        {});
    EXPECT_TRUE(r5.findings.empty())
        << "5-axis seed " << seed << ": " << r5.findings.front().effect;
  }
}

TEST(ExplainConfounded, OneDirectionSweepWithDriftIsConfoundedNotGuessed) {
  const json res = run_explain("samples/recordings/drift-one-direction.csv", kM3);
  bool confounded = false;
  for (const json& c : res.at("confounded")) {
    const std::set<std::string> e(c.at("effects").begin(), c.at("effects").end());
    if (e.count("thermal_drift") && c.at("axis") == "X") {
      confounded = true;
      EXPECT_FALSE(c.at("remedy").get<std::string>().empty());
      EXPECT_FALSE(c.at("explanation").get<std::string>().empty());
    }
  }
  EXPECT_TRUE(confounded) << res.dump(1);
  for (const json& f : res.at("findings")) EXPECT_NE(f.at("effect"), "thermal_drift");
  EXPECT_TRUE(res.at("baseline").at("heldout_rms_um").is_null());  // a single run
  EXPECT_TRUE(res.at("final").at("heldout_rms_um").is_null());
}

TEST(ExplainConfounded, ReversalAtASingleFeedIsConfoundedWithServoLag) {
  const json res = run_explain("samples/recordings/reversal-one-feed.csv", kM3);
  bool confounded = false;
  for (const json& c : res.at("confounded")) {
    const std::set<std::string> e(c.at("effects").begin(), c.at("effects").end());
    confounded =
        confounded || (e == std::set<std::string>{"reversal", "servo_lag"} && c.at("axis") == "X");
  }
  EXPECT_TRUE(confounded) << res.dump(1);
  for (const json& f : res.at("findings")) {
    EXPECT_NE(f.at("effect"), "reversal");
    EXPECT_NE(f.at("effect"), "servo_lag");
  }
  // The structure is still removed from the residual (it is real, only its name is open).
  EXPECT_LT(res.at("final").at("rms_um").get<double>(),
            0.5 * res.at("baseline").at("rms_um").get<double>());
}

}  // namespace
}  // namespace volmap
