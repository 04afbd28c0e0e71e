#include "cli/program_setup.h"

#include "cli/parse_util.h"

namespace volmap::cli {

void ProgramSetupOptions::add_to(CLI::App& sub) {
  sub.add_option("--work-offset", work_offset,
                 "Machine position X,Y,Z (mm) of the program origin for G54");
  sub.add_option("--var-file", var_file, "LinuxCNC parameter file with the G54-G59.3 offsets");
  sub.add_option("--tool-table", tool_table,
                 "LinuxCNC tool table (.tbl) for G43 H: Z is the tool length offset in mm, "
                 "relative to the machine file's tool");
  sub.add_option("--initial-position", initial,
                 "Where the tool stands at the start, X,Y,Z in program coordinates (G54, mm); "
                 "for programs that never command an axis");
}

nc::ProgramSetup ProgramSetupOptions::load(const Machine& m) const {
  nc::ProgramSetup setup;
  if (!var_file.empty()) nc::read_var_file(var_file, setup);
  if (!work_offset.empty()) {
    const AxisVector wo = parse_axis_position(m, work_offset, "--work-offset");
    for (int a = 0; a < 3; ++a) setup.work_offset_mm[0][a] = wo[a];
  }
  if (!tool_table.empty()) nc::read_tool_table(tool_table, setup);
  if (!initial.empty()) {
    Machine any = m;
    for (auto& L : any.limits) L.unlimited = true;  // a program position, not an axis value
    const AxisVector p = parse_axis_position(any, initial, "--initial-position");
    setup.initial_position_mm = Eigen::Vector3d(p[0], p[1], p[2]) + setup.work_offset_mm[0];
  }
  return setup;
}

}  // namespace volmap::cli
