// What `volmap map` does, as a library (docs/maps.md): the inputs of the
// per-node uncertainty, the full table built on a given grid or on the
// coarsest grid within a tolerance and checked, the extremes reported of a
// table, the factorized form from a machine file. The verb (cli/map_command)
// parses its options into these, calls them and prints.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "maps/tables/factorized_table.h"
#include "maps/tables/node_uncertainty.h"
#include "maps/tables/table_builder.h"

namespace volmap::maps {

/// The per-node uncertainty's inputs: the errors file's repeatability
/// (its metadata), overridden by the values given, and the covariance of an
/// identify report.
struct UncertaintySources {
  std::optional<Repeatability> repeatability;  ///< none: no channel u
  std::optional<ParameterCovariance> covariance;
};

/// repeatability_um / repeatability_urad: negative when not given.
/// covariance_path: an identify --json report, empty for none; read for
/// machine m and formulation f. Throws std::invalid_argument naming the
/// report when it cannot be read.
UncertaintySources uncertainty_sources(const ErrorSet& errors, double repeatability_um,
                                       double repeatability_urad,
                                       const std::string& covariance_path, const Machine& m,
                                       Formulation f);

/// A full table to build and check.
struct FullTableJob {
  /// Per-axis spacing (mm, rad); empty: the coarsest grid within the
  /// tolerances (auto spacing).
  std::vector<double> spacing;
  double tolerance_um = 0.0;    ///< auto spacing; <= 0: 1 um
  double tolerance_urad = 0.0;  ///< auto spacing, rotary axes; <= 0: 1 urad
  BuildOptions build;
  CheckOptions check;

  double tolerance_um_or_default() const { return tolerance_um > 0.0 ? tolerance_um : 1.0; }
  double tolerance_urad_or_default() const { return tolerance_urad > 0.0 ? tolerance_urad : 1.0; }
};

struct FullTableResult {
  VolumetricTable table;  ///< achieved_um and checked_with set
  BuildSummary summary;
  CheckResult checked;
  Interpolation method = Interpolation::kLinear;  ///< the check's
  double tolerance_urad = 0.0;                    ///< the dQ tolerance searched for (0: none)
  int grids_tried = 0;                            ///< auto spacing: the grids built
  /// The interpolation error the tolerance applies to: of dv for a table
  /// with pose corrections (du reported beside), else the largest of dv, du.
  double interpolation_um() const;
};

FullTableResult build_full_table(const ErrorModel& model, const FullTableJob& job);

/// Largest |dv|, |du| and u over the nodes and layers (um; the tool-axis
/// error dQ and the rotary corrections urad), each where the table has it.
struct TableExtremes {
  double max_dv_um = 0.0;
  std::optional<double> max_du_um;           ///< three linear corrections ux uy uz
  std::optional<double> max_dq_urad;         ///< channels ei ej ek
  std::optional<double> max_du_rotary_urad;  ///< tables with pose corrections
  std::optional<double> max_u_um;            ///< channel u
};

TableExtremes table_extremes(const VolumetricTable& table);

/// The factorized form of `model`, whose machine is the file machine_path.
FactorizedTable factorized_table_of(const std::string& machine_path, const ErrorModel& model);

}  // namespace volmap::maps
