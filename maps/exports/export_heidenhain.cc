// HEIDENHAIN TNC exports (docs/exports.md, "heidenhain"):
//
//  * Nonlinear axis error compensation: one compensation-value table
//    <K>.COM per input axis K (AXISPOS = the position of K, columns X Y Z =
//    the error of that output axis as a function of K on the home
//    line), and the assignment table VOLMAP.CMA that enters <K>.COM in the
//    column of K ("[axis of the .COM column] = F(axis of the .CMA column)").
//    Values are errors, as HEIDENHAIN's axis-error compensation takes them
//    (MP720: "positive if the table travel is too long"; the nonlinear
//    example plots the error): -du, the error along the output axis at the
//    commanded position. The own-axis column is absolute; cross columns are
//    relative to the home node so that the three tables add up to the
//    home-line decomposition du(x,y,z) ~ du(home) + sum_K [du along K -
//    du(home)] without counting the home value twice.
//  * KinematicsComp-style per-axis tables KC_<K>.COM of the six ISO 230-1
//    component errors of axis K (columns C1..C6 = EXK EYK EZK EAK EBK ECK,
//    the order HEIDENHAIN recommends), when the errors are given.
//  * HEIDENHAIN.txt: what was written, signs, units, resampling, the
//    location errors for the kinematics description.
//
// Tables: "BEGIN <name> MM", a header row, one row per point, "[END]".
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "maps/exports/exporters.h"

namespace volmap::maps::exporters {

namespace {

constexpr std::int64_t kMaxPointsPerTable = 256;  // see docs/exports.md

// "+0.0012" / "-0.0012"; a rounded zero is "+0.0000" whatever its sign.
std::string signed_fixed(double v, int decimals) {
  std::string s = fixed(v, decimals);
  return s[0] == '-' ? s : "+" + s;
}

// Nodes kept for a table of at most kMaxPointsPerTable points: every k-th
// node from the first, and always the last (the travel end).
std::vector<std::int64_t> resampled_nodes(const GridAxis& g) {
  std::vector<std::int64_t> keep;
  const std::int64_t step = g.count <= kMaxPointsPerTable
                                ? 1
                                : (g.count - 1 + kMaxPointsPerTable - 2) / (kMaxPointsPerTable - 1);
  for (std::int64_t k = 0; k < g.count - 1; k += step) keep.push_back(k);
  keep.push_back(g.count - 1);
  return keep;
}

// A TNC table as the control and the open readers (pyLSV2's table reader)
// read it: "BEGIN <name>[ MM]", the header row, one row per entry, "[END]",
// CRLF line ends. A column starts where its name starts in the header and
// runs to where the next name starts; values are left-aligned at the
// column's start and blank-padded, every line padded to the full width, so
// slicing at the header's positions gives each value whole. Width: the
// longest of the name and its values, plus one blank (the header names stay
// separated, also the last one, which a regex reader needs).
std::string tnc_table(const std::string& begin, const std::vector<std::string>& columns,
                      const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> width;
  for (size_t c = 0; c < columns.size(); ++c) {
    size_t w = columns[c].size();
    for (const auto& r : rows) w = std::max(w, r[c].size());
    width.push_back(w + 1);
  }
  auto line = [&](const std::vector<std::string>& cells) {
    std::string s;
    for (size_t c = 0; c < cells.size(); ++c) s += fmt::format("{:<{}}", cells[c], width[c]);
    return s + "\r\n";
  };
  std::string text = "BEGIN " + begin + "\r\n" + line(columns);
  for (const auto& r : rows) text += line(r);
  return text + "[END]\r\n";
}

// ISG-style name of a location error for the notes: EC0X stays EC0X.
std::string location_line(const std::string& name, double value) {
  const bool angular = name.size() > 1 && (name[1] == 'A' || name[1] == 'B' || name[1] == 'C');
  return angular ? fmt::format("  {} = {} deg ({} µrad)\n", name,
                               signed_fixed(value * 180.0 / M_PI, 8), fixed(value * 1e6, 3))
                 : fmt::format("  {} = {} mm\n", name, signed_fixed(value, 6));
}

// <K>.COM of axis `in`: the error of every axis (minus the correction) on
// the home line at the nodes `keep` of K, with the BACKLASH column of a
// bidirectional K.
ExportFile axis_com_file(const VolumetricTable& t, const std::vector<std::int64_t>& home, int in,
                         const std::vector<std::int64_t>& keep) {
  const GridAxis& g = t.grid[static_cast<size_t>(in)];
  const char k = axis_char(g.axis);
  const bool bidir = is_bidirectional(t, in);
  std::vector<std::vector<double>> col(3);
  for (int out = 0; out < 3; ++out) {
    col[static_cast<size_t>(out)] =
        along_axis(t, home, in, du_channel(t, out), out == in && bidir ? +1 : 0);
    for (double& v : col[static_cast<size_t>(out)]) v = -v;  // error = -correction
    if (out != in) {
      const double at_home =
          col[static_cast<size_t>(out)][static_cast<size_t>(home[static_cast<size_t>(in)])];
      for (double& v : col[static_cast<size_t>(out)]) v -= at_home;
    }
  }
  std::vector<double> backlash;
  if (bidir) {
    backlash = along_axis(t, home, in, du_channel(t, in), -1);
    for (double& v : backlash) v = -v;
  }
  std::vector<std::string> columns = {"NR", "AXISPOS"};
  for (int out = 0; out < 3; ++out)
    columns.push_back(std::string(1, axis_char(t.grid[static_cast<size_t>(out)].axis)));
  if (bidir) columns.push_back("BACKLASH");
  std::vector<std::vector<std::string>> rows;
  for (std::int64_t node : keep) {
    std::vector<std::string> cells = {std::to_string(rows.size()),
                                      signed_fixed(display_position(g.axis, g.node(node)), 4)};
    for (int out = 0; out < 3; ++out)
      cells.push_back(signed_fixed(col[static_cast<size_t>(out)][static_cast<size_t>(node)], 4));
    if (bidir) cells.push_back(signed_fixed(backlash[static_cast<size_t>(node)], 4));
    rows.push_back(std::move(cells));
  }
  const std::string name = fmt::format("{}.COM", k);
  return {name, tnc_table(name + " MM", columns, rows)};
}

// KC_<K>.COM: the component errors of axis g (all zero without errors) at the
// table's nodes of K, resampled to the table limit.
ExportFile kinematics_comp_file(const GridAxis& g, const AxisErrors* e) {
  const std::vector<std::int64_t> keep = resampled_nodes(g);
  std::vector<std::vector<std::string>> rows;
  for (std::int64_t node : keep) {
    std::array<double, kComponentCount> v{};
    if (e != nullptr) {
      try {
        evaluate_axis(*e, g.node(node), 0, OutsidePolicy::kError, v);
      } catch (const std::out_of_range& ex) {
        throw ExportError(
            fmt::format("`format` heidenhain: the errors do not cover the table: {}", ex.what()));
      }
    }
    std::vector<std::string> cells = {std::to_string(rows.size()),
                                      signed_fixed(display_position(g.axis, g.node(node)), 4)};
    for (int c = 0; c < kComponentCount; ++c)
      cells.push_back(c < 3 ? signed_fixed(v[static_cast<size_t>(c)], 6)
                            : signed_fixed(v[static_cast<size_t>(c)] * 180.0 / M_PI, 8));
    rows.push_back(std::move(cells));
  }
  const std::string name = fmt::format("KC_{}.COM", axis_char(g.axis));
  return {name,
          tnc_table(name + " MM", {"NR", "AXISPOS", "C1", "C2", "C3", "C4", "C5", "C6"}, rows)};
}

}  // namespace

std::vector<ExportFile> heidenhain(const VolumetricTable& t, const ExportOptions& o) {
  const bool nonlinear = t.three_axis_correction();
  if (!nonlinear && o.errors == nullptr)
    throw ExportError(fmt::format(
        "`format` heidenhain: nonlinear axis error compensation takes three-axis tables only (this "
        "one has {} axes); give `errors` E.csv for the KinematicsComp component-error tables",
        t.axis_count()));
  std::vector<ExportFile> files;
  std::string notes = fmt::format(
      "volmap export for HEIDENHAIN TNC: machine {}, errors {}\n"
      "Units: positions (AXISPOS) mm or degrees; values mm (angles of KC_*.COM in degrees).\n"
      "Layout: TNC tables, CRLF line ends; a column starts where its name starts in the header\n"
      "row, values are left-aligned in it (as the TNC's own tables and pyLSV2's reader have\n"
      "them). Enter VOLMAP.CMA and the .COM tables as the machine's documentation says for\n"
      "nonlinear axis error compensation (MP730 on the TNC 4xx; the setting on newer controls\n"
      "is not confirmed).\n"
      "Not confirmed by a HEIDENHAIN source, check on the control before use: the sign of the\n"
      "<K>.COM values (error, as MP720's linear compensation takes it); the points a table may\n"
      "have on an iTNC 530 / TNC 6x0 (256 on the TNC 4xx); the NR column (volmap numbers the\n"
      "points from 0); what the control applies outside a table's AXISPOS range; the unit of\n"
      "the KC_*.COM angles and the syntax of a COMPTAB cell; and which controls (TNC 640/620,\n"
      "iTNC 530, MANUALplus) read this .COM layout at all: the column layout is taken from\n"
      "TNC tool and pallet tables, not from .COM files. Open each table in the control's table\n"
      "editor and check its columns before activating it.\n",
      t.machine_name, t.errors_source);
  const std::vector<std::int64_t> home = home_line_nodes(t, o);

  if (nonlinear) {
    notes +=
        "\nNonlinear axis error compensation (<K>.COM, VOLMAP.CMA):\n"
        "  value = error (mm) of the column's axis as a function of the axis K of the table, on\n"
        "  the home line: minus the correction du, i.e. the error along that axis at the\n"
        "  commanded position (positive: the axis travels too far), which the control\n"
        "  compensates. Own-axis column absolute; cross columns relative to the home node, so\n"
        "  that the tables add up. Bidirectional K: the own-axis column holds the positive\n"
        "  direction, BACKLASH the value for the negative direction of traverse; cross columns\n"
        "  the mean.\n";
    std::vector<std::string> cma_columns = {"NR"}, cma_row = {"0"};
    for (int in = 0; in < 3; ++in) {
      const GridAxis& g = t.grid[static_cast<size_t>(in)];
      const char k = axis_char(g.axis);
      const std::vector<std::int64_t> keep = resampled_nodes(g);
      if (static_cast<std::int64_t>(keep.size()) < g.count)
        notes += fmt::format(
            "  {}.COM: {} nodes resampled to {} points (every {}th node and the travel "
            "end; at most {} points per table)\n",
            k, g.count, keep.size(), keep[1] - keep[0], kMaxPointsPerTable);
      files.push_back(axis_com_file(t, home, in, keep));
      cma_columns.push_back(std::string(1, k));
      cma_row.push_back(fmt::format("{}.COM", k));
    }
    cma_columns.push_back("ACTIVE");
    cma_row.push_back("*");
    files.push_back({"VOLMAP.CMA", tnc_table("VOLMAP.CMA", cma_columns, {cma_row})});
  }

  if (o.errors != nullptr) {
    const ErrorSet& errors = *o.errors;
    notes +=
        "\nKinematicsComp component-error tables (KC_<K>.COM):\n"
        "  C1 C2 C3 = EXK EYK EZK (mm), C4 C5 C6 = EAK EBK ECK (degrees): the ISO 230-1 errors\n"
        "  (actual minus nominal, right-handed rotations of the moving component) of axis K at\n"
        "  the table's nodes of K, mean of both approach directions for a bidirectional axis.\n"
        "  Enter them in the COMPTAB column of the kinematics description before MachAxis K\n"
        "  (at most 100 COMPTAB entries including the MachAxis entries). The positioning error\n"
        "  (C1 of a linear axis) is usually corrected in the axis column of <K>.COM instead:\n"
        "  do not enter it twice.\n";
    for (int a = 0; a < t.axis_count(); ++a) {
      const GridAxis& g = t.grid[static_cast<size_t>(a)];
      files.push_back(kinematics_comp_file(g, errors.errors_of(g.axis)));
    }
    if (!errors.location.empty()) {
      notes +=
          "\nLocation errors (constants, ISO 230-1 meaning: an axis line's position and\n"
          "orientation; the axis turns about that line). A Trans entry before the axis alone\n"
          "also moves what the axis carries (Lei & Hsu's link meaning): enter an offset of a\n"
          "rotary axis's line before the axis and its inverse after it. Not confirmed against\n"
          "the kinematics description's documentation: check on the control.\n";
      for (const auto& [name, value] : errors.location) notes += location_line(name, value);
    }
  }
  files.push_back({"HEIDENHAIN.txt", notes});
  return files;
}

}  // namespace volmap::maps::exporters
