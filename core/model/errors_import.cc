#include "core/model/errors_import.h"

#include <fmt/format.h>

#include <charconv>
#include <cstdlib>
#include <iostream>
#include <iterator>
#include <map>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "core/common/axis_name.h"
#include "core/common/csv.h"
#include "core/common/input_error.h"
#include "core/common/input_file.h"
#include "core/common/units.h"
#include "core/model/errors_csv.h"

namespace volmap {

namespace {

std::string strip_comment(const std::string& line) {
  const size_t at = line.find("//");
  std::string s = at == std::string::npos ? line : line.substr(0, at);
  const size_t b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> tokens(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == ' ' || c == '\t' || c == ',' || c == ';') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

// Value in mm / rad -> um / urad as text; a cell that is not a number is
// passed on unchanged for the volmap reader to report.
std::string scaled(const std::string& cell, double factor) {
  double v = 0.0;
  const auto r = std::from_chars(cell.data(), cell.data() + cell.size(), v);
  if (r.ec != std::errc() || r.ptr != cell.data() + cell.size()) return cell;
  return fmt::format("{}", v * factor);
}

// ISO name of an ISG / Etalon parameter: "C0X" -> EC0X, "EXY" stays.
std::optional<ErrorName> iso_name(const std::string& raw) {
  std::string n = raw;
  for (char& c : n) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (n.size() == 3 && (n[1] == '0' || n[1] == 'O')) n = "E" + n;
  return parse_error_name(n);
}

/// File unit (mm, rad) -> errors.md unit (um, urad).
double unit_factor(const ErrorName& n) {
  return is_angular(n.component) ? units::kUradPerRad : units::kUmPerMm;
}

bool is_axis_letter(const std::string& t) {
  return t.size() == 1 &&
         axis_from_char(static_cast<char>(std::toupper(static_cast<unsigned char>(t[0]))))
             .has_value();
}

struct Emitter {
  std::string text;
  std::vector<int>& line_of;
  void line(const std::string& s, int origin) {
    text += s + "\n";
    line_of.push_back(origin);
  }
};

}  // namespace

ErrorsFormat parse_errors_format(const std::string& name) {
  if (name == "auto") return ErrorsFormat::kAuto;
  if (name == "volmap") return ErrorsFormat::kVolmap;
  if (name == "isg-csv") return ErrorsFormat::kIsgCsv;
  if (name == "etalon") return ErrorsFormat::kEtalon;
  throw std::invalid_argument("errors format " + name +
                              ": expected auto, volmap, isg-csv or etalon");
}

const char* errors_format_name(ErrorsFormat f) {
  switch (f) {
    case ErrorsFormat::kAuto:
      return "auto";
    case ErrorsFormat::kVolmap:
      return "volmap";
    case ErrorsFormat::kIsgCsv:
      return "isg-csv";
    case ErrorsFormat::kEtalon:
      return "etalon";
  }
  return "?";
}

ErrorsFormat detect_errors_format(const std::string& text, int* ambiguous_line) {
  if (ambiguous_line) *ambiguous_line = 0;
  bool slash_comments = false, hash_comments = false;
  int n = 0;
  for (const std::string& raw : csv::split_lines(text)) {
    ++n;
    const size_t b = raw.find_first_not_of(" \t");
    if (b == std::string::npos) continue;
    if (raw.compare(b, 2, "//") == 0) {
      slash_comments = true;
      continue;
    }
    if (raw[b] == '#') {
      if (slash_comments) return ErrorsFormat::kIsgCsv;  // an ISG block break
      hash_comments = true;                              // a volmap comment
      continue;
    }
    if (raw[b] == '[') return ErrorsFormat::kEtalon;
    if (slash_comments) return ErrorsFormat::kIsgCsv;
    if (raw.find(',') != std::string::npos) return ErrorsFormat::kVolmap;
    // No comma: ISG's blank- or tab-separated header, unless it is one name
    // alone (a one-column location block, "EC0X"), which both formats
    // write alike with values 1e6 apart. Comments with # before it say
    // errors.md; otherwise nothing tells them apart.
    const size_t e = raw.find_last_not_of(" \t\r");
    const bool one_token = raw.find_first_of(" \t;", b) > e;
    if (!one_token) return ErrorsFormat::kIsgCsv;
    if (hash_comments) return ErrorsFormat::kVolmap;
    if (ambiguous_line) *ambiguous_line = n;
    return ErrorsFormat::kIsgCsv;
  }
  return slash_comments ? ErrorsFormat::kIsgCsv : ErrorsFormat::kVolmap;
}

std::string isg_csv_to_errors_csv(const std::string& text, const std::string& file,
                                  std::vector<int>& line_of) {
  line_of.clear();
  Emitter out{"", line_of};
  out.line("# volmap component errors v1", 0);
  out.line("# source: ISG CSV " + file, 0);
  const std::vector<std::string> lines = csv::split_lines(text);
  bool in_block = false;       // a header has been read in this block
  std::vector<double> factor;  // per column, mm/rad -> um/urad (argument: 1)
  for (size_t i = 0; i < lines.size(); ++i) {
    const int n = static_cast<int>(i + 1);
    const std::string s = strip_comment(lines[i]);
    if (s.empty()) continue;
    if (s[0] == '#') {
      in_block = false;
      continue;
    }
    const std::vector<std::string> t = tokens(s);
    if (t.empty()) continue;  // only separators (";", ",,"): no cell, as a blank line
    if (!in_block) {
      in_block = true;
      factor.assign(t.size(), 1.0);
      std::string header;
      const bool component_block = is_axis_letter(t[0]);
      for (size_t j = 0; j < t.size(); ++j) {
        if (j == 0 && component_block) {
          header =
              std::string(1, static_cast<char>(std::toupper(static_cast<unsigned char>(t[0][0]))));
          continue;
        }
        if (is_axis_letter(t[j]))
          throw InputError(file, n, static_cast<int>(j + 1),
                           "argument " + t[j] +
                               " after the first column: blocks that depend on two axes "
                               "(functional dependencies) are not supported by volmap; give one "
                               "argument per block");
        const std::optional<ErrorName> name = iso_name(t[j]);
        if (!name)
          throw InputError(
              file, n, static_cast<int>(j + 1),
              "\"" + t[j] + "\" is not an ISO 230-1 error name (EXX, EAY) or position error (C0X)");
        factor[j] = unit_factor(*name);
        header += (header.empty() ? "" : ",") + error_name_string(*name);
      }
      out.line("", 0);
      out.line(header, n);
      continue;
    }
    std::string row;
    for (size_t j = 0; j < t.size(); ++j)
      row += (j ? "," : "") + (j < factor.size() ? scaled(t[j], factor[j]) : t[j]);
    out.line(row, n);
  }
  return out.text;
}

std::string etalon_to_errors_csv(const std::string& text, const std::string& file,
                                 std::vector<int>& line_of, std::string* skipped) {
  line_of.clear();
  Emitter out{"", line_of};
  out.line("# volmap component errors v1", 0);
  out.line("# source: Etalon exchange format " + file, 0);
  const std::vector<std::string> lines = csv::split_lines(text);
  std::string location_header, location_row;
  int location_line = 0;
  std::optional<ErrorName> section;
  std::string section_raw;
  int section_line = 0;
  bool in_grid = false;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int n = static_cast<int>(i + 1);
    const std::string s = strip_comment(lines[i]);
    if (s.empty()) continue;
    if (in_grid) {
      if (s[0] == '}') {
        in_grid = false;
        continue;
      }
      const std::vector<std::string> t = tokens(s);
      if (t.size() != 2)
        throw InputError(file, n,
                         "a Gridpoints row has two numbers, the argument and the value; this has " +
                             std::to_string(t.size()));
      out.line(t[0] + "," + scaled(t[1], unit_factor(*section)), n);
      continue;
    }
    if (s[0] == '[') {
      const size_t close = s.find(']');
      if (close == std::string::npos) throw InputError(file, n, "section name without ]");
      section_raw = strip_comment(s.substr(1, close - 1));
      section = iso_name(section_raw);
      section_line = n;
      if (!section && skipped != nullptr) *skipped += (skipped->empty() ? "" : " ") + section_raw;
      continue;
    }
    const size_t eq = s.find('=');
    if (eq == std::string::npos) throw InputError(file, n, "expected KEY = VALUE or a [SECTION]");
    std::string key = strip_comment(s.substr(0, eq));
    std::string value = strip_comment(s.substr(eq + 1));
    for (char& c : key) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (!section) {
      if (key == "GRIDPOINTS" && value.find('}') == std::string::npos) {
        // Skip the rows of an unknown section's grid.
        while (i + 1 < lines.size() && strip_comment(lines[i + 1]).rfind('}', 0) != 0) ++i;
        ++i;
      }
      continue;
    }
    if (key == "VALUE") {
      if (!section->location)
        throw InputError(file, n,
                         section_raw + " is a component error: give it as Gridpoints = { ... }");
      location_header += (location_header.empty() ? "" : ",") + error_name_string(*section);
      location_row += (location_row.empty() ? "" : ",") + scaled(value, unit_factor(*section));
      if (location_line == 0) location_line = n;
    } else if (key == "GRIDPOINTS") {
      if (section->location)
        throw InputError(file, n, section_raw + " is a position error: give it as VALUE = v");
      if (value.empty() || value[0] != '{')
        throw InputError(file, n, "Gridpoints = must be followed by {");
      if (value.size() > 1)
        throw InputError(
            file, n, "put the Gridpoints rows on the lines after \"Gridpoints = {\", one per line");
      out.line("", 0);
      out.line(fmt::format("{},{}", axis_char(section->axis), error_name_string(*section)),
               section_line);
      in_grid = true;
    }
    // Other keys (units, comments of the measuring software) carry nothing volmap models.
  }
  if (in_grid)
    throw InputError(file, static_cast<int>(lines.size()), "Gridpoints without the closing }");
  if (!location_header.empty()) {
    out.line("", 0);
    out.line(location_header, location_line);
    out.line(location_row, location_line);
  }
  return out.text;
}

ErrorSet read_errors(std::istream& in, const std::string& file, ErrorsFormat format) {
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (format == ErrorsFormat::kAuto) {
    int ambiguous = 0;
    format = detect_errors_format(text, &ambiguous);
    if (ambiguous > 0)
      throw InputError(file, ambiguous,
                       "a block of one column and no comment before it: errors.md (µm, µrad) "
                       "and ISG CSV (mm, rad) write it alike, with values a million times apart; "
                       "give `errors_format` volmap or isg-csv");
  }
  if (format == ErrorsFormat::kVolmap) {
    std::istringstream s(text);
    return read_errors_csv(s, file);
  }
  std::vector<int> line_of;
  std::string skipped;
  const std::string converted = format == ErrorsFormat::kIsgCsv
                                    ? isg_csv_to_errors_csv(text, file, line_of)
                                    : etalon_to_errors_csv(text, file, line_of, &skipped);
  std::istringstream s(converted);
  try {
    ErrorSet set = read_errors_csv(s, file);
    // Tables name their block "file:line" for later messages (outside the
    // table): the line of the original file.
    for (auto& axis : set.axis) {
      if (!axis) continue;
      for (AxisErrorTable* t : {&axis->plus, &axis->minus}) {
        const std::string prefix = file + ":";
        if (t->source.rfind(prefix, 0) != 0) continue;
        const int line = std::atoi(t->source.c_str() + prefix.size());
        if (line > 0 && static_cast<size_t>(line) <= line_of.size())
          t->source = prefix + std::to_string(line_of[static_cast<size_t>(line - 1)]);
      }
    }
    set.metadata["format"] = errors_format_name(format);
    if (!skipped.empty()) set.metadata["skipped"] = skipped;
    return set;
  } catch (const InputError& e) {
    // Same message, with the line of the original file.
    std::string message = e.what();
    std::string prefix = file + ":";
    if (e.line() > 0) {
      prefix += std::to_string(e.line()) + ":";
      if (e.column() > 0) prefix += std::to_string(e.column()) + ":";
    }
    prefix += " ";
    if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
    const int line = e.line() > 0 && static_cast<size_t>(e.line()) <= line_of.size()
                         ? line_of[static_cast<size_t>(e.line() - 1)]
                         : 0;
    throw InputError(file, line,
                     message + " (" + errors_format_name(format) + " file, read as errors.md)");
  }
}

ErrorSet load_errors(const std::string& path, ErrorsFormat format) {
  return read_input_file(path, "the errors file",
                         [format](std::istream& in, const std::string& file) {
                           return read_errors(in, file, format);
                         });
}

}  // namespace volmap
