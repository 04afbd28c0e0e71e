// Measurement recordings, CSV version 1 (spec: shared/spec/recordings.md):
// commanded axis positions and the deviation of the tool relative to the
// workpiece, one observation per row. Laser runs, probe-ball / R-test sphere
// tests, tracker points and on-machine probing all reduce to this table.
//
// Storage is columnar (one std::vector per column, all of size() rows), for
// files of 100 000 rows and more. A column that is absent from the file is an
// empty vector. Units: axis positions in internal units (mm, rad), converted
// in the reader and the writer only; every other field carries its unit in
// its name (e_um, t_s, feed_mm_min, temperature_c).
//
// Not recorded (an empty cell) is NaN for numbers, 0 for dir_* ("did not
// move / unknown"), 1 for weight, -1 for run.
#pragma once

#include <array>
#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include "core/common/axis_name.h"

namespace volmap {

/// Frame of the deviations: the workpiece (turns with the table; the
/// default) or the machine base ("# frame: machine"). For machines without
/// rotary axes the two coincide.
enum class RecordingFrame : std::uint8_t { kWorkpiece, kMachine };

/// A numeric column known by pattern (temp_<sensor>_c).
struct NamedColumn {
  std::string name;            ///< as in the header, "temp_spindle_c"
  std::vector<double> values;  ///< NaN where not recorded
};

/// A column the format does not define: kept with its text and, where the
/// text is a number, its value (NaN otherwise), as a candidate regressor.
struct ExtraColumn {
  std::string name;
  std::vector<std::string> text;
  std::vector<double> value;
};

struct Recordings {
  std::string file;                             ///< as named on input
  std::map<std::string, std::string> metadata;  ///< "# key: value" before the header
  RecordingFrame frame = RecordingFrame::kWorkpiece;

  /// Source line of each row (1-based; 0 for rows made in memory).
  std::vector<int> line;
  /// Commanded positions by AxisName: mm (X Y Z) or rad (A B C).
  std::array<std::vector<double>, kAxisNameCount> position;
  /// Deviation components ex_um, ey_um, ez_um (actual - nominal).
  std::array<std::vector<double>, 3> e_um;
  /// Projection form: unit direction (nx, ny, nz) and the deviation along it.
  std::array<std::vector<double>, 3> n;
  std::vector<double> e_along_n_um;  ///< the e_um column
  /// Run of each row: index into run_names, -1 for an empty cell.
  std::vector<std::int32_t> run;
  std::vector<std::string> run_names;  ///< in order of first appearance
  std::vector<double> t_s;
  std::array<std::vector<std::int8_t>, kAxisNameCount> dir;  ///< -1, 0, +1
  std::vector<double> feed_mm_min;
  std::vector<double> tool_mm;
  std::vector<double> weight;
  std::vector<NamedColumn> temperature_c;  ///< temp_<sensor>_c columns
  std::vector<ExtraColumn> extra;          ///< unknown columns, file order

  std::size_t size() const { return line.size(); }
  bool has_axis(AxisName a) const { return !position[static_cast<int>(a)].empty(); }
  bool has_component(int c) const { return !e_um[static_cast<std::size_t>(c)].empty(); }
  bool has_projection() const { return !e_along_n_um.empty(); }
  bool has_run() const { return !run.empty(); }
  /// Index of the run named `name`, appending it to run_names when new.
  std::int32_t run_index(const std::string& name);
  /// Throws std::logic_error unless every present column has size() rows
  /// (for recordings built in memory; the reader guarantees it).
  void check_consistent() const;
};

/// Parses a recordings CSV. `file` names the input in messages. Throws
/// InputError ("file:line[:column]: what is wrong; what to do") on every
/// bad-input rule of the spec; nothing is partially returned.
Recordings read_recordings_csv(std::istream& in, const std::string& file);
/// Opens and parses `path` ("-" reads standard input).
Recordings load_recordings_csv(const std::string& path);

/// Writes the recordings deterministically (the same recordings give the
/// same bytes). First line "# volmap recordings v1", then the metadata in
/// key order ("frame" from the `frame` field), then the header in this
/// column order: run, t_s, x_mm y_mm z_mm a_deg b_deg c_deg, dir_x..dir_c,
/// feed_mm_min, tool_mm, temp_*_c, weight, ex_um ey_um ez_um, nx ny nz e_um,
/// extra columns. Fixed decimals (RecordingDecimals below); NaN is an empty
/// cell; "-0" is written as 0.
void write_recordings_csv(std::ostream& out, const Recordings& r);

/// Decimals of the writer, by kind of column.
struct RecordingDecimals {
  static constexpr int kMillimetre = 6;  ///< x_mm .. z_mm, tool_mm (1 nm)
  static constexpr int kDegree = 9;      ///< a_deg .. c_deg
  static constexpr int kMicrometre = 9;  ///< ex_um .. e_um: noise-free data survives the file
  static constexpr int kDirection = 12;  ///< nx ny nz
  static constexpr int kSecond = 3;      ///< t_s
  static constexpr int kFeed = 3;        ///< feed_mm_min
  static constexpr int kCelsius = 4;     ///< temp_*_c
  static constexpr int kWeight = 6;      ///< weight
};

/// The position (internal units) that writing and reading back yields: a
/// simulator evaluates its model here so the file is self-consistent.
double quantize_recorded_position(AxisName a, double position);

/// Column name of axis a's position ("x_mm", "c_deg") and direction ("dir_x").
std::string position_column_name(AxisName a);

/// The tool length of the recording (the tool_mm column, else the
/// "# tool_mm:" metadata) must be the machine's: the fits of identify and
/// explain predict with the machine's tool, so a recording made with
/// another tool (an Abbe lever of angular errors times the difference) would
/// be fitted wrongly. Throws InputError naming the file and the first line
/// that differs by more than 1 um, and what to do.
void require_machine_tool_length(const Recordings& r, double machine_tool_mm,
                                 const std::string& machine_name);
std::string dir_column_name(AxisName a);

}  // namespace volmap
