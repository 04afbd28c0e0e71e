// Reader for the component and location errors CSV, version 1
// (spec: shared/spec/errors.md; contract: core/errors_csv.h).
//
// Steps: split the text into physical lines (BOM and CR stripped), take the
// "# key: value" metadata before the first block, group the other lines into
// blocks at blank lines, read each block into per-component tables (file
// units converted to mm / rad), and finally merge the components of each axis
// and direction onto one knot vector (AxisErrorTable).
//
// Bidirectional data: a component given with dir=+1 and dir=-1 rows has one
// table per direction; a component given without direction (no dir column,
// or rows of one direction only) serves both. An axis is bidirectional when
// any of its components is.
#include "core/model/errors_csv.h"

#include <array>
#include <cmath>
#include <istream>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/common/csv.h"
#include "core/common/input_error.h"
#include "core/common/input_file.h"
#include "core/common/units.h"
#include "core/model/errors_csv_tables.h"

namespace volmap {
namespace {

using csv::Cell;
using csv::parse_number;
using csv::split_cells;
using errors_csv_tables::AxisDraft;
using errors_csv_tables::ComponentData;
using errors_csv_tables::ComponentRows;
using errors_csv_tables::make_component_table;
using errors_csv_tables::merge_component_tables;

struct Line {
  int number = 0;  ///< 1-based physical line
  std::string text;
};

std::string quoted(std::string_view s) {
  // Appended piecewise: GCC 12 warns falsely (-Wrestrict, bug 105651) on
  // "literal" + std::string&&.
  std::string out(1, '\'');
  out += s;
  out += '\'';
  return out;
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
// Reader

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) { set_.file = file_; }

  ErrorSet read(std::istream& in) {
    std::vector<Line> block;
    bool seen_block = false;
    csv::LineReader lines(in, file_);
    std::string text;
    while (lines.next(text)) {
      if (csv::is_comment(text)) {
        if (!seen_block) read_metadata(text, lines.number());
        continue;
      }
      if (csv::is_blank(text)) {
        if (!block.empty()) read_block(block);
        block.clear();
        continue;
      }
      seen_block = true;
      block.push_back({lines.number(), std::move(text)});
    }
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

  void read_metadata(std::string_view text, int line) {
    const std::optional<csv::MetadataComment> entry = csv::parse_metadata_comment(csv::trim(text));
    if (!entry) return;
    set_.metadata[std::string(entry->key)] = std::string(entry->value);
    set_.metadata_line[std::string(entry->key)] = line;
    if (entry->key == "convention") {
      const std::optional<LocationConvention> c = parse_location_convention(entry->value);
      if (!c)
        fail(line, "unknown convention " + quoted(entry->value) +
                       "; write `# convention: iso230-1` (the default: location errors as ISO "
                       "230-1 defines them) or `# convention: link` (Lei & Hsu's link errors)");
      set_.convention = *c;
    }
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

  /// The columns of a component block's header.
  struct ComponentColumns {
    std::optional<std::size_t> dir_column;
    /// component_of[j]: component of header column j (columns 1..), -1 for dir.
    std::vector<int> component_of;
    std::array<bool, kComponentCount> in_header{};
  };

  void read_component_block(const std::vector<Line>& block, const std::vector<Cell>& header,
                            AxisName axis) {
    const int header_line = block.front().number;
    const ComponentColumns columns = read_component_header(header, header_line, axis);
    const std::array<ComponentRows, 2> rows = read_component_rows(block, header, columns, axis);

    const bool bidirectional = !rows[0].line.empty() && !rows[1].line.empty();
    AxisDraft& draft = axis_draft(axis, header_line);
    for (int c = 0; c < kComponentCount; ++c) {
      if (!columns.in_header[c]) continue;
      ComponentData data;
      const int single = rows[0].line.empty() ? 1 : 0;
      data.plus = make_component_table(rows[bidirectional ? 0 : single], axis,
                                       static_cast<Component>(c), header_line, file_);
      if (bidirectional)
        data.minus =
            make_component_table(rows[1], axis, static_cast<Component>(c), header_line, file_);
      draft.component[c] = std::move(data);
    }
  }

  ComponentColumns read_component_header(const std::vector<Cell>& header, int header_line,
                                         AxisName axis) {
    const std::string axis_letter(1, axis_char(axis));
    ComponentColumns columns;
    columns.component_of.assign(header.size(), -1);
    bool any_error = false;
    for (std::size_t j = 1; j < header.size(); ++j) {
      const Cell& cell = header[j];
      if (cell.text == "dir") {
        if (columns.dir_column)
          fail(header_line, cell.column, "duplicate column dir; give the direction once per row");
        columns.dir_column = j;
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
      if (columns.in_header[c])
        fail(header_line, cell.column, "duplicate column " + canonical + "; give each error once");
      columns.in_header[c] = true;
      claim_name(canonical, header_line, cell.column);
      columns.component_of[j] = c;
      any_error = true;
    }
    if (!any_error)
      fail(header_line, "the " + axis_letter +
                            " block has no error column; add columns such "
                            "as " +
                            component_names_of(axis));
    return columns;
  }

  /// The data rows of a component block, by direction: 0 = +1 (or no dir
  /// column), 1 = -1.
  std::array<ComponentRows, 2> read_component_rows(const std::vector<Line>& block,
                                                   const std::vector<Cell>& header,
                                                   const ComponentColumns& columns,
                                                   AxisName axis) const {
    const std::string axis_letter(1, axis_char(axis));
    std::array<ComponentRows, 2> rows;
    std::array<std::string_view, 2> last_position_text;
    const bool rotary = is_rotary(axis);
    for (std::size_t r = 1; r < block.size(); ++r) {
      const Line& row = block[r];
      const std::vector<Cell> cells = split_cells(row.text);
      check_cell_count(row, cells, header, block.front());
      int direction = 0;
      if (columns.dir_column) {
        const std::string_view d = cells[*columns.dir_column].text;
        if (d == "+1" || d == "1") {
          direction = 0;
        } else if (d == "-1") {
          direction = 1;
        } else {
          fail(row.number, cells[*columns.dir_column].column,
               "dir is " + quoted(d) +
                   "; it must be +1 (measured moving in the positive "
                   "direction) or -1 (negative direction)");
        }
      }
      const double position = number_in(row, cells[0], header[0], true);
      ComponentRows& rs = rows[direction];
      if (!rs.position_file.empty()) {
        const double previous = rs.position_file.back();
        const double previous_internal = rotary ? previous * units::kRadPerDeg : previous;
        const double internal = rotary ? position * units::kRadPerDeg : position;
        if (!(position > previous) || !(internal > previous_internal)) {
          std::string which = columns.dir_column ? (direction == 0 ? " dir=+1" : " dir=-1") : "";
          fail(row.number, cells[0].column,
               axis_letter + " position " + std::string(cells[0].text) +
                   " is not greater than the previous" + which + " position " +
                   std::string(last_position_text[direction]) + " (line " +
                   std::to_string(rs.line.back()) + "); positions must be strictly increasing" +
                   (columns.dir_column ? " within each direction" : "") +
                   ": sort the rows and remove duplicates");
        }
      }
      std::array<double, kComponentCount> values{};
      for (std::size_t j = 1; j < header.size(); ++j) {
        if (columns.component_of[j] < 0) continue;
        values[columns.component_of[j]] = number_in(row, cells[j], header[j], false);
      }
      rs.position_file.push_back(position);
      rs.line.push_back(row.number);
      rs.value_file.push_back(values);
      last_position_text[direction] = cells[0].text;
    }
    return rows;
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
      set_.location[canonical[j]] = v / (angular[j] ? units::kUradPerRad : units::kUmPerMm);
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
      errors.plus = merge_component_tables(draft, errors.axis, false, file_);
      if (bidirectional) errors.minus = merge_component_tables(draft, errors.axis, true, file_);
      set_.axis[a] = std::move(errors);
    }
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
  return read_input_file(path, "the errors CSV", read_errors_csv);
}

}  // namespace volmap
