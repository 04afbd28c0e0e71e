// Exports (maps/exporters.h, docs/exports.md): golden files for every
// format (UPDATE_GOLDEN=1 regenerates tests/golden/exports/), and for each
// format at least one value checked against an independent derivation
// (the direct model or the errors file, with the documented sign and
// units), the controllers' limits, and the volmap export command.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/errors_csv.h"
#include "core/machine_json.h"
#include "maps/exporters.h"
#include "maps/table_builder.h"
#include "maps/table_file.h"
#include "tests/support/test_paths.h"

namespace volmap::maps {
namespace {

namespace fs = std::filesystem;

const ErrorModel& small_model() {
  static const ErrorModel model(
      load_machine_json(test::source_path("tests/data/maps/small-3axis.json")),
      load_errors_csv(test::source_path("tests/data/maps/small-3axis.csv")));
  return model;
}

// The table every golden file is made from: 50 mm spacing, 5 x 3 x 3 nodes,
// two X direction layers; provenance fixed so the files do not depend on
// the checkout's path.
const VolumetricTable& small_table() {
  static const VolumetricTable t = [] {
    VolumetricTable t = build_table(small_model(), {50, 50, 50});
    t.errors_source = "tests/data/maps/small-3axis.csv";
    return t;
  }();
  return t;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void check_golden(const std::string& format) {
  const std::vector<ExportFile> files = export_table(small_table(), format);
  const fs::path dir = fs::path(test::source_path("tests/golden/exports")) / format;
  const bool update = std::getenv("UPDATE_GOLDEN") != nullptr &&
                      std::string(std::getenv("UPDATE_GOLDEN")) == "1";
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

const ExportFile& file_named(const std::vector<ExportFile>& files, const std::string& name) {
  for (const ExportFile& f : files)
    if (f.name == name) return f;
  throw std::runtime_error("no file " + name);
}

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

// The errors file's own value of a component of X in one direction (mm).
double x_error(Component c, double x, int dir) {
  const AxisErrors& e = *small_model().errors().errors_of(AxisName::X);
  std::array<double, kComponentCount> v;
  evaluate_table(dir > 0 ? e.plus : e.minus, x, OutsidePolicy::kError, v);
  return v[static_cast<size_t>(c)];
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
    const double expected_mm = 0.5 * (x_error(Component::EX, x, +1) + x_error(Component::EX, x, -1));
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

TEST(ExportFormats, UnknownAndUnimplementedFormatsAreRefused) {
  EXPECT_THROW(export_table(small_table(), "gcode"), ExportError);
  EXPECT_THROW(export_table(small_table(), "fanuc"), ExportError);
}

// ---- the command ----

struct RunResult {
  int status;
  std::string out;
};
RunResult run(const std::string& args) {
  const std::string cmd = test::volmap_binary() + " " + args + " 2>&1";
  RunResult r{};
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int st = pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

TEST(ExportCommand, MapThenExportWritesTheFiles) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("export_cmd_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string table = (dir / "t.vmt").string();
  const std::string machine = test::source_path("tests/data/maps/small-3axis.json");
  const std::string errors = test::source_path("tests/data/maps/small-3axis.csv");
  RunResult r = run("map --machine " + machine + " --errors " + errors + " --spacing 50,50,50 -o " + table +
              " --json");
  ASSERT_EQ(r.status, 0) << r.out;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["nodes"], 45);
  EXPECT_EQ(doc["layers"].size(), 2u);
  r = run("export --table " + table + " --format linuxcnc -o " + (dir / "lcnc").string());
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_TRUE(fs::exists(dir / "lcnc" / "X.comp"));
  // The exported files equal the library's export of the same table.
  const VolumetricTable t = load_table(table);
  EXPECT_EQ(read_file(dir / "lcnc" / "Y.comp"), file_named(export_table(t, "linuxcnc"), "Y.comp").text);
  // Errors: one line, exit 1, nothing written.
  r = run("export --table " + table + " --format fanuc -o " + (dir / "fanuc").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  EXPECT_FALSE(fs::exists(dir / "fanuc"));
  r = run("export --table " + table + " --format csv -o " + table);
  EXPECT_EQ(r.status, 1) << r.out;
  r = run("map --machine " + machine + " --errors " + errors + " --spacing 50,50,50 -o " + errors);
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.out.find("input"), std::string::npos) << r.out;
  std::ofstream(dir / "bad.vmt") << "VOLMAPTB garbage";
  r = run("export --table " + (dir / "bad.vmt").string() + " --format csv -o " + (dir / "x").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("bad.vmt"), std::string::npos) << r.out;
  r = run("map --machine " + machine + " --errors " + errors + " --spacing 50,50 -o " + table);
  EXPECT_EQ(r.status, 1);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace volmap::maps
