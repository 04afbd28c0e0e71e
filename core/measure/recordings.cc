// Reader and writer of the recordings CSV (contract: core/recordings.h,
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
// separates cells).
#include "core/measure/recordings.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <fstream>
#include <functional>
#include <iostream>
#include <istream>
#include <numbers>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include "core/common/input_error.h"

namespace volmap {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kUnitTolerance = 1e-3;

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\f' || c == '\v' || c == '\r' || c == '\n';
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

struct Cell {
  std::string_view text;  ///< trimmed
  int column = 0;         ///< 1-based character column
};

void split_cells(std::string_view line, std::vector<Cell>& cells) {
  cells.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    const std::size_t end = comma == std::string_view::npos ? line.size() : comma;
    const std::string_view raw = line.substr(start, end - start);
    std::size_t lead = 0;
    while (lead < raw.size() && is_space(raw[lead])) ++lead;
    cells.push_back({trim(raw), static_cast<int>(start + lead) + 1});
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
}

/// A decimal number, locale-independent, leading '+' accepted; NaN and
/// infinity parse (the caller judges them).
std::optional<double> parse_number(std::string_view s) {
  if (!s.empty() && s.front() == '+') {
    s.remove_prefix(1);
    if (!s.empty() && (s.front() == '+' || s.front() == '-')) return std::nullopt;
  }
  if (s.empty()) return std::nullopt;
  double v = 0.0;
  const std::from_chars_result r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

bool is_metadata_key(std::string_view key) {
  if (key.empty()) return false;
  return std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-' || c == '.';
  });
}

constexpr std::array<const char*, kAxisNameCount> kPositionColumns = {"x_mm",  "y_mm",  "z_mm",
                                                                      "a_deg", "b_deg", "c_deg"};
constexpr std::array<const char*, kAxisNameCount> kDirColumns = {"dir_x", "dir_y", "dir_z",
                                                                 "dir_a", "dir_b", "dir_c"};
constexpr std::array<const char*, 3> kDeviationColumns = {"ex_um", "ey_um", "ez_um"};
constexpr std::array<const char*, 3> kNormalColumns = {"nx", "ny", "nz"};

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
    std::string text;
    int number = 0;
    bool have_header = false;
    std::vector<Cell> cells;
    while (std::getline(in, text)) {
      ++number;
      if (number == 1 && text.starts_with("\xEF\xBB\xBF")) text.erase(0, 3);
      if (!text.empty() && text.back() == '\r') text.pop_back();
      const std::string_view t = trim(text);
      if (t.empty()) continue;
      if (t.front() == '#') {
        if (!have_header) read_metadata(t, number);
        continue;
      }
      split_cells(text, cells);
      if (!have_header) {
        read_header(cells, number);
        have_header = true;
      } else {
        read_row(cells, number);
      }
    }
    if (in.bad()) throw InputError(file_, number, "read error; check the file and the device");
    if (!have_header)
      throw InputError(file_, number,
                       "no header row; the first non-comment line names the columns, "
                       "e.g. x_mm,ex_um (shared/spec/recordings.md)");
    return std::move(r_);
  }

 private:
  [[noreturn]] void fail(int line, int column, const std::string& message) const {
    throw InputError(file_, line, column, message);
  }

  void read_metadata(std::string_view t, int line) {
    t.remove_prefix(1);
    const std::size_t colon = t.find(':');
    if (colon == std::string_view::npos) return;
    const std::string_view key = trim(t.substr(0, colon));
    if (!is_metadata_key(key)) return;
    const std::string value(trim(t.substr(colon + 1)));
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
          r_.position[idx].push_back(is_rotary(static_cast<AxisName>(s.index)) ? v * kDegToRad : v);
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

std::string fixed(double v, int decimals) {
  if (std::isnan(v)) return std::string();
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

}  // namespace

std::int32_t Recordings::run_index(const std::string& name) {
  for (std::size_t k = 0; k < run_names.size(); ++k)
    if (run_names[k] == name) return static_cast<std::int32_t>(k);
  run_names.push_back(name);
  return static_cast<std::int32_t>(run_names.size() - 1);
}

void Recordings::check_consistent() const {
  const std::size_t n_rows = size();
  auto check = [&](std::size_t s, const std::string& what) {
    if (s != 0 && s != n_rows)
      throw std::logic_error(
          fmt::format("recordings column {} has {} rows, expected {}", what, s, n_rows));
  };
  for (int a = 0; a < kAxisNameCount; ++a) {
    check(position[static_cast<std::size_t>(a)].size(),
          kPositionColumns[static_cast<std::size_t>(a)]);
    check(dir[static_cast<std::size_t>(a)].size(), kDirColumns[static_cast<std::size_t>(a)]);
  }
  for (std::size_t c = 0; c < 3; ++c) {
    check(e_um[c].size(), kDeviationColumns[c]);
    check(n[c].size(), kNormalColumns[c]);
    if (n[c].size() != e_along_n_um.size())
      throw std::logic_error("recordings: nx, ny, nz and e_um must come together");
  }
  check(e_along_n_um.size(), "e_um");
  check(run.size(), "run");
  check(t_s.size(), "t_s");
  check(feed_mm_min.size(), "feed_mm_min");
  check(tool_mm.size(), "tool_mm");
  check(weight.size(), "weight");
  for (const NamedColumn& c : temperature_c)
    if (c.values.size() != n_rows)
      throw std::logic_error(fmt::format("recordings column {} has {} rows, expected {}", c.name,
                                         c.values.size(), n_rows));
  for (const ExtraColumn& c : extra)
    if (c.text.size() != n_rows || c.value.size() != n_rows)
      throw std::logic_error(fmt::format("recordings column {} has {} rows, expected {}", c.name,
                                         c.text.size(), n_rows));
}

Recordings read_recordings_csv(std::istream& in, const std::string& file) {
  return Reader(file).read(in);
}

Recordings load_recordings_csv(const std::string& path) {
  if (path == "-") return read_recordings_csv(std::cin, "<stdin>");
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const std::string reason = std::generic_category().message(errno);
    throw InputError(
        path, 0,
        "cannot open the recordings CSV (" + reason + "); check the path and the permissions");
  }
  return read_recordings_csv(in, path);
}

std::string position_column_name(AxisName a) {
  return kPositionColumns[static_cast<std::size_t>(a)];
}
std::string dir_column_name(AxisName a) { return kDirColumns[static_cast<std::size_t>(a)]; }

double quantize_recorded_position(AxisName a, double position) {
  const bool rotary = is_rotary(a);
  const std::string s = fixed(rotary ? position / kDegToRad : position,
                              rotary ? RecordingDecimals::kDegree : RecordingDecimals::kMillimetre);
  const double v = *parse_number(s);
  return rotary ? v * kDegToRad : v;
}

void write_recordings_csv(std::ostream& out, const Recordings& r) {
  r.check_consistent();
  using D = RecordingDecimals;
  struct Out {
    std::string name;
    std::function<std::string(std::size_t)> cell;
  };
  std::vector<Out> cols;
  if (r.has_run())
    cols.push_back({"run", [&](std::size_t i) {
                      const std::int32_t k = r.run[i];
                      return k < 0 ? std::string() : r.run_names[static_cast<std::size_t>(k)];
                    }});
  if (!r.t_s.empty())
    cols.push_back({"t_s", [&](std::size_t i) { return fixed(r.t_s[i], D::kSecond); }});
  for (int a = 0; a < kAxisNameCount; ++a) {
    const auto& v = r.position[static_cast<std::size_t>(a)];
    if (v.empty()) continue;
    const bool rotary = is_rotary(static_cast<AxisName>(a));
    cols.push_back({kPositionColumns[static_cast<std::size_t>(a)], [&v, rotary](std::size_t i) {
                      return rotary ? fixed(v[i] / kDegToRad, D::kDegree)
                                    : fixed(v[i], D::kMillimetre);
                    }});
  }
  for (int a = 0; a < kAxisNameCount; ++a) {
    const auto& v = r.dir[static_cast<std::size_t>(a)];
    if (v.empty()) continue;
    cols.push_back(
        {kDirColumns[static_cast<std::size_t>(a)], [&v](std::size_t i) {
           return v[i] > 0 ? std::string("+1") : v[i] < 0 ? std::string("-1") : std::string("0");
         }});
  }
  if (!r.feed_mm_min.empty())
    cols.push_back(
        {"feed_mm_min", [&](std::size_t i) { return fixed(r.feed_mm_min[i], D::kFeed); }});
  if (!r.tool_mm.empty())
    cols.push_back({"tool_mm", [&](std::size_t i) { return fixed(r.tool_mm[i], D::kMillimetre); }});
  for (const NamedColumn& c : r.temperature_c)
    cols.push_back({c.name, [&c](std::size_t i) { return fixed(c.values[i], D::kCelsius); }});
  if (!r.weight.empty())
    cols.push_back({"weight", [&](std::size_t i) { return fixed(r.weight[i], D::kWeight); }});
  for (std::size_t c = 0; c < 3; ++c) {
    const auto& v = r.e_um[c];
    if (v.empty()) continue;
    cols.push_back(
        {kDeviationColumns[c], [&v](std::size_t i) { return fixed(v[i], D::kMicrometre); }});
  }
  if (r.has_projection()) {
    for (std::size_t c = 0; c < 3; ++c) {
      const auto& v = r.n[c];
      cols.push_back(
          {kNormalColumns[c], [&v](std::size_t i) { return fixed(v[i], D::kDirection); }});
    }
    cols.push_back(
        {"e_um", [&](std::size_t i) { return fixed(r.e_along_n_um[i], D::kMicrometre); }});
  }
  for (const ExtraColumn& c : r.extra)
    cols.push_back({c.name, [&c](std::size_t i) { return c.text[i]; }});

  std::string text = "# volmap recordings v1\n";
  std::map<std::string, std::string> meta = r.metadata;
  meta.erase("frame");
  bool any_rotary = false;
  for (int a = 3; a < kAxisNameCount; ++a)
    any_rotary = any_rotary || !r.position[static_cast<std::size_t>(a)].empty();
  if (r.frame == RecordingFrame::kMachine || any_rotary)
    meta["frame"] = r.frame == RecordingFrame::kMachine ? "machine" : "workpiece";
  for (const auto& [k, v] : meta) text += "# " + k + ": " + v + "\n";
  for (std::size_t j = 0; j < cols.size(); ++j) {
    if (j > 0) text += ',';
    text += cols[j].name;
  }
  text += '\n';
  out << text;
  for (std::size_t i = 0; i < r.size(); ++i) {
    text.clear();
    for (std::size_t j = 0; j < cols.size(); ++j) {
      if (j > 0) text += ',';
      text += cols[j].cell(i);
    }
    text += '\n';
    out << text;
  }
}

void require_machine_tool_length(const Recordings& r, double machine_tool_mm,
                                 const std::string& machine_name) {
  constexpr double kTolMm = 1e-3;
  auto refuse = [&](int line, double tool_mm) {
    throw InputError(
        r.file, line,
        fmt::format(
            "tool length {:g} mm, machine \"{}\" has {:g} mm; the fit predicts with the machine's "
            "tool: set tool_length_mm in the machine file to the tool of the recording, or split "
            "the recording by tool",
            tool_mm, machine_name, machine_tool_mm));
  };
  for (std::size_t i = 0; i < r.tool_mm.size(); ++i)
    if (std::isfinite(r.tool_mm[i]) && std::abs(r.tool_mm[i] - machine_tool_mm) > kTolMm)
      refuse(i < r.line.size() ? r.line[i] : 0, r.tool_mm[i]);
  const auto it = r.metadata.find("tool_mm");
  if (it != r.metadata.end() && r.tool_mm.empty()) {
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (end != it->second.c_str() && std::isfinite(v) && std::abs(v - machine_tool_mm) > kTolMm)
      refuse(0, v);
  }
}

}  // namespace volmap
