// The options that place an NC program on the machine, shared by post and
// verify: work offsets, tool table, where the tool starts.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "core/model/machine.h"
#include "gcode/nc_interpreter.h"

namespace volmap::cli {

struct ProgramSetupOptions {
  std::string work_offset, var_file, tool_table, initial;
  /// Adds --work-offset, --var-file, --tool-table, --initial-position.
  void add_to(CLI::App& sub);
  /// Reads the files and parses the values (mm; the initial position in
  /// program coordinates, G54). Throws InputError / std::invalid_argument.
  nc::ProgramSetup load(const Machine& m) const;
};

}  // namespace volmap::cli
