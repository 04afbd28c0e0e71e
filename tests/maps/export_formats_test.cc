// Exports (maps/exporters.h, docs/exports.md): golden files for every
// format (UPDATE_GOLDEN=1 regenerates tests/golden/exports/), and for the
// csv, json, LinuxCNC and Siemens formats at least one value checked against
// an independent derivation (the direct model or the errors file, with the
// documented sign and units) and the controllers' limits. HEIDENHAIN, Fanuc
// and ISG: export_controllers_test.cc; the command: export_command_test.cc.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/model/errors_csv.h"
#include "core/model/errors_import.h"
#include "core/model/machine_json.h"
#include "maps/exports/exporters.h"
#include "maps/tables/table_builder.h"
#include "maps/tables/table_file.h"
#include "tests/maps/export_fixture.h"
#include "tests/support/test_paths.h"

namespace volmap::maps {
namespace {

namespace fs = std::filesystem;

using namespace test_exports;  // the fixture of export_fixture.h

void check_golden(const std::string& format) {
  const std::vector<ExportFile> files = export_table(small_table(), format, with_errors());
  const fs::path dir = fs::path(test::source_path("tests/golden/exports")) / format;
  const bool update =
      std::getenv("UPDATE_GOLDEN") != nullptr && std::string(std::getenv("UPDATE_GOLDEN")) == "1";
  if (update) {
    fs::remove_all(dir);
    write_export(dir.string(), files);
    GTEST_SKIP() << "regenerated " << dir;
  }
  size_t on_disk = 0;
  for (const auto& e : fs::directory_iterator(dir)) on_disk += e.is_regular_file();
  EXPECT_EQ(on_disk, files.size()) << "files in " << dir << " (UPDATE_GOLDEN=1 regenerates)";
  for (const ExportFile& f : files) {
    const fs::path p = dir / f.name;
    ASSERT_TRUE(fs::exists(p)) << p << " missing (UPDATE_GOLDEN=1 regenerates)";
    EXPECT_EQ(read_file(p), f.text) << p << " differs (UPDATE_GOLDEN=1 regenerates)";
  }
}

TEST(ExportGolden, Csv) { check_golden("csv"); }
TEST(ExportGolden, Json) { check_golden("json"); }
TEST(ExportGolden, LinuxCnc) { check_golden("linuxcnc"); }
TEST(ExportGolden, SiemensLec) { check_golden("siemens-lec"); }
TEST(ExportGolden, SiemensCec) { check_golden("siemens-cec"); }
TEST(ExportGolden, Heidenhain) { check_golden("heidenhain"); }
TEST(ExportGolden, Fanuc) { check_golden("fanuc"); }
TEST(ExportGolden, IsgCsv) { check_golden("isg-csv"); }

std::vector<std::vector<double>> parse_rows(const std::string& text, char sep, bool header) {
  std::vector<std::vector<double>> rows;
  std::istringstream in(text);
  std::string line;
  if (header) std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::istringstream l(line);
    std::string cell;
    while (std::getline(l, cell, sep)) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

TEST(ExportCsv, RowsAreTheModelsToolTipErrorInMicrometres) {
  const std::vector<ExportFile> files = export_table(small_table(), "csv");
  ASSERT_EQ(files.size(), 2u);
  const ExportFile& minus = file_named(files, "table_Xneg.csv");
  EXPECT_EQ(minus.text.substr(0, minus.text.find('\n')),
            "x_mm,y_mm,z_mm,ex_um,ey_um,ez_um,ux_um,uy_um,uz_um");
  const auto rows = parse_rows(minus.text, ',', true);
  ASSERT_EQ(rows.size(), 45u);
  for (const auto& r : rows) {
    AxisVector u(3);
    u << r[0], r[1], r[2];
    const Eigen::Vector3d dP_um = small_model().exact(u, {-1, 0, 0, 0, 0, 0}).dP_mm * 1e3;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(r[static_cast<size_t>(3 + c)], dP_um[c], 6e-7);
  }
}

TEST(ExportJson, ValuesAreTheModelsToolTipError) {
  const auto doc = nlohmann::json::parse(export_table(small_table(), "json").at(0).text);
  EXPECT_EQ(doc["grid"][0]["nodes"], 5);
  EXPECT_EQ(doc["layers"][1]["directions"]["X"], "-");
  // Node (i, j, k) = (3, 1, 2): index 3 + 5 * (1 + 3 * 2) = 38.
  AxisVector u(3);
  u << 150, 50, 100;
  const Eigen::Vector3d dP_um = small_model().exact(u, {+1, 0, 0, 0, 0, 0}).dP_mm * 1e3;
  EXPECT_NEAR(doc["layers"][0]["ex_um"][38].get<double>(), dP_um.x(), 1e-6);
  EXPECT_NEAR(doc["layers"][0]["ez_um"][38].get<double>(), dP_um.z(), 1e-6);
}

TEST(ExportLinuxCnc, ForwardAndReverseAreNominalPlusEXXOfEachDirection) {
  // Home line Y = Z = 0; there the tool-tip X error is EXX(x) of the
  // errors file (Y and Z errors are zero at 0, squareness moves Y only), so
  // the type-0 "actual position" columns are nominal + EXX(+) and nominal
  // + EXX(-), to the first-order difference between error and correction
  // (EXX' du < 0.01 um).
  const std::vector<ExportFile> files = export_table(small_table(), "linuxcnc");
  const auto rows = parse_rows(file_named(files, "X.comp").text, ' ', false);
  ASSERT_EQ(rows.size(), 5u);
  for (size_t k = 0; k < rows.size(); ++k) {
    const double x = 50.0 * static_cast<double>(k);
    ASSERT_EQ(rows[k].size(), 3u);
    EXPECT_EQ(rows[k][0], x);
    EXPECT_NEAR((rows[k][1] - x) * 1e3, x_error(Component::EX, x, +1) * 1e3, 0.01);
    EXPECT_NEAR((rows[k][2] - x) * 1e3, x_error(Component::EX, x, -1) * 1e3, 0.01);
  }
  // No header or comment lines; strictly increasing nominal positions.
  for (const char* name : {"X.comp", "Y.comp", "Z.comp"}) {
    const std::string& text = file_named(files, name).text;
    EXPECT_EQ(text.find('#'), std::string::npos);
    const auto r = parse_rows(text, ' ', false);
    for (size_t k = 1; k < r.size(); ++k) EXPECT_GT(r[k][0], r[k - 1][0]);
  }
  EXPECT_NE(file_named(files, "linuxcnc-joints.ini").text.find("COMP_FILE_TYPE = 0"),
            std::string::npos);
}

TEST(ExportLinuxCnc, MoreThan256EntriesPerJointAreRefused) {
  const VolumetricTable fine = build_table(small_model(), {0.5, 50, 50});  // 401 X nodes
  try {
    export_table(fine, "linuxcnc");
    FAIL();
  } catch (const ExportError& e) {
    EXPECT_NE(std::string(e.what()).find("256"), std::string::npos) << e.what();
  }
}

std::string value_of(const std::string& text, const std::string& key) {
  const size_t at = text.find(key + "=");
  if (at == std::string::npos) throw std::runtime_error("no " + key);
  const size_t start = at + key.size() + 1;
  return text.substr(start, text.find('\n', start) - start);
}

TEST(ExportSiemensLec, ValuesAreTheMeanErrorAlongTheAxis) {
  // A positive $AA_ENC_COMP moves the axis negative: the value is the error
  // along the axis, here the mean of EXX(+) and EXX(-) on the home line.
  const std::string text = export_table(small_table(), "siemens-lec").at(0).text;
  EXPECT_EQ(text.substr(0, 15), "%_N_AX_EEC_INI\n");
  EXPECT_EQ(text.substr(text.size() - 4), "M17\n");
  for (int k = 0; k < 5; ++k) {
    const double x = 50.0 * k;
    const double expected_mm =
        0.5 * (x_error(Component::EX, x, +1) + x_error(Component::EX, x, -1));
    EXPECT_NEAR(std::stod(value_of(text, fmt::format("$AA_ENC_COMP[0,{},AX1]", k))) * 1e3,
                expected_mm * 1e3, 0.01);
  }
  EXPECT_EQ(std::stod(value_of(text, "$AA_ENC_COMP_STEP[0,AX1]")), 50.0);
  EXPECT_EQ(std::stod(value_of(text, "$AA_ENC_COMP_MIN[0,AX2]")), 0.0);
  EXPECT_EQ(std::stod(value_of(text, "$AA_ENC_COMP_MAX[0,AX3]")), 100.0);
  EXPECT_EQ(text.find("$AA_ENC_COMP[0,5,AX1]"), std::string::npos);
  EXPECT_NE(text.find("$AA_ENC_COMP[0,4,AX1]"), std::string::npos);
}

TEST(ExportSiemensLec, NonEquidistantGridIsRefused) {
  const VolumetricTable t = build_table(small_model(), {30, 50, 50});  // 200 / 30: short last cell
  EXPECT_THROW(export_table(t, "siemens-lec"), ExportError);
  EXPECT_THROW(export_table(t, "siemens-cec"), ExportError);
}

TEST(ExportSiemensCec, CrossTableIsTheCorrectionOfTheOutputAxisRelativeToHome) {
  // Table "Y = F(X), moving positive": the correction of Y along X on the
  // home line, zero at X = 0: -(dP_y(x,0,0) - dP_y(0,0,0)) of the direct
  // model to first order.
  const std::string text = export_table(small_table(), "siemens-cec").at(0).text;
  EXPECT_EQ(value_of(text, "$AN_CEC_INPUT_AXIS[0]"), "(AX1)");
  EXPECT_EQ(value_of(text, "$AN_CEC_OUTPUT_AXIS[0]"), "(AX2)");
  EXPECT_EQ(value_of(text, "$AN_CEC_DIRECTION[0]"), "1");
  EXPECT_EQ(value_of(text, "$AN_CEC_DIRECTION[1]"), "-1");
  AxisVector home(3);
  home << 0, 0, 0;
  const ApproachDirections plus = {+1, 0, 0, 0, 0, 0};
  const double dy0 = small_model().exact(home, plus).dP_mm.y();
  for (int k = 0; k < 5; ++k) {
    AxisVector u(3);
    u << 50.0 * k, 0, 0;
    const double expected_mm = -(small_model().exact(u, plus).dP_mm.y() - dy0);
    EXPECT_NEAR(std::stod(value_of(text, fmt::format("$AN_CEC[0,{}]", k))) * 1e3, expected_mm * 1e3,
                0.01);
  }
  EXPECT_EQ(std::stod(value_of(text, "$AN_CEC_STEP[0]")), 50.0);
  EXPECT_EQ(std::stod(value_of(text, "$AN_CEC_MAX[0]")), 200.0);
}

TEST(ExportFormats, UnknownFormatsAndMissingErrorsAreRefused) {
  EXPECT_THROW(export_table(small_table(), "gcode"), ExportError);
  EXPECT_THROW(export_table(small_table(), "isg-csv"), ExportError);  // needs the errors
  EXPECT_NO_THROW(export_table(small_table(), "heidenhain"));         // .COM/.CMA without them
  EXPECT_EQ(export_formats().size(), 8u);
}

}  // namespace
}  // namespace volmap::maps
