// volmap verify --report: the deviation profile (exact maxima per bin under
// doubling, the worst lines) against hand-made sample streams, and the page
// on the sample programs: its numbers are verify's own (--json), it is
// self-contained, loads in Chromium without console messages, and an output
// onto an input is refused with the input untouched.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "postproc/verify/deviation_profile.h"
#include "tests/support/browser.h"
#include "tests/support/cli_run.h"
#include "tests/support/layout_probe.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

namespace fs = std::filesystem;
using post::DeviationProfile;

std::string temp_path(const std::string& name) {
  return ::testing::TempDir() + "verify_report_test_" + name;
}

TEST(DeviationProfile, BinsKeepTheExactMaximumWhileTheyDouble) {
  DeviationProfile p;
  // 10 000 mm of path, a sample every 0.5 mm, deviation a known function;
  // one spike of 7 um at 6 123.5 mm on line 4242.
  auto dev = [](double s) { return 1.0 + 0.5 * std::sin(s / 100.0); };
  for (int k = 0; k <= 20000; ++k) {
    const double s = 0.5 * k;
    const int line = 1 + k / 10;
    p.add(s, s == 6123.5 ? 7.0 : dev(s), 0.0, line);
  }
  // 10 000 mm in at most 512 bins: 1 mm doubled five times = 32 mm.
  EXPECT_DOUBLE_EQ(p.bin_width_mm(), 32.0);
  EXPECT_LE(p.bins().size(), static_cast<size_t>(DeviationProfile::kMaxBins));
  EXPECT_DOUBLE_EQ(p.path_length_mm(), 10000.0);
  std::uint64_t n = 0;
  for (size_t b = 0; b < p.bins().size(); ++b) {
    n += p.bins()[b].samples;
    // The maximum of the samples in [32 b, 32 (b + 1)), computed here.
    double expect = 0;
    int expect_line = 0;
    for (int k = 0; k <= 20000; ++k) {
      const double s = 0.5 * k;
      if (s < 32.0 * b || s >= 32.0 * (b + 1)) continue;
      const double d = s == 6123.5 ? 7.0 : dev(s);
      if (d > expect) expect = d, expect_line = 1 + k / 10;
    }
    EXPECT_DOUBLE_EQ(p.bins()[b].max_um, expect) << b;
    EXPECT_EQ(p.bins()[b].line, expect_line) << b;
  }
  EXPECT_EQ(n, 20001u);
  const auto worst = p.worst_lines();
  ASSERT_EQ(worst.size(), static_cast<size_t>(DeviationProfile::kWorstLines));
  EXPECT_EQ(worst[0].line, 1 + 12247 / 10);  // the spike: sample 12247 = 6123.5 mm
  EXPECT_DOUBLE_EQ(worst[0].max_um, 7.0);
  for (size_t i = 1; i < worst.size(); ++i) EXPECT_GE(worst[i - 1].max_um, worst[i].max_um);
  EXPECT_FALSE(p.has_angles());
}

TEST(DeviationProfile, WorstLinesAreThePerLineMaxima) {
  DeviationProfile p;
  // Lines 1..30, line L's samples peak at (L * 7) % 31 um.
  double s = 0;
  for (int line = 1; line <= 30; ++line)
    for (int k = 0; k < 5; ++k)
      p.add(s += 1.0, (k == 2 ? 1.0 : 0.5) * ((line * 7) % 31), 2.0, line);
  const auto w = p.worst_lines();
  ASSERT_EQ(w.size(), 10u);
  // The ten largest of (L * 7) % 31 for L = 1..30 are 30, 29, ..., 21.
  for (int i = 0; i < 10; ++i) {
    EXPECT_DOUBLE_EQ(w[static_cast<size_t>(i)].max_um, 30.0 - i);
    EXPECT_EQ((w[static_cast<size_t>(i)].line * 7) % 31, 30 - i);
  }
  EXPECT_TRUE(p.has_angles());
}

struct Case {
  const char* machine;
  const char* errors;
  const char* program;
  const char* placement;
  bool five_axis;
};

void check_report(const Case& c) {
  SCOPED_TRACE(c.program);
  const std::string m = test::source_path(c.machine), e = test::source_path(c.errors),
                    in = test::source_path(c.program);
  const std::string out = temp_path(fs::path(c.program).stem().string() + "-out.ngc");
  const std::string html = temp_path(fs::path(c.program).stem().string() + ".html");
  ASSERT_EQ(test::run_volmap("post --machine " + m + " --errors " + e + " " + c.placement + " " +
                             in + " -o " + out)
                .status,
            0);
  const std::string args = "verify --machine " + m + " --errors " + e + " " + c.placement +
                           " --nominal " + in + " --program " + out;
  const test::CliResult js = test::run_volmap(args + " --json");
  ASSERT_EQ(js.status, 0) << js.err;
  const test::CliResult r = test::run_volmap(args + " --report " + html);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string page = test::read_text_file(html);
  const auto doc = nlohmann::json::parse(js.out);
  // The summary carries verify's own figures.
  for (const char* run : {"before", "after"}) {
    char cell[64];
    std::snprintf(cell, sizeof cell, "<td>%.3f</td>", doc[run]["max_um"].get<double>());
    EXPECT_NE(page.find(cell), std::string::npos) << run << " " << cell;
  }
  EXPECT_NE(page.find("id=\"summary\""), std::string::npos);
  EXPECT_NE(page.find("<polyline"), std::string::npos);
  EXPECT_EQ(page.find("<script"), std::string::npos);
  EXPECT_EQ(page.find("http"), std::string::npos);  // nothing fetched
  EXPECT_EQ(page.find("urad") != std::string::npos || page.find("&#181;rad") != std::string::npos,
            c.five_axis);
  if (test::chromium_or_skip()) {
    test::expect_console_check_sees_errors(temp_path("bad.html"));
    std::string dom, console;
    test::load_in_chromium(html, dom, console);
    EXPECT_TRUE(console.empty()) << console;
    EXPECT_NE(dom.find("<svg"), std::string::npos);
    // As laid out: round path lengths, decades of deviation, the last label
    // inside the plot, the legend clear of the curves.
    const nlohmann::json plots = test::probe_plot_layout(html);
    test::expect_plots_read_at_a_glance(plots);
    ASSERT_EQ(plots.size(), c.five_axis ? 2u : 1u);
    for (const auto& p : plots) EXPECT_FALSE(p["legend"].is_null());
    EXPECT_EQ(test::plot_texts(plots, "x-label")[0], "path length, mm");
    EXPECT_EQ(test::plot_texts(plots, "y-label")[0], "largest deviation, µm");
    if (c.five_axis) {
      EXPECT_EQ(test::plot_texts(plots, "y-label")[1], "largest deviation, µrad");
    }
  }
}

TEST(VerifyReport, ThreeAxisPocket) {
  check_report({"samples/machines/hsu-3axis.json", "samples/errors/hsu-3axis.csv",
                "samples/programs/pocket.ngc", "--work-offset 250,200,100", false});
}

TEST(VerifyReport, FiveAxisCone) {
  check_report({"samples/machines/lei-hsu-xyzac.json", "samples/errors/lei-hsu-xyzac.csv",
                "samples/programs/cone-vector.ngc", "", true});
}

TEST(VerifyReport, OntoAnInputIsRefusedAndTheInputUntouched) {
  const std::string copy = temp_path("pocket-copy.ngc");
  fs::copy_file(test::source_path("samples/programs/pocket.ngc"), copy,
                fs::copy_options::overwrite_existing);
  const std::string before = test::read_text_file(copy);
  const std::string m = test::source_path("samples/machines/hsu-3axis.json"),
                    e = test::source_path("samples/errors/hsu-3axis.csv");
  const test::CliResult r = test::run_volmap("verify --machine " + m + " --errors " + e +
                                             " --work-offset 250,200,100 --nominal " + copy +
                                             " --program " + copy + " --report " + copy);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(copy), std::string::npos) << r.err;
  EXPECT_EQ(test::read_text_file(copy), before);
}

}  // namespace
}  // namespace volmap
