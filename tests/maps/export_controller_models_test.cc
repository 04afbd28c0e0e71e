// Each controller export read by a model of its controller
// (tests/maps/controller_models.h) and applied to the simulated real
// machine: where the controller compensates, the tool tip must land where
// the program wanted it, within the interpolation error of the table's own
// grid (computed here from the exact correction) plus the rounding of the
// file's numbers. A wrong sign, unit or index shows as a residual of the
// size of the error itself (tens of micrometres).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "maps/exports/exporters.h"
#include "maps/tables/table_builder.h"
#include "tests/maps/component_controller_model.h"
#include "tests/maps/controller_models.h"
#include "tests/maps/export_fixture.h"
#include "tests/maps/fanuc_controller_model.h"
#include "tests/support/test_paths.h"

namespace volmap::maps {
namespace {

using namespace test_exports;
using namespace controller_models;

// The fixture's machine with every angular component error zero: its error
// field is a sum of one function per axis, which is what one-dimensional
// tables can represent everywhere, not only on the home lines.
const ErrorModel& separable_model() {
  static const ErrorModel model(
      load_machine_json(test::source_path("tests/data/maps/small-3axis.json")),
      load_errors_csv(test::source_path("tests/data/maps/small-3axis-separable.csv")));
  return model;
}

const VolumetricTable& separable_table() {
  static const VolumetricTable t = build_table(separable_model(), {50, 50, 50});
  return t;
}

constexpr std::array<double, 3> kTravel = {200.0, 100.0, 100.0};

// Points along axis `axis` through the home position (the machine's, 0 0 0,
// unless given), off the grid's nodes (3.7 mm apart) and at both ends.
std::vector<Eigen::Vector3d> home_line(int axis,
                                       const Eigen::Vector3d& home = Eigen::Vector3d::Zero()) {
  std::vector<Eigen::Vector3d> out;
  for (double s = 0.0; s < kTravel[static_cast<size_t>(axis)]; s += 3.7) {
    Eigen::Vector3d p = home;
    p[axis] = s;
    out.push_back(p);
  }
  Eigen::Vector3d end = home;
  end[axis] = kTravel[static_cast<size_t>(axis)];
  out.push_back(end);
  return out;
}

// Points through the whole volume, off the nodes.
std::vector<Eigen::Vector3d> volume_points() {
  std::vector<Eigen::Vector3d> out;
  for (double x = 1.3; x < 200.0; x += 23.1)
    for (double y = 0.7; y < 100.0; y += 17.3)
      for (double z = 2.9; z < 100.0; z += 19.7) out.emplace_back(x, y, z);
  return out;
}

// What linear interpolation between the 50 mm nodes of the exact correction
// costs at p (per component, mm), along the given axis: the bound a
// faithful controller table of that grid can reach on that line.
Eigen::Vector3d interpolation_cost(const ErrorModel& m, const Eigen::Vector3d& p, int axis,
                                   int x_dir) {
  const double s = p[axis];
  const double lo = std::min(std::floor(s / 50.0) * 50.0, kTravel[static_cast<size_t>(axis)] - 50);
  Eigen::Vector3d a = p, b = p;
  a[axis] = lo;
  b[axis] = lo + 50.0;
  const double f = (s - lo) / 50.0;
  const Eigen::Vector3d lin =
      (1 - f) * (exact_command(m, a, x_dir) - a) + f * (exact_command(m, b, x_dir) - b);
  return (lin - (exact_command(m, p, x_dir) - p)).cwiseAbs();
}

// The worst interpolation cost along every axis's home line (mm).
double worst_interpolation_cost(const ErrorModel& m, int x_dir,
                                const Eigen::Vector3d& home = Eigen::Vector3d::Zero()) {
  double worst = 0.0;
  for (int axis = 0; axis < 3; ++axis)
    for (const Eigen::Vector3d& p : home_line(axis, home))
      worst = std::max(worst, interpolation_cost(m, p, axis, x_dir).maxCoeff());
  return worst;
}

// ---- LinuxCNC ----

TEST(ControllerModelLinuxCnc, EachJointLandsOnItsNominalPositionInBothDirections) {
  const std::vector<ExportFile> files = export_table(small_table(), "linuxcnc");
  std::array<LinuxCncJoint, 3> joints;
  for (int j = 0; j < 3; ++j)
    joints[static_cast<size_t>(j)] =
        read_linuxcnc_comp(file_named(files, std::string(1, "XYZ"[j]) + ".comp").text);
  ASSERT_EQ(joints[0].nominal.size(), 5u);
  for (int dir : {+1, -1}) {
    const double bound = worst_interpolation_cost(small_model(), dir) + 2e-6;
    for (int j = 0; j < 3; ++j) {
      double worst = 0.0;
      for (const Eigen::Vector3d& p : home_line(j)) {
        Eigen::Vector3d c = p;
        for (int k = 0; k < 3; ++k) c[k] += joints[static_cast<size_t>(k)].trim(p[k], dir);
        // Joint compensation corrects each joint along itself only.
        worst = std::max(worst, std::abs((actual_tip(small_model(), c, dir) - p)[j]));
      }
      EXPECT_LE(worst, bound) << "joint " << j << " direction " << dir;
    }
  }
  // Without the files the positioning error is there to see: the check can fail.
  EXPECT_GT(std::abs((actual_tip(small_model(), {200, 0, 0}, +1) - Eigen::Vector3d(200, 0, 0))[0]),
            0.01);
}

// ---- SINUMERIK LEC and CEC together ----

// The error at the reference point each LEC table leaves out (K3: the table
// is zero there), from the comment that says where it goes.
Eigen::Vector3d lec_reference_errors(const std::string& text) {
  Eigen::Vector3d e = Eigen::Vector3d::Constant(NAN);
  for (const std::string& line : lines_of(text)) {
    const size_t at = line.find("error there ");
    if (line.rfind("; AX", 0) != 0 || at == std::string::npos) continue;
    e[siemens_axis(line.substr(2, 3))] = std::stod(line.substr(at + 12));
  }
  if (!e.allFinite()) throw std::runtime_error("an axis without its reference point error");
  return e;
}

struct SinumerikRun {
  SiemensLec lec;
  SiemensCec cec;
  Eigen::Vector3d reference_error;
  // Axis positions for the wanted position p: CEC adds to the setpoints,
  // then each axis's LEC moves it to where its modified actual value
  // equals the setpoint.
  Eigen::Vector3d command(const Eigen::Vector3d& p, int x_dir) const {
    const Eigen::Vector3d s = p + cec.added(p, {x_dir, 0, 0});
    return {lec.axis_position(0, s[0]), lec.axis_position(1, s[1]), lec.axis_position(2, s[2])};
  }
};

// The CEC file as an export with a defect would write it: every table
// value negated (the sign of LEC), or without the SD41300 enables.
enum class CecDefect { kNone, kSignFlipped, kNoEnable };

std::string with_defect(const std::string& cec, CecDefect d) {
  std::string out;
  for (const std::string& line : lines_of(cec)) {
    if (d == CecDefect::kNoEnable && line.rfind("$SN_CEC_TABLE_ENABLE[", 0) == 0) continue;
    const size_t eq = line.find('=');
    if (d == CecDefect::kSignFlipped && line.rfind("$AN_CEC[", 0) == 0)
      out += line.substr(0, eq + 1) +
             (line[eq + 1] == '-' ? line.substr(eq + 2) : "-" + line.substr(eq + 1)) + "\n";
    else
      out += line + "\n";
  }
  return out;
}

SinumerikRun sinumerik(const VolumetricTable& t, const ExportOptions& o,
                       CecDefect defect = CecDefect::kNone) {
  const std::string lec_text = export_table(t, "siemens-lec", o)[0].text;
  const std::string cec_text = export_table(t, "siemens-cec", o)[0].text;
  return {read_siemens_lec(read_siemens_ini(lec_text)),
          read_siemens_cec(read_siemens_ini(with_defect(cec_text, defect))),
          lec_reference_errors(lec_text)};
}

// Worst residual over `points` after the documented reference-point errors
// (the only thing the tables leave out by K3's rule) are taken off; X's
// own component is the mean of both approach directions (LEC has one table
// for both; the reversal goes to the backlash machine data).
double sinumerik_worst(const ErrorModel& m, const SinumerikRun& run,
                       const std::vector<Eigen::Vector3d>& points) {
  double worst = 0.0;
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d plus = actual_tip(m, run.command(p, +1), +1) - p;
    const Eigen::Vector3d minus = actual_tip(m, run.command(p, -1), -1) - p;
    Eigen::Vector3d r = 0.5 * (plus + minus) - run.reference_error;
    worst = std::max(worst, r.cwiseAbs().maxCoeff());
    for (const Eigen::Vector3d& d : {plus, minus})
      worst = std::max({worst, std::abs(d[1] - run.reference_error[1]),
                        std::abs(d[2] - run.reference_error[2])});
  }
  return worst;
}

TEST(ControllerModelSinumerik, LecAndCecPutTheTipOnTheHomeLinesUpToTheReferencePointError) {
  ExportOptions o;
  o.home = {100.0, 50.0, 50.0};  // reference points inside the travel, where the error is not 0
  const SinumerikRun run = sinumerik(small_table(), o);
  const Eigen::Vector3d home(100, 50, 50);
  // The reference-point errors are the errors at home, which the tables leave out.
  const Eigen::Vector3d at_home =
      0.5 * (actual_tip(small_model(), home, +1) + actual_tip(small_model(), home, -1)) - home;
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(run.reference_error[d], at_home[d], 1e-6) << d;
  EXPECT_GT(run.reference_error.cwiseAbs().maxCoeff(), 0.002);
  std::vector<Eigen::Vector3d> points;
  for (int axis = 0; axis < 3; ++axis)
    for (const Eigen::Vector3d& p : home_line(axis, home)) points.push_back(p);
  const double bound = 3 * std::max(worst_interpolation_cost(small_model(), +1, home),
                                    worst_interpolation_cost(small_model(), -1, home)) +
                       4e-6;
  EXPECT_LE(sinumerik_worst(small_model(), run, points), bound);
  // The check can fail: CEC with LEC's sign doubles the cross errors, and
  // without SD41300 the tables are loaded but leave them (both far above
  // the bound).
  const double flipped =
      sinumerik_worst(small_model(), sinumerik(small_table(), o, CecDefect::kSignFlipped), points);
  const double no_enable =
      sinumerik_worst(small_model(), sinumerik(small_table(), o, CecDefect::kNoEnable), points);
  EXPECT_GT(flipped, 0.005);            // seen: 7.7 um against a bound of 0.5 um
  EXPECT_GT(no_enable, 0.003);          // seen: 3.8 um
  EXPECT_GT(flipped, 1.5 * no_enable);  // the wrong sign doubles what is left
}

TEST(ControllerModelSinumerik, LecAndCecAddUpOverTheVolumeOfASeparableMachine) {
  const SinumerikRun run = sinumerik(separable_table(), {});
  const double bound = 3 * std::max(worst_interpolation_cost(separable_model(), +1),
                                    worst_interpolation_cost(separable_model(), -1)) +
                       4e-6;
  EXPECT_LE(sinumerik_worst(separable_model(), run, volume_points()), bound);
  // The check can fail: without CEC, with CEC's sign flipped or without
  // SD41300 the straightness and squareness remain (twice over when flipped).
  SinumerikRun lec_only = run;
  lec_only.cec.tables.clear();
  EXPECT_GT(sinumerik_worst(separable_model(), lec_only, volume_points()), 0.001);
  const double flipped =
      sinumerik_worst(separable_model(), sinumerik(separable_table(), {}, CecDefect::kSignFlipped),
                      volume_points());
  const double no_enable = sinumerik_worst(
      separable_model(), sinumerik(separable_table(), {}, CecDefect::kNoEnable), volume_points());
  EXPECT_GT(flipped, 0.005);    // seen: 9.2 um against a bound of 0.5 um
  EXPECT_GT(no_enable, 0.003);  // seen: 4.7 um
  EXPECT_GT(flipped, 1.5 * no_enable);
}

// ---- FANUC stored pitch error compensation and 3-D error compensation ----

// The compensation at the reference position each axis's table leaves out
// (FANUC.txt, "the compensation at the reference position, V µm").
Eigen::Vector3d fanuc_dropped_mm(const std::string& notes) {
  Eigen::Vector3d d = Eigen::Vector3d::Constant(NAN);
  for (const std::string& line : lines_of(notes)) {
    const size_t at = line.find("at the reference position, ");
    if (line.rfind("  A", 0) != 0 || at == std::string::npos) continue;
    d[line[3] - '1'] = std::stod(line.substr(at + 27)) * 1e-3;
  }
  if (!d.allFinite()) throw std::runtime_error("an axis without its reference compensation");
  return d;
}

// Every axis on its home line, in both directions: the control's
// compensation puts the axis on its nominal position up to the
// compensation at the reference position, which the table leaves out.
void expect_fanuc_axes_land(const ExportOptions& o, const Eigen::Vector3d& home) {
  const std::vector<ExportFile> files = export_table(small_table(), "fanuc", o);
  const FanucTape tape = read_fanuc_tape(file_named(files, "fanuc_pitch.txt").text);
  EXPECT_EQ(tape.q1, o.fanuc.series == FanucOptions::Series::k30i);
  const Eigen::Vector3d dropped = fanuc_dropped_mm(file_named(files, "FANUC.txt").text);
  for (int dir : {+1, -1}) {
    for (int j = 0; j < 3; ++j) {
      const double bound = worst_interpolation_cost(small_model(), dir, home) +
                           (tape.param(3623, j) + 1) * o.detection_unit_mm;
      double worst = 0.0;
      for (const Eigen::Vector3d& p : home_line(j, home)) {
        Eigen::Vector3d c = p;
        c[j] += fanuc_pitch_compensation(tape, j, p[j], dir, home[j], o.fanuc.reference_direction,
                                         o.detection_unit_mm, o.fanuc.input_increment_mm);
        worst = std::max(worst, std::abs((actual_tip(small_model(), c, dir) - p)[j] + dropped[j]));
      }
      EXPECT_LE(worst, bound) << "axis " << j << " moving " << dir << " series "
                              << (tape.q1 ? "30i" : "16i") << " ZMI "
                              << o.fanuc.reference_direction;
    }
  }
}

TEST(ControllerModelFanuc, PitchCompensationPutsEachAxisOnItsNominalPosition) {
  const std::vector<Eigen::Vector3d> homes = {Eigen::Vector3d(0, 0, 0),
                                              Eigen::Vector3d(100, 50, 50)};
  for (auto series : {FanucOptions::Series::k30i, FanucOptions::Series::k16i})
    for (int zmi : {+1, -1})
      for (const Eigen::Vector3d& home : homes) {
        ExportOptions o;
        o.fanuc.series = series;
        o.fanuc.reference_direction = zmi;
        o.home = {home[0], home[1], home[2]};
        expect_fanuc_axes_land(o, home);
      }
}

// 30i three-dimensional error compensation: the control interpolates the
// vertex vectors trilinearly in the cell holding the position (FANUC
// A-79351E) and adds them to the command. Over the whole volume of the
// machine with angular errors, the mean of both X directions lands within
// the trilinear interpolation error of the grid plus half a unit.
TEST(ControllerModelFanuc, ThreeDimensionalCompensationCorrectsTheWholeVolume) {
  const std::string sheet =
      file_named(export_table(small_table(), "fanuc"), "fanuc_3d_transcription.csv").text;
  std::map<std::array<int, 3>, Eigen::Vector3d> vertex;
  for (const std::string& line : lines_of(sheet)) {
    if (line.empty() || line[0] == '#' || line[0] == 'i') continue;
    std::vector<double> r;
    std::istringstream l(line);
    std::string cell;
    while (std::getline(l, cell, ',')) r.push_back(std::stod(cell));
    ASSERT_EQ(r.size(), 9u);
    vertex[{static_cast<int>(r[0]), static_cast<int>(r[1]), static_cast<int>(r[2])}] =
        Eigen::Vector3d(r[6], r[7], r[8]) * 1e-3;
  }
  ASSERT_EQ(vertex.size(), 45u);
  auto trilinear = [](const std::function<Eigen::Vector3d(int, int, int)>& at,
                      const Eigen::Vector3d& p) {
    const int i = std::min(static_cast<int>(p.x() / 50), 3),
              j = std::min(static_cast<int>(p.y() / 50), 1),
              k = std::min(static_cast<int>(p.z() / 50), 1);
    const Eigen::Vector3d f(p.x() / 50 - i, p.y() / 50 - j, p.z() / 50 - k);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int c = 0; c < 8; ++c) {
      const int a = c & 1, b = (c >> 1) & 1, d = (c >> 2) & 1;
      sum += (a ? f.x() : 1 - f.x()) * (b ? f.y() : 1 - f.y()) * (d ? f.z() : 1 - f.z()) *
             at(i + a, j + b, k + d);
    }
    return sum;
  };
  auto mean_correction = [](const Eigen::Vector3d& q) -> Eigen::Vector3d {
    return 0.5 *
           ((exact_command(small_model(), q, +1) - q) + (exact_command(small_model(), q, -1) - q));
  };
  double worst = 0.0, excess = 0.0;
  for (const Eigen::Vector3d& p : volume_points()) {
    const Eigen::Vector3d c = p + trilinear(
                                      [&](int i, int j, int k) {
                                        return vertex.at({i, j, k});
                                      },
                                      p);
    const Eigen::Vector3d r =
        0.5 * ((actual_tip(small_model(), c, +1) - p) + (actual_tip(small_model(), c, -1) - p));
    // What trilinear interpolation of the exact vertex corrections costs here.
    const Eigen::Vector3d ideal =
        trilinear(
            [&](int i, int j, int k) {
              return mean_correction(Eigen::Vector3d(50.0 * i, 50.0 * j, 50.0 * k));
            },
            p) -
        mean_correction(p);
    worst = std::max(worst, r.cwiseAbs().maxCoeff());
    excess = std::max(excess, (r.cwiseAbs() - ideal.cwiseAbs()).maxCoeff());
  }
  EXPECT_LE(excess, 0.5e-3 + 1e-6) << "worst residual " << worst;
  EXPECT_GT(worst, 0.0);
}

// ---- controls that take the component errors: ISG CSV, KinematicsComp ----

// The control's model fed with what it read commands the axes; the real
// machine (both X directions: the files carry the mean) moves to the
// wanted position within the rounding of the file's numbers.
double component_control_worst(const ComponentErrors& read) {
  const ErrorModel control(small_model().machine(), as_error_set(read));
  double worst = 0.0;
  for (const Eigen::Vector3d& p : volume_points()) {
    const Eigen::Vector3d c = exact_command(control, p, 0);
    const Eigen::Vector3d r =
        0.5 * ((actual_tip(small_model(), c, +1) - p) + (actual_tip(small_model(), c, -1) - p));
    worst = std::max(worst, r.cwiseAbs().maxCoeff());
  }
  return worst;
}

TEST(ControllerModelComponentErrors, IsgCsvReadAsTheKernelReadsItCorrectsTheWholeVolume) {
  const ComponentErrors read =
      read_isg_csv(export_table(small_table(), "isg-csv", with_errors())[0].text);
  EXPECT_EQ(read.axes.size(), 3u);
  EXPECT_EQ(read.location.size(), 3u);
  EXPECT_LE(component_control_worst(read), 1e-6);
  // The check can fail: the same file with every angle read as degrees.
  ComponentErrors degrees = read;
  for (auto& [k, rows] : degrees.axes)
    for (auto& [pos, v] : rows)
      for (int c = 3; c < 6; ++c) v[static_cast<size_t>(c)] *= M_PI / 180.0;
  EXPECT_GT(component_control_worst(degrees), 1e-4);
}

TEST(ControllerModelComponentErrors, KinematicsCompTablesCorrectTheWholeVolume) {
  const std::vector<ExportFile> files = export_table(small_table(), "heidenhain", with_errors());
  const ComponentErrors read = read_kinematics_comp({{'X', file_named(files, "KC_X.COM").text},
                                                     {'Y', file_named(files, "KC_Y.COM").text},
                                                     {'Z', file_named(files, "KC_Z.COM").text}},
                                                    file_named(files, "HEIDENHAIN.txt").text);
  EXPECT_EQ(read.location.size(), 3u);
  // 8 decimals of a degree: 1.7e-10 rad, times levers of a few 100 mm.
  EXPECT_LE(component_control_worst(read), 1e-6);
  ComponentErrors no_location = read;
  no_location.location.clear();
  EXPECT_GT(component_control_worst(no_location), 1e-3);
}

// ---- HEIDENHAIN nonlinear axis error compensation ----

// The TNC's compensation from the active line of the .CMA: every table
// entered in the column of axis K gives, per axis column O of the table, a
// value interpolated linearly at the position of K (AXISPOS); a BACKLASH
// column holds the own axis's value for the negative direction of
// traverse. Values are errors (MP720's sign: positive when the axis travels
// too far), so the control commands O at the wanted position minus the
// error.
struct TncCompensation {
  // (input axis K, table) of the active .CMA line
  std::vector<std::pair<int, TncTable>> tables;

  Eigen::Vector3d command(const Eigen::Vector3d& p, const std::array<int, 3>& dir) const {
    Eigen::Vector3d c = p;
    for (const auto& [k, table] : tables) {
      std::vector<double> pos;
      for (size_t r = 0; r < table.rows.size(); ++r) pos.push_back(table.number_at(r, "AXISPOS"));
      for (int o = 0; o < 3; ++o) {
        const std::string col(1, "XYZ"[o]);
        const bool own_negative =
            o == k && dir[static_cast<size_t>(k)] < 0 && table.rows[0].count("BACKLASH") != 0;
        if (table.rows[0].count(col) == 0) continue;
        std::vector<double> val;
        for (size_t r = 0; r < table.rows.size(); ++r)
          val.push_back(table.number_at(r, own_negative ? "BACKLASH" : col));
        c[o] -= interpolate(pos, val, p[k]);
      }
    }
    return c;
  }
};

TncCompensation read_tnc_compensation(const std::vector<ExportFile>& files) {
  TncCompensation comp;
  const TncTable cma = read_tnc_table(file_named(files, "VOLMAP.CMA").text);
  int active = 0;
  for (size_t r = 0; r < cma.rows.size(); ++r)
    if (cma.rows[r].at("ACTIVE") == "*") {
      ++active;
      for (int k = 0; k < 3; ++k) {
        const std::string& name = cma.rows[r].at(std::string(1, "XYZ"[k]));
        if (!name.empty())
          comp.tables.emplace_back(k, read_tnc_table(file_named(files, name).text));
      }
    }
  EXPECT_EQ(active, 1) << "one active line";
  return comp;
}

TEST(ControllerModelHeidenhain, TheTablesSlicedAtTheHeaderPositionsPutTheTipOnTheHomeLines) {
  const TncCompensation comp = read_tnc_compensation(export_table(small_table(), "heidenhain"));
  ASSERT_EQ(comp.tables.size(), 3u);
  for (int dir : {+1, -1}) {
    // 4 decimals: each of up to three table values rounds by 0.05 um.
    const double bound = worst_interpolation_cost(small_model(), dir) + 1.6e-4;
    for (int axis = 0; axis < 3; ++axis) {
      double worst = 0.0;
      for (const Eigen::Vector3d& p : home_line(axis)) {
        const Eigen::Vector3d c = comp.command(p, {dir, 0, 0});
        worst = std::max(worst, (actual_tip(small_model(), c, dir) - p).cwiseAbs().maxCoeff());
      }
      EXPECT_LE(worst, bound) << "along "
                              << "XYZ"[axis] << ", X moving " << dir;
    }
  }
}

TEST(ControllerModelHeidenhain, TheTablesAddUpOverTheVolumeOfASeparableMachine) {
  const TncCompensation comp = read_tnc_compensation(export_table(separable_table(), "heidenhain"));
  for (int dir : {+1, -1}) {
    const double bound = 3 * worst_interpolation_cost(separable_model(), dir) + 1.6e-4;
    double worst = 0.0;
    for (const Eigen::Vector3d& p : volume_points()) {
      const Eigen::Vector3d c = comp.command(p, {dir, 0, 0});
      worst = std::max(worst, (actual_tip(separable_model(), c, dir) - p).cwiseAbs().maxCoeff());
    }
    EXPECT_LE(worst, bound) << "X moving " << dir;
    EXPECT_GT(worst, 0.0);
  }
}

}  // namespace
}  // namespace volmap::maps
