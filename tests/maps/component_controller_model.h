// Models of controls that compensate with the ISO 230-1 component and
// location errors themselves (the ISG kernel reading ISG CSV; a TNC with
// KinematicsComp reading KC_<K>.COM tables). Such a control holds its own
// kinematic model of the machine (the geometry is its configuration, not
// the file's) and feeds it the errors read from the file; here that model
// is volmap's model of the same machine, fed from what these readers
// parse, so what is checked is the file: its names, signs, units and
// positions. The readers follow the formats' documentation
// (docs/exports.md cites it), not maps/exports.
#pragma once

#include <fmt/format.h>

#include <array>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "tests/maps/controller_models.h"

namespace volmap::maps::controller_models {

/// Component errors per axis letter: (position mm or rad, EX EY EZ mm,
/// EA EB EC rad); location errors by ISO name (mm, rad).
struct ComponentErrors {
  std::map<char, std::vector<std::pair<double, std::array<double, 6>>>> axes;
  std::map<std::string, double> location;
};

/// The same errors as an errors.md file (µm, µrad), for the control's model.
inline ErrorSet as_error_set(const ComponentErrors& c) {
  std::string text = "# volmap component errors v1\n";
  for (const auto& [k, rows] : c.axes) {
    text += fmt::format("\n{0},EX{0},EY{0},EZ{0},EA{0},EB{0},EC{0}\n", k);
    for (const auto& [pos, v] : rows)
      text += fmt::format("{:.9f},{:.9f},{:.9f},{:.9f},{:.9f},{:.9f},{:.9f}\n", pos, v[0] * 1e3,
                          v[1] * 1e3, v[2] * 1e3, v[3] * 1e6, v[4] * 1e6, v[5] * 1e6);
  }
  if (!c.location.empty()) {
    std::string names, values;
    for (const auto& [name, v] : c.location) {
      const bool angular = name[1] == 'A' || name[1] == 'B' || name[1] == 'C';
      names += (names.empty() ? "" : ",") + name;
      values += (values.empty() ? "" : ",") + fmt::format("{:.9f}", v * (angular ? 1e6 : 1e3));
    }
    text += "\n" + names + "\n" + values + "\n";
  }
  std::istringstream in(text);
  return read_errors_csv(in, "controller model");
}

// ISG CSV (Beckhoff TF5280, "ISG CSV format"): "//" starts a comment line,
// "#" starts a new block, cells separated by blanks or tabs, each block its
// own header. A position-error block names the errors without the E
// ("C0X" = EC0X) and has one row; a component-error block has the axis
// first (mm; degrees for rotary axes), then E<dir><axis> columns. Values mm
// and rad.
inline ComponentErrors read_isg_csv(const std::string& text) {
  ComponentErrors out;
  std::vector<std::string> header;
  for (const std::string& line : lines_of(text)) {
    if (line.rfind("//", 0) == 0) continue;
    if (line.rfind("#", 0) == 0) {
      header.clear();
      continue;
    }
    std::istringstream cells(line);
    std::vector<std::string> row;
    for (std::string c; cells >> c;) row.push_back(c);
    if (row.empty()) continue;
    if (header.empty()) {
      header = row;
      continue;
    }
    if (row.size() != header.size()) throw std::runtime_error("row length: " + line);
    if (header[0].size() == 3 && header[0][1] == '0') {  // position errors
      for (size_t i = 0; i < row.size(); ++i) out.location["E" + header[i]] = number(row[i], line);
      continue;
    }
    const char k = header[0].at(0);
    std::array<double, 6> v{};
    for (size_t i = 1; i < header.size(); ++i) {
      const std::string& h = header[i];
      if (h.size() != 3 || h[0] != 'E' || h[2] != k) throw std::runtime_error("column " + h);
      v[static_cast<size_t>(std::string("XYZABC").find(h[1]))] = number(row[i], line);
    }
    out.axes[k].emplace_back(number(row[0], line), v);
  }
  return out;
}

// KC_<K>.COM tables (TNC tables, read as read_tnc_table does): AXISPOS the
// position of K, C1 C2 C3 = EXK EYK EZK (mm), C4 C5 C6 = EAK EBK ECK
// (degrees); the location errors from the notes' "  <name> = <v> deg" /
// "  <name> = <v> mm" lines (the kinematics description's Trans entries).
inline ComponentErrors read_kinematics_comp(const std::map<char, std::string>& tables,
                                            const std::string& notes) {
  ComponentErrors out;
  for (const auto& [k, text] : tables) {
    const TncTable t = read_tnc_table(text);
    for (size_t r = 0; r < t.rows.size(); ++r) {
      std::array<double, 6> v{};
      for (int c = 0; c < 6; ++c)
        v[static_cast<size_t>(c)] =
            t.number_at(r, "C" + std::to_string(c + 1)) * (c < 3 ? 1.0 : M_PI / 180.0);
      out.axes[k].emplace_back(t.number_at(r, "AXISPOS"), v);
    }
  }
  for (const std::string& line : lines_of(notes)) {
    const size_t eq = line.find(" = ");
    if (line.rfind("  E", 0) != 0 || eq != 6) continue;
    const std::string name = line.substr(2, 4);
    const size_t unit = line.find(' ', eq + 3);
    const double v = number(line.substr(eq + 3, unit - eq - 3), line);
    out.location[name] = line.compare(unit + 1, 3, "deg") == 0 ? v * M_PI / 180.0 : v;
  }
  return out;
}

}  // namespace volmap::maps::controller_models
