// Reader and writer of the recordings CSV (contract: core/measure/recordings.h,
// spec: shared/spec/recordings.md).
//
// Reader steps: physical lines (BOM and CR stripped); comments and blank
// lines skipped, "# key: value" comments before the header kept as metadata;
// the header classified column by column (axis, deviation, projection,
// context, temperature, extra) and checked (an axis column, a deviation
// column, a complete projection set, no duplicates); then every row checked
// cell by cell against its column's rule.
//
// Cell rules ("required" cells):
//  - axis positions: required, a finite number;
//  - ex_um ey_um ez_um e_um t_s feed_mm_min tool_mm temp_*_c: empty = not
//    recorded (NaN); otherwise a finite number (a literal nan/inf is an error);
//  - nx ny nz: required where e_um holds a value; a unit vector within 1e-3;
//  - dir_*: empty = 0; otherwise -1, 0 or +1;
//  - weight: empty = 1; otherwise a finite number >= 0;
//  - run and extra columns: any text.
// Cells are separated by commas; there is no quoting (a comma always
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/common/csv.h"
#include "core/common/input_error.h"
#include "core/common/input_file.h"
#include "core/common/units.h"
#include "core/measure/recordings.h"
#include "core/measure/recordings_columns.h"

namespace volmap {
namespace {

using csv::Cell;
using csv::parse_number;
using namespace recordings_columns;

constexpr double kUnitTolerance = 1e-3;

enum class Kind : std::uint8_t {
  kPosition,
  kDir,
  kDeviation,
  kNormal,
  kAlongNormal,
  kRun,
  kTime,
  kFeed,
  kTool,
  kWeight,
  kTemperature,
  kExtra
};

struct ColumnSpec {
  Kind kind = Kind::kExtra;
  int index = 0;  ///< axis, component or position in temperature_c / extra
  std::string name;
};

ColumnSpec classify(std::string_view name) {
  ColumnSpec s;
  s.name = std::string(name);
  for (int a = 0; a < kAxisNameCount; ++a) {
    if (name == kPositionColumns[static_cast<std::size_t>(a)]) return {Kind::kPosition, a, s.name};
    if (name == kDirColumns[static_cast<std::size_t>(a)]) return {Kind::kDir, a, s.name};
  }
  for (int c = 0; c < 3; ++c) {
    if (name == kDeviationColumns[static_cast<std::size_t>(c)])
      return {Kind::kDeviation, c, s.name};
    if (name == kNormalColumns[static_cast<std::size_t>(c)]) return {Kind::kNormal, c, s.name};
  }
  if (name == "e_um") return {Kind::kAlongNormal, 0, s.name};
  if (name == "run") return {Kind::kRun, 0, s.name};
  if (name == "t_s") return {Kind::kTime, 0, s.name};
  if (name == "feed_mm_min") return {Kind::kFeed, 0, s.name};
  if (name == "tool_mm") return {Kind::kTool, 0, s.name};
  if (name == "weight") return {Kind::kWeight, 0, s.name};
  if (name.size() > 7 && name.starts_with("temp_") && name.ends_with("_c"))
    return {Kind::kTemperature, 0, s.name};
  return s;
}

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) { r_.file = file_; }

  Recordings read(std::istream& in) {
    csv::LineReader lines(in, file_);
    std::string text;
    bool have_header = false;
    std::vector<Cell> cells;
    while (lines.next(text)) {
      const int number = lines.number();
      const std::string_view t = csv::trim(text);
      if (t.empty()) continue;
      if (t.front() == '#') {
        if (!have_header) read_metadata(t, number);
        continue;
      }
      csv::split_cells(text, cells);
      if (!have_header) {
        read_header(cells, number);
        have_header = true;
      } else {
        read_row(cells, number);
      }
    }
    if (!have_header)
      throw InputError(file_, lines.number(),
                       "no header row; the first non-comment line names the columns, "
                       "e.g. x_mm,ex_um (shared/spec/recordings.md)");
    return std::move(r_);
  }

 private:
  [[noreturn]] void fail(int line, int column, const std::string& message) const {
    throw InputError(file_, line, column, message);
  }

  void read_metadata(std::string_view t, int line) {
    const std::optional<csv::MetadataComment> entry = csv::parse_metadata_comment(t);
    if (!entry) return;
    const std::string_view key = entry->key;
    const std::string value(entry->value);
    r_.metadata[std::string(key)] = value;
    if (key == "frame") {
      if (value == "machine") {
        r_.frame = RecordingFrame::kMachine;
      } else if (value == "workpiece") {
        r_.frame = RecordingFrame::kWorkpiece;
      } else {
        fail(line, 0,
             "frame '" + value +
                 "' is not known; write '# frame: workpiece' or "
                 "'# frame: machine'");
      }
    }
  }

  void read_header(const std::vector<Cell>& cells, int line) {
    header_line_ = line;
    bool any_axis = false, any_deviation = false;
    std::array<bool, 4> projection{};  // nx ny nz e_um
    for (std::size_t j = 0; j < cells.size(); ++j) {
      const Cell& c = cells[j];
      if (c.text.empty())
        fail(line, c.column,
             fmt::format("empty column name in header column {}; name every "
                         "column, and remove trailing commas",
                         j + 1));
      for (std::size_t k = 0; k < j; ++k)
        if (cells[k].text == c.text)
          fail(line, c.column,
               fmt::format("duplicate column {} (also column {}); give each "
                           "column once",
                           c.text, k + 1));
      ColumnSpec s = classify(c.text);
      switch (s.kind) {
        case Kind::kPosition:
          any_axis = true;
          break;
        case Kind::kDeviation:
          any_deviation = true;
          break;
        case Kind::kNormal:
          projection[static_cast<std::size_t>(s.index)] = true;
          break;
        case Kind::kAlongNormal:
          projection[3] = true;
          break;
        case Kind::kTemperature:
          s.index = static_cast<int>(r_.temperature_c.size());
          r_.temperature_c.push_back({s.name, {}});
          break;
        case Kind::kExtra:
          s.index = static_cast<int>(r_.extra.size());
          r_.extra.push_back({s.name, {}, {}});
          break;
        default:
          break;
      }
      columns_.push_back(std::move(s));
    }
    const bool any_projection =
        std::any_of(projection.begin(), projection.end(), [](bool b) { return b; });
    const bool full_projection =
        std::all_of(projection.begin(), projection.end(), [](bool b) { return b; });
    if (any_projection && !full_projection) {
      std::string missing;
      const std::array<const char*, 4> names = {"nx", "ny", "nz", "e_um"};
      for (std::size_t k = 0; k < 4; ++k)
        if (!projection[k]) missing += std::string(missing.empty() ? "" : ", ") + names[k];
      fail(line, 0,
           "the projection form needs all of nx, ny, nz and e_um; missing " + missing +
               "; add them, or use ex_um, ey_um, ez_um");
    }
    if (!any_axis)
      fail(line, 0,
           "the header has no axis column; add at least one of x_mm, y_mm, z_mm, "
           "a_deg, b_deg, c_deg (commanded positions)");
    if (!any_deviation && !full_projection)
      fail(line, 0,
           "the header has no deviation column; add ex_um, ey_um or ez_um, or the "
           "projection form nx, ny, nz, e_um");
  }

  double number_or_fail(const Cell& c, int line, const ColumnSpec& s) const {
    const std::optional<double> v = parse_number(c.text);
    if (!v)
      fail(line, c.column,
           fmt::format("{} '{}' is not a number; write a decimal number with "
                       "'.' as the decimal point",
                       s.name, c.text));
    if (!std::isfinite(*v))
      fail(line, c.column,
           fmt::format("{} is {}; give a finite number, or leave the cell "
                       "empty where nothing was recorded",
                       s.name, c.text));
    return *v;
  }

  /// Empty: NaN; otherwise a finite number.
  double optional_number(const Cell& c, int line, const ColumnSpec& s) const {
    if (c.text.empty()) return std::nan("");
    return number_or_fail(c, line, s);
  }

  void read_row(const std::vector<Cell>& cells, int line) {
    if (cells.size() != columns_.size())
      fail(line, 0,
           fmt::format("row has {} cells, the header (line {}) has {}; give one cell "
                       "per column (an empty cell for a value not recorded)",
                       cells.size(), header_line_, columns_.size()));
    r_.line.push_back(line);
    std::array<double, 3> n{std::nan(""), std::nan(""), std::nan("")};
    std::array<int, 3> n_column{};
    double along = std::nan("");
    for (std::size_t j = 0; j < cells.size(); ++j) {
      const Cell& c = cells[j];
      const ColumnSpec& s = columns_[j];
      const auto idx = static_cast<std::size_t>(s.index);
      switch (s.kind) {
        case Kind::kPosition: {
          if (c.text.empty())
            fail(line, c.column,
                 fmt::format("{} is empty; every row needs the commanded "
                             "position of each axis column (or remove the "
                             "column when the axis stood still)",
                             s.name));
          const double v = number_or_fail(c, line, s);
          r_.position[idx].push_back(
              is_rotary(static_cast<AxisName>(s.index)) ? v * units::kRadPerDeg : v);
          break;
        }
        case Kind::kDir: {
          std::int8_t d = 0;
          if (!c.text.empty()) {
            const double v = number_or_fail(c, line, s);
            if (v != -1.0 && v != 0.0 && v != 1.0)
              fail(line, c.column,
                   fmt::format("{} is {}; an approach direction is -1, 0 or +1", s.name, c.text));
            d = static_cast<std::int8_t>(v);
          }
          r_.dir[idx].push_back(d);
          break;
        }
        case Kind::kDeviation:
          r_.e_um[idx].push_back(optional_number(c, line, s));
          break;
        case Kind::kNormal:
          n[idx] = c.text.empty() ? std::nan("") : number_or_fail(c, line, s);
          n_column[idx] = c.column;
          break;
        case Kind::kAlongNormal:
          along = optional_number(c, line, s);
          break;
        case Kind::kRun:
          r_.run.push_back(c.text.empty() ? -1 : r_.run_index(std::string(c.text)));
          break;
        case Kind::kTime:
          r_.t_s.push_back(optional_number(c, line, s));
          break;
        case Kind::kFeed:
          r_.feed_mm_min.push_back(optional_number(c, line, s));
          break;
        case Kind::kTool:
          r_.tool_mm.push_back(optional_number(c, line, s));
          break;
        case Kind::kWeight: {
          double w = 1.0;
          if (!c.text.empty()) {
            w = number_or_fail(c, line, s);
            if (w < 0.0)
              fail(line, c.column,
                   fmt::format("weight {} is negative; a weight is >= 0 (0 "
                               "leaves the row out of fits)",
                               c.text));
          }
          r_.weight.push_back(w);
          break;
        }
        case Kind::kTemperature:
          r_.temperature_c[idx].values.push_back(optional_number(c, line, s));
          break;
        case Kind::kExtra: {
          ExtraColumn& e = r_.extra[idx];
          e.text.emplace_back(c.text);
          const std::optional<double> v = parse_number(c.text);
          e.value.push_back(v ? *v : std::nan(""));
          break;
        }
      }
    }
    if (!r_.e_along_n_um.empty() || has_projection_columns()) {
      r_.e_along_n_um.push_back(along);
      for (std::size_t k = 0; k < 3; ++k) r_.n[k].push_back(n[k]);
      if (!std::isnan(along)) {
        for (std::size_t k = 0; k < 3; ++k)
          if (std::isnan(n[k]))
            fail(line, n_column[k],
                 fmt::format("{} is empty but e_um holds a value; give the "
                             "unit direction nx, ny, nz of every projected "
                             "deviation",
                             kNormalColumns[k]));
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (std::abs(len - 1.0) > kUnitTolerance)
          fail(line, n_column[0],
               fmt::format("projection vector ({}, {}, {}) has length {:.6g}, "
                           "not 1 within {}; normalise nx, ny, nz",
                           n[0], n[1], n[2], len, kUnitTolerance));
      }
    }
  }

  bool has_projection_columns() const {
    return std::any_of(columns_.begin(), columns_.end(),
                       [](const ColumnSpec& s) { return s.kind == Kind::kAlongNormal; });
  }

  std::string file_;
  Recordings r_;
  std::vector<ColumnSpec> columns_;
  int header_line_ = 0;
};

}  // namespace

Recordings read_recordings_csv(std::istream& in, const std::string& file) {
  return Reader(file).read(in);
}

Recordings load_recordings_csv(const std::string& path) {
  return read_input_file(path, "the recordings CSV", read_recordings_csv);
}

}  // namespace volmap
