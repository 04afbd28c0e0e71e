// The options of the five-axis post and verify (docs/post-five-axis.md),
// shared by `volmap post` and `volmap verify`. A machine with rotary axes
// (or --five-axis) selects the five-axis path.
#pragma once

#include <CLI/CLI.hpp>
#include <map>
#include <string>

#include "cli/program_setup.h"
#include "core/model/machine.h"
#include "postproc/five_axis/five_axis_input.h"

namespace volmap::cli {

struct FiveAxisCliOptions {
  bool five_axis = false;
  std::string input_form = "auto";
  std::string part_origin;
  std::string feed_output = "inverse-time";
  double angle_tolerance_urad = 50.0;
  int angle_decimals = 5;
  bool iterate = false;

  /// post: all options; verify: --five-axis, --input-form, --part-origin.
  void add_to(CLI::App& sub, bool post);
  /// Whether the five-axis path applies (throws std::invalid_argument for
  /// --five-axis on a machine without rotary axes).
  bool applies(const Machine& m) const;
  /// The machine with the part origin placed (Machine::workpiece_origin_mm).
  Machine place_part(Machine m) const;
  post::InputForm form() const;
  /// --initial-position X,Y,Z[,rotary...]: the tip in program coordinates
  /// (mm) and the rotary angles (degrees).
  post::InitialPose initial(const Machine& m, const ProgramSetupOptions& placement) const;
  /// --tool-table: tool number -> how much longer than the machine file's
  /// tool (mm); empty without a table.
  static std::map<int, double> tool_offsets_mm(const ProgramSetupOptions& placement);
};

}  // namespace volmap::cli
