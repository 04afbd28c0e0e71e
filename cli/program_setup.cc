#include "cli/program_setup.h"

#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include "cli/parse_util.h"

namespace volmap::cli {

void ProgramSetupOptions::add_to(CLI::App& sub) {
  sub.add_option("--work-offset", work_offset,
                 "Machine position X,Y,Z (mm) of the program origin for G54");
  sub.add_option("--var-file", var_file, "LinuxCNC parameter file with the G54-G59.3 offsets");
  sub.add_option("--tool-table", tool_table,
                 "LinuxCNC tool table (.tbl) for G43 H (five axes: the lengths of the tools the "
                 "program changes to): Z is the tool length offset in mm, relative to the machine "
                 "file's tool; D the diameter (mm) for cutter compensation G41/G42 D");
  sub.add_option("--initial-position", initial,
                 "Where the tool stands at the start, X,Y,Z in program coordinates (G54, mm); "
                 "for programs that never command an axis");
  sub.add_option("--subroutine-path", subroutine_path,
                 "Folders (DIR[:DIR...]) where O<name> call finds NAME.ngc (LinuxCNC's "
                 "SUBROUTINE_PATH); default: the program's folder");
  sub.add_option("--dialect", dialect,
                 "The program's NC language: auto (default: fanuc when the program opens with a "
                 "program number O1234 or :1234, else linuxcnc; stderr says which), linuxcnc, "
                 "fanuc (Fanuc and Haas)")
      ->check(CLI::IsMember({"auto", "linuxcnc", "fanuc"}));
}

std::vector<std::string> ProgramSetupOptions::subroutine_dirs(const std::string& program) const {
  std::vector<std::string> dirs;
  if (subroutine_path.empty()) {
    const std::filesystem::path folder =
        program == "-" ? std::filesystem::path() : std::filesystem::path(program).parent_path();
    dirs.push_back(folder.empty() ? "." : folder.string());
    return dirs;
  }
  std::size_t b = 0;
  for (;;) {
    const std::size_t e = subroutine_path.find(':', b);
    const std::string dir = subroutine_path.substr(b, e == std::string::npos ? e : e - b);
    if (!dir.empty()) dirs.push_back(dir);
    if (e == std::string::npos) break;
    b = e + 1;
  }
  return dirs;
}

nc::ProgramSetup ProgramSetupOptions::load(const Machine& m) const {
  nc::ProgramSetup setup;
  setup.dialect = nc::parse_dialect(dialect);
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

void print_read_notes(const std::string& in_name, const nc::ReadReport& r,
                      bool flattened_written_as_read) {
  if (r.dialect.detected)
    std::cerr << fmt::format("note: {}: read as {} (--dialect auto: {})\n", in_name,
                             r.dialect.dialect == nc::Dialect::kFanuc ? "Fanuc/Haas" : "LinuxCNC",
                             r.dialect.reason);
  if (r.leader_lines > 0)
    std::cerr << fmt::format(
        "note: {}: line{} 1{} before the first '%' (tape leader) written as they are, not run\n",
        in_name, r.leader_lines > 1 ? "s" : "",
        r.leader_lines > 1 ? fmt::format("-{}", r.leader_lines) : "");
  if (r.flattened_from > 0 && flattened_written_as_read)
    std::cerr << fmt::format(
        "note: {}:{}: from here on the program uses parameters, expressions or O-word control "
        "flow: evaluated, {} line{} ran as {} block{}; none needed a change, so written as "
        "read\n",
        in_name, r.flattened_from, r.flat_source_lines, r.flat_source_lines == 1 ? "" : "s",
        r.flat_blocks, r.flat_blocks == 1 ? "" : "s");
  else if (r.flattened_from > 0)
    std::cerr << fmt::format(
        "note: {}:{}: from here on the program uses parameters, expressions or O-word control "
        "flow: written flat (evaluated), {} line{} ran as {} block{}\n",
        in_name, r.flattened_from, r.flat_source_lines, r.flat_source_lines == 1 ? "" : "s",
        r.flat_blocks, r.flat_blocks == 1 ? "" : "s");
  if (r.trailer_lines > 0)
    std::cerr << fmt::format(
        "note: {}: {} line{} after the closing '%' written as they are, not "
        "run\n",
        in_name, r.trailer_lines, r.trailer_lines > 1 ? "s" : "");
}

}  // namespace volmap::cli
