// The conformance engine's program generator: whole three-axis programs in
// LinuxCNC's language from a grammar of what volmap's reader accepts, as a
// CAM system or a person writes them (moves of sensible size inside the
// sample machine's travel at the work offset), with a share of odd
// constructs. Seeded: the same seed gives the same files.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace volmap::conformance {

struct Program {
  std::string main;  ///< the bytes of the program file
  /// Subroutine files beside it: file name, bytes.
  std::vector<std::pair<std::string, std::string>> files;
  /// What it contains (feature names), for the statistics.
  std::vector<std::string> features;
};

Program generate_program(std::uint64_t seed);

/// The program's file name in its folder.
inline constexpr const char* kProgramName = "prog.ngc";

}  // namespace volmap::conformance
