// Builds a VolumetricTable from an ErrorModel, and chooses the spacing for a
// tolerance.
//
// Every node is one evaluation of ErrorModel::exact per direction layer
// (plus the fixed-point correction solve on three-axis machines, or the
// iterated CorrectionSolver of Lei & Hsu eqs. 4-6 on five-axis ones), written
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

#include "core/kinematics/correction.h"
#include "core/model/error_model.h"
#include "maps/tables/node_uncertainty.h"
#include "maps/tables/volumetric_table.h"

namespace volmap::maps {

struct BuildOptions {
  int threads = 0;  ///< 0: std::thread::hardware_concurrency()
  /// Called from the calling thread about 20 times a second with the rows
  /// done and the total, and once at the end; may be empty.
  std::function<void(std::int64_t done, std::int64_t total)> progress;
  /// When set, the table gets the channel "u" (maps/node_uncertainty.h),
  /// filled after the other channels.
  std::optional<Repeatability> repeatability;
  /// With repeatability set: the covariance of identified location errors
  /// too (maps/node_uncertainty.h). Not owned; may be null.
  const ParameterCovariance* covariance = nullptr;
  /// build_table refuses (TableTooLarge, before allocating) beyond this.
  std::size_t max_bytes = kMaxTableBytes;
};

struct BuildSummary {
  double seconds = 0.0;
  std::int64_t evaluations = 0;         ///< calls of ErrorModel::exact
  std::int64_t correction_clamped = 0;  ///< nodes whose du solve held a travel end
  std::int64_t correction_unconverged = 0;
  /// Five-axis: nodes at the singular position (tool axis along the outer
  /// rotary axis, A = 0 for X'Y'ZA'C'), where CorrectionSolver suppresses
  /// the outer axis's correction (its du is 0 there).
  std::int64_t correction_singular = 0;
  /// Five-axis: largest position residual |F_e(u + du).P - F_n(u).P| (mm)
  /// of the iterated correction over the nodes outside the singular
  /// position.
  double correction_max_residual_mm = 0.0;
};

/// The options of the five-axis correction in tables: CorrectionSolver
/// iterated to the solution of Lei & Hsu eq. 4 (chord Newton from the
/// one-step eq. 6), singular band as in core/correction.h.
CorrectionOptions table_correction_options();

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
  double max_du_um = 0.0;  ///< same for the correction's linear axes, um
  /// Five-axis: max |interpolated dQ - exact dQ| (urad), and the same for
  /// the rotary axes' correction (urad).
  double max_dq_urad = 0.0;
  double max_du_rot_urad = 0.0;
  /// Five-axis: check points whose du was not compared because they lie
  /// in the band around the singular position (docs/maps.md).
  std::int64_t du_excluded = 0;
  AxisVector worst_at;      ///< where the larger of the two occurred (mm, rad)
  std::int64_t points = 0;  ///< check points per layer
  double max_um() const { return max_dv_um > max_du_um ? max_dv_um : max_du_um; }
  double max_urad() const { return max_dq_urad > max_du_rot_urad ? max_dq_urad : max_du_rot_urad; }
};

struct CheckOptions {
  Interpolation method = Interpolation::kLinear;
  /// Random points per layer (fixed seed, deterministic), added to the
  /// centres of every cell.
  std::int64_t random_points = 20000;
  std::uint64_t seed = 20240607;
  int threads = 0;
  bool check_correction = true;
  /// Check points only: no cell centres (used by the automatic spacing's
  /// refinement, which checks one group of axes at a time).
  bool cell_centres = true;
  /// Bit d set: random points take axis d at a grid node (chosen at random)
  /// instead of anywhere, so the interpolation error is that of the other
  /// axes alone.
  unsigned at_nodes_mask = 0;
  /// Five-axis: du is compared only where the sine of the angle between the
  /// tool axis and the outer rotary axis is at least this times
  /// sin(inner rotary spacing); closer, the outer axis's correction grows
  /// like 1 / sin (Lei & Hsu section 4.1) and is not interpolable.
  double singular_band_spacings = 2.0;
};

/// Compares the table with the model at every cell centre and at random
/// points, in every layer.
CheckResult check_table(const ErrorModel& model, const VolumetricTable& table,
                        const CheckOptions& options = {});

/// Automatic spacing: the coarsest grid from the sequence of spacings
/// 100, 50, 25, 20, 10, 5, 2.5, 2, 1, 0.5, 0.25, 0.2, 0.1 mm (the same for
/// every linear axis, capped at the axis's travel) whose interpolation
/// error against the model stays below tolerance_um at every check point.
///
/// Machines with rotary axes: linear spacings from that sequence, rotary
/// ones from auto_rotary_spacing_sequence() (the same for every rotary
/// axis); criterion: dP within tolerance_um and dQ within tolerance_urad.
/// Greedy refinement from the coarsest pair: when the full check fails,
/// the group (linear or rotary) whose own interpolation error (random
/// points with the other group's axes at nodes) is the larger fraction of
/// the tolerance is refined. Deterministic.
///
/// Throws std::invalid_argument when no spacing of the sequences reaches
/// the tolerance, and TableTooLarge (naming the grid, suggesting --spacing)
/// when the next table would exceed max_bytes.
struct AutoSpacingResult {
  VolumetricTable table;
  double spacing_mm = 0.0;
  double spacing_rad = 0.0;  ///< rotary axes (0: none)
  CheckResult check;
  BuildSummary build;
  int tables_tried = 0;
};
AutoSpacingResult build_for_tolerance(const ErrorModel& model, double tolerance_um,
                                      const CheckOptions& check, const BuildOptions& build = {},
                                      std::size_t max_bytes = kMaxTableBytes,
                                      double tolerance_urad = 1.0);

/// The spacings tried by build_for_tolerance, coarse to fine (mm).
const std::vector<double>& auto_spacing_sequence();
/// The rotary spacings tried, coarse to fine (degrees).
const std::vector<double>& auto_rotary_spacing_sequence();

}  // namespace volmap::maps
