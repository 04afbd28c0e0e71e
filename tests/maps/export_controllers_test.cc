// Exports for HEIDENHAIN (.COM/.CMA and KinematicsComp tables), Fanuc
// (pitch error tape, 3D lattice) and Beckhoff/ISG CSV (maps/exporters.h,
// docs/exports.md): values checked against independent derivations (the
// direct model or the errors file, with the documented sign and units) and
// the controllers' limits.
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

using namespace test_exports;  // the fixture of export_fixture.h

// ---- independent derivations for heidenhain, fanuc, isg-csv ----

// The correction du at u (workpiece frame = axis frame for this machine:
// every axis carries the tool along +x, +y, +z, so the nominal tip moves
// one to one): du solves du = -e(u + du), by fixed-point iteration on the
// direct model; independent of maps/axis_correction.
Eigen::Vector3d correction_mm(double x, double y, double z, int x_dir) {
  Eigen::Vector3d du = Eigen::Vector3d::Zero();
  for (int it = 0; it < 20; ++it) {
    AxisVector u(3);
    u << x + du.x(), y + du.y(), z + du.z();
    for (int d = 0; d < 3; ++d) u[d] = std::clamp(u[d], 0.0, d == 0 ? 200.0 : 100.0);
    du = -small_model().exact(u, {static_cast<signed char>(x_dir), 0, 0, 0, 0, 0}).dP_mm;
  }
  return du;
}

// Rows of a HEIDENHAIN table between the header row and [END].
std::vector<std::vector<std::string>> com_rows(const std::string& text,
                                               std::vector<std::string>* header) {
  std::istringstream in(text);
  std::string line;
  std::vector<std::vector<std::string>> rows;
  auto next = [&] {
    const bool ok = static_cast<bool>(std::getline(in, line));
    EXPECT_TRUE(!ok || (!line.empty() && line.back() == '\r')) << "TNC lines end in CRLF";
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return ok;
  };
  next();
  EXPECT_EQ(line.rfind("BEGIN ", 0), 0u) << line;
  next();
  {
    std::istringstream h(line);
    std::string c;
    while (h >> c) header->push_back(c);
  }
  bool ended = false;
  while (next()) {
    if (line == "[END]") {
      ended = true;
      break;
    }
    std::istringstream r(line);
    std::vector<std::string> cells;
    std::string c;
    while (r >> c) cells.push_back(c);
    rows.push_back(cells);
  }
  EXPECT_TRUE(ended) << "no [END]";
  return rows;
}

TEST(ExportHeidenhain, ComTablesAreTheCorrectionAlongEachAxis) {
  const std::vector<ExportFile> files = export_table(small_table(), "heidenhain", with_errors());
  std::vector<std::string> header;
  // X.COM: the error (minus the correction) of X = F(X) absolute (positive
  // direction; BACKLASH: negative), Y = F(X) and Z = F(X) relative to the
  // home node.
  const auto rows = com_rows(file_named(files, "X.COM").text, &header);
  EXPECT_EQ(header, (std::vector<std::string>{"NR", "AXISPOS", "X", "Y", "Z", "BACKLASH"}));
  ASSERT_EQ(rows.size(), 5u);
  const Eigen::Vector3d home = correction_mm(0, 0, 0, +1);
  for (size_t k = 0; k < rows.size(); ++k) {
    const double x = 50.0 * static_cast<double>(k);
    EXPECT_EQ(std::stoi(rows[k][0]), static_cast<int>(k));
    EXPECT_EQ(std::stod(rows[k][1]), x);
    const Eigen::Vector3d plus = correction_mm(x, 0, 0, +1);
    const Eigen::Vector3d minus = correction_mm(x, 0, 0, -1);
    const Eigen::Vector3d mean = 0.5 * (plus + minus);
    const Eigen::Vector3d home_mean = 0.5 * (home + correction_mm(0, 0, 0, -1));
    EXPECT_NEAR(std::stod(rows[k][2]), -plus.x(), 0.51e-4);
    EXPECT_NEAR(std::stod(rows[k][3]), -(mean.y() - home_mean.y()), 0.51e-4);
    EXPECT_NEAR(std::stod(rows[k][4]), -(mean.z() - home_mean.z()), 0.51e-4);
    EXPECT_NEAR(std::stod(rows[k][5]), -minus.x(), 0.51e-4);
  }
  header.clear();
  const auto zrows = com_rows(file_named(files, "Z.COM").text, &header);
  EXPECT_EQ(header,
            (std::vector<std::string>{"NR", "AXISPOS", "X", "Y", "Z"}));  // Z is not bidirectional
  ASSERT_EQ(zrows.size(), 3u);
  const Eigen::Vector3d zplus = correction_mm(0, 0, 100, +1), zminus = correction_mm(0, 0, 100, -1);
  EXPECT_NEAR(std::stod(zrows[2][4]), -0.5 * (zplus.z() + zminus.z()), 0.51e-4);
  // At the home line X.COM's own column is about EXX of the errors file (+).
  EXPECT_NEAR(std::stod(rows[4][2]), x_error(Component::EX, 200, +1), 1e-5);
  // The assignment table enters each table in the column of its input axis.
  const std::string cma = file_named(files, "VOLMAP.CMA").text;
  EXPECT_EQ(cma.substr(0, 18), "BEGIN VOLMAP.CMA\r\n");
  EXPECT_NE(cma.find("X.COM Y.COM Z.COM *"), std::string::npos) << cma;
  EXPECT_EQ(cma.substr(cma.size() - 7), "[END]\r\n");
}

TEST(ExportHeidenhain, KinematicsCompTablesAreTheComponentErrors) {
  const std::vector<ExportFile> files = export_table(small_table(), "heidenhain", with_errors());
  std::vector<std::string> header;
  const auto rows = com_rows(file_named(files, "KC_X.COM").text, &header);
  EXPECT_EQ(header,
            (std::vector<std::string>{"NR", "AXISPOS", "C1", "C2", "C3", "C4", "C5", "C6"}));
  ASSERT_EQ(rows.size(), 5u);
  for (size_t k = 0; k < rows.size(); ++k) {
    const double x = 50.0 * static_cast<double>(k);
    for (int c = 0; c < 6; ++c) {
      const double mean = 0.5 * (x_error(static_cast<Component>(c), x, +1) +
                                 x_error(static_cast<Component>(c), x, -1));
      const double expected = c < 3 ? mean : mean * 180.0 / M_PI;  // mm, degrees
      EXPECT_NEAR(std::stod(rows[k][static_cast<size_t>(2 + c)]), expected,
                  c < 3 ? 0.51e-6 : 0.51e-8)
          << k << " " << c;
    }
  }
  // The hand values of the file: EXX at X = 50 is 5.10 um (+) and 1.10 um (-).
  EXPECT_EQ(rows[1][2], "+0.003100");
  EXPECT_NE(file_named(files, "HEIDENHAIN.txt").text.find("EC0X"), std::string::npos);
}

TEST(ExportHeidenhain, LongAxesAreResampledToTheTableLimit) {
  const VolumetricTable fine = build_table(small_model(), {0.5, 50, 50});  // 401 X nodes
  const std::vector<ExportFile> files = export_table(fine, "heidenhain");
  std::vector<std::string> header;
  const auto rows = com_rows(file_named(files, "X.COM").text, &header);
  EXPECT_LE(rows.size(), 256u);
  EXPECT_EQ(std::stod(rows.back()[1]), 200.0);  // the travel end is kept
  EXPECT_EQ(std::stod(rows[1][1]), 1.0);        // every second node
  EXPECT_NE(file_named(files, "HEIDENHAIN.txt").text.find("resampled"), std::string::npos);
}

TEST(ExportHeidenhain, TablesWithoutCorrectionOrErrorsAreRefused) {
  VolumetricTable t = small_table();
  t.channels = {"ex", "ey", "ez", "ei", "ej", "ek"};  // as a five-axis table would have
  EXPECT_THROW(export_table(t, "heidenhain"), ExportError);
  EXPECT_THROW(export_table(t, "fanuc"), ExportError);
  EXPECT_NO_THROW(export_table(t, "heidenhain", with_errors()));  // KinematicsComp tables only
}

// The parameter records of a tape as text per axis, e.g. "3621" -> {"0", "5", "8"}.
std::map<int, std::array<std::string, 3>> fanuc_parameters(const std::string& tape) {
  std::map<int, std::array<std::string, 3>> out;
  std::istringstream in(tape);
  std::string line;
  while (std::getline(in, line)) {
    if (line.size() < 6 || line[0] != 'N' || line[1] != '0') continue;
    std::array<std::string, 3> v;
    for (int a = 0; a < 3; ++a) {
      const size_t at = line.find(fmt::format("A{}P", a + 1)) + 3;
      v[static_cast<size_t>(a)] = line.substr(at, line.find('A', at) - at);
    }
    out[std::stoi(line.substr(1, 5))] = v;
  }
  return out;
}

std::string pitch_tape(const ExportOptions& o, const VolumetricTable& t = small_table()) {
  return file_named(export_table(t, "fanuc", o), "fanuc_pitch.txt").text;
}

TEST(ExportFanuc, PointNumbersFollowFanucsFormula) {
  // Home X = 100 on a 0..200 travel, 50 mm interval: FANUC's formula
  // 3621 = 3620 - (100 / 50) + 1, 3622 = 3620 + 100 / 50.
  ExportOptions o;
  o.home = {100.0, 50.0, 0.0};
  const auto p = fanuc_parameters(pitch_tape(o));
  const long ref = std::stol(p.at(3620)[0]);
  EXPECT_EQ(std::stol(p.at(3621)[0]), ref - 2 + 1);
  EXPECT_EQ(std::stol(p.at(3622)[0]), ref + 2);
  EXPECT_EQ(std::stol(p.at(3621)[0]), 0);
  // X bidirectional: its negative-direction points are 3000 + the positive ones.
  EXPECT_EQ(p.at(3626)[0], "3000");
  EXPECT_EQ(p.at(3626)[1], "0");
  // Y (home 50 of 0..100) follows X's 4 points: 3621 = 4 = 3620 - 50 / 50 + 1.
  EXPECT_EQ(p.at(3621)[1], "4");
  EXPECT_EQ(p.at(3620)[1], "4");
  // A reference position at the travel start: FANUC's rotary example puts
  // the reference point's own (zero) section in, 3621 = 3620.
  const auto q = fanuc_parameters(pitch_tape({}));
  EXPECT_EQ(q.at(3621)[0], q.at(3620)[0]);
}

TEST(ExportFanuc, TheSeriesSetsTheRecordFormUnitsAndLimits) {
  ExportOptions o;
  const std::string t30 = pitch_tape(o);
  EXPECT_NE(t30.find("\nN03624Q1A1P50.0000A2P50.0000A3P50.0000\n"), std::string::npos) << t30;
  EXPECT_NE(t30.find("\nN10000Q1P0\n"), std::string::npos);
  o.fanuc.series = FanucOptions::Series::k16i;
  o.fanuc.input_increment_mm = 0.0001;  // IS-C: 3624 in 0.1 um
  const std::string t16 = pitch_tape(o);
  EXPECT_NE(t16.find("\nN03624A1P500000A2P500000A3P500000\n"), std::string::npos) << t16;
  EXPECT_EQ(t16.find("Q1"), std::string::npos);
  // 16i: -7..7 per point and 1024 points; 30i: -128..127 and 1536.
  const VolumetricTable fine = build_table(small_model(), {0.125, 50, 50});  // X: 1600 points
  for (auto [series, points] : {std::pair{FanucOptions::Series::k16i, "1024"},
                                std::pair{FanucOptions::Series::k30i, "1536"}}) {
    o.fanuc.series = series;
    o.fanuc.input_increment_mm = 0.001;
    try {
      export_table(fine, "fanuc", o);
      ADD_FAILURE() << points;
    } catch (const ExportError& e) {
      EXPECT_NE(std::string(e.what()).find(points), std::string::npos) << e.what();
    }
  }
  // A 0.1 um detection unit: X's error rises by about 3.1 um over the first
  // 50 mm (EXX 2.00 -> 5.10 um), 30-31 units, which needs magnification 5 on
  // the 16i series (31 / 7 > 4) and 1 on the 30i series.
  o.detection_unit_mm = 1e-4;
  o.fanuc.series = FanucOptions::Series::k16i;
  EXPECT_EQ(fanuc_parameters(pitch_tape(o)).at(3623)[0], "5");
  o.fanuc.series = FanucOptions::Series::k30i;
  EXPECT_EQ(fanuc_parameters(pitch_tape(o)).at(3623)[0], "1");
  EXPECT_EQ(parse_fanuc_series("0i-F"), FanucOptions::Series::k30i);
  EXPECT_EQ(parse_fanuc_series("18i"), FanucOptions::Series::k16i);
  EXPECT_THROW(parse_fanuc_series("0i"), std::invalid_argument);
}

TEST(ExportFanuc, Parameter3605KeepsTheMachinesOtherBits) {
  ExportOptions o;
  EXPECT_EQ(pitch_tape(o).find("N03605"), std::string::npos);  // not written without the value
  EXPECT_NE(file_named(export_table(small_table(), "fanuc", o), "FANUC.txt")
                .text.find("set bit 0 (BDPx) by hand to A1 1, A2 0, A3 0"),
            std::string::npos);
  o.fanuc.param_3605 = {"10100100"};
  EXPECT_NE(pitch_tape(o).find("\nN03605Q1A1P10100101A2P10100100A3P10100100\n"), std::string::npos);
  o.fanuc.param_3605 = {"00000010", "00000011", "10000000"};
  EXPECT_NE(pitch_tape(o).find("\nN03605Q1A1P00000011A2P00000010A3P10000000\n"), std::string::npos);
  o.fanuc.param_3605 = {"1010010"};
  EXPECT_THROW(pitch_tape(o), ExportError);
}

TEST(ExportFanuc, LimitsAreEnforced) {
  ExportOptions o;
  // With a 0.0001 um detection unit a 50 mm interval changes by 31000
  // units, more than -128..127 x magnification 100.
  o.detection_unit_mm = 1e-7;
  EXPECT_THROW(export_table(small_table(), "fanuc", o), ExportError);
  // The interval must be a whole number of detection units.
  o.detection_unit_mm = 0.003;
  EXPECT_THROW(export_table(small_table(), "fanuc", o), ExportError);
  // Equidistant points only.
  EXPECT_THROW(export_table(build_table(small_model(), {30, 50, 50}), "fanuc"), ExportError);
  // The reference position must be a compensation point (a grid node).
  o = {};
  o.home = {120.0, 0.0, 0.0};
  try {
    export_table(small_table(), "fanuc", o);
    FAIL();
  } catch (const ExportError& e) {
    EXPECT_NE(std::string(e.what()).find("reference position 120 mm is not a node"),
              std::string::npos)
        << e.what();
  }
}

TEST(ExportIsgCsv, ValuesAreTheComponentErrorsInMillimetresAndRadians) {
  const std::string text = export_table(small_table(), "isg-csv", with_errors()).at(0).text;
  // EXX at X = 50: mean of 5.10 and 1.10 um = 0.0031 mm; EC0X 10 urad = 1e-5 rad.
  EXPECT_NE(text.find("X\tEXX\tEYX\tEZX\tEAX\tEBX\tECX\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\n50.0000\t0.003100000\t0.001800000\t-0.001000000\t0.000002000000\t"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("C0X"), std::string::npos);
  EXPECT_NE(text.find("0.000010000000"), std::string::npos);
  // Read back as an error source: the same errors at every node.
  std::istringstream in(text);
  const ErrorSet back = read_errors(in, "isg_errors.csv", ErrorsFormat::kIsgCsv);
  for (AxisName a : {AxisName::X, AxisName::Y, AxisName::Z}) {
    const GridAxis& g = small_table().grid[static_cast<size_t>(a)];
    for (std::int64_t k = 0; k < g.count; ++k) {
      std::array<double, kComponentCount> want{}, got{};
      evaluate_axis(*small_model().errors().errors_of(a), g.node(k), 0, OutsidePolicy::kError,
                    want);
      evaluate_axis(*back.errors_of(a), g.node(k), 0, OutsidePolicy::kError, got);
      for (int c = 0; c < kComponentCount; ++c)
        EXPECT_NEAR(got[static_cast<size_t>(c)], want[static_cast<size_t>(c)], 1e-12);
    }
  }
  EXPECT_NEAR(back.location_error("EC0X"), 10e-6, 1e-15);
  EXPECT_NEAR(back.location_error("EB0Z"), -6e-6, 1e-15);
}

}  // namespace
}  // namespace volmap::maps
