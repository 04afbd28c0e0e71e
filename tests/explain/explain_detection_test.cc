// explain at the statistical limit (issue #20): an effect the recording's
// statistics reveal is reported however small its share of the RMS, every
// candidate carries the smallest amplitude the design can reveal, and a
// design that cannot reveal an effect says so with the test that would.
#include "tests/explain/explain_test_support.h"

namespace volmap {
namespace {

using namespace explain_testing;

/// Two-sided normal critical value z with 2 P(Z > z) = p, by bisection on erfc.
double two_sided_z(double p) {
  double lo = 0, hi = 40;
  for (int i = 0; i < 200; ++i) {
    const double m = 0.5 * (lo + hi);
    (std::erfc(m / std::sqrt(2.0)) > p ? lo : hi) = m;
  }
  return 0.5 * (lo + hi);
}

const json& candidate(const json& res, const std::string& effect, const std::string& axis) {
  for (const json& c : res.at("candidates"))
    if (c.at("effect") == effect && c.at("axis") == axis) return c;
  ADD_FAILURE() << "no candidate " << effect << " " << axis;
  static const json none = json::object();
  return none;
}

// The case of the issue: a lost motion of one noise sigma on X, recorded
// with ey and ez beside ex, so it moves the whole recording's RMS by under
// 5 % (the old practical-significance margin refused it) while its
// t-statistic is above 10.
TEST(ExplainDetection, LostMotionOfOneSigmaAmongThreeComponentsIsReported) {
  const Machine m = test::sample_machine("hsu-3axis");
  const ErrorModel model(
      m, load_errors_csv(test::source_path("samples/recordings/geometry-3axis.csv")));
  const Plan plan = test::plan_from_text(
      R"({"format": "volmap-plan/1", "seed": 5, "noise_um": 1.5,
          "tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 10,
                     "bidirectional": true, "cycles": 5, "at": {"Y": 200, "Z": 150},
                     "record": ["ex", "ey", "ez"], "dwell_s": 4, "move_s": 2}]})",
      m);
  std::istringstream fx(
      R"({"format": "volmap-effects/1",
          "effects": [{"effect": "reversal", "axis": "X", "value_um": 1.5}]})");
  const GainEvaluator g(m, Formulation::kIndependent);
  const EffectSet effects = read_effects_json(fx, "fx.json", m, g);
  Recordings rec = simulate(model, plan, &effects);
  rec.file = "one-sigma-reversal";
  const json res = explain_json(explain(m, rec, {}));
  ASSERT_EQ(res.at("findings").size(), 1u) << res.at("findings").dump(1);
  const json& f = res.at("findings").at(0);
  EXPECT_EQ(f.at("effect"), "reversal");
  EXPECT_EQ(f.at("axis"), "X");
  const double value = f.at("parameters").at("value_um"), se = f.at("std_errors").at("value_um");
  EXPECT_LT(std::abs(value - 1.5), 3 * se) << value << " +- " << se;
  EXPECT_GT(value / se, 10.0);
  // The RMS moves by less than the old 5 % margin.
  EXPECT_GT(f.at("rms_after_um").get<double>(), 0.95 * f.at("rms_before_um").get<double>());

  // Its detectable size by hand: the design is balanced (each target from
  // both sides in every run), so the polynomial baseline absorbs none of
  // the +-1/2 column: ||P_perp g||^2 = n_ex / 4. The test is two-sided at
  // 0.1 % over the m candidates tried; power 95 %: z_beta = 1.6449.
  const json& rev = candidate(res, "reversal", "X");
  EXPECT_EQ(rev.at("status"), "finding");
  int tried = 0;
  for (const json& c : res.at("candidates")) tried += c.at("status") != "not estimable";
  const double n_ex = 510, sigma = res.at("final").at("rms_um");
  const double by_hand = (two_sided_z(0.001 / tried) + 1.6449) * sigma / std::sqrt(n_ex / 4);
  EXPECT_NEAR(rev.at("detectable_um").get<double>(), by_hand, 0.02 * by_hand);
  EXPECT_NEAR(rev.at("critical_chi2").get<double>(), std::pow(two_sided_z(0.001 / tried), 2),
              0.02 * rev.at("critical_chi2").get<double>());
}

TEST(ExplainDetection, EveryCandidateCarriesItsDetectableSize) {
  for (const auto& [recording, machine] : {std::pair{"samples/recordings/null.csv", kM3},
                                           {"samples/recordings/null-5axis.csv", kM5},
                                           {"samples/recordings/cyclic.csv", kM3},
                                           {"samples/recordings/setup-shift.csv", kM3}}) {
    const json res = run_explain(recording, machine);
    ASSERT_FALSE(res.at("candidates").empty()) << recording;
    for (const json& c : res.at("candidates")) {
      int keys = 0;
      for (const auto& [k, v] : c.items())
        if (k.rfind("detectable_", 0) == 0) {
          ++keys;
          EXPECT_TRUE(v.is_null() || v.get<double>() > 0) << recording << " " << c.dump();
        }
      EXPECT_EQ(keys, 1) << recording << " " << c.dump();
      if (c.at("status") != "not estimable") {
        EXPECT_GT(c.at("critical_chi2").get<double>(), 10.0) << c.dump();
      }
    }
  }
}

TEST(ExplainDetection, CyclicErrorIsQuotedAtItsPeriod) {
  // The cyclic sample: 1 um at a 16 mm period under 1 um of noise. The
  // detectable amplitude, at the fitted period, is below the found one.
  const json res = run_explain("samples/recordings/cyclic.csv", kM3);
  const json& c = candidate(res, "cyclic", "X");
  EXPECT_EQ(c.at("status"), "finding");
  EXPECT_LT(c.at("detectable_um").get<double>(), 1.0);
  EXPECT_NEAR(c.at("at").at("period_mm").get<double>(), 16.0, 0.1);
}

TEST(ExplainDetection, ADesignThatCannotRevealAnEffectSaysWhichTestWould) {
  // reversal-one-feed: 11 targets, so the baseline takes a value per
  // target and no periodic error along X can show; one feed, so servo lag
  // is the reversal's twin.
  const json res = run_explain("samples/recordings/reversal-one-feed.csv", kM3);
  const json& cyc = candidate(res, "cyclic", "X");
  EXPECT_TRUE(cyc.at("detectable_um").is_null()) << cyc.dump();
  bool noted = false;
  for (const json& n : res.at("notes"))
    noted |= n.get<std::string>().find("cyclic X: this recording's design cannot reveal it") == 0 &&
             n.get<std::string>().find("2.2 points per period") != std::string::npos;
  EXPECT_TRUE(noted) << res.at("notes").dump(1);
}

}  // namespace
}  // namespace volmap
