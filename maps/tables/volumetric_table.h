// A gridded volumetric error table: at every grid node over the machine's
// travel, the tool pose error dv (actual minus nominal, workpiece
// coordinates, ErrorModel::exact) and the commanded-position correction du
// beside it: maps/axis_correction.h for three-axis machines,
// CorrectionSolver (core/correction.h, Lei & Hsu 2003 eqs. 4-6) for
// machines with two rotary axes.
//
// Channels (values in internal units, per node):
//   three-axis: ex ey ez (dP, mm), ux uy uz (du, mm of axis X Y Z)
//   five-axis:  ex ey ez (dP, mm), ei ej ek (dQ, tool-axis error, unitless),
//               then u<axis> per axis in axis order (du: mm for linear
//               axes, rad for rotary ones), e.g. ux uy uz ua uc
//   other:      ex ey ez (dP, mm), ei ej ek (dQ)
// and "u" (uncertainty, mm) last when present.
// Direction layers: bidirectional error tables make the error depend on the
// approach direction. The table holds one layer per combination of approach
// directions of the bidirectional axes (2^b layers for b such axes): bit j
// of the layer index set means the j-th bidirectional axis (in axis order)
// is approached in the minus direction; layer 0 is "all plus".
//
// Storage: one contiguous std::vector<double>, index
//   ((layer * nodes + node) * channels + channel),
//   node = i0 + n0 * (i1 + n1 * (i2 + ...))   (first axis fastest),
// allocated once by the builder or the reader (no per-node allocation).
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model/error_model.h"
#include "maps/tables/grid.h"

namespace volmap::maps {

enum class Interpolation : std::uint8_t { kLinear, kCubic };

/// "linear" / "cubic"; parse throws std::invalid_argument on other names.
const char* interpolation_name(Interpolation m);
Interpolation parse_interpolation(const std::string& name);

struct VolumetricTable {
  // ---- provenance (written to the file, shown in summaries) ----
  std::string machine_name;
  std::string errors_source;  ///< the errors file as named on input
  Formulation formulation = Formulation::kIndependent;
  /// Requested tolerance (um) when the spacing was chosen automatically,
  /// 0 otherwise; the max interpolation error found by the check (um, of
  /// |dv| and |du|, whichever larger), negative when not checked; and the
  /// interpolation it was checked with.
  double tolerance_um = 0.0;
  double achieved_um = -1.0;
  Interpolation checked_with = Interpolation::kLinear;

  // ---- layout ----
  std::vector<GridAxis> grid;           ///< one per machine axis, axis order
  std::vector<std::string> channels;    ///< channel names, see above
  std::vector<int> bidirectional_axes;  ///< axis indices, ascending
  std::vector<double> values;           ///< see above

  int axis_count() const { return static_cast<int>(grid.size()); }
  int channel_count() const { return static_cast<int>(channels.size()); }
  int layer_count() const { return 1 << bidirectional_axes.size(); }
  std::int64_t node_count() const;
  /// Index of a channel by name.
  std::optional<int> channel(const std::string& name) const;
  /// Approach directions (+1 / -1 per bidirectional axis, 0 elsewhere) of a layer.
  ApproachDirections layer_directions(int layer) const;
  /// The layer for the given directions (a 0 direction on a bidirectional
  /// axis counts as plus).
  int layer_of(const ApproachDirections& dir) const;
  /// Multi-index of a node (first axis fastest).
  void node_index(std::int64_t node, std::int64_t* index) const;
  /// Axis positions of a node (mm, rad).
  AxisVector node_position(std::int64_t node) const;
  const double* at(int layer, std::int64_t node) const {
    return values.data() +
           (static_cast<std::int64_t>(layer) * node_count() + node) * channel_count();
  }
  double* at(int layer, std::int64_t node) {
    return values.data() +
           (static_cast<std::int64_t>(layer) * node_count() + node) * channel_count();
  }
  std::size_t size_bytes() const { return values.size() * sizeof(double); }
  /// Linear X, Y, Z only, with ux uy uz (maps/axis_correction.h).
  bool three_axis_correction() const;
  /// Rotary axes and a correction channel per axis (CorrectionSolver).
  bool pose_correction() const;
  /// Index of the first correction channel (u<first axis>), or -1.
  int correction_channel() const;
};

/// "u" + the axis letter in lower case: the correction channel of an axis.
std::string correction_channel_name(AxisName a);

/// True for channels holding angles or unit-vector differences (rad or
/// unitless; exported in urad): ei ej ek, and ua ub uc.
bool is_angular_channel(const std::string& name);

/// Channel names for a machine: three-axis tables carry du; machines the
/// backward transformation handles (two rotary axes) dQ and du; others dQ.
std::vector<std::string> channels_for(const Machine& m);

/// Default cap of a table's values (make_table_layout, automatic spacing).
inline constexpr std::size_t kMaxTableBytes = std::size_t{2} << 30;

/// An empty table shaped for the machine: grid from spacing (per axis, mm
/// or rad), channels, bidirectional axes from the errors; values allocated
/// (zero). Throws std::invalid_argument on a bad spacing, and TableTooLarge
/// (before allocating) when the values would exceed max_bytes.
/// extra_channels: channels appended after channels_for's (e.g. "u").
class TableTooLarge : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};
VolumetricTable make_table_layout(const ErrorModel& model, const std::vector<double>& spacing,
                                  std::size_t max_bytes = kMaxTableBytes, int extra_channels = 0);
/// Bytes the table of that spacing would take (no allocation); throws as
/// make_table_layout does for a bad spacing.
std::size_t table_bytes(const ErrorModel& model, const std::vector<double>& spacing,
                        int extra_channels = 0);

/// Interpolates all channels at axis position u (mm, rad) in one layer.
/// Outside the grid: kError throws std::out_of_range naming the axis,
/// position and grid range; kClamp holds the boundary value (clamps the
/// position) and increments *clamped once per call. Periodic axes wrap.
/// No allocation. Linear: multilinear over the 2^N cell corners. Cubic: the
/// tensor product of 1-D cubic Hermite interpolants with centred-difference
/// slopes (Catmull-Rom on a uniform grid; one-sided at the grid's ends and
/// correct for the shorter last cell), 4^N nodes; C1; both return the
/// node value exactly at a node.
void interpolate(const VolumetricTable& t, const AxisVector& u, int layer, Interpolation method,
                 OutsidePolicy outside, double* out, std::uint64_t* clamped = nullptr);

}  // namespace volmap::maps
