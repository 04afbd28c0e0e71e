// The files a conformance run gives volmap and rs274: random smooth error
// fields (docs/errors-format.md) with or without lost motion, a zero field,
// the parameter files (G54-G56, the G28/G30 homes) and the tool tables, the
// same values for both: volmap reads mm, rs274 without an INI file inches.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>

namespace volmap::conformance {

/// The sample machine and where the programs run on it.
inline constexpr const char* kMachine = "samples/machines/hsu-3axis.json";
inline const Eigen::Vector3d kWorkOffsetMm(250, 200, 100);
/// The parameter files' other positions (machine mm): G55 and G56 origins
/// relative to G54's, the G28 and G30 homes.
inline const Eigen::Vector3d kG55FromG54Mm(30, -25, 8), kG56FromG54Mm(-40, 20, -6);
inline const Eigen::Vector3d kG28HomeMm(300, 250, 240), kG30HomeMm(150, 120, 220);
/// The tool table: length offsets (mm) and diameters (mm) of tools 1..6.
struct ToolRow {
  double z_mm, d_mm;
};
inline constexpr ToolRow kTools[] = {{0, 6},      {12.7, 1},  {25.4, 0.5},
                                     {-5.08, 10}, {3.175, 2}, {0, 0.2}};

/// An error field: "zero", "smooth:SEED" (component errors and squareness,
/// one direction) or "lost:SEED" (the same with bidirectional positioning
/// tables: lost motion on X and, by the seed, Y and Z).
struct FieldSpec {
  enum Kind { kZero, kSmooth, kLostMotion } kind = kZero;
  std::uint64_t seed = 0;
  std::string name() const;
  static FieldSpec parse(const std::string& name);  ///< throws std::invalid_argument
};

/// The errors CSV of a field (seeded: the same text for the same spec).
std::string error_csv(const FieldSpec& spec);

struct SetupFiles {
  std::string volmap_var, rs274_var;  ///< parameter files (mm, inch)
  std::string volmap_tools, rs274_tools;
};

/// Writes the parameter files and tool tables into `dir` (short names:
/// rs274 cuts long ones).
SetupFiles write_setup_files(const std::string& dir);

}  // namespace volmap::conformance
