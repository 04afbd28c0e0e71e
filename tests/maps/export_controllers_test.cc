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

struct FanucTape {
  std::map<int, std::array<long, 3>> param;  // number -> value per axis A1..A3
  std::map<int, long> pitch;                 // compensation point -> value
};

FanucTape parse_fanuc(const std::string& text) {
  FanucTape tape;
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "%");
  while (std::getline(in, line) && line != "%") {
    EXPECT_EQ(line[0], 'N') << line;
    const size_t p = line.find('P');
    const int number = std::stoi(line.substr(1, line.find_first_of("AP") - 1));
    if (number >= 10000) {
      tape.pitch[number - 10000] = std::stol(line.substr(p + 1));
      continue;
    }
    std::array<long, 3> v{};
    for (int a = 0; a < 3; ++a) {
      const size_t at = line.find(fmt::format("A{}P", a + 1));
      EXPECT_NE(at, std::string::npos) << line;
      v[static_cast<size_t>(a)] = std::stol(line.substr(at + 3), nullptr, number == 3605 ? 2 : 10);
    }
    tape.param[number] = v;
  }
  EXPECT_EQ(line, "%");
  return tape;
}

TEST(ExportFanuc, IncrementsResumToTheAbsoluteCorrectionWithinQuantization) {
  const std::vector<ExportFile> files = export_table(small_table(), "fanuc", with_errors());
  const FanucTape tape = parse_fanuc(file_named(files, "fanuc_pitch.txt").text);
  const double unit_um = 1.0;
  for (int a = 0; a < 3; ++a) {
    const size_t ai = static_cast<size_t>(a);
    const long first = tape.param.at(3621)[ai], ref = tape.param.at(3620)[ai],
               last = tape.param.at(3622)[ai];
    const long m = tape.param.at(3623)[ai];
    EXPECT_EQ(tape.param.at(3624)[ai], 50000);  // 50 mm in 1 um units
    EXPECT_EQ(ref, first);                      // home at the travel start
    EXPECT_EQ(last - first + 1, a == 0 ? 5 : 3);
    EXPECT_GE(m, 1);
    long sum = 0;
    for (long p = first; p <= last; ++p) {
      const long v = tape.pitch.at(static_cast<int>(p));
      EXPECT_LE(std::abs(v), 7) << "point " << p;
      if (p > ref) sum += v;
      const int k = static_cast<int>(p - first);
      double q[3] = {0, 0, 0};
      q[a] = 50.0 * k;
      // Positive direction (X bidirectional) or mean (Y, Z, both layers equal).
      const Eigen::Vector3d du =
          a == 0
              ? correction_mm(q[0], q[1], q[2], +1)
              : 0.5 * (correction_mm(q[0], q[1], q[2], +1) + correction_mm(q[0], q[1], q[2], -1));
      const Eigen::Vector3d du0 =
          a == 0 ? correction_mm(0, 0, 0, +1)
                 : 0.5 * (correction_mm(0, 0, 0, +1) + correction_mm(0, 0, 0, -1));
      EXPECT_NEAR(static_cast<double>(sum * m) * unit_um, (du[a] - du0[a]) * 1e3,
                  0.5 * static_cast<double>(m) * unit_um + 1e-6)
          << "axis " << a << " point " << p;
    }
  }
  // X is bidirectional: the negative-direction points follow, and 3627 is
  // the negative-direction correction at the reference minus the positive one (4 um).
  EXPECT_EQ(tape.param.at(3605)[0], 1);
  EXPECT_EQ(tape.param.at(3605)[1], 0);
  EXPECT_EQ(tape.param.at(3626)[0], 5);
  EXPECT_EQ(tape.param.at(3627)[0],
            std::lround((correction_mm(0, 0, 0, -1).x() - correction_mm(0, 0, 0, +1).x()) * 1e3));
  EXPECT_EQ(tape.param.at(3621)[1], 10);  // X uses points 0..9 (both directions)
}

TEST(ExportFanuc, ReferenceInsideTheTravelSumsOnBothSides) {
  // Home at X = 100, Y = 50: points before the reference carry the
  // increments that lead up to it, C(k) = -sum of the values of points
  // k+1 .. reference.
  ExportOptions o = with_errors();
  o.home = {100.0, 50.0, 0.0};
  const FanucTape tape =
      parse_fanuc(file_named(export_table(small_table(), "fanuc", o), "fanuc_pitch.txt").text);
  const long first = tape.param.at(3621)[0], ref = tape.param.at(3620)[0],
             m = tape.param.at(3623)[0];
  EXPECT_EQ(ref - first, 2);
  // The home line is Y = 50, Z = 0 now.
  const double c_ref = correction_mm(100, 50, 0, +1).x();
  for (long p = first; p <= first + 4; ++p) {
    long sum = 0;
    if (p > ref)
      for (long q = ref + 1; q <= p; ++q) sum += tape.pitch.at(static_cast<int>(q));
    else
      for (long q = p + 1; q <= ref; ++q) sum -= tape.pitch.at(static_cast<int>(q));
    const double x = 50.0 * static_cast<double>(p - first);
    EXPECT_NEAR(static_cast<double>(sum * m), (correction_mm(x, 50, 0, +1).x() - c_ref) * 1e3,
                0.5 * static_cast<double>(m) + 1e-6)
        << "point " << p;
  }
  EXPECT_EQ(tape.param.at(3620)[1] - tape.param.at(3621)[1], 1);  // Y reference at its middle node
}

TEST(ExportFanuc, LatticeHoldsTheCorrectionVectorsInDetectionUnits) {
  const std::string text =
      file_named(export_table(small_table(), "fanuc", with_errors()), "fanuc_3d.csv").text;
  std::istringstream in(text);
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    if (line[0] == '#' || line[0] == 'i') continue;
    std::vector<double> r;
    std::istringstream l(line);
    std::string cell;
    while (std::getline(l, cell, ',')) r.push_back(std::stod(cell));
    ASSERT_EQ(r.size(), 9u);
    const Eigen::Vector3d du_um =
        0.5 * (correction_mm(r[3], r[4], r[5], +1) + correction_mm(r[3], r[4], r[5], -1)) * 1e3;
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(r[static_cast<size_t>(6 + c)], du_um[c], 0.5 + 1e-6) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 45);
}

TEST(ExportFanuc, LimitsAreEnforced) {
  ExportOptions o;
  // More than 1024 points: X 801 x 2 directions + Y 3 + Z 3.
  const VolumetricTable fine = build_table(small_model(), {0.25, 50, 50});
  try {
    export_table(fine, "fanuc", o);
    FAIL();
  } catch (const ExportError& e) {
    EXPECT_NE(std::string(e.what()).find("1024"), std::string::npos) << e.what();
  }
  // +-7 x magnification 100 per point: with a 0.001 um detection unit a
  // 50 mm interval changes by thousands of units.
  o.detection_unit_mm = 1e-6;
  EXPECT_THROW(export_table(small_table(), "fanuc", o), ExportError);
  // The interval must be a whole number of detection units.
  o.detection_unit_mm = 0.003;
  EXPECT_THROW(export_table(small_table(), "fanuc", o), ExportError);
  // Equidistant points only.
  EXPECT_THROW(export_table(build_table(small_model(), {30, 50, 50}), "fanuc"), ExportError);
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
