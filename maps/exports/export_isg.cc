// Beckhoff / ISG volumetric compensation, ISG CSV format (docs/exports.md,
// "isg-csv"): the ISO 230-1 errors of the machine as the ISG kernel reads
// them. Row comments start with "//", "#" is the break between blocks, each
// block has its own header; columns are separated by a tab. Position
// (location) errors in one block with one row (names without the E: C0X is
// EC0X), then one block per axis: the argument (axis position, mm or
// degrees) at the table's nodes of that axis and its six component errors,
// translational in mm, angular in rad. A bidirectional axis gets the mean of
// both directions (the reversal is given in a comment).
#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "maps/exports/exporters.h"

namespace volmap::maps::exporters {

std::vector<ExportFile> isg_csv(const VolumetricTable& t, const ExportOptions& o) {
  const ErrorSet& errors = require_errors(o, "isg-csv");
  std::string text = fmt::format(
      "// volmap export, ISG CSV: machine {}, errors {}\n"
      "// ISO 230-1 errors (actual minus nominal; right-handed rotations of the moving component)\n"
      "// values: translational mm, angular rad; arguments: linear axes mm, rotary axes degrees\n",
      t.machine_name, t.errors_source);
  bool first_block = true;
  auto block_break = [&] {
    if (!first_block) text += "#\n";
    first_block = false;
  };
  if (!errors.location.empty()) {
    block_break();
    text += "// position errors\n";
    std::string names, values;
    for (const auto& [name, value] : errors.location) {
      const bool angular = name[1] == 'A' || name[1] == 'B' || name[1] == 'C';
      names += (names.empty() ? "" : "\t") + name.substr(1);
      values += (values.empty() ? "" : "\t") + fixed(value, angular ? 12 : 9);
    }
    text += names + "\n" + values + "\n";
  }
  for (int a = 0; a < t.axis_count(); ++a) {
    const GridAxis& g = t.grid[static_cast<size_t>(a)];
    const AxisErrors* e = errors.errors_of(g.axis);
    if (e == nullptr) continue;
    block_break();
    text += fmt::format("// component errors of {}{}\n", axis_char(g.axis),
                        e->bidirectional() ? " (mean of both approach directions)" : "");
    text += std::string(1, axis_char(g.axis));
    for (int c = 0; c < kComponentCount; ++c)
      text += "\t" + component_error_name(static_cast<Component>(c), g.axis);
    text += "\n";
    // The axis's own positioning component: EXX for X, ..., ECC for C.
    const size_t own = static_cast<size_t>(g.axis);
    double reversal = 0.0;
    for (std::int64_t k = 0; k < g.count; ++k) {
      std::array<double, kComponentCount> v{};
      try {
        evaluate_axis(*e, g.node(k), 0, OutsidePolicy::kError, v);
        if (e->bidirectional()) {
          std::array<double, kComponentCount> plus{}, minus{};
          evaluate_axis(*e, g.node(k), +1, OutsidePolicy::kError, plus);
          evaluate_axis(*e, g.node(k), -1, OutsidePolicy::kError, minus);
          reversal = std::max(reversal, std::abs(minus[own] - plus[own]));
        }
      } catch (const std::out_of_range& ex) {
        throw ExportError(
            fmt::format("`format` isg-csv: the errors do not cover the table: {}", ex.what()));
      }
      text += fixed(display_position(g.axis, g.node(k)), 4);
      for (int c = 0; c < kComponentCount; ++c)
        text += "\t" + fixed(v[static_cast<size_t>(c)], c < 3 ? 9 : 12);
      text += "\n";
    }
    if (e->bidirectional())
      text += fmt::format(
          "// {}: largest reversal of {} between the directions {} {}\n", axis_char(g.axis),
          component_error_name(static_cast<Component>(own), g.axis),
          fixed(reversal, is_rotary(g.axis) ? 12 : 9), is_rotary(g.axis) ? "rad" : "mm");
  }
  return {{"isg_errors.csv", text}};
}

}  // namespace volmap::maps::exporters
