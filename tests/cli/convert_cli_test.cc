// volmap convert as scripts call it, and the exports that refuse link
// errors (docs/cli.md, *convert*; docs/exports.md, *Location errors mean ISO
// 230-1*).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace {

using volmap::test::run_volmap;

std::string sample(const std::string& rel) { return volmap::test::source_path("samples/" + rel); }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The lines of a file that belong to component-error blocks (a header whose
/// first cell is an axis letter, and its rows).
std::vector<std::string> component_lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string line;
  bool in_component = false;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') {
      in_component = false;
      continue;
    }
    if (line.size() > 1 && line[1] == ',' &&
        std::string("XYZABC").find(line[0]) != std::string::npos)
      in_component = true;
    else if (line[0] == 'E' && !in_component)
      continue;
    if (in_component) out.push_back(line);
  }
  return out;
}

// ISO -> link -> ISO through the command line: the location errors come
// back to the printed precision, every component-error line is as it was,
// and the JSON report has its keys.
TEST(ConvertCli, RoundTripKeepsEveryOtherLine) {
  const std::string dir = ::testing::TempDir();
  const std::string link = dir + "convert_link.csv", back = dir + "convert_back.csv";
  std::filesystem::remove(link);
  std::filesystem::remove(back);
  const std::string m = sample("machines/lei-hsu-xyzac.json");
  const auto a =
      run_volmap("convert --machine " + m + " --errors " + sample("errors/lei-hsu-xyzac.csv") +
                 " --to link -o " + link + " --json");
  ASSERT_EQ(a.status, 0) << a.err;
  const nlohmann::json doc = nlohmann::json::parse(a.out);
  EXPECT_EQ(doc["from"], "iso230-1");
  EXPECT_EQ(doc["to"], "link");
  EXPECT_LT(doc["check"]["tip_um"].get<double>(), 2e-3);
  EXPECT_EQ(doc["check"]["poses"], 243);
  // The workpiece set-up, to first order: the last rotary axis's placement
  // (the C line's offsets EX0C 28, EY0C -40 um and tilts EA0C 80, EB0C -35
  // urad), shifted along the C line by the A line's offset EZ0A (-22 um);
  // the rest is second order (below 0.01).
  const nlohmann::json& w = doc["workpiece_setup"];
  const double shift[3] = {28.0, -40.0, -22.0}, turn[2] = {80.0, -35.0};
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(w["shift_um"][i].get<double>(), shift[i], 0.01) << i;
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(w["turn_urad"][i].get<double>(), turn[i], 0.01) << i;
  const std::string link_text = slurp(link);
  EXPECT_NE(link_text.find("# convention: link\n"), std::string::npos);
  const std::vector<std::string> components = component_lines(link_text);
  EXPECT_EQ(components.size(), 79u);  // five headers, 13 + 11 + 11 + 14 + 25 rows
  EXPECT_EQ(components, component_lines(slurp(sample("errors/lei-hsu-xyzac.csv"))));

  const auto b =
      run_volmap("convert --machine " + m + " --errors " + link + " --to iso230-1 -o " + back);
  ASSERT_EQ(b.status, 0) << b.err;
  EXPECT_NE(b.out.find("Location errors converted from link to iso230-1."), std::string::npos)
      << b.out;
  const volmap::ErrorSet original = volmap::load_errors_csv(sample("errors/lei-hsu-xyzac.csv"));
  const volmap::ErrorSet round = volmap::load_errors_csv(back);
  EXPECT_EQ(round.convention, volmap::LocationConvention::kIso230);
  for (const auto& [name, value] : original.location)
    EXPECT_NEAR(round.location_error(name), value, 1e-9) << name;  // 1e-6 um / urad printed
}

TEST(ConvertCli, AFileAlreadyInTheTargetIsWrittenUnchanged) {
  const std::string out = ::testing::TempDir() + "convert_same.csv";
  const auto r =
      run_volmap("convert --machine " + sample("machines/hsu-3axis.json") + " --errors " +
                 sample("errors/hsu-3axis.csv") + " --to iso230-1 -o " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(slurp(out), slurp(sample("errors/hsu-3axis.csv")));
}

// The controllers take ISO 230-1 location errors: a link file is refused,
// with the command that converts it, and nothing is written.
TEST(ConvertCli, ExportsRefuseLinkErrors) {
  const std::string dir = ::testing::TempDir();
  const std::string link = dir + "export_link.csv", table = dir + "export_link.vmt",
                    out = dir + "export_link_out";
  std::filesystem::remove_all(out);
  std::ofstream(link) << "# volmap component errors v1\n# convention: link\n\nEC0X\n10\n";
  const auto map =
      run_volmap("map --machine " + sample("machines/hsu-3axis.json") + " --errors " +
                 sample("errors/hsu-3axis.csv") + " --spacing 100,100,100 -o " + table);
  ASSERT_EQ(map.status, 0) << map.err;
  for (const char* format : {"isg-csv", "heidenhain"}) {
    const auto r = run_volmap("export --table " + table + " --format " + format + " --errors " +
                              link + " -o " + out);
    EXPECT_EQ(r.status, 1) << format << r.err;
    EXPECT_NE(r.err.find("link convention"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("volmap convert"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << format;
  }
}

// A map's uncertainty from an identify report in the other meaning than the
// errors file is refused: its standard errors belong to other parameters.
TEST(ConvertCli, CovarianceOfTheOtherConventionIsRefused) {
  const std::string dir = ::testing::TempDir();
  const std::string m = sample("machines/lei-hsu-xyzac.json"), rec = dir + "cov_rec.csv",
                    ident = dir + "cov_link.csv", report = dir + "cov_link.json",
                    table = dir + "cov.vmt";
  std::filesystem::remove(table);
  ASSERT_EQ(
      run_volmap("simulate --machine " + m + " --errors " + sample("errors/lei-hsu-xyzac.csv") +
                 " --plan " + sample("plans/probe-ball.json") + " -o " + rec)
          .status,
      0);
  const auto id = run_volmap("identify --machine " + m + " --recordings " + rec +
                             " --convention link --setup-offsets -o " + ident + " --json");
  ASSERT_EQ(id.status, 0) << id.err;
  std::ofstream(report) << id.out;
  const auto r =
      run_volmap("map --machine " + m + " --errors " + sample("errors/lei-hsu-xyzac.csv") +
                 " --spacing 300,250,250,65,90 --covariance " + report + " -o " + table);
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("identified in the link convention"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(table));
}

}  // namespace
