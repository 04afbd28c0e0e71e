// Builds a VolumetricTable from an ErrorModel, and chooses the spacing for a
// tolerance.
//
// Every node is one evaluation of ErrorModel::exact per direction layer
// (plus the fixed-point correction solve on three-axis machines), written
// straight into the table's preallocated storage. Work is split into rows
// (all nodes along the first axis, one layer) handed out by an atomic
// counter to std::threads; a node's value depends only on its position, so
// the bytes do not depend on the thread count. Peak memory: the table plus
// a few hundred bytes per thread.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/error_model.h"
#include "maps/node_uncertainty.h"
#include "maps/volumetric_table.h"

namespace volmap::maps {

struct BuildOptions {
  int threads = 0;  ///< 0: std::thread::hardware_concurrency()
  /// Called from the calling thread about 20 times a second with the rows
  /// done and the total, and once at the end; may be empty.
  std::function<void(std::int64_t done, std::int64_t total)> progress;
  /// When set, the table gets the channel "u" (maps/node_uncertainty.h),
  /// filled after the other channels.
  std::optional<Repeatability> repeatability;
};

struct BuildSummary {
  double seconds = 0.0;
  std::int64_t evaluations = 0;        ///< calls of ErrorModel::exact
  std::int64_t correction_clamped = 0;  ///< nodes whose du solve held a travel end
  std::int64_t correction_unconverged = 0;
};

/// Builds the table with the given spacing (one per axis, mm or rad).
/// Throws what the model throws (e.g. an error table that does not cover
/// the travel), from the lowest failing row, whatever the thread count.
VolumetricTable build_table(const ErrorModel& model, const std::vector<double>& spacing,
                            const BuildOptions& options = {}, BuildSummary* summary = nullptr);

/// Fills an allocated layout (make_table_layout).
void fill_table(const ErrorModel& model, VolumetricTable& table, const BuildOptions& options = {},
                BuildSummary* summary = nullptr);

/// Interpolation error of a table against the direct model.
struct CheckResult {
  double max_dv_um = 0.0;  ///< max |interpolated dP - exact dP| (um)
  double max_du_um = 0.0;  ///< same for the correction (three-axis), um
  AxisVector worst_at;     ///< where the larger of the two occurred (mm, rad)
  std::int64_t points = 0; ///< check points per layer
  double max_um() const { return max_dv_um > max_du_um ? max_dv_um : max_du_um; }
};

struct CheckOptions {
  Interpolation method = Interpolation::kLinear;
  /// Random points per layer (fixed seed, deterministic), added to the
  /// centres of every cell.
  std::int64_t random_points = 20000;
  std::uint64_t seed = 20240607;
  int threads = 0;
  bool check_correction = true;
};

/// Compares the table with the model at every cell centre and at random
/// points, in every layer.
CheckResult check_table(const ErrorModel& model, const VolumetricTable& table,
                        const CheckOptions& options = {});

/// Automatic spacing: the coarsest grid from the sequence of spacings
/// 100, 50, 25, 20, 10, 5, 2.5, 2, 1, 0.5, 0.25, 0.2, 0.1 mm (the same for
/// every linear axis, capped at the axis's travel) whose interpolation
/// error against the model stays below tolerance_um at every check point.
/// Three-axis machines only. Throws std::invalid_argument when no spacing
/// of the sequence reaches the tolerance (or the table would exceed
/// max_bytes).
struct AutoSpacingResult {
  VolumetricTable table;
  double spacing_mm = 0.0;
  CheckResult check;
  BuildSummary build;
};
AutoSpacingResult build_for_tolerance(const ErrorModel& model, double tolerance_um,
                                      const CheckOptions& check, const BuildOptions& build = {},
                                      std::size_t max_bytes = std::size_t{2} << 30);

/// The spacings tried by build_for_tolerance, coarse to fine (mm).
const std::vector<double>& auto_spacing_sequence();

}  // namespace volmap::maps
