// Controller exports: LinuxCNC joint compensation files, Siemens SINUMERIK
// leadscrew error compensation (LEC, $AA_ENC_COMP) and interpolatory cross
// compensation (CEC, $AN_CEC). Layouts, signs and limits: docs/exports.md.
#include <fmt/format.h>

#include <cmath>

#include "maps/exports/exporters.h"

namespace volmap::maps::exporters {

namespace {

std::string provenance(const VolumetricTable& t, const char* comment) {
  return fmt::format("{} volmap export of machine {} (errors {})\n", comment, t.machine_name,
                     t.errors_source);
}

}  // namespace

// LinuxCNC: one COMP_FILE per joint, COMP_FILE_TYPE 0: "nominal forward
// reverse" (mm), forward/reverse the actual joint position when commanded
// to nominal moving in the positive/negative direction. LinuxCNC turns
// them into trims nominal - forward and adds the trim to the command, so
// actual = nominal - du (du the exact correction along the joint).
std::vector<ExportFile> linuxcnc(const VolumetricTable& t, const ExportOptions& o) {
  require_three_axis(t, "linuxcnc");
  constexpr std::int64_t kMaxEntries = 256;  // EMCMOT_COMP_SIZE
  const std::vector<std::int64_t> home = home_line_nodes(t, o);
  std::vector<ExportFile> files;
  std::string ini = "# volmap: LinuxCNC joint compensation (add to the [JOINT_n] sections)\n";
  for (int j = 0; j < 3; ++j) {
    const GridAxis& g = t.grid[static_cast<size_t>(j)];
    if (g.count > kMaxEntries)
      throw ExportError(fmt::format(
          "`format` linuxcnc: axis {} has {} nodes; LinuxCNC takes at most {} entries per joint: "
          "build the table with a spacing of at least {:g} mm on {}",
          axis_char(g.axis), g.count, kMaxEntries, (g.end - g.start) / (kMaxEntries - 1),
          axis_char(g.axis)));
    const int c = du_channel(t, j);
    const std::vector<double> fwd = along_axis(t, home, j, c, +1);
    const std::vector<double> rev = along_axis(t, home, j, c, -1);
    ExportFile f;
    f.name = fmt::format("{}.comp", axis_char(g.axis));
    for (std::int64_t k = 0; k < g.count; ++k) {
      const double nominal = g.node(k);
      f.text +=
          fmt::format("{} {} {}\n", fixed(nominal), fixed(nominal - fwd[static_cast<size_t>(k)]),
                      fixed(nominal - rev[static_cast<size_t>(k)]));
    }
    files.push_back(std::move(f));
    ini +=
        fmt::format("[JOINT_{}]\nCOMP_FILE = {}.comp\nCOMP_FILE_TYPE = 0\n", j, axis_char(g.axis));
  }
  files.push_back({"linuxcnc-joints.ini", ini});
  return files;
}

// Siemens LEC: $AA_ENC_COMP[0,N,AXn] per axis, equidistant from _MIN to
// _MAX in _STEP (SINUMERIK 840D sl Extended Functions, K3 4.4.2). MSEC
// modifies the axis's actual value by the table value, and "a positive
// compensation value causes the corresponding machine axis to move in the
// negative direction", so the value is the error along the axis at the
// position, -du, mean of both approach directions (half the difference
// belongs in the backlash machine data and is given in a comment). "The
// compensation value at the reference point [should be] zero" (K3 4.4.1):
// the table holds the error minus its value at the reference point (the
// machine's home position, interpolated between the nodes), and that value
// is given in a comment as the offset the reference point or a work offset
// must take.
std::vector<ExportFile> siemens_lec(const VolumetricTable& t, const ExportOptions& o) {
  require_three_axis(t, "siemens-lec");
  constexpr std::int64_t kMaxPoints = 5000;
  const std::vector<std::int64_t> home = home_line_nodes(t, o);
  std::string text = "%_N_AX_EEC_INI\n";
  text += provenance(t, ";");
  text +=
      "; values: error along the axis at the position minus the error at the reference point,\n"
      ";   mm (a positive value moves the axis negative; K3: zero at the reference point)\n"
      "; load with MD32700 $MA_ENC_COMP_ENABLE[0,AXn]=0, then set it to 1 (the table becomes\n"
      ";   write-protected) and POWER ON; MD38000 $MA_MM_ENC_COMP_MAX_POINTS[0,AXn] >= the\n"
      ";   points of the axis\n"
      "; not confirmed by a Siemens source, check on the control: MD38000's upper limit\n"
      ";   (volmap allows 5000 points per axis)\n";
  text += "CHANDATA(1)\n";
  for (int j = 0; j < 3; ++j) {
    const GridAxis& g = t.grid[static_cast<size_t>(j)];
    require_uniform(t, j, "siemens-lec");
    if (g.count > kMaxPoints)
      throw ExportError(fmt::format(
          "`format` siemens-lec: axis {} has {} points; $AA_ENC_COMP takes at most {} per axis "
          "(MD38000 MM_ENC_COMP_MAX_POINTS): build the table with a coarser spacing",
          axis_char(g.axis), g.count, kMaxPoints));
    const int c = du_channel(t, j);
    std::vector<double> error = along_axis(t, home, j, c, 0);
    for (double& v : error) v = -v;
    const double reference =
        static_cast<size_t>(j) < o.home.size() ? o.home[static_cast<size_t>(j)] : g.start;
    const double at_reference = interpolate_nodes(g, error, reference);
    const std::string ax = fmt::format("AX{}", j + 1);
    text += fmt::format("; axis {} = {}, {} points\n", ax, axis_char(g.axis), g.count);
    text += fmt::format(
        "; {} reference point {} mm: error there {} mm, not in the table; the reference point "
        "offset (MD34090 $MA_REFP_MOVE_DIST_CORR) or the work offset takes it\n",
        ax, fixed(reference), fixed(at_reference));
    if (is_bidirectional(t, j)) {
      const std::vector<double> fwd = along_axis(t, home, j, c, +1);
      const std::vector<double> rev = along_axis(t, home, j, c, -1);
      double sum = 0.0;
      for (size_t k = 0; k < fwd.size(); ++k) sum += fwd[k] - rev[k];
      text += fmt::format(
          "; {} is bidirectional: mean reversal (error minus - error plus) {} mm "
          "(MD32450 BACKLASH)\n",
          axis_char(g.axis), fixed(sum / static_cast<double>(fwd.size())));
    }
    for (std::int64_t k = 0; k < g.count; ++k)
      text += fmt::format("$AA_ENC_COMP[0,{},{}]={}\n", k, ax,
                          fixed(error[static_cast<size_t>(k)] - at_reference));
    text += fmt::format("$AA_ENC_COMP_STEP[0,{}]={}\n", ax, fixed(g.spacing));
    text += fmt::format("$AA_ENC_COMP_MIN[0,{}]={}\n", ax, fixed(g.start));
    text += fmt::format("$AA_ENC_COMP_MAX[0,{}]={}\n", ax, fixed(g.end));
    text += fmt::format("$AA_ENC_COMP_IS_MODULO[0,{}]=0\n", ax);
  }
  text += "M17\n";
  return {{"siemens_lec.ini", text}};
}

// Siemens CEC: one table per (input axis, output axis) pair with input !=
// output: the straightness / squareness of the output axis along the input
// axis on the home line. Sign: the table is read at the input axis's
// setpoint and its output "is applied" to the output axis "as an additional
// setpoint" (K3 4.4.3: the setpoint position of the compensation axis is
// altered) -- unlike LEC, which modifies the actual value -- so the value
// is the correction to add to the output axis (du of the output axis, mm),
// zero at the home node (K3's rule for the reference point) so that tables
// of several inputs add up without counting the home value twice. A
// bidirectional input axis gets one table per direction ($AN_CEC_DIRECTION
// 1 / -1), others one table for both (0). A table acts only while SD41300
// $SN_CEC_TABLE_ENABLE[t] = 1 (K3 4.4.3, preconditions): the file sets it.
std::vector<ExportFile> siemens_cec(const VolumetricTable& t, const ExportOptions& o) {
  require_three_axis(t, "siemens-cec");
  constexpr std::int64_t kMaxPoints = 2000;
  constexpr int kMaxTables = 62;
  const std::vector<std::int64_t> home = home_line_nodes(t, o);
  std::string text = "%_N_NC_CEC_INI\n";
  text += provenance(t, ";");
  text +=
      "; values: correction added to the output axis setpoint, mm, zero at the home node\n"
      "; load with MD32710 $MA_CEC_ENABLE[AXn]=0 on the output axes, then set it to 1 and\n"
      ";   POWER ON; SD41300 $SN_CEC_TABLE_ENABLE[t]=1 (set below) enables each table\n"
      "; not confirmed by a Siemens source, check on the control: the limits volmap allows\n"
      ";   (2000 points per table, 62 tables); the sign, derived from K3 (the table's output\n"
      ";   is an additional setpoint of the output axis): a one-point test table of +0.010\n"
      ";   must move the output axis by +0.010 mm\n";
  text += "CHANDATA(1)\n";
  std::string sizes, enables;
  int table = 0;
  for (int in = 0; in < 3; ++in) {
    const GridAxis& g = t.grid[static_cast<size_t>(in)];
    require_uniform(t, in, "siemens-cec");
    if (g.count > kMaxPoints)
      throw ExportError(
          fmt::format("`format` siemens-cec: axis {} has {} points; a CEC table takes at most {} "
                      "(MD18342 MM_CEC_MAX_POINTS): build the table with a coarser spacing",
                      axis_char(g.axis), g.count, kMaxPoints));
    for (int out = 0; out < 3; ++out) {
      if (out == in) continue;
      const std::vector<int> dirs =
          is_bidirectional(t, in) ? std::vector<int>{+1, -1} : std::vector<int>{0};
      for (int dir : dirs) {
        if (table >= kMaxTables)
          throw ExportError(fmt::format("`format` siemens-cec: more than {} tables", kMaxTables));
        const std::vector<double> du = along_axis(t, home, in, du_channel(t, out), dir);
        const double at_home = du[static_cast<size_t>(home[static_cast<size_t>(in)])];
        text += fmt::format("; table {}: {} = F({}){}\n", table,
                            axis_char(t.grid[static_cast<size_t>(out)].axis), axis_char(g.axis),
                            dir == 0  ? ""
                            : dir > 0 ? ", moving positive"
                                      : ", moving negative");
        for (std::int64_t k = 0; k < g.count; ++k)
          text += fmt::format("$AN_CEC[{},{}]={}\n", table, k,
                              fixed(du[static_cast<size_t>(k)] - at_home));
        text += fmt::format("$AN_CEC_INPUT_AXIS[{}]=(AX{})\n", table, in + 1);
        text += fmt::format("$AN_CEC_OUTPUT_AXIS[{}]=(AX{})\n", table, out + 1);
        text += fmt::format("$AN_CEC_STEP[{}]={}\n", table, fixed(g.spacing));
        text += fmt::format("$AN_CEC_MIN[{}]={}\n", table, fixed(g.start));
        text += fmt::format("$AN_CEC_MAX[{}]={}\n", table, fixed(g.end));
        text += fmt::format("$AN_CEC_DIRECTION[{}]={}\n", table, dir);
        text += fmt::format("$AN_CEC_MULT_BY_TABLE[{}]=0\n", table);
        text += fmt::format("$AN_CEC_IS_MODULO[{}]=0\n", table);
        sizes += fmt::format("; MD18342 $MN_MM_CEC_MAX_POINTS[{}] >= {}\n", table, g.count);
        enables += fmt::format("$SN_CEC_TABLE_ENABLE[{}]=1\n", table);
        ++table;
      }
    }
  }
  text += enables + sizes;
  text += "M17\n";
  return {{"siemens_cec.ini", text}};
}

}  // namespace volmap::maps::exporters
