// volmap explain (shared/spec/explain.md, docs/explain.md) on recordings
// where the truth is known: samples/recordings/<name>.csv were made by
// `volmap simulate` with the effects of <name>.effects.json concealed under
// noise, a larger geometric error or the order of the test. Every check
// compares with that truth file or with a quantity derived here directly
// from the recorded columns (ISO 230-2 reversal value), never with a pasted
// output.
#include "tests/explain/explain_test_support.h"

namespace volmap {
namespace {

using namespace explain_testing;

// ---------------------------------------------------------------- samples --

TEST(ExplainSamples, ReversalUnderNoiseFittedBaseline) {
  const json truth = truth_of("reversal");
  const json res = run_explain("samples/recordings/reversal.csv", kM3);
  const json& f = expect_single_finding(res, truth);
  ASSERT_FALSE(f.empty());
  // Tolerance: 0.6 um (about 2.5 standard errors at 1.5 um noise, 168 readings).
  EXPECT_NEAR(param(f, "value_um"), truth.at("value_um").get<double>(), 0.6);
  // The standard error is honest: the truth lies within 3 of them.
  EXPECT_LT(std::abs(param(f, "value_um") - truth.at("value_um").get<double>()),
            3 * f.at("std_errors").at("value_um").get<double>());

  // Independent derivation: ISO 230-2 reversal value B = mean(+) - mean(-)
  // from the recorded columns (balanced targets, geometry direction-free).
  const Recordings rec = load_recordings_csv(test::source_path("samples/recordings/reversal.csv"));
  double sp = 0, sm = 0;
  int np = 0, nm = 0;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const int s = rec.dir[0][i];
    (s > 0 ? sp : sm) += rec.e_um[0][i];
    (s > 0 ? np : nm) += 1;
  }
  EXPECT_NEAR(param(f, "value_um"), sp / np - sm / nm, 0.3);
  // Locate: the approach direction is where the structure is.
  EXPECT_EQ(res.at("mismatch").at(0).at("regressor"), "dir_x");
}

TEST(ExplainSamples, ThermalDriftUnderGeometryFixedBaselineProjectionForm) {
  const json truth = truth_of("thermal-drift");
  const json res =
      run_explain("samples/recordings/thermal-drift.csv", kM3, "samples/errors/hsu-3axis.csv");
  const json& f = expect_single_finding(res, truth);
  ASSERT_FALSE(f.empty());
  EXPECT_EQ(f.at("parameters").at("kind"), "offset");
  // Tolerances: amplitude 1 um, time constant 35 %.
  EXPECT_NEAR(param(f, "amplitude_um"), truth.at("amplitude_um").get<double>(), 1.0);
  EXPECT_NEAR(param(f, "tau_s"), truth.at("tau_s").get<double>(),
              0.35 * truth.at("tau_s").get<double>());
  // The mismatch points at time (or run) first.
  const std::string top = res.at("mismatch").at(0).at("regressor");
  EXPECT_TRUE(top == "t_s" || top == "run") << top;
  EXPECT_EQ(res.at("mismatch").at(0).at("component"), "e");  // projection form
}

TEST(ExplainSamples, ThermalExpansionAgainstATemperatureColumn) {
  const json truth = truth_of("thermal-temperature");
  const json res = run_explain("samples/recordings/thermal-temperature.csv", kM3,
                               "samples/errors/hsu-3axis.csv");
  const json& f = expect_single_finding(res, truth);
  ASSERT_FALSE(f.empty());
  EXPECT_EQ(f.at("parameters").at("kind"), truth.at("kind"));
  EXPECT_EQ(f.at("parameters").at("sensor"), truth.at("sensor"));
  EXPECT_NEAR(param(f, "um_per_k"), truth.at("um_per_k").get<double>(), 1.2);  // 10 %
}

TEST(ExplainSamples, CyclicUnderNoiseFittedBaseline) {
  const json truth = truth_of("cyclic");
  const json res = run_explain("samples/recordings/cyclic.csv", kM3);
  const json& f = expect_single_finding(res, truth);
  ASSERT_FALSE(f.empty());
  // Tolerances: period 1 %, amplitude 0.25 um, phase 15 degrees.
  EXPECT_NEAR(param(f, "period_mm"), truth.at("period_mm").get<double>(),
              0.01 * truth.at("period_mm").get<double>());
  EXPECT_NEAR(param(f, "amplitude_um"), truth.at("amplitude_um").get<double>(), 0.25);
  EXPECT_NEAR(angle_diff(param(f, "phase_deg"), truth.at("phase_deg").get<double>()), 0.0, 15.0);
  // Locate: binned means cannot see 30 periods over the travel; the periodic scan does.
  EXPECT_EQ(res.at("mismatch").at(0).at("regressor"), "x_mm (periodic)");
}

TEST(ExplainSamples, ServoLagAtThreeFeedsFixedBaseline) {
  const json truth = truth_of("servo-lag");
  const json res =
      run_explain("samples/recordings/servo-lag.csv", kM3, "samples/errors/hsu-3axis.csv");
  const json& f = expect_single_finding(res, truth);
  ASSERT_FALSE(f.empty());
  EXPECT_NEAR(param(f, "um_per_m_min"), truth.at("um_per_m_min").get<double>(), 0.08);  // 10 %
  EXPECT_TRUE(res.at("confounded").empty()) << "three feeds separate lag from lost motion";
}

TEST(ExplainSamples, SagUnderGeometryFixedBaselineVectorForm) {
  const json truth = truth_of("sag");
  const json res = run_explain("samples/recordings/sag.csv", kM3, "samples/errors/hsu-3axis.csv");
  const json& f = expect_single_finding(res, truth);
  ASSERT_FALSE(f.empty());
  EXPECT_EQ(f.at("parameters").at("input_axis"), truth.at("input_axis"));
  EXPECT_EQ(f.at("parameters").at("power").get<int>(), truth.at("power").get<int>());
  // Tolerances: coefficient 15 %, origin 15 mm.
  EXPECT_NEAR(param(f, "coefficient"), truth.at("coefficient").get<double>(),
              0.15 * std::abs(truth.at("coefficient").get<double>()));
  EXPECT_NEAR(param(f, "origin"), truth.at("origin").get<double>(), 15.0);
  EXPECT_EQ(res.at("mismatch").at(0).at("component"), "ez");
  EXPECT_EQ(res.at("mismatch").at(0).at("regressor"), "x_mm");
}

TEST(ExplainSamples, SetupShiftBetweenRunsFittedBaseline) {
  const json truth = truth_of("setup-shift");
  const json res = run_explain("samples/recordings/setup-shift.csv", kM3);
  const json& f = expect_single_finding(res, truth);
  ASSERT_FALSE(f.empty());
  const json& per = f.at("parameters").at("per_run_um");
  const json& want = truth.at("per_run_um");
  ASSERT_EQ(per.size(), want.size());
  for (std::size_t r = 0; r < want.size(); ++r)  // relative to the first run; 0.5 um each
    EXPECT_NEAR(per[r].get<double>(), want[r].get<double>() - want[0].get<double>(), 0.5)
        << "run " << r + 1;
  EXPECT_EQ(res.at("mismatch").at(0).at("regressor"), "run");
}

TEST(ExplainSamples, RotaryWobbleFiveAxisFixedBaseline) {
  const json truth = truth_of("rotary-wobble");
  const json res =
      run_explain("samples/recordings/rotary-wobble.csv", kM5, "samples/errors/lei-hsu-xyzac.csv");
  const json& f = expect_single_finding(res, truth);
  ASSERT_FALSE(f.empty());
  EXPECT_EQ(f.at("parameters").at("order").get<int>(), truth.at("order").get<int>());
  EXPECT_NEAR(param(f, "amplitude_urad"), truth.at("amplitude_urad").get<double>(), 2.0);  // 10 %
  EXPECT_EQ(res.at("mismatch").at(0).at("regressor"), "c_deg");
  EXPECT_NEAR(angle_diff(param(f, "phase_deg"), truth.at("phase_deg").get<double>()), 0.0, 10.0);
}

TEST(ExplainSamples, RotaryPositioningFiveAxisFixedBaseline) {
  const json truth = truth_of("rotary-positioning");
  const json res = run_explain("samples/recordings/rotary-positioning.csv", kM5,
                               "samples/errors/lei-hsu-xyzac.csv");
  const json& f = expect_single_finding(res, truth);
  ASSERT_FALSE(f.empty());
  EXPECT_EQ(f.at("parameters").at("order").get<int>(), truth.at("order").get<int>());
  EXPECT_NEAR(param(f, "amplitude_urad"), truth.at("amplitude_urad").get<double>(), 4.0);  // 10 %
  EXPECT_NEAR(angle_diff(param(f, "phase_deg"), truth.at("phase_deg").get<double>()), 0.0, 10.0);
}

TEST(ExplainSamples, FixedBaselineLackingTheXTableReportsItsPositioningError) {
  // The null recording against a baseline without the component errors of X:
  // explain must name the missing geometry (scale of X, EXX) and its curve
  // must follow what the missing table does to ex, computed here with the
  // exact model (both files), up to the instrument's constant.
  const std::string full_path = "samples/recordings/geometry-3axis.csv";
  std::istringstream full_text(slurp(test::source_path(full_path)));
  std::string no_x, line;
  bool skipping = false;
  while (std::getline(full_text, line)) {
    if (line.rfind("X,", 0) == 0) skipping = true;
    if (skipping && line.empty()) {
      skipping = false;
      continue;
    }
    if (!skipping) no_x += line + "\n";
  }
  const std::string no_x_path = temp_path("geometry-no-x.csv");
  std::ofstream(no_x_path) << no_x;
  const std::string out = temp_path("no_x.json");
  const test::CliResult r = test::run_volmap(
      "explain --recordings " + test::source_path("samples/recordings/null.csv") + " --machine " +
      test::source_path(kM3) + " --baseline " + no_x_path + " --json " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  const json res = json::parse(slurp(out));
  ASSERT_FALSE(res.at("findings").empty()) << res.dump(1);
  const json& f = res.at("findings").at(0);
  EXPECT_EQ(f.at("effect"), "scale");
  EXPECT_EQ(f.at("axis"), "X");
  EXPECT_EQ(f.at("parameters").at("error"), "EXX");

  const Machine m = load_machine_json(test::source_path(kM3));
  const ErrorModel with(m, load_errors_csv(test::source_path(full_path)));
  std::istringstream no_x_in(no_x);
  const ErrorModel without(m, read_errors_csv(no_x_in, "no-x.csv"));
  std::vector<double> diff, fitted;
  for (double x = 0; x <= 500; x += 25) {
    AxisVector u(3);
    u << x, 200, 150;
    diff.push_back((with.exact(u).dP_mm.x() - without.exact(u).dP_mm.x()) * 1e3);
    const double sc = (x - 250) / 250;
    fitted.push_back(param(f, "um_per_m") * x / 1000 + param(f, "quadratic_um") * sc * sc +
                     param(f, "cubic_um") * sc * sc * sc);
  }
  double offset = 0;
  for (std::size_t i = 0; i < diff.size(); ++i)
    offset += (diff[i] - fitted[i]) / static_cast<double>(diff.size());
  for (std::size_t i = 0; i < diff.size(); ++i)
    EXPECT_NEAR(fitted[i] + offset, diff[i], 0.6) << "X " << 25 * i;
}

// A fixed baseline that lacks squareness errors: explain names each missing
// location error (not a sag or a wobble standing in for them) and recovers
// its value, read here from the block removed from the baseline.
TEST(ExplainSamples, BaselineLackingSquarenessNamesEachMissingError) {
  std::ifstream in(test::source_path("samples/recordings/geometry-5axis.csv"));
  std::string text, line, names, values;
  while (std::getline(in, line)) {
    if (line == "EC0X,EB0Z,EA0Z") {
      names = line;
      std::getline(in, values);
      continue;
    }
    text += line + "\n";
  }
  ASSERT_FALSE(values.empty());
  std::map<std::string, double> truth;
  {
    std::stringstream ns(names), vs(values);
    std::string n, v;
    while (std::getline(ns, n, ',') && std::getline(vs, v, ',')) truth[n] = std::stod(v);
  }
  const std::string base = ::testing::TempDir() + "explain_test_nosq.csv";
  std::ofstream(base) << text;
  const std::string out = ::testing::TempDir() + "explain_test_nosq.json";
  const test::CliResult r = test::run_volmap(
      "explain --recordings " + test::source_path("samples/recordings/null-5axis.csv") +
      " --machine " + test::source_path("samples/machines/lei-hsu-xyzac.json") + " --baseline " +
      base + " --json " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream jf(out);
  const nlohmann::json j = nlohmann::json::parse(jf);
  // In ISO 230-1 meaning EC0X turns the X motion alone: on this probe-ball
  // plan X stays within +-40 mm, so its y error EC0X * x is 0.4 um at most
  // against 0.3 um of noise, which explain's fixed thresholds do not report
  // (issue #20 asks for detection at the statistical limit). What it
  // reports is right: the two squareness errors of Z with their values,
  // EC0X only with its value, nothing else.
  std::map<std::string, double> found;
  for (const auto& f : j["findings"]) {
    EXPECT_EQ(f["effect"], "squareness") << f.dump();
    found[f["parameters"]["error"].get<std::string>()] =
        f["parameters"]["value_urad"].get<double>();
  }
  for (const char* name : {"EA0Z", "EB0Z"}) {
    ASSERT_TRUE(found.count(name)) << name << j["findings"].dump();
    EXPECT_NEAR(found[name], truth[name], 1.0) << name;
  }
  if (found.count("EC0X")) {
    EXPECT_NEAR(found["EC0X"], truth["EC0X"], 1.0);
  }
  EXPECT_LE(found.size(), truth.size());
}

}  // namespace
}  // namespace volmap
