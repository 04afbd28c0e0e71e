// What places an NC program on the machine before its first block: work
// offsets, tool lengths, where the tool stands.
#pragma once

#include <Eigen/Core>
#include <array>
#include <map>
#include <optional>
#include <string>

#include "gcode/dialect.h"

namespace volmap::nc {

/// The largest tool number of a T or H word or a tool table: beyond it a
/// number would overflow int.
inline constexpr double kMaxToolNumber = 99999;

struct ProgramSetup {
  /// G54 .. G59.3 (index 0 .. 8): machine position of each program origin, mm.
  /// Zero unless given (LinuxCNC's default; Eigen's default constructor
  /// leaves a vector uninitialised, so `{}` alone would not zero them).
  std::array<Eigen::Vector3d, 9> work_offset_mm = [] {
    std::array<Eigen::Vector3d, 9> zero;
    zero.fill(Eigen::Vector3d::Zero());
    return zero;
  }();
  /// Tool table: tool (pocket) number -> tool length offset, mm (a LinuxCNC
  /// .tbl Z: how much longer the tool is than the one whose offset is zero,
  /// the machine file's tool).
  std::map<int, double> tool_length_mm;
  /// Tool table: tool number -> diameter, mm (a .tbl D), for cutter
  /// compensation (G41/G42 D). A Fanuc program's D offset number n reads
  /// the row T n.
  std::map<int, double> tool_diameter_mm;
  /// Tool table: a lathe tool's orientation (a .tbl Q other than 0 or 9):
  /// LinuxCNC refuses G41/G42 with it outside G18.
  std::map<int, int> tool_orientation;
  /// Where the tool stands when the program starts (machine coordinates, mm),
  /// when known: lets a program that never commands an axis (a 2D plasma
  /// program without Z) be corrected. Unknown by default: then the first
  /// feed move must come after a rapid that sets X, Y and Z.
  std::optional<Eigen::Vector3d> initial_position_mm;
  /// Numbered parameters of a LinuxCNC parameter (.var) file, as given
  /// (the work offsets among them are also in work_offset_mm): what a
  /// program that reads #5161 (G28's home) or its own persistent
  /// parameters sees.
  std::map<int, double> parameters;

  // Five-axis programs (the five-axis post reads them through this same
  // interpreter).
  /// The rotary axis words a program may carry ("AC" on an X'Y'ZA'C'
  /// machine): degrees, absolute under G90 and incremental under G91 like X
  /// Y Z, without work offsets, moving linearly with the straight move or
  /// arc of their block. Empty (the three-axis post): A B C are refused.
  std::string rotary_axes;
  /// I J K of a straight move (G0 G1) give the tool axis (tool-vector
  /// programs), not an arc centre; unit or not (normalised).
  bool tool_axis_words = false;
  /// Rotary axes A B C (rad) and tool axis when the program starts.
  std::array<double, 3> initial_rotary_rad{};
  Eigen::Vector3d initial_tool_axis = Eigen::Vector3d::UnitZ();
  /// The program's NC language (--dialect): `auto` is resolved by the
  /// program reader from the program's head (Interpreter::set_dialect);
  /// an interpreter given no reader reads `auto` as LinuxCNC.
  Dialect dialect = Dialect::kAuto;
};

}  // namespace volmap::nc
