// Reader for the component and location errors CSV, version 1
// (spec: shared/spec/errors.md; contract: core/errors_csv.h).
//
// Steps: split the text into physical lines (BOM and CR stripped), take the
// "# key: value" metadata before the first block, group the other lines into
// blocks at blank lines, read each block into per-component tables (file
// units converted to mm / rad), and finally merge the components of each axis
// and direction onto one knot vector (AxisErrorTable).
//
// Merging policy (the spec asks for "a stated policy" outside a table): the
// merged table of an axis spans the union of its components' ranges. A
// component whose own table is shorter takes, at every merged knot beyond its
// own ends, its end value with slope zero: it is held at its end value, and
// only in the first merged interval past its end does the cubic blend from
// its own end slope to zero (the Hermite form keeps one slope per knot, so
// the blend keeps the table C1). Inside its own range every component is
// reproduced exactly: at an inserted knot its value and slope are those of
// its own PCHIP interpolant. The blend departs from the end value y_e by at
// most (4/27) h |m_e| (h the blend interval, m_e the component's own end
// slope); when every component covers the same range, there is no blend.
//
// Bidirectional data: a component given with dir=+1 and dir=-1 rows has one
// table per direction; a component given without direction (no dir column,
// or rows of one direction only) serves both. An axis is bidirectional when
// any of its components is.
//
// Periodic tables: a rotary-axis table spanning exactly 360 degrees is one
// full turn; its ends must hold the same values, and its slopes are the
// periodic PCHIP slopes (C1 through the wrap). All components of a rotary
// axis in one direction must then cover the same full turn.
#include "core/model/errors_csv.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iostream>
#include <istream>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "core/common/input_error.h"

namespace volmap {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kFullTurnDeg = 360.0;
constexpr double kFullTurnTolerance = 1e-9;  // degrees
constexpr double kClosureTolerance = 1e-9;   // um or urad, file units

// ---------------------------------------------------------------------------
// Text

struct Line {
  int number = 0;  ///< 1-based physical line
  std::string text;
};

struct Cell {
  std::string_view text;  ///< trimmed
  int column = 0;         ///< 1-based character column of the cell's text
};

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\f' || c == '\v' || c == '\r' || c == '\n';
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool is_blank(std::string_view s) { return trim(s).empty(); }

bool is_comment(std::string_view s) {
  s = trim(s);
  return !s.empty() && s.front() == '#';
}

std::vector<Cell> split_cells(std::string_view line) {
  std::vector<Cell> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    const std::size_t end = comma == std::string_view::npos ? line.size() : comma;
    std::string_view raw = line.substr(start, end - start);
    std::size_t lead = 0;
    while (lead < raw.size() && is_space(raw[lead])) ++lead;
    cells.push_back({trim(raw), static_cast<int>(start + lead) + 1});
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return cells;
}

/// A decimal number, locale-independent; a leading '+' is accepted. Returns
/// nothing unless the whole cell is one number. NaN and infinity parse.
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

std::string quoted(std::string_view s) {
  // Appended piecewise: GCC 12 warns falsely (-Wrestrict, bug 105651) on
  // "literal" + std::string&&.
  std::string out(1, '\'');
  out += s;
  out += '\'';
  return out;
}

bool is_metadata_key(std::string_view key) {
  if (key.empty()) return false;
  return std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-' || c == '.';
  });
}

/// A single axis letter, as the first header cell of a component block.
std::optional<AxisName> axis_column(std::string_view cell) {
  if (cell.size() != 1) return std::nullopt;
  return axis_from_char(cell[0]);
}

std::string component_names_of(AxisName a) {
  std::string s;
  for (int c = 0; c < kComponentCount; ++c) {
    if (c > 0) s += ' ';
    s += component_error_name(static_cast<Component>(c), a);
  }
  return s;
}

// ---------------------------------------------------------------------------
// Tables

/// One component's own table in one direction, internal units.
struct ComponentTable {
  std::vector<double> position;  ///< mm or rad, strictly increasing
  std::vector<double> value;     ///< mm or rad
  std::vector<double> slope;     ///< PCHIP slopes
  bool periodic = false;
  int line = 0;  ///< header line of its block
};

/// One component of an axis: one table serving both directions, or two.
struct ComponentData {
  ComponentTable plus;                  ///< dir +1, or both directions
  std::optional<ComponentTable> minus;  ///< dir -1 when bidirectional
};

struct AxisDraft {
  int first_line = 0;  ///< header line of the axis's first block
  std::array<std::optional<ComponentData>, kComponentCount> component;
};

/// Value and slope of a component's own interpolant at q inside its range.
std::pair<double, double> value_and_slope(const ComponentTable& t, double q) {
  const std::vector<double>& x = t.position;
  const std::size_t n = x.size();
  const auto at = std::lower_bound(x.begin(), x.end(), q);
  if (at != x.end() && *at == q) {
    const auto k = static_cast<std::size_t>(at - x.begin());
    return {t.value[k], t.slope[k]};
  }
  // x[i] < q < x[i+1]: the caller keeps q inside [x.front(), x.back()].
  const std::size_t i = static_cast<std::size_t>(at - x.begin()) - 1;
  assert(i + 1 < n);
  (void)n;
  const double h = x[i + 1] - x[i];
  const double s = (q - x[i]) / h;
  const double y0 = t.value[i], y1 = t.value[i + 1];
  const double m0 = t.slope[i], m1 = t.slope[i + 1];
  const double value = (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s) * y0 +
                       s * (1.0 - s) * (1.0 - s) * h * m0 + s * s * (3.0 - 2.0 * s) * y1 +
                       s * s * (s - 1.0) * h * m1;
  const double slope = (6.0 * s * s - 6.0 * s) * (y0 - y1) / h +
                       (3.0 * s * s - 4.0 * s + 1.0) * m0 + (3.0 * s * s - 2.0 * s) * m1;
  return {value, slope};
}

// ---------------------------------------------------------------------------
// Reader

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) { set_.file = file_; }

  ErrorSet read(std::istream& in) {
    std::vector<Line> block;
    bool seen_block = false;
    std::string text;
    int number = 0;
    while (std::getline(in, text)) {
      ++number;
      if (number == 1 && text.starts_with("\xEF\xBB\xBF")) text.erase(0, 3);
      if (!text.empty() && text.back() == '\r') text.pop_back();
      if (is_comment(text)) {
        if (!seen_block) read_metadata(text);
        continue;
      }
      if (is_blank(text)) {
        if (!block.empty()) read_block(block);
        block.clear();
        continue;
      }
      seen_block = true;
      block.push_back({number, std::move(text)});
    }
    if (in.bad()) throw InputError(file_, number, "read error; check the file and the device");
    if (!block.empty()) read_block(block);
    merge_axes();
    return std::move(set_);
  }

 private:
  [[noreturn]] void fail(int line, const std::string& message) const {
    throw InputError(file_, line, message);
  }
  [[noreturn]] void fail(int line, int column, const std::string& message) const {
    throw InputError(file_, line, column, message);
  }

  std::string where(int line) const { return file_ + ":" + std::to_string(line); }

  void read_metadata(std::string_view text) {
    text = trim(text);
    text.remove_prefix(1);  // '#'
    const std::size_t colon = text.find(':');
    if (colon == std::string_view::npos) return;
    const std::string_view key = trim(text.substr(0, colon));
    if (!is_metadata_key(key)) return;  // prose that happens to hold a colon
    set_.metadata[std::string(key)] = std::string(trim(text.substr(colon + 1)));
  }

  void read_block(const std::vector<Line>& block) {
    const Line& header = block.front();
    const std::vector<Cell> cells = split_cells(header.text);
    for (std::size_t j = 0; j < cells.size(); ++j) {
      if (cells[j].text.empty())
        fail(header.number, cells[j].column,
             "empty column name in header column " + std::to_string(j + 1) +
                 "; name every column, and remove trailing commas");
    }
    if (parse_number(cells[0].text))
      fail(header.number, cells[0].column,
           "block starts with a data row, not a header; begin every block with "
           "its header row (e.g. X,EXX,EYX) and separate blocks by a blank line");
    for (std::size_t j = 1; j < cells.size(); ++j) {
      if (axis_column(cells[j].text))
        fail(header.number, cells[j].column,
             "axis column " + std::string(cells[j].text) +
                 " must be the first column of its block; move it to the front");
    }
    if (block.size() < 2)
      fail(header.number,
           "block has a header but no data row; add the data rows below the "
           "header, or delete the header");
    if (std::optional<AxisName> axis = axis_column(cells[0].text)) {
      read_component_block(block, cells, *axis);
    } else {
      read_location_block(block, cells);
    }
  }

  /// Records `canonical` as given at `line`; a second time is an error.
  void claim_name(const std::string& canonical, int line, int column) {
    auto [it, inserted] = name_line_.emplace(canonical, line);
    if (!inserted)
      fail(line, column,
           "duplicate error name " + canonical + ", already given at line " +
               std::to_string(it->second) + "; give each error once");
  }

  [[noreturn]] void fail_unknown_name(int line, const Cell& cell) const {
    fail(line, cell.column,
         "unknown error name " + quoted(cell.text) +
             "; component errors are E, a direction X Y Z A B C and the axis "
             "letter (EXX, EAY), location errors carry a zero (EC0X)");
  }

  // ---- component block ----------------------------------------------------

  void read_component_block(const std::vector<Line>& block, const std::vector<Cell>& header,
                            AxisName axis) {
    const int header_line = block.front().number;
    const std::string axis_letter(1, axis_char(axis));
    std::optional<std::size_t> dir_column;
    // component_of[j]: component of header column j (columns 1..), -1 for dir.
    std::vector<int> component_of(header.size(), -1);
    std::array<bool, kComponentCount> in_header{};
    bool any_error = false;
    for (std::size_t j = 1; j < header.size(); ++j) {
      const Cell& cell = header[j];
      if (cell.text == "dir") {
        if (dir_column)
          fail(header_line, cell.column, "duplicate column dir; give the direction once per row");
        dir_column = j;
        continue;
      }
      const std::optional<ErrorName> name = parse_error_name(cell.text);
      if (!name) fail_unknown_name(header_line, cell);
      const std::string canonical = error_name_string(*name);
      if (name->location)
        fail(header_line, cell.column,
             "location error " + canonical + " in the " + axis_letter +
                 " component-error block; put location errors in a block of "
                 "their own, whose header has no axis column");
      if (name->axis != axis)
        fail(header_line, cell.column,
             "error name " + canonical + " belongs to the " +
                 std::string(1, axis_char(name->axis)) + " axis, not to the " + axis_letter +
                 " axis of this block; the " + axis_letter + " axis has " +
                 component_names_of(axis) + ", so move the column to a " +
                 std::string(1, axis_char(name->axis)) + " block");
      const int c = static_cast<int>(name->component);
      if (in_header[c])
        fail(header_line, cell.column, "duplicate column " + canonical + "; give each error once");
      in_header[c] = true;
      claim_name(canonical, header_line, cell.column);
      component_of[j] = c;
      any_error = true;
    }
    if (!any_error)
      fail(header_line, "the " + axis_letter +
                            " block has no error column; add columns such "
                            "as " +
                            component_names_of(axis));

    // Rows by direction: 0 = +1 (or no dir column), 1 = -1.
    struct Rows {
      std::vector<double> position_file;  // mm or degrees
      std::vector<int> line;
      std::vector<std::array<double, kComponentCount>> value_file;  // um, urad
    };
    std::array<Rows, 2> rows;
    std::array<std::string_view, 2> last_position_text;
    const bool rotary = is_rotary(axis);
    for (std::size_t r = 1; r < block.size(); ++r) {
      const Line& row = block[r];
      const std::vector<Cell> cells = split_cells(row.text);
      check_cell_count(row, cells, header, block.front());
      int direction = 0;
      if (dir_column) {
        const std::string_view d = cells[*dir_column].text;
        if (d == "+1" || d == "1") {
          direction = 0;
        } else if (d == "-1") {
          direction = 1;
        } else {
          fail(row.number, cells[*dir_column].column,
               "dir is " + quoted(d) +
                   "; it must be +1 (measured moving in the positive "
                   "direction) or -1 (negative direction)");
        }
      }
      const double position = number_in(row, cells[0], header[0], true);
      Rows& rs = rows[direction];
      if (!rs.position_file.empty()) {
        const double previous = rs.position_file.back();
        const double previous_internal = rotary ? previous * kDegToRad : previous;
        const double internal = rotary ? position * kDegToRad : position;
        if (!(position > previous) || !(internal > previous_internal)) {
          std::string which = dir_column ? (direction == 0 ? " dir=+1" : " dir=-1") : "";
          fail(row.number, cells[0].column,
               axis_letter + " position " + std::string(cells[0].text) +
                   " is not greater than the previous" + which + " position " +
                   std::string(last_position_text[direction]) + " (line " +
                   std::to_string(rs.line.back()) + "); positions must be strictly increasing" +
                   (dir_column ? " within each direction" : "") +
                   ": sort the rows and remove duplicates");
        }
      }
      std::array<double, kComponentCount> values{};
      for (std::size_t j = 1; j < header.size(); ++j) {
        if (component_of[j] < 0) continue;
        values[component_of[j]] = number_in(row, cells[j], header[j], false);
      }
      rs.position_file.push_back(position);
      rs.line.push_back(row.number);
      rs.value_file.push_back(values);
      last_position_text[direction] = cells[0].text;
    }

    const bool bidirectional = !rows[0].line.empty() && !rows[1].line.empty();
    AxisDraft& draft = axis_draft(axis, header_line);
    for (int c = 0; c < kComponentCount; ++c) {
      if (!in_header[c]) continue;
      ComponentData data;
      const int single = rows[0].line.empty() ? 1 : 0;
      data.plus = make_table(rows[bidirectional ? 0 : single], axis, static_cast<Component>(c),
                             header_line);
      if (bidirectional)
        data.minus = make_table(rows[1], axis, static_cast<Component>(c), header_line);
      draft.component[c] = std::move(data);
    }
  }

  template <typename Rows>
  ComponentTable make_table(const Rows& rows, AxisName axis, Component c, int header_line) const {
    const bool rotary = is_rotary(axis);
    const double value_scale = is_angular(c) ? 1e6 : 1e3;  // file unit per internal
    const std::size_t n = rows.position_file.size();
    ComponentTable t;
    t.line = header_line;
    t.position.reserve(n);
    t.value.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      t.position.push_back(rotary ? rows.position_file[i] * kDegToRad : rows.position_file[i]);
      t.value.push_back(rows.value_file[i][static_cast<int>(c)] / value_scale);
    }
    const double span_deg = rows.position_file.back() - rows.position_file.front();
    t.periodic = rotary && n >= 2 && std::abs(span_deg - kFullTurnDeg) <= kFullTurnTolerance;
    if (t.periodic) {
      const double first = rows.value_file.front()[static_cast<int>(c)];
      const double last = rows.value_file.back()[static_cast<int>(c)];
      if (std::abs(last - first) > kClosureTolerance) {
        const std::string name = component_error_name(c, axis);
        fail(rows.line.back(), std::string(1, axis_char(axis)) +
                                   " table spans 360 degrees, so it is one full turn, and a "
                                   "periodic table must close: " +
                                   name + " is " + format(last) + " here but " + format(first) +
                                   " at line " + std::to_string(rows.line.front()) +
                                   "; make the values at both ends equal");
      }
      t.slope = pchip_slopes_periodic(t.position, t.value);
    } else {
      t.slope = pchip_slopes(t.position, t.value);
    }
    return t;
  }

  static std::string format(double v) {
    char buffer[64];
    const std::to_chars_result r = std::to_chars(buffer, buffer + sizeof buffer, v);
    return std::string(buffer, r.ptr);
  }

  AxisDraft& axis_draft(AxisName axis, int header_line) {
    std::optional<AxisDraft>& d = drafts_[static_cast<int>(axis)];
    if (!d) {
      d.emplace();
      d->first_line = header_line;
    }
    return *d;
  }

  void check_cell_count(const Line& row, const std::vector<Cell>& cells,
                        const std::vector<Cell>& header, const Line& header_line) const {
    if (cells.size() != header.size())
      fail(row.number, "row has " + std::to_string(cells.size()) +
                           " cells but the header "
                           "(line " +
                           std::to_string(header_line.number) + ") has " +
                           std::to_string(header.size()) +
                           "; give one value per column (a new block must follow a blank "
                           "line)");
  }

  /// The finite number in `cell` of column `column_name`.
  double number_in(const Line& row, const Cell& cell, const Cell& column_name,
                   bool position) const {
    const std::string column = std::string(column_name.text);
    if (cell.text.empty())
      fail(row.number, cell.column, "empty cell in column " + column + "; give a number");
    const std::optional<double> v = parse_number(cell.text);
    if (!v) {
      std::string hint = "; give a decimal number such as -1.25";
      if (position && (axis_column(cell.text) || parse_error_name(cell.text)))
        hint =
            "; if this line is the header of a new block, separate it from "
            "the previous block by a blank line";
      fail(row.number, cell.column,
           "non-numeric cell " + quoted(cell.text) + " in column " + column + hint);
    }
    if (!std::isfinite(*v))
      fail(row.number, cell.column,
           "non-finite value " + quoted(cell.text) + " in column " + column +
               "; give a finite number (leave out a component that was not "
               "measured: a missing component is zero)");
    return *v;
  }

  // ---- location block -----------------------------------------------------

  void read_location_block(const std::vector<Line>& block, const std::vector<Cell>& header) {
    const int header_line = block.front().number;
    std::vector<std::string> canonical(header.size());
    std::vector<bool> angular(header.size());
    for (std::size_t j = 0; j < header.size(); ++j) {
      const Cell& cell = header[j];
      const std::optional<ErrorName> name = parse_error_name(cell.text);
      if (!name) fail_unknown_name(header_line, cell);
      canonical[j] = error_name_string(*name);
      if (!name->location) {
        const std::string axis(1, axis_char(name->axis));
        fail(header_line, cell.column,
             "component error " + canonical[j] +
                 " in a location-error block (a "
                 "header without an axis column); put it in a block whose first "
                 "column is the axis, e.g. " +
                 axis + "," + canonical[j]);
      }
      if (std::optional<std::string> problem = location_error_problem(*name))
        fail(header_line, cell.column,
             canonical[j] + " is not a location error volmap models: " + *problem +
                 "; remove the column");
      for (std::size_t k = 0; k < j; ++k)
        if (canonical[k] == canonical[j])
          fail(header_line, cell.column,
               "duplicate column " + canonical[j] + "; give each error once");
      angular[j] = is_angular(name->component);
    }
    if (block.size() > 2)
      fail(block[2].number,
           "a location-error block has exactly one data row, this is a second "
           "one; keep one row (location errors are constants), or separate "
           "blocks by a blank line");
    const Line& row = block[1];
    const std::vector<Cell> cells = split_cells(row.text);
    check_cell_count(row, cells, header, block.front());
    for (std::size_t j = 0; j < header.size(); ++j) {
      claim_name(canonical[j], header_line, header[j].column);
      const double v = number_in(row, cells[j], header[j], false);
      set_.location[canonical[j]] = v / (angular[j] ? 1e6 : 1e3);
    }
  }

  // ---- merge --------------------------------------------------------------

  void merge_axes() {
    for (int a = 0; a < kAxisNameCount; ++a) {
      if (!drafts_[a]) continue;
      const AxisDraft& draft = *drafts_[a];
      AxisErrors errors;
      errors.axis = static_cast<AxisName>(a);
      bool bidirectional = false;
      for (int c = 0; c < kComponentCount; ++c) {
        errors.present[c] = draft.component[c].has_value();
        if (draft.component[c] && draft.component[c]->minus) bidirectional = true;
      }
      errors.plus = merge(draft, errors.axis, false);
      if (bidirectional) errors.minus = merge(draft, errors.axis, true);
      set_.axis[a] = std::move(errors);
    }
  }

  AxisErrorTable merge(const AxisDraft& draft, AxisName axis, bool minus) const {
    std::array<const ComponentTable*, kComponentCount> tables{};
    std::vector<double> knots;
    const ComponentTable* periodic = nullptr;  // the first full-turn table
    for (int c = 0; c < kComponentCount; ++c) {
      if (!draft.component[c]) continue;
      const ComponentData& data = *draft.component[c];
      const ComponentTable& t = minus && data.minus ? *data.minus : data.plus;
      tables[c] = &t;
      knots.insert(knots.end(), t.position.begin(), t.position.end());
      if (t.periodic && periodic == nullptr) periodic = &t;
    }
    if (periodic != nullptr) {
      // A merged table wraps as a whole: every component must be the same
      // full turn, or the wrap would jump.
      for (int c = 0; c < kComponentCount; ++c) {
        const ComponentTable* t = tables[c];
        if (t == nullptr) continue;
        if (!t->periodic || t->position.front() != periodic->position.front() ||
            t->position.back() != periodic->position.back()) {
          const std::string a(1, axis_char(axis));
          fail(t->line, component_error_name(static_cast<Component>(c), axis) +
                            " does not cover the same full turn as the " + a + " table at line " +
                            std::to_string(periodic->line) +
                            "; give every component error of the " + a +
                            " axis over the same 360 degrees (same first and last "
                            "position), or none over a full turn");
        }
      }
    }
    std::sort(knots.begin(), knots.end());
    knots.erase(std::unique(knots.begin(), knots.end()), knots.end());

    AxisErrorTable merged;
    merged.axis = axis;
    merged.periodic = periodic != nullptr;
    merged.source = where(draft.first_line);
    merged.position = knots;
    merged.value.assign(knots.size(), {});
    merged.slope.assign(knots.size(), {});
    for (int c = 0; c < kComponentCount; ++c) {
      const ComponentTable* t = tables[c];
      if (t == nullptr) continue;  // missing component: zero
      for (std::size_t i = 0; i < knots.size(); ++i) {
        const double q = knots[i];
        if (q < t->position.front()) {
          merged.value[i][c] = t->value.front();  // held at its end value
        } else if (q > t->position.back()) {
          merged.value[i][c] = t->value.back();
        } else {
          const auto [value, slope] = value_and_slope(*t, q);
          merged.value[i][c] = value;
          merged.slope[i][c] = slope;
        }
      }
    }
    return merged;
  }

  std::string file_;
  ErrorSet set_;
  std::map<std::string, int> name_line_;  ///< canonical name -> header line
  std::array<std::optional<AxisDraft>, kAxisNameCount> drafts_;
};

}  // namespace

ErrorSet read_errors_csv(std::istream& in, const std::string& file) {
  ErrorSet set = Reader(file).read(in);
  prepare_lookup(set);
  return set;
}

ErrorSet load_errors_csv(const std::string& path) {
  if (path == "-") return read_errors_csv(std::cin, "<stdin>");
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const std::string reason = std::generic_category().message(errno);
    throw InputError(
        path, 0, "cannot open the errors CSV (" + reason + "); check the path and the permissions");
  }
  return read_errors_csv(in, path);
}

}  // namespace volmap
