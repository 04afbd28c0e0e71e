// LinuxCNC's files that place a program on the machine: the parameter
// (.var) file's work offsets and the tool table (.tbl).
#pragma once

#include <string>

#include "gcode/program_setup.h"

namespace volmap::nc {

/// Reads a LinuxCNC parameter (.var) file's work offsets (parameters
/// 5221-5223 for G54, 20 apart up to G59.3). Throws InputError.
void read_var_file(const std::string& path, ProgramSetup& setup);
/// Reads a LinuxCNC tool table (.tbl): "T1 P1 Z12.5 ... ;comment". Z is the
/// tool length offset in mm, as LinuxCNC applies it: relative to the tool of
/// offset zero, which volmap takes to be the machine file's tool.
void read_tool_table(const std::string& path, ProgramSetup& setup);

}  // namespace volmap::nc
