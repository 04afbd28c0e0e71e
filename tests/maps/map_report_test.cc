// Per-node uncertainty (maps/node_uncertainty.h) and the map report
// (maps/map_report.h, volmap map --report).
#include "maps/tables/map_report.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "core/model/sensitivity.h"
#include "maps/exports/exporters.h"
#include "maps/tables/table_builder.h"
#include "tests/support/browser.h"
#include "tests/support/cli_run.h"
#include "tests/support/layout_probe.h"
#include "tests/support/test_paths.h"

namespace volmap::maps {
namespace {

namespace fs = std::filesystem;

Machine small_machine() {
  return load_machine_json(test::source_path("tests/data/maps/small-3axis.json"));
}

ErrorSet small_errors() {
  return load_errors_csv(test::source_path("tests/data/maps/small-3axis.csv"));
}

ErrorSet errors_from(const std::string& text) {
  std::istringstream in(text);
  return read_errors_csv(in, "inline.csv");
}

TEST(NodeUncertainty, OnePositioningErrorGivesItsOwnUncertaintyEverywhere) {
  // Only EXX is given: the tool tip's x moves one to one with it, so u is
  // sigma at every node, whatever the position.
  const ErrorModel model(small_machine(), errors_from("X,EXX\n0,0\n100,1.5\n200,2\n"));
  BuildOptions o;
  o.repeatability = Repeatability{0.7e-3, 5e-6};
  const VolumetricTable t = build_table(model, {50, 50, 50}, o);
  const int u = *t.channel("u");
  for (int layer = 0; layer < t.layer_count(); ++layer)
    for (std::int64_t n = 0; n < t.node_count(); ++n) EXPECT_NEAR(t.at(layer, n)[u], 0.7e-3, 1e-15);
}

TEST(NodeUncertainty, EqualsTheGainsPropagationOfEveryGivenError) {
  const ErrorModel model(small_machine(), small_errors());
  BuildOptions o;
  o.repeatability = Repeatability{0.5e-3, 1e-6};
  o.threads = 2;
  const VolumetricTable t = build_table(model, {50, 50, 50}, o);
  const int u = *t.channel("u");
  // Given: all 18 component errors and EC0X, EB0Z, EA0Z (every error of
  // this machine's model).
  for (std::int64_t n = 0; n < t.node_count(); n += 7) {
    double sum = 0.0;
    for (const ErrorGain& g :
         error_gains(model.machine(), Formulation::kIndependent, t.node_position(n))) {
      const double sigma = g.angular ? 1e-6 : 0.5e-3;
      sum += sigma * sigma * g.dP.squaredNorm();
    }
    EXPECT_NEAR(t.at(0, n)[u], std::sqrt(sum), 1e-15);
    EXPECT_EQ(t.at(0, n)[u], t.at(1, n)[u]);  // direction-independent
  }
  // The same bytes with one thread.
  o.threads = 1;
  EXPECT_EQ(build_table(model, {50, 50, 50}, o).values, t.values);
}

TEST(NodeUncertainty, MetadataGivesTheRepeatability) {
  ErrorSet e = small_errors();
  EXPECT_FALSE(repeatability_from(e).has_value());
  e.metadata["repeatability_um"] = "0.8";
  const std::optional<Repeatability> r = repeatability_from(e);
  ASSERT_TRUE(r.has_value());
  EXPECT_DOUBLE_EQ(r->translational_mm, 0.8e-3);
  EXPECT_EQ(r->angular_rad, 0.0);
  e.metadata["repeatability_urad"] = "-1";
  EXPECT_THROW(repeatability_from(e), std::invalid_argument);
}

TEST(NodeUncertainty, CsvAndJsonExportsCarryU) {
  const ErrorModel model(small_machine(), small_errors());
  BuildOptions o;
  o.repeatability = Repeatability{0.5e-3, 1e-6};
  const VolumetricTable t = build_table(model, {50, 50, 50}, o);
  const std::string csv = export_table(t, "csv").at(0).text;
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "x_mm,y_mm,z_mm,ex_um,ey_um,ez_um,ux_um,uy_um,uz_um,u_um");
  const auto doc = nlohmann::json::parse(export_table(t, "json").at(0).text);
  ASSERT_TRUE(doc["layers"][0].contains("u_um"));
  EXPECT_NEAR(doc["layers"][0]["u_um"][3].get<double>(), t.at(0, 3)[*t.channel("u")] * 1e3, 1e-6);
}

// A small XML well-formedness check: every element closed in order,
// attributes quoted, entities known. Enough for the page volmap writes.
std::string xml_problem(const std::string& s) {
  std::vector<std::string> open;
  size_t i = 0;
  while ((i = s.find('<', i)) != std::string::npos) {
    if (s.compare(i, 9, "<!DOCTYPE") == 0 || s.compare(i, 4, "<!--") == 0) {
      i = s.find('>', i);
      continue;
    }
    const size_t end = s.find('>', i);
    if (end == std::string::npos) return "unterminated tag";
    std::string tag = s.substr(i + 1, end - i - 1);
    if (tag.empty()) return "empty tag";
    if (tag[0] == '/') {
      const std::string name = tag.substr(1);
      if (open.empty() || open.back() != name)
        return "</" + name + "> closes " + (open.empty() ? "nothing" : open.back());
      open.pop_back();
    } else if (tag.back() != '/') {
      open.push_back(tag.substr(0, tag.find_first_of(" \n")));
    }
    if (std::count(tag.begin(), tag.end(), '"') % 2 != 0)
      return "unbalanced quotes in <" + tag + ">";
    i = end;
  }
  if (!open.empty()) return "<" + open.back() + "> not closed";
  for (size_t a = 0; (a = s.find('&', a)) != std::string::npos; ++a) {
    const std::string ent = s.substr(a, s.find(';', a) - a + 1);
    if (ent != "&amp;" && ent != "&lt;" && ent != "&gt;" && ent != "&quot;") return "entity " + ent;
  }
  return "";
}

TEST(MapReport, PageIsWellFormedSelfContainedAndShowsEverySlice) {
  const ErrorModel model(small_machine(), small_errors());
  BuildOptions o;
  o.repeatability = Repeatability{0.5e-3, 1e-6};
  const VolumetricTable t = build_table(model, {10, 10, 10}, o);
  ReportInfo info;
  info.model = "independent";
  const std::string page = map_report_html(t, info);
  EXPECT_EQ(xml_problem(page), "");
  EXPECT_EQ(page.find("http"), std::string::npos);  // nothing from the network
  EXPECT_EQ(page.find("<script"), std::string::npos);
  for (const char* s :
       {"Plane XY at Z = 50 mm", "Plane XZ at Y = 50 mm", "Plane YZ at X = 100 mm", "ex, µm",
        "ux, µm", "u, standard uncertainty, µm", "in-plane error (ex, ey)"})
    EXPECT_NE(page.find(s), std::string::npos) << s;
  // Three slices of 8 colour maps (21 x 11, 21 x 11, 11 x 11 cells) and 3 vector panels.
  EXPECT_EQ(std::count(page.begin(), page.end(), '\n') > 0, true);
  size_t svgs = 0;
  for (size_t a = 0; (a = page.find("<svg", a)) != std::string::npos; ++a) ++svgs;
  EXPECT_EQ(svgs, 27u);
  // The cell of node (2, 0, 5) in the XY slice carries the node's value.
  const std::int64_t node = 2 + 21 * (0 + 11 * 5);
  EXPECT_NE(page.find(fmt::format("<title>X = 20, Y = 0: {:.4f}</title>", t.at(0, node)[0] * 1e3)),
            std::string::npos);
  EXPECT_EQ(map_report_html(t, info), page);  // deterministic
}

TEST(MapReport, CommandWritesTheReportAndLoadsInChromiumWhenInstalled) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("map_report_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "e.csv")
      << "# repeatability_um: 0.5\n# repeatability_urad: 1\n"
      << std::ifstream(test::source_path("tests/data/maps/small-3axis.csv")).rdbuf();
  const test::CliResult r = test::run_volmap(
      "map --machine " + test::source_path("tests/data/maps/small-3axis.json") + " --errors " +
      (dir / "e.csv").string() + " --spacing 25,25,25 --json --report " +
      (dir / "map.html").string() + " -o " + (dir / "t.vmt").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_GT(doc["max_u_um"].get<double>(), 0.5);
  std::ifstream in(dir / "map.html");
  std::stringstream page;
  page << in.rdbuf();
  EXPECT_EQ(xml_problem(page.str()), "");
  // A real browser loads it without console messages (skipped without
  // Chromium unless VOLMAP_REQUIRE_CHROMIUM=1).
  if (test::chromium_or_skip()) {
    std::string dom, console;
    test::load_in_chromium((dir / "map.html").string(), dom, console);
    EXPECT_TRUE(console.empty()) << console;
    EXPECT_NE(dom.find("<svg"), std::string::npos);
    // As laid out: every heatmap with its axes in mm, round ticks and a
    // colour bar with the component and unit; every arrow in its frame.
    const nlohmann::json plots = test::probe_plot_layout((dir / "map.html").string());
    test::expect_plots_read_at_a_glance(plots);
    EXPECT_EQ(plots.size(), 27u);  // 3 slices x (8 colour maps + arrows)
    const std::vector<std::string> x = test::plot_texts(plots, "x-label"),
                                   y = test::plot_texts(plots, "y-label"),
                                   bar = test::plot_texts(plots, "c-label");
    ASSERT_EQ(x.size(), 27u);
    ASSERT_EQ(y.size(), 27u);
    EXPECT_EQ(bar.size(), 24u);
    for (std::size_t i = 0; i < 27; ++i) {
      const char* want[3][2] = {{"X, mm", "Y, mm"}, {"X, mm", "Z, mm"}, {"Y, mm", "Z, mm"}};
      EXPECT_EQ(x[i], want[i / 9][0]) << i;
      EXPECT_EQ(y[i], want[i / 9][1]) << i;
    }
    for (const char* name : {"ex, µm", "ey, µm", "ez, µm", "|e|, µm", "ux, µm", "uy, µm", "uz, µm",
                             "u, standard uncertainty, µm"})
      EXPECT_EQ(std::count(bar.begin(), bar.end(), name), 3) << name;
    for (std::size_t i = 8; i < 27; i += 9) {  // the arrows: the last plot of each slice
      std::size_t arrows = 0;
      for (const auto& m : plots[i]["marks"]) arrows += m[0] == "line";
      EXPECT_GT(arrows, 0u) << i;
    }
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace volmap::maps
