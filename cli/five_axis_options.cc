#include "cli/five_axis_options.h"

#include <stdexcept>

#include "cli/commands.h"
#include "cli/parse_util.h"
#include "gcode/linuxcnc_files.h"

namespace volmap::cli {

void FiveAxisCliOptions::add_to(CLI::App& sub, bool post) {
  sub.add_flag(
      "--five-axis", five_axis,
      "Five-axis program (default for a machine with rotary axes): a tool path in workpiece "
      "coordinates in, machine axes out (docs/post-five-axis.md)");
  sub.add_option(
         "--input-form", input_form,
         "Five-axis input: auto (default), tcp (X Y Z tip + rotary angles), vector (X Y Z + I J K "
         "or A3 B3 C3), apt (CLDATA GOTO/x,y,z,i,j,k)")
      ->check(CLI::IsMember({"auto", "tcp", "vector", "apt"}));
  sub.add_option(
      "--part-origin", part_origin,
      "Five-axis: the program origin X,Y,Z (mm) in the frame of the table nearest the workpiece "
      "(for X'Y'ZA'C': on the C axis at the table face); default the machine file's workpiece "
      "origin");
  if (!post) return;
  sub.add_option(
         "--angle-tolerance-urad", angle_tolerance_urad,
         "Five-axis: bound on the angle between the actual and the nominal tool axis, also between "
         "points (default 50)")
      ->check(CLI::PositiveNumber);
  sub.add_option(
         "--feed-output", feed_output,
         "Five-axis feeds: inverse-time (G93, default) or per-minute (G94 over the machine X Y Z "
         "length of each piece)")
      ->check(CLI::IsMember({"inverse-time", "per-minute"}));
  sub.add_option("--angle-decimals", angle_decimals,
                 "Five-axis: decimals of rotary axis words, degrees (default 5)")
      ->check(CLI::Range(0, 9));
  sub.add_flag(
      "--iterate", iterate,
      "Five-axis: iterate the correction to the exact solution of eq. 4 (default one step, eq. 6)");
}

bool FiveAxisCliOptions::applies(const Machine& m) const {
  if (five_axis && !m.has_rotary_axes())
    throw UsageError("--five-axis: machine \"" + m.name + "\" has no rotary axes");
  return m.has_rotary_axes();
}

Machine FiveAxisCliOptions::place_part(Machine m) const {
  if (part_origin.empty()) return m;
  const std::vector<double> v = parse_numbers(part_origin, "--part-origin");
  if (v.size() != 3) throw UsageError("--part-origin needs X,Y,Z (mm)");
  m.workpiece_origin_mm = Eigen::Vector3d(v[0], v[1], v[2]);
  return m;
}

post::InputForm FiveAxisCliOptions::form() const { return *post::parse_input_form(input_form); }

std::map<int, double> FiveAxisCliOptions::tool_offsets_mm(const ProgramSetupOptions& placement) {
  if (placement.tool_table.empty()) return {};
  nc::ProgramSetup setup;
  nc::read_tool_table(placement.tool_table, setup);
  return setup.tool_length_mm;
}

post::InitialPose FiveAxisCliOptions::initial(const Machine& m,
                                              const ProgramSetupOptions& placement) const {
  if (!placement.work_offset.empty() || !placement.var_file.empty())
    throw UsageError(
        "five-axis programs: --work-offset and --var-file do not apply; place the part with "
        "--part-origin");
  post::InitialPose p;
  p.q = m.home;
  if (placement.initial.empty()) return p;
  const std::vector<double> v = parse_numbers(placement.initial, "--initial-position");
  int rotary = 0;
  for (AxisName a : m.axis_order) rotary += is_rotary(a) ? 1 : 0;
  if (v.size() != 3 && v.size() != static_cast<size_t>(3 + rotary))
    throw UsageError("--initial-position needs X,Y,Z or X,Y,Z and every rotary axis (degrees)");
  p.tip_mm = Eigen::Vector3d(v[0], v[1], v[2]);
  size_t next = 3;
  for (int k = 0; k < m.axis_count() && v.size() > 3; ++k)
    if (is_rotary(m.axis_order[static_cast<size_t>(k)])) p.q[k] = v[next++] * M_PI / 180.0;
  return p;
}

}  // namespace volmap::cli
