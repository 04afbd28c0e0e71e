// explain on circular tests (ISO 230-4, the ballbar): each pattern a
// ballbar diagnoses, simulated alone on an XY circle (r 100 mm, 1000
// mm/min, both directions, 0.2 um noise) and explained against an empty
// fixed baseline, is named with its number and standard error; G and H are
// checked against their hand derivations.
#include <Eigen/QR>

#include "tests/explain/explain_test_support.h"

namespace volmap {
namespace {

using namespace explain_testing;

constexpr double kNoise = 0.2, kRadius = 100, kFeed = 1000;

/// The circle simulated with `errors` and `effects` (JSON array text), and
/// explained against an empty baseline; at each of `heights_mm` (Z) a test.
ExplainResult ballbar(const ErrorSet& errors, const std::string& effects,
                      const std::vector<double>& heights_mm = {150}) {
  const Machine m = test::sample_machine("hsu-3axis");
  std::string tests;
  for (double z : heights_mm)
    tests += fmt::format(R"({}{{"type": "circular", "plane": "XY", "center": {{"X": 250, "Y": 200,
        "Z": {}}}, "radius_mm": {}, "feed_mm_min": {}, "cycles": 2}})",
                         tests.empty() ? "" : ", ", z, kRadius, kFeed);
  const Plan plan = test::plan_from_text(
      fmt::format(R"({{"format": "volmap-plan/1", "seed": 3, "noise_um": {}, "tests": [{}]}})",
                  kNoise, tests),
      m);
  const GainEvaluator g(m, Formulation::kIndependent);
  std::istringstream fx(R"({"format": "volmap-effects/1", "effects": )" + effects + "}");
  const EffectSet e = read_effects_json(fx, "fx.json", m, g);
  Recordings rec = simulate(ErrorModel(m, errors), plan, &e);
  rec.file = "ballbar.csv";
  static const ErrorSet empty;
  ExplainOptions opt;
  opt.baseline = &empty;
  return explain(m, rec, opt);
}

const Finding& only_finding(const ExplainResult& r, const std::string& effect) {
  EXPECT_EQ(r.findings.size(), 1u) << explain_text(r);
  for (const Finding& f : r.findings)
    if (f.effect == effect) return f;
  ADD_FAILURE() << "no " << effect << " finding:\n" << explain_text(r);
  static const Finding none;
  return none;
}

double parameter(const Finding& f, const std::string& name) {
  for (const auto& [k, v] : f.parameters)
    if (k == name) return v.get<double>();
  ADD_FAILURE() << "no parameter " << name;
  return NAN;
}

double std_error(const Finding& f, const std::string& name) {
  for (const auto& [k, v] : f.std_errors)
    if (k == name) return v;
  ADD_FAILURE() << "no standard error of " << name;
  return NAN;
}

// Band of pure noise on G or H: the extremes of 360 readings are about
// +-3 sigma; the tests allow 5 sigma on each side (sqrt 2 for a difference).
constexpr double kBand = 2 * 5 * kNoise;

TEST(ExplainCircular, BacklashIsAReversalWhoseHysteresisIsItsValue) {
  // s_X B/2 cos(phi) flips between the directions: the paths differ by
  // B |cos phi|, so H = B; within one direction the path swings by B too.
  const ExplainResult r =
      ballbar(ErrorSet{}, R"([{"effect": "reversal", "axis": "X", "value_um": 4}])");
  const Finding& f = only_finding(r, "reversal");
  EXPECT_EQ(f.axis, AxisName::X);
  EXPECT_NEAR(parameter(f, "value_um"), 4.0, 3 * std_error(f, "value_um"));
  ASSERT_EQ(r.circular_tests.size(), 2u);  // two cycles, each a ccw and a cw run
  for (const CircularTest& t : r.circular_tests) {
    EXPECT_EQ(t.plane, "XY");
    EXPECT_NEAR(t.radius_mm, kRadius, 1e-6);
    ASSERT_TRUE(t.h_um && t.h_after_um);
    EXPECT_NEAR(*t.h_um, 4.0, kBand * std::sqrt(2.0));
    EXPECT_LT(*t.h_after_um, kBand * std::sqrt(2.0));
    for (const CircularTest::Path& p : t.paths) EXPECT_LT(p.g_after_um, kBand);
  }
}

TEST(ExplainCircular, ServoMismatchIsTheLagOfOneAxisRelativeToTheOther) {
  // Y lags c um per m/min: -c F/1000 m_Y sin(phi) with m_Y = +-cos(phi):
  // (c F / 2000) sin 2 phi, turning with the direction: G = H = c F / 1000.
  const ExplainResult r =
      ballbar(ErrorSet{}, R"([{"effect": "servo_lag", "axis": "Y", "um_per_m_min": 2}])");
  const Finding& f = only_finding(r, "servo_lag");
  const double c = parameter(f, "um_per_m_min");
  const bool y = f.axis == AxisName::Y;  // which axis is named is the data's choice: the sign says
  EXPECT_NEAR(y ? c : -c, 2.0, 3 * std_error(f, "um_per_m_min"));
  EXPECT_NEAR(std::abs(parameter(f, "mismatch_ms")), 0.06 * 2.0, 3 * std_error(f, "mismatch_ms"));
  for (const CircularTest& t : r.circular_tests) {
    EXPECT_NEAR(*t.h_um, 2.0 * kFeed / 1000, kBand * std::sqrt(2.0));
    for (const CircularTest::Path& p : t.paths) EXPECT_NEAR(p.g_um, 2.0 * kFeed / 1000, kBand);
  }
}

TEST(ExplainCircular, SquarenessIsTheSameDiagonalEllipseInBothDirections) {
  // alpha x sin(phi) = (alpha R / 2) sin 2 phi about the centre: G = alpha R,
  // H only noise. At one height a roll of X that grows along X gives the
  // same ellipse through the tool's Abbe lever: confounded, and said so;
  // circles at two heights tell them apart.
  ErrorSet errors;
  errors.location["EC0X"] = 30e-6;
  const ExplainResult one = ballbar(errors, "[]");
  EXPECT_TRUE(one.findings.empty()) << explain_text(one);
  ASSERT_EQ(one.confounded.size(), 1u) << explain_text(one);
  EXPECT_EQ(
      std::set<std::string>(one.confounded[0].effects.begin(), one.confounded[0].effects.end()),
      (std::set<std::string>{"squareness", "angular"}));
  for (const CircularTest& t : one.circular_tests) {
    EXPECT_LT(*t.h_um, kBand * std::sqrt(2.0));
    for (const CircularTest::Path& p : t.paths) EXPECT_NEAR(p.g_um, 30e-6 * kRadius * 1000, kBand);
  }
  // Named as the location error EC0X (urad) or as the slope of EYX (um per
  // m of X travel): the same squareness, 30 either way.
  const ExplainResult two = ballbar(errors, "[]", {100, 250});
  const Finding& f = only_finding(two, "squareness");
  const std::string unit = f.parameters.at(1).first;
  ASSERT_TRUE(unit == "value_urad" || unit == "um_per_m") << unit;
  EXPECT_NEAR(parameter(f, unit), 30.0, 3 * std_error(f, unit)) << explain_text(two);
}

TEST(ExplainCircular, ScaleMismatchIsAnEllipseAlongTheAxis) {
  // EXX = k x: k x cos(phi) = (k R / 2) cos 2 phi about the centre: G = k R.
  // One circle shows only the difference of the two axes' scales (the
  // ballbar's own length is the reference), and at one height a pitch
  // through the Abbe lever looks the same: at two heights, the scale
  // mismatch of X against Y.
  const ErrorSet errors = test::errors_from_text(
      "X,EXX,EYX,EZX,EAX,EBX,ECX\n0,0,0,0,0,0,0\n500,10,0,0,0,0,0\n");  // 20 um per m
  const ExplainResult one = ballbar(errors, "[]");
  for (const CircularTest& t : one.circular_tests)
    for (const CircularTest::Path& p : t.paths) EXPECT_NEAR(p.g_um, 20e-3 * kRadius, kBand);
  const ExplainResult two = ballbar(errors, "[]", {100, 250});
  const Finding& f = only_finding(two, "scale");
  const double k = parameter(f, "um_per_m");
  EXPECT_NEAR(f.axis == AxisName::X ? k : -k, 20.0, 3 * std_error(f, "um_per_m"));
}

TEST(ExplainCircular, CyclicErrorOfTheScrewIsFoundAtItsPeriod) {
  const ExplainResult r = ballbar(
      ErrorSet{},
      R"([{"effect": "cyclic", "axis": "X", "period_mm": 20, "amplitude_um": 1, "phase_deg": 10}])");
  const Finding& f = only_finding(r, "cyclic");
  EXPECT_EQ(f.axis, AxisName::X);
  EXPECT_NEAR(parameter(f, "period_mm"), 20.0, 3 * std_error(f, "period_mm"));
  EXPECT_NEAR(parameter(f, "amplitude_um"), 1.0, 3 * std_error(f, "amplitude_um"));
}

TEST(ExplainCircular, ReportHasTheReadingsAndThePolarPlots) {
  const ExplainResult r =
      ballbar(ErrorSet{}, R"([{"effect": "reversal", "axis": "X", "value_um": 4}])");
  const json j = json::parse(explain_json(r).dump());
  ASSERT_EQ(j.at("circular_tests").size(), 2u);
  const json& t = j.at("circular_tests").at(0);
  EXPECT_EQ(t.at("paths").size(), 2u);
  EXPECT_EQ(t.at("paths").at(0).at("direction"), "ccw");
  EXPECT_EQ(t.at("paths").at(1).at("direction"), "cw");
  EXPECT_EQ(t.at("paths").at(0).at("readings"), 360);
  const std::string html = explain_html(r);
  EXPECT_NE(html.find("Circular tests (ISO 230-4)"), std::string::npos);
  EXPECT_GE(std::count(html.begin(), html.end(), '<'), 10);
  std::size_t polylines = 0;
  for (std::size_t p = html.find("<polyline"); p != std::string::npos;
       p = html.find("<polyline", p + 1))
    ++polylines;
  EXPECT_GE(polylines, 2u * (2 * 2 + 2));  // per test: 2 paths + 2 fits, then 2 residuals
  EXPECT_NE(explain_text(r).find("circular test XY r 100 mm"), std::string::npos);
}

TEST(ExplainCircular, BallbarSampleUnderTheMachinesGeometry) {
  // samples/recordings/ballbar: backlash of X 3 um and Y lagging 1 um per
  // m/min more than X, under the sample machine's geometric error (the
  // fixed baseline).
  const json res =
      run_explain("samples/recordings/ballbar.csv", kM3, "samples/errors/hsu-3axis.csv");
  const auto& f = res.at("findings");
  ASSERT_EQ(f.size(), 2u) << f.dump(1);
  EXPECT_EQ(f.at(0).at("effect"), "reversal");
  EXPECT_EQ(f.at(0).at("axis"), "X");
  EXPECT_NEAR(f.at(0).at("parameters").at("value_um").get<double>(), 3.0,
              3 * f.at(0).at("std_errors").at("value_um").get<double>());
  EXPECT_EQ(f.at(1).at("effect"), "servo_lag");
  // the lag of Y less that of X is 1, however the finding names the pair
  const double c = f.at(1).at("parameters").at("um_per_m_min").get<double>();
  const double y_less_x = f.at(1).at("axis") == "Y" ? c : -c;
  EXPECT_NEAR(y_less_x, 1.0, 3 * f.at(1).at("std_errors").at("um_per_m_min").get<double>());
  EXPECT_NE(f.at(1).at("explanation").get<std::string>().find("Y lags"), std::string::npos);
  ASSERT_EQ(res.at("circular_tests").size(), 2u);
  for (const auto& t : res.at("circular_tests")) {
    EXPECT_GT(t.at("h_um").get<double>(), 3.0);  // the backlash opens the two directions
    EXPECT_LT(t.at("h_after_um").get<double>(), 2 * 5 * 0.3 * std::sqrt(2.0));
  }
}

TEST(ExplainCircular, ReversalSpikeAndLateralPlayAreTheirOwnForms) {
  // A spike: X stays 5 um behind after each reversal and catches up over
  // 3 mm; lateral play: X shifts 2 um with the direction of Y. Radially:
  // -s_X 5 exp(-d_X / 3) cos(phi) at the 0 and 180 degree points, and
  // s_Y cos(phi) at the 90 and 270 degree points, with opposite signs in
  // the two directions.
  const json fx = json::parse(R"([
      {"effect": "reversal", "axis": "X", "kind": "spike", "value_um": 5, "length_mm": 3},
      {"effect": "reversal", "axis": "X", "kind": "lateral", "input_axis": "Y", "value_um": 2}])");
  const ExplainResult r = ballbar(ErrorSet{}, fx.dump());
  ASSERT_EQ(r.findings.size(), 2u) << explain_text(r);
  std::map<std::string, const Finding*> by_kind;
  for (const Finding& f : r.findings) {
    EXPECT_EQ(f.effect, "reversal");
    EXPECT_EQ(f.axis, AxisName::X);
    by_kind[f.parameters.at(0).second.get<std::string>()] = &f;
  }
  ASSERT_TRUE(by_kind.count("spike") && by_kind.count("lateral")) << explain_text(r);
  const Finding& spike = *by_kind["spike"];
  EXPECT_NEAR(parameter(spike, "value_um"), 5.0, 3 * std_error(spike, "value_um"));
  EXPECT_NEAR(parameter(spike, "length_mm"), 3.0, 3 * std_error(spike, "length_mm"));
  const Finding& lateral = *by_kind["lateral"];
  EXPECT_NEAR(parameter(lateral, "value_um"), 2.0, 3 * std_error(lateral, "value_um"));
  for (const CircularTest& t : r.circular_tests) EXPECT_LT(*t.h_after_um, kBand * std::sqrt(2.0));
}

}  // namespace
}  // namespace volmap
