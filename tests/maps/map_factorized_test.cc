// The factorized form (maps/factorized_table.h): written, read back and
// evaluated through the HTM chain, it reproduces the direct model
// (ErrorModel::exact of the machine and errors files) at arbitrary points
// of the travel, in every approach direction; and the command line writes
// it and reports five-axis full tables.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>

#include "core/common/input_error.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "maps/tables/factorized_table.h"
#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace volmap::maps {
namespace {

nlohmann::ordered_json definition(const std::string& machine) {
  std::ifstream in(test::source_path(machine));
  return nlohmann::ordered_json::parse(in);
}

void expect_reproduces(const std::string& machine, const std::string& errors) {
  const ErrorModel direct(load_machine_json(test::source_path(machine)),
                          load_errors_csv(test::source_path(errors)));
  const std::string text = factorized_json(make_factorized(definition(machine), direct));
  std::istringstream in(text);
  const ErrorModel factorized = factorized_model(read_factorized(in, "f.json"));
  const Machine& m = direct.machine();
  std::mt19937_64 rng(4);
  double worst_mm = 0.0, worst_axis = 0.0;
  for (int k = 0; k < 5000; ++k) {
    AxisVector u(m.axis_count());
    ApproachDirections dir{};
    for (int i = 0; i < m.axis_count(); ++i) {
      const AxisLimits& L = m.limits[static_cast<size_t>(i)];
      const double lo = L.unlimited ? -4 * M_PI : L.min, hi = L.unlimited ? 4 * M_PI : L.max;
      u[i] = std::uniform_real_distribution<double>(lo, hi)(rng);
      dir[static_cast<size_t>(i)] = static_cast<std::int8_t>(rng() % 3) - 1;
    }
    const PoseError a = direct.exact(u, dir), b = factorized.exact(u, dir);
    worst_mm = std::max(worst_mm, (a.dP_mm - b.dP_mm).norm());
    worst_axis = std::max(worst_axis, (a.dQ - b.dQ).norm());
  }
  EXPECT_LE(worst_mm, 1e-12) << machine;
  EXPECT_LE(worst_axis, 1e-15) << machine;
}

TEST(MapFactorized, ReproducesTheDirectModelAtArbitraryPointsFiveAxis) {
  expect_reproduces("samples/machines/lei-hsu-xyzac.json", "samples/errors/lei-hsu-xyzac.csv");
}

TEST(MapFactorized, ReproducesTheDirectModelAtArbitraryPointsThreeAxisBidirectional) {
  expect_reproduces("samples/machines/hsu-3axis.json", "samples/errors/hsu-3axis.csv");
}

// The location errors' meaning travels with them; a document without it was
// written when they meant link errors.
TEST(MapFactorized, KeepsTheLocationErrorsMeaning) {
  const std::string machine = "samples/machines/lei-hsu-xyzac.json";
  ErrorSet link = load_errors_csv(test::source_path("samples/errors/lei-hsu-xyzac.csv"));
  link.convention = LocationConvention::kLink;
  const ErrorModel direct(load_machine_json(test::source_path(machine)), link);
  nlohmann::ordered_json doc =
      nlohmann::ordered_json::parse(factorized_json(make_factorized(definition(machine), direct)));
  EXPECT_EQ(doc["location_convention"], "link");
  for (const char* meaning : {"iso230-1", ""}) {
    if (*meaning)
      doc["location_convention"] = meaning;
    else
      doc.erase("location_convention");
    std::istringstream in(doc.dump());
    EXPECT_EQ(read_factorized(in, "f.json").errors.convention,
              *meaning ? LocationConvention::kIso230 : LocationConvention::kLink);
  }
}

TEST(MapFactorized, DamagedDocumentIsRefusedWithItsPath) {
  const ErrorModel direct(load_machine_json(test::source_path("samples/machines/hsu-3axis.json")),
                          load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv")));
  nlohmann::ordered_json doc = nlohmann::ordered_json::parse(
      factorized_json(make_factorized(definition("samples/machines/hsu-3axis.json"), direct)));
  doc["component_errors"][0]["plus"]["position"][1] = -1e9;
  std::istringstream in(doc.dump());
  try {
    (void)read_factorized(in, "f.json");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/component_errors/0"), std::string::npos) << what;
    EXPECT_NE(what.find("strictly increasing"), std::string::npos) << what;
  }
}

TEST(MapCli, FiveAxisFullAndFactorizedTables) {
  const std::string dir = ::testing::TempDir();
  const std::string machine = test::source_path("samples/machines/lei-hsu-xyzac.json");
  const std::string errors = test::source_path("samples/errors/lei-hsu-xyzac.csv");
  test::CliResult r = test::run_volmap("map --machine " + machine + " --errors " + errors +
                                       " --spacing 150,125,125,26,45 --json --report " + dir +
                                       "x5.html -o " + dir + "x5.vmt");
  ASSERT_EQ(r.status, 0) << r.err;
  {
    std::ifstream page(dir + "x5.html");
    const std::string html((std::istreambuf_iterator<char>(page)),
                           std::istreambuf_iterator<char>());
    EXPECT_NE(html.find("uc, µrad"), std::string::npos);
    EXPECT_NE(html.find("|tool-axis error|, µrad"), std::string::npos);
  }
  const nlohmann::json s = nlohmann::json::parse(r.out);
  EXPECT_EQ(s["channels"].size(), 11u);
  EXPECT_EQ(s["grid"][3]["unit"], "deg");
  EXPECT_GT(s["max_dq_urad"].get<double>(), 1.0);
  EXPECT_GT(s["max_du_rotary_urad"].get<double>(), 1.0);
  EXPECT_LT(s["correction_max_residual_um"].get<double>(), 1e-6);
  r = test::run_volmap("export --table " + dir + "x5.vmt --format linuxcnc -o " + dir + "x5lcnc");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("three-axis"), std::string::npos) << r.err;
  r = test::run_volmap("map --machine " + machine + " --errors " + errors +
                       " --form factorized --json -o " + dir + "x5.json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["form"], "factorized");
  std::ifstream in(dir + "x5.json");
  EXPECT_NO_THROW((void)read_factorized(in, dir + "x5.json"));
}

// identify --json -> map --covariance: the report identify writes is what
// map reads (the contract between the two), and u appears.
TEST(MapCli, CovarianceFromAnIdentifyReport) {
  const std::string dir = ::testing::TempDir();
  const std::string machine = test::source_path("samples/machines/lei-hsu-xyzac.json");
  const std::string errors = test::source_path("samples/errors/lei-hsu-xyzac.csv");
  test::CliResult r = test::run_volmap(
      "simulate --machine " + machine + " --errors " + errors + " --plan " +
      test::source_path("samples/plans/probe-ball.json") + " -o " + dir + "x5rec.csv");
  ASSERT_EQ(r.status, 0) << r.err;
  r = test::run_volmap("identify --machine " + machine + " --recordings " + dir + "x5rec.csv -o " +
                       dir + "x5id.csv --json");
  ASSERT_EQ(r.status, 0) << r.err;
  {
    std::ofstream report(dir + "x5id.json");
    report << r.out;
  }
  r = test::run_volmap("map --machine " + machine + " --errors " + dir + "x5id.csv --covariance " +
                       dir + "x5id.json --spacing 300,250,250,65,90 --json -o " + dir +
                       "x5cov.vmt");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json s = nlohmann::json::parse(r.out);
  EXPECT_EQ(s["channels"].back(), "u");
  EXPECT_GT(s["max_u_um"].get<double>(), 0.0);
}

}  // namespace
}  // namespace volmap::maps
