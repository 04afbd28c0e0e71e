// What places an NC program on the machine before its first block: work
// offsets, tool lengths, where the tool stands.
#pragma once

#include <Eigen/Core>
#include <array>
#include <map>
#include <optional>

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
  /// Where the tool stands when the program starts (machine coordinates, mm),
  /// when known: lets a program that never commands an axis (a 2D plasma
  /// program without Z) be corrected. Unknown by default: then the first
  /// feed move must come after a rapid that sets X, Y and Z.
  std::optional<Eigen::Vector3d> initial_position_mm;
};

}  // namespace volmap::nc
