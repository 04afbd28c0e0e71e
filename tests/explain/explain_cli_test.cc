// volmap explain's interface: the JSON keys of the spec, deterministic
// bytes, bad input named by file and line, the tool of each row, the
// library against identify, the Cartesian machine, and the HTML report
// loading in headless Chromium without console errors.
#include "tests/explain/explain_test_support.h"
#include "tests/support/layout_probe.h"

namespace volmap {
namespace {

using namespace explain_testing;

// ------------------------------------------------------------- interface --

TEST(ExplainCli, JsonHasEveryKeyOfTheSpec) {
  // shared/spec/explain.md: keys that must be present, effect names of its table.
  const std::set<std::string> names{
      "reversal",      "thermal_drift",      "cyclic",     "servo_lag",    "sag",   "setup_shift",
      "rotary_wobble", "rotary_positioning", "squareness", "straightness", "scale", "angular"};
  for (const char* name : {"reversal", "setup-shift", "drift-one-direction", "reversal-one-feed"}) {
    SCOPED_TRACE(name);
    const json r = run_explain(std::string("samples/recordings/") + name + ".csv", kM3);
    EXPECT_EQ(r.at("format"), "volmap-explain/1");
    EXPECT_TRUE(r.at("observations").is_number_unsigned());
    for (const char* k : {"description", "rms_um", "heldout_rms_um"})
      EXPECT_TRUE(r.at("baseline").contains(k)) << k;
    for (const json& m : r.at("mismatch"))
      for (const char* k : {"component", "regressor", "where", "strength"})
        EXPECT_TRUE(m.contains(k)) << k;
    for (const json& f : r.at("findings")) {
      for (const char* k :
           {"effect", "axis", "parameters", "std_errors", "rms_before_um", "rms_after_um",
            "heldout_rms_before_um", "heldout_rms_after_um", "evidence", "explanation"})
        EXPECT_TRUE(f.contains(k)) << k;
      EXPECT_TRUE(f.at("evidence").contains("delta_bic"));
      EXPECT_TRUE(names.count(f.at("effect").get<std::string>())) << f.at("effect");
    }
    for (const json& c : r.at("confounded")) {
      for (const char* k : {"effects", "axis", "explanation", "remedy"})
        EXPECT_TRUE(c.contains(k)) << k;
      for (const json& e : c.at("effects")) EXPECT_TRUE(names.count(e.get<std::string>())) << e;
    }
    for (const char* k : {"rms_um", "heldout_rms_um"}) EXPECT_TRUE(r.at("final").contains(k)) << k;
  }
}

TEST(ExplainCli, SameInputsGiveTheSameBytes) {
  const std::string a = temp_path("det_a.json"), b = temp_path("det_b.json");
  const std::string args = "explain --recordings " +
                           test::source_path("samples/recordings/cyclic.csv") + " --machine " +
                           test::source_path(kM3);
  ASSERT_EQ(test::run_volmap(args + " --json " + a).status, 0);
  ASSERT_EQ(test::run_volmap(args + " --json " + b).status, 0);
  EXPECT_EQ(slurp(a), slurp(b));
  const test::CliResult out = test::run_volmap(args + " --json -");
  ASSERT_EQ(out.status, 0);
  EXPECT_EQ(out.out, slurp(a));  // --json - : the document alone on stdout
}

TEST(ExplainCli, BadInputNamesFileAndLineAndWritesNothing) {
  const std::string bad = temp_path("bad.csv");
  {
    std::ofstream o(bad);
    o << "# volmap recordings v1\nrun,x_mm,ex_um\n1,0,1.0\n1,abc,2.0\n";
  }
  const std::string out = temp_path("bad_out.json");
  std::remove(out.c_str());
  const test::CliResult r = test::run_volmap("explain --recordings " + bad + " --json " + out);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("bad.csv:4"), std::string::npos) << r.err;
  EXPECT_FALSE(std::ifstream(out).good());
  // output == input refused
  const test::CliResult same = test::run_volmap("explain --recordings " + bad + " --json " + bad);
  EXPECT_NE(same.status, 0);
  EXPECT_EQ(test::run_volmap("explain").status, 2);  // usage
}

TEST(ExplainLibrary, FittedBaselineAgreesWithIdentify) {
  // The fitted rigid-body baseline is the linearised model of `volmap
  // identify`: on a single run (identify's per-run setup offsets = explain's
  // constant per component) with the X positioning error as a cubic, both
  // leave the same residual and see the same rank.
  const Machine m = load_machine_json(test::source_path(kM3));
  const Recordings rec =
      load_recordings_csv(test::source_path("samples/recordings/drift-one-direction.csv"));
  IdentifyOptions io;
  io.components = {{"EXX", 3}};
  io.setup_offsets = true;
  const IdentifyResult id = identify(m, rec, io);
  ExplainOptions eo;
  eo.degree = 3;
  const ExplainResult ex = explain(m, rec, eo);
  EXPECT_NEAR(ex.baseline_rms_um, id.rms_after_um, 1e-4);
  EXPECT_NE(ex.baseline_description.find(std::to_string(id.rank) + " of "), std::string::npos)
      << ex.baseline_description << " vs rank " << id.rank;
}

TEST(ExplainLibrary, CartesianMachineHasTheRecordedAxes) {
  const Recordings rec =
      load_recordings_csv(test::source_path("tests/data/ecmc-b02/x_recordings.csv"));
  const Machine m = cartesian_machine_for(rec);
  ASSERT_EQ(m.axis_count(), 1);
  EXPECT_EQ(m.axis_order[0], AxisName::X);
  EXPECT_NEAR(m.limits[0].min, -20.0, 1e-9);
  EXPECT_NEAR(m.limits[0].max, 20.0, 1e-9);
}

// ------------------------------------------------------------------ report --

TEST(ExplainReport, SelfContainedHtmlLoadsInChromiumWithoutConsoleErrors) {
  const std::string html = temp_path("report.html");
  const test::CliResult r = test::run_volmap(
      "explain --recordings " + test::source_path("samples/recordings/reversal.csv") +
      " --machine " + test::source_path(kM3) + " --report " + html);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string page = slurp(html);
  EXPECT_NE(page.find("<svg"), std::string::npos);
  EXPECT_NE(page.find("id=\"summary\""), std::string::npos);
  EXPECT_EQ(page.find("<script"), std::string::npos);
  EXPECT_EQ(page.find("http://"),
            std::string::npos);  // no network (the SVG namespace is https-free below)
  EXPECT_EQ(page.find("https://"), std::string::npos);

  if (!test::chromium_or_skip()) GTEST_SKIP() << "chromium not installed";
  // Positive control: the check sees a console error when there is one.
  test::expect_console_check_sees_errors(temp_path("bad.html"));
  std::string dom, console;
  test::load_in_chromium(html, dom, console);
  EXPECT_TRUE(console.empty()) << console;
  EXPECT_NE(dom.find("<svg"), std::string::npos);
  EXPECT_NE(dom.find("reversal"), std::string::npos);
  // As laid out: the residuals against X position with round ticks between
  // the extremes, the fitted term drawn over the "before" residuals only,
  // the parameter written to the digits its standard error supports.
  const nlohmann::json plots = test::probe_plot_layout(html);
  test::expect_plots_read_at_a_glance(plots);
  ASSERT_EQ(plots.size(), 2u);
  EXPECT_EQ(test::plot_texts(plots, "x-label"),
            (std::vector<std::string>{"X position, mm", "X position, mm"}));
  EXPECT_EQ(test::plot_texts(plots, "y-label"),
            (std::vector<std::string>{"residual, µm", "residual, µm"}));
  for (int k = 0; k < 2; ++k) {
    std::size_t fit = 0;
    for (const auto& m : plots[k]["marks"]) fit += m[0] == "fit";
    EXPECT_EQ(fit > 0, k == 0) << k;
  }
  const test::CliResult js = test::run_volmap("explain --recordings " +
                                              test::source_path("samples/recordings/reversal.csv") +
                                              " --machine " + test::source_path(kM3) + " --json -");
  ASSERT_EQ(js.status, 0) << js.err;
  const auto doc = nlohmann::json::parse(js.out);
  const double b = doc["findings"][0]["parameters"]["value_um"],
               se = doc["findings"][0]["std_errors"]["value_um"];
  // Two significant digits of the error (0.1 <= se < 1 here: two decimals).
  ASSERT_TRUE(se >= 0.1 && se < 1.0) << se;
  char want[64];
  std::snprintf(want, sizeof want, "value %.2f ± %.2f µm", b, se);
  EXPECT_NE(page.find(want), std::string::npos) << want;
}

// The tool of each row (recordings.md tool_mm) sets the tool tip and with
// it the Abbe levers: a laser run made with a 300 mm tool on the Hsu sample
// (errors measured with its 100 mm tool), computed here from the exact
// model, is the fixed baseline to a few nm when the recording says
// tool_mm = 300, and misses by the tool's lever without the column.
// identify, which fits with the machine's tool, refuses such a recording
// with the file and line; a recording with no rows says so.
TEST(ExplainCli, ToolOfEachRowSetsTheLevers) {
  Machine m300 = test::sample_machine("hsu-3axis");
  m300.measurement_tool_length_mm = m300.tool_length_mm;  // the errors' tool
  m300.tool_length_mm = 300.0;
  const ErrorModel model(m300, load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv")));
  std::string with_tool = "# volmap recordings v1\nrun,x_mm,y_mm,z_mm,dir_x,ex_um,tool_mm\n";
  std::string without = "# volmap recordings v1\nrun,x_mm,y_mm,z_mm,dir_x,ex_um\n";
  for (int run = 1; run <= 2; ++run)
    for (int dir : {+1, -1})
      for (int k = 0; k <= 20; ++k) {
        const double x = dir > 0 ? 25.0 * k : 500.0 - 25.0 * k;
        AxisVector u(3);
        u << x, 200, 150;
        const double ex =
            model.exact(u, {static_cast<std::int8_t>(dir), 0, 0, 0, 0, 0}).dP_mm.x() * 1e3;
        const std::string row = fmt::format("{},{},200,150,{},{:.4f}", run, x, dir, ex);
        with_tool += row + ",300\n";
        without += row + "\n";
      }
  const std::string a = ::testing::TempDir() + "explain_test_tool300.csv";
  const std::string b = ::testing::TempDir() + "explain_test_tool_default.csv";
  std::ofstream(a) << with_tool;
  std::ofstream(b) << without;
  auto baseline_rms = [&](const std::string& rec, json* doc) {
    const test::CliResult r = test::run_volmap(
        "explain --recordings " + rec + " --machine " + test::source_path(kM3) + " --baseline " +
        test::source_path("samples/errors/hsu-3axis.csv") + " --json -");
    EXPECT_EQ(r.status, 0) << r.err;
    *doc = json::parse(r.out);
    return (*doc)["baseline"]["rms_um"].get<double>();
  };
  json da, db;
  const double rms_tool = baseline_rms(a, &da), rms_default = baseline_rms(b, &db);
  EXPECT_LT(rms_tool, 0.01) << da.dump(1);
  // The recording is rounded to 1e-4 um: anything explain finds is below it.
  for (const auto& f : da["findings"]) EXPECT_LT(f["rms_before_um"].get<double>(), 1e-4);
  EXPECT_GT(rms_default, 0.3) << db.dump(1);

  const test::CliResult r = test::run_volmap("identify --recordings " + a + " --machine " +
                                             test::source_path(kM3) + " -o " + a + ".out.csv");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(a + ":3:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("tool length 300"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(a + ".out.csv"));

  const std::string empty = ::testing::TempDir() + "explain_test_empty.csv";
  std::ofstream(empty) << "# volmap recordings v1\nrun,t_s,x_mm,ex_um\n";
  const test::CliResult e = test::run_volmap("explain --recordings " + empty);
  EXPECT_EQ(e.status, 1);
  EXPECT_NE(e.err.find("no observations"), std::string::npos) << e.err;
}

}  // namespace
}  // namespace volmap
