// The options that place an NC program on the machine, shared by post and
// verify: work offsets, tool table, where the tool starts.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "core/model/machine.h"
#include "gcode/nc_interpreter.h"
#include "gcode/program_reader.h"

namespace volmap::cli {

struct ProgramSetupOptions {
  std::string work_offset, var_file, tool_table, initial, subroutine_path;
  std::string dialect = "auto";
  /// Adds --work-offset, --var-file, --tool-table, --initial-position,
  /// --subroutine-path, --dialect.
  void add_to(CLI::App& sub);
  /// Where `O<name> call` finds NAME.ngc: --subroutine-path's folders
  /// (':'-separated), else the folder of `program` (the working folder for
  /// standard input).
  std::vector<std::string> subroutine_dirs(const std::string& program) const;
  /// Reads the files and parses the values (mm; the initial position in
  /// program coordinates, G54). Throws InputError / std::invalid_argument.
  nc::ProgramSetup load(const Machine& m) const;
};

/// What stderr says about how a program was read: tape leader and trailer
/// written as they are, the program flattened from a line on (or, when no
/// line of it needed a change, evaluated and written as it was read).
void print_read_notes(const std::string& in_name, const nc::ReadReport& r,
                      bool flattened_written_as_read);

}  // namespace volmap::cli
