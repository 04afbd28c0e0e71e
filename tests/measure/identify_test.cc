// volmap identify: recovery of known link errors of the X'Y'ZA'C' sample
// from simulated probe-ball tests (exactly without noise, within three
// standard errors with noise), identifiability flags with named
// combinations, component curves, setup offsets, the errors CSV it writes,
// and the command line (refusals, nothing written on failure).
#include "core/measure/identify.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/measure/effects.h"
#include "core/measure/plan.h"
#include "core/measure/simulate.h"
#include "core/model/errors_csv.h"
#include "core/model/gain_evaluator.h"
#include "core/model/machine_json.h"
#include "core/model/sensitivity.h"
#include "tests/support/cli_run.h"
#include "tests/support/plans.h"
#include "tests/support/samples.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

Machine machine(const std::string& name) { return test::sample_machine(name); }
ErrorSet errors_from(const std::string& text) { return test::errors_from_text(text); }
Plan plan_from(const std::string& json, const Machine& m) { return test::plan_from_text(json, m); }
std::string sample_text(const std::string& rel) {
  std::ifstream in(test::source_path("samples/" + rel));
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The sample's errors split into its location blocks and its component blocks.
std::string blocks_of_sample(bool location) {
  const std::string text = sample_text("errors/lei-hsu-xyzac.csv");
  std::string out = "# volmap component errors v1\n";
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find("\n\n", start);
    if (end == std::string::npos) end = text.size();
    const std::string block = text.substr(start, end - start);
    if (!block.empty() && block[0] != '#' && (block[0] == 'E') == location)
      out += "\n" + block + "\n";
    start = end + 2;
  }
  return out;
}

// Truth: the sample's location errors (um, urad), errors.md values.
const std::map<std::string, double> kTruth = {{"EC0X", 10.0},  {"EB0Z", -12.0}, {"EA0Z", 18.0},
                                              {"EY0A", 35.0},  {"EZ0A", -22.0}, {"EB0A", 60.0},
                                              {"EC0A", -45.0}, {"EX0C", 28.0},  {"EY0C", -40.0},
                                              {"EA0C", 80.0},  {"EB0C", -35.0}, {"EC0C", 0.0}};

std::vector<std::string> truth_names() {
  std::vector<std::string> n;
  for (const auto& [k, v] : kTruth) n.push_back(k);
  return n;
}

const std::string kTwoBalls = R"({"seed": SEED, "noise_um": NOISE, "tests": [{"type": "probe_ball",
    "centers_mm": [[40, 0, 0], [0, 30, 80]], "a_deg": {"from": -90, "to": 0, "step": 30},
    "c_deg": {"from": 0, "to": 315, "step": 45}}]})";

std::string two_balls(int seed, double noise) {
  std::string s = kTwoBalls;
  s.replace(s.find("SEED"), 4, std::to_string(seed));
  s.replace(s.find("NOISE"), 5, std::to_string(noise));
  return s;
}

const IdentifiedParameter& param(const IdentifyResult& r, const std::string& name) {
  for (const IdentifiedParameter& p : r.parameters)
    if (p.name == name) return p;
  throw std::runtime_error("no parameter " + name);
}

TEST(GainEvaluator, EqualsErrorGainsEverywhere) {
  for (const char* name : {"hsu-3axis", "lei-hsu-xyzac"}) {
    const Machine m = machine(name);
    for (Formulation f : {Formulation::kDependent, Formulation::kIndependent}) {
      GainEvaluator g(m, f);
      for (int k = 0; k < 5; ++k) {
        AxisVector u(m.axis_count());
        for (int i = 0; i < m.axis_count(); ++i) {
          const AxisLimits& L = m.limits[static_cast<std::size_t>(i)];
          const double s = 0.13 + 0.19 * k + 0.07 * i;
          u[i] = L.unlimited ? 6.0 * s : L.min + (L.max - L.min) * (s - std::floor(s));
        }
        g.at(u);
        const std::vector<ErrorGain> ref = error_gains(m, f, u);
        ASSERT_EQ(ref.size(), g.names().size());
        for (std::size_t j = 0; j < ref.size(); ++j) {
          EXPECT_EQ(ref[j].name, g.names()[j]);
          EXPECT_LT((ref[j].dP - g.dP(static_cast<int>(j))).norm(), 1e-12) << ref[j].name;
          EXPECT_LT((ref[j].dQ - g.dQ(static_cast<int>(j))).norm(), 1e-12) << ref[j].name;
        }
      }
    }
  }
}

// The sphere test simulated with the sample's location errors in ISO 230-1
// meaning (the file's, by default) and identified back in it.
TEST(Identify, RecoversSampleLocationErrorsExactlyWithoutNoise) {
  const Machine m = machine("lei-hsu-xyzac");
  const ErrorModel truth(m, errors_from(blocks_of_sample(true)));
  const Recordings rec = simulate(truth, plan_from(two_balls(1, 0.0), m), nullptr);
  IdentifyOptions opt;
  opt.parameters = truth_names();
  const IdentifyResult r = identify(m, rec, opt);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.rank, 12);
  EXPECT_TRUE(r.unidentifiable.empty());
  for (const auto& [name, value] : kTruth) {
    const IdentifiedParameter& p = param(r, name);
    EXPECT_TRUE(p.identifiable) << name;
    EXPECT_NEAR(p.estimate, value, 1e-6) << name;
  }
  EXPECT_LT(r.rms_after_um, 1e-6);
  EXPECT_GT(r.rms_before_um, 10.0);

  // The first-order solution alone (one step) is not exact: the iterations
  // on the exact model are what reach 1e-6 um.
  opt.max_iterations = 1;
  const IdentifyResult one = identify(m, rec, opt);
  double worst = 0;
  for (const auto& [name, value] : kTruth)
    worst = std::max(worst, std::abs(param(one, name).estimate - value));
  EXPECT_GT(worst, 1e-5);
}

TEST(Identify, KnownComponentErrorsHeldFixedLinkErrorsRecovered) {
  // Lei & Hsu's workflow: motional errors measured by laser (the sample's
  // component tables), link errors identified from the probe-ball test.
  const Machine m = machine("lei-hsu-xyzac");
  const ErrorModel truth(m, load_errors_csv(test::source_path("samples/errors/lei-hsu-xyzac.csv")));
  const Recordings rec = simulate(truth, plan_from(two_balls(1, 0.0), m), nullptr);
  const ErrorSet known = errors_from(blocks_of_sample(false));
  IdentifyOptions opt;
  opt.parameters = truth_names();
  opt.known = &known;
  const IdentifyResult r = identify(m, rec, opt);
  for (const auto& [name, value] : kTruth)
    EXPECT_NEAR(param(r, name).estimate, value, 1e-6) << name;
}

TEST(Identify, WithNoiseWithinThreeStandardErrors) {
  const Machine m = machine("lei-hsu-xyzac");
  const ErrorModel truth(m, errors_from(blocks_of_sample(true)));
  for (int seed : {11, 12, 13}) {
    const Recordings rec = simulate(truth, plan_from(two_balls(seed, 0.5), m), nullptr);
    IdentifyOptions opt;
    opt.parameters = truth_names();
    const IdentifyResult r = identify(m, rec, opt);
    EXPECT_NEAR(r.sigma_um, 0.5, 0.1) << "seed " << seed;
    for (const auto& [name, value] : kTruth) {
      const IdentifiedParameter& p = param(r, name);
      ASSERT_TRUE(std::isfinite(p.std_error));
      EXPECT_GT(p.std_error, 0.0);
      EXPECT_LT(std::abs(p.estimate - value), 3.0 * p.std_error)
          << name << " seed " << seed << ": " << p.estimate << " +- " << p.std_error;
    }
  }
}

/// One ball, only C turning, A at 0; the sample's location errors in the
/// given meaning, identified in it.
IdentifyResult single_ball_c_only(LocationConvention convention) {
  const Machine m = machine("lei-hsu-xyzac");
  ErrorSet e = errors_from(blocks_of_sample(true));
  e.convention = convention;
  const ErrorModel truth(m, e);
  const Recordings rec =
      simulate(truth,
               plan_from(R"({"tests": [{"type": "probe_ball", "center_mm": [40, 0, 0],
      "a_deg": 0, "c_deg": {"from": 0, "to": 330, "step": 30}}]})",
                         m),
               nullptr);
  IdentifyOptions opt;
  opt.parameters = truth_names();
  opt.convention = convention;
  return identify(m, rec, opt);
}

// ISO 230-1: at A = 0 the A line's offsets and tilts move nothing, so no
// observation sees them; the plan has to turn A.
TEST(Identify, SingleBallOnlyCRotationSeesNoALineErrorInIso) {
  const IdentifyResult r = single_ball_c_only(LocationConvention::kIso230);
  for (const char* name : {"EY0A", "EZ0A", "EB0A", "EC0A"}) {
    EXPECT_FALSE(param(r, name).identifiable) << name;
    bool named = false;
    for (const UnidentifiableCombination& u : r.unidentifiable) {
      if (u.fixed != name) continue;
      named = true;
      EXPECT_EQ(u.terms.size(), 1u) << u.text;
      EXPECT_NE(u.explanation.find("no observation is sensitive"), std::string::npos);
      EXPECT_NE(u.remedy.find("move A"), std::string::npos) << u.remedy;
    }
    EXPECT_TRUE(named) << name;
  }
}

// Link errors: the A line's y offset moves the C line with it when A stands
// at 0, so EY0A acts exactly like EY0C.
TEST(Identify, SingleBallOnlyCRotationFlagsTheACombination) {
  const IdentifyResult r = single_ball_c_only(LocationConvention::kLink);
  EXPECT_LT(r.rank, 12);
  // EY0A (the A line's y offset) acts exactly like EY0C when A stands at 0.
  const IdentifiedParameter& ey0a = param(r, "EY0A");
  EXPECT_FALSE(ey0a.identifiable);
  EXPECT_EQ(ey0a.estimate, 0.0);
  bool named = false;
  for (const UnidentifiableCombination& u : r.unidentifiable) {
    if (u.fixed != "EY0A") continue;
    named = true;
    ASSERT_GE(u.terms.size(), 2u);
    bool with_ey0c = false;
    for (const auto& [n, c] : u.terms)
      if (n == "EY0C") {
        with_ey0c = true;
        EXPECT_NEAR(c, -1.0, 1e-6);  // +1 um on one, -1 um on the other: the same line
      }
    EXPECT_TRUE(with_ey0c) << u.text;
    EXPECT_NE(u.explanation.find("A does not move"), std::string::npos) << u.explanation;
    EXPECT_NE(u.remedy.find("add positions of A"), std::string::npos) << u.remedy;
  }
  EXPECT_TRUE(named);
  for (const IdentifiedParameter& p : r.parameters)
    if (!p.identifiable) {
      EXPECT_TRUE(std::isnan(p.std_error)) << p.name;
    }
  const nlohmann::ordered_json j = identify_report_json(r);
  bool in_json = false;
  for (const auto& p : j["parameters"]) {
    if (p["name"] != "EY0A") continue;
    in_json = true;
    EXPECT_EQ(p["status"], "not_identifiable");
    EXPECT_TRUE(p["estimate"].is_null());
  }
  EXPECT_TRUE(in_json);
}

// --known with component errors only (a laser file, no convention line)
// serves a fit in either meaning; with location errors it must be in the
// fit's meaning.
TEST(Identify, KnownErrorsAndTheFitsMeaning) {
  const Machine m = machine("lei-hsu-xyzac");
  ErrorSet truth = errors_from(blocks_of_sample(true));
  truth.convention = LocationConvention::kLink;
  const Recordings rec = simulate(ErrorModel(m, truth), plan_from(two_balls(1, 0.0), m), nullptr);
  ErrorSet laser = errors_from(blocks_of_sample(false));
  ASSERT_TRUE(laser.location.empty());
  IdentifyOptions opt;
  opt.convention = LocationConvention::kLink;
  opt.known = &laser;
  opt.parameters = truth_names();
  EXPECT_NO_THROW(identify(m, rec, opt));
  ErrorSet iso_location = errors_from("EC0X\n10\n");
  opt.known = &iso_location;
  opt.parameters = {"EX0C"};
  EXPECT_THROW(identify(m, rec, opt), std::invalid_argument);
}

TEST(Identify, EveryIsoLocationErrorIsIdentifiable) {
  const Machine m = machine("lei-hsu-xyzac");
  const ErrorModel truth(m, errors_from(blocks_of_sample(true)));
  const Recordings rec = simulate(truth, plan_from(two_balls(1, 0.0), m), nullptr);
  const IdentifyResult r = identify(m, rec, IdentifyOptions{});
  for (const UnidentifiableCombination& u : r.unidentifiable) ADD_FAILURE() << u.text;
  for (const auto& [name, value] : kTruth) EXPECT_NEAR(param(r, name).estimate, value, 1e-6);
  EXPECT_NEAR(param(r, "EA0A").estimate, 0.0, 1e-6);
  EXPECT_NEAR(param(r, "EC0C").estimate, 0.0, 1e-6);
}

TEST(Identify, RedundantNamesAreFlaggedAsSuch) {
  // Link errors: EA0A (A zero) and EA0C (C tilt about x) are one error
  // motion (the C frame turned about x moves like A's zero): every location
  // error of the model, the default, contains the pair. In ISO 230-1 the C
  // line's tilt turns about the actual line and moves nothing at C = 0, so
  // the two differ (Identify.EveryIsoLocationErrorIsIdentifiable).
  const Machine m = machine("lei-hsu-xyzac");
  ErrorSet e = errors_from(blocks_of_sample(true));
  e.convention = LocationConvention::kLink;
  const ErrorModel truth(m, e);
  const Recordings rec = simulate(truth, plan_from(two_balls(1, 0.0), m), nullptr);
  IdentifyOptions opt;
  opt.convention = LocationConvention::kLink;
  const IdentifyResult r = identify(m, rec, opt);
  ASSERT_EQ(r.unidentifiable.size(), 1u);
  EXPECT_EQ(r.unidentifiable[0].fixed, "EA0A");
  EXPECT_NE(r.unidentifiable[0].explanation.find("redundancy of the parameter set"),
            std::string::npos);
  EXPECT_NEAR(param(r, "EA0C").estimate, 80.0, 1e-6);
  EXPECT_FALSE(param(r, "EA0A").identifiable);
}

TEST(Identify, ComponentCurveAndErrorsCsvLoadsBack) {
  // Three-axis sample, a linear positioning error of X (zero at mid-travel,
  // +-5 um at the ends: EXX(x) = 5 (x - 250) / 250) and the squareness
  // errors; a grid records ex, ey, ez.
  const Machine m = machine("hsu-3axis");
  const ErrorModel truth(m, errors_from("X,EXX\n0,-5\n500,5\n\nEC0X,EB0Z,EA0Z\n12,-5,3\n"));
  const Recordings rec = simulate(truth,
                                  plan_from(R"({"tests": [{"type": "grid", "axes": {"X": {"from": 0,
      "to": 500, "step": 100}, "Y": [0, 200, 400], "Z": [0, 300]}}]})",
                                            m),
                                  nullptr);
  IdentifyOptions opt;
  opt.components = {{"EXX", 2}};
  const IdentifyResult r = identify(m, rec, opt);
  EXPECT_NEAR(param(r, "EXX.p1").estimate, 5.0, 1e-6);
  EXPECT_NEAR(param(r, "EXX.p2").estimate, 0.0, 1e-6);
  EXPECT_NEAR(param(r, "EC0X").estimate, 12.0, 1e-6);
  EXPECT_NEAR(param(r, "EB0Z").estimate, -5.0, 1e-6);
  EXPECT_NEAR(param(r, "EA0Z").estimate, 3.0, 1e-6);

  std::ostringstream a, b;
  write_identified_errors_csv(a, r, {{"machine", "hsu-3axis.json"}}, "");
  write_identified_errors_csv(b, r, {{"machine", "hsu-3axis.json"}}, "");
  EXPECT_EQ(a.str(), b.str());
  const ErrorSet back = errors_from(a.str());
  EXPECT_NEAR(back.location_error("EC0X"), 12e-6, 1e-12);
  EXPECT_NEAR(back.location_error("EA0Z"), 3e-6, 1e-12);
  std::array<double, kComponentCount> v;
  evaluate_axis(*back.errors_of(AxisName::X), 100.0, 0, OutsidePolicy::kError, v);
  EXPECT_NEAR(v[0], -3e-3, 1e-9);  // mm
}

TEST(Identify, SetupOffsetsPerRun) {
  const Machine m = machine("hsu-3axis");
  const ErrorModel truth(m, errors_from("EC0X,EB0Z,EA0Z\n12,-5,3\n"));
  const Plan plan =
      plan_from(R"({"tests": [{"type": "grid", "axes": {"X": [0, 250, 500], "Y": [0, 400],
      "Z": [0, 300]}, "cycles": 2}]})",
                m);
  std::istringstream fx(
      R"({"effects": [{"effect": "setup_shift", "per_run_um": [[1, 2, 3], [-4, 5, 0.5]]}]})");
  const GainEvaluator g(m, Formulation::kIndependent);
  const EffectSet e = read_effects_json(fx, "fx.json", m, g);
  const Recordings rec = simulate(truth, plan, &e);
  IdentifyOptions opt;
  opt.setup_offsets = true;
  const IdentifyResult r = identify(m, rec, opt);
  EXPECT_NEAR(param(r, "offset_x.run1").estimate, 1.0, 1e-6);
  EXPECT_NEAR(param(r, "offset_z.run2").estimate, 0.5, 1e-6);
  EXPECT_NEAR(param(r, "EC0X").estimate, 12.0, 1e-6);
}

// ---- command line --------------------------------------------------------

using Result = test::CliResult;

Result run(const std::string& args) { return test::run_volmap(args); }

bool exists(const std::string& p) { return std::ifstream(p).good(); }

TEST(IdentifyCli, SimulateThenIdentifyThroughFiles) {
  const std::string dir = ::testing::TempDir() + "volmap_id_" + std::to_string(getpid()) + "_";
  const std::string machine_path = test::source_path("samples/machines/lei-hsu-xyzac.json");
  const std::string rec_path = dir + "probe.csv", out_path = dir + "identified.csv";
  Result s = run("simulate --machine " + machine_path + " --errors " +
                 test::source_path("samples/errors/lei-hsu-xyzac.csv") + " --plan " +
                 test::source_path("samples/plans/probe-ball.json") + " -o -");
  ASSERT_EQ(s.status, 0) << s.err;
  EXPECT_EQ(s.out.rfind("# volmap recordings v1\n", 0), 0u);
  s = run("simulate --machine " + machine_path + " --errors " +
          test::source_path("samples/errors/lei-hsu-xyzac.csv") + " --plan " +
          test::source_path("samples/plans/probe-ball.json") + " -o " + rec_path);
  ASSERT_EQ(s.status, 0) << s.err;

  const Result r = run("identify --machine " + machine_path + " --recordings " + rec_path + " -o " +
                       out_path + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["format"], "volmap-identify/1");
  for (const char* k : {"parameters", "rank", "condition_number", "unidentifiable", "correlation",
                        "strong_correlations", "rms_after_um", "sigma_um"})
    EXPECT_TRUE(doc.contains(k)) << k;
  EXPECT_NO_THROW((void)load_errors_csv(out_path));

  // Output equal to an input: refused, exit 1, the input untouched.
  const std::string before = [&] {
    std::ifstream in(rec_path);
    std::stringstream t;
    t << in.rdbuf();
    return t.str();
  }();
  const Result same =
      run("identify --machine " + machine_path + " --recordings " + rec_path + " -o " + rec_path);
  EXPECT_EQ(same.status, 1);
  EXPECT_NE(same.err.find("the output is also an input"), std::string::npos) << same.err;
  const std::string after = [&] {
    std::ifstream in(rec_path);
    std::stringstream t;
    t << in.rdbuf();
    return t.str();
  }();
  EXPECT_EQ(before, after);

  // A bad recording: one line naming file:line, nothing written.
  const std::string bad = dir + "bad.csv", none = dir + "none.csv";
  std::ofstream(bad) << "x_mm,ex_um\n0,1\n5,x\n";
  const Result b =
      run("identify --machine " + machine_path + " --recordings " + bad + " -o " + none);
  EXPECT_EQ(b.status, 1);
  EXPECT_NE(b.err.find(bad + ":3:"), std::string::npos) << b.err;
  EXPECT_EQ(std::count(b.err.begin(), b.err.end(), '\n'), 1);
  EXPECT_FALSE(exists(none));

  // A plan with a point outside travel: nothing written.
  const std::string plan = dir + "plan.json";
  std::ofstream(plan) << R"({"tests": [{"type": "grid", "axes": {"X": [0, 400]}}]})";
  const Result p = run("simulate --machine " + machine_path + " --errors " +
                       test::source_path("samples/errors/lei-hsu-xyzac.csv") + " --plan " + plan +
                       " -o " + none);
  EXPECT_EQ(p.status, 1);
  EXPECT_NE(p.err.find(plan + ":/tests/0"), std::string::npos) << p.err;
  EXPECT_FALSE(exists(none));
  for (const std::string& f : {rec_path, out_path, bad, plan}) std::remove(f.c_str());
}

// A real one-axis laser recording (ISO 230-2, X only) says nothing about the
// three-axis sample's squareness errors: identify reports all three as not
// identifiable and estimates nothing. (It crashed here, SIGSEGV in Eigen's
// eigensolver on the 0 x 0 normal matrix of the estimated parameters.)
TEST(Identify, NothingIdentifiableIsReportedNotACrash) {
  const Recordings rec =
      load_recordings_csv(test::source_path("tests/data/ecmc-b02/x_recordings.csv"));
  const IdentifyResult r = identify(machine("hsu-3axis"), rec, IdentifyOptions{});
  EXPECT_EQ(r.rank, 0);
  ASSERT_EQ(r.parameters.size(), 3u);
  for (const IdentifiedParameter& p : r.parameters) {
    EXPECT_FALSE(p.identifiable) << p.name;
    EXPECT_EQ(p.estimate, 0.0) << p.name;
  }
  EXPECT_EQ(r.rms_after_um, r.rms_before_um);
}

}  // namespace
}  // namespace volmap
