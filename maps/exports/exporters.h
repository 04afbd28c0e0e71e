// Exports of a VolumetricTable for people and controllers (docs/exports.md
// for each format's layout, sign convention, units and limits).
//
// An exporter returns its files as (name, text) pairs; write_export puts
// them into a folder atomically per file (temporary name, then rename, all
// renames after every file is complete). A table that does not fit a
// controller's limits is refused with ExportError (nothing written).
//
// One-dimensional controller tables (LinuxCNC, Siemens LEC / CEC,
// HEIDENHAIN .COM, Fanuc pitch error compensation) take the table along one
// axis with the other axes at the grid nodes nearest the machine's home
// position ("the home line"); see docs/exports.md. isg-csv and HEIDENHAIN's
// KinematicsComp tables carry the component errors themselves
// (ExportOptions::errors).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "core/model/error_set.h"
#include "maps/tables/volumetric_table.h"

namespace volmap::maps {

class ExportError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct ExportFile {
  std::string name;  ///< file name inside the export folder
  std::string text;
};

/// What the FANUC export needs to know about the control (docs/exports.md,
/// "fanuc"): its series, the current value of the bit parameter it changes,
/// the direction of reference position return, the least input increment.
struct FanucOptions {
  /// k16i: Series 16i/18i/21i and 0i-A/B/C/D (points 0..1023, -7..7 per
  /// point, 3624 an integer in least input increments, tapes without Q1).
  /// k30i: Series 30i/31i/32i and 0i-F (points 0..1535, -128..127 per
  /// point, 3624 a real number in mm, Q1 records, 3D error compensation).
  enum class Series : std::uint8_t { k16i, k30i };
  Series series = Series::k30i;
  /// Parameter 3605 of axes 1..3 as the control shows it (8 binary digits,
  /// bit 7 first): bit 0 (BDPx) is set from the table, the other bits are
  /// kept. Empty: 3605 is not written (FANUC.txt says which bit to set).
  std::vector<std::string> param_3605;
  /// Reference position return direction of every axis (1006#5 ZMIx = 0:
  /// +1, 1: -1): the table of that direction is zero at the reference
  /// position, 3627 holds the other direction's value there.
  int reference_direction = +1;
  /// 3624's unit on the 16i series (mm).
  double input_increment_mm = 0.001;
};

/// "16i" (also 18i, 21i, 0i-d and older 0i), "30i" (also 31i, 32i, 0i-f);
/// throws std::invalid_argument naming the choices ("0i" alone is refused:
/// 0i-D and 0i-F differ).
FanucOptions::Series parse_fanuc_series(const std::string& name);

struct ExportOptions {
  /// Machine home position (mm, rad) by axis: picks the home line of the
  /// one-dimensional formats. Empty: each grid's start.
  std::vector<double> home;
  /// The component and location errors the table was built from (an errors
  /// file in any format core/errors_import.h reads). Needed by the formats
  /// that carry the ISO 230-1 component errors themselves: isg-csv, and the
  /// KinematicsComp tables of heidenhain. May be null.
  const ErrorSet* errors = nullptr;
  /// Fanuc detection unit (mm): pitch and 3D compensation values are
  /// integers in this unit, the interval must be a whole multiple of it.
  double detection_unit_mm = 0.001;
  FanucOptions fanuc;
};

/// The formats, in the order of shared/spec/cli.md's priority.
const std::vector<std::string>& export_formats();

/// Throws ExportError for an unknown format or a table that does not fit.
std::vector<ExportFile> export_table(const VolumetricTable& table, const std::string& format,
                                     const ExportOptions& options = {});

/// Writes the files into dir (created when missing). Every file goes to a
/// temporary name first; the renames happen once all are written.
void write_export(const std::string& dir, const std::vector<ExportFile>& files);

// ---- shared by the exporters (maps/export_*.cc) ----
namespace exporters {
std::vector<ExportFile> csv(const VolumetricTable& t, const ExportOptions& o);
std::vector<ExportFile> json(const VolumetricTable& t, const ExportOptions& o);
std::vector<ExportFile> linuxcnc(const VolumetricTable& t, const ExportOptions& o);
std::vector<ExportFile> siemens_lec(const VolumetricTable& t, const ExportOptions& o);
std::vector<ExportFile> siemens_cec(const VolumetricTable& t, const ExportOptions& o);
std::vector<ExportFile> heidenhain(const VolumetricTable& t, const ExportOptions& o);
std::vector<ExportFile> fanuc(const VolumetricTable& t, const ExportOptions& o);
std::vector<ExportFile> isg_csv(const VolumetricTable& t, const ExportOptions& o);

/// One axis of the FANUC pitch error compensation, for FANUC.txt.
struct AxisPitchSummary {
  std::int64_t reference = 0, first = 0, last = 0;  ///< 3620, 3621, 3622
  bool bidirectional = false;
  int magnification = 1;                ///< 3623
  std::int64_t other_at_reference = 0;  ///< 3627, detection units
  double dropped_mm = 0.0;              ///< compensation at the reference position, left out
};
/// FANUC.txt (export_fanuc_notes.cc); outside: 3-D sheet values beyond -128..127.
std::string fanuc_notes(const VolumetricTable& t, const std::vector<std::int64_t>& home,
                        const std::vector<AxisPitchSummary>& axes, const ExportOptions& o,
                        std::int64_t outside);

/// Index of the grid node nearest the home position on each axis.
std::vector<std::int64_t> home_line_nodes(const VolumetricTable& t, const ExportOptions& o);
/// Channel c along axis `axis` through the home line, for approach
/// direction dir of that axis (+1, -1; 0: mean over its layers), averaged
/// over the direction layers of the other bidirectional axes. Internal units.
std::vector<double> along_axis(const VolumetricTable& t, const std::vector<std::int64_t>& home,
                               int axis, int channel, int dir);
/// Values given at the nodes of g, interpolated linearly at pos (held at the
/// travel ends).
double interpolate_nodes(const GridAxis& g, const std::vector<double>& values, double pos);
/// Refuses tables without the three-axis correction channels.
void require_three_axis(const VolumetricTable& t, const std::string& format);
/// Refuses when options.errors is null (formats that need the component errors).
const ErrorSet& require_errors(const ExportOptions& o, const std::string& format);
/// Index of channel "u<x|y|z>" for axis 0..2.
int du_channel(const VolumetricTable& t, int axis);
bool is_bidirectional(const VolumetricTable& t, int axis);
/// fmt "{:.{}f}" with "-0.000" written as "0.000" (same bytes whatever the sign of a rounded zero).
std::string fixed(double v, int decimals = 6);
/// Refuses an axis whose last cell is shorter (controllers that need equidistant points).
void require_uniform(const VolumetricTable& t, int axis, const std::string& format);
/// Degrees for rotary axes, mm for linear ones.
double display_position(AxisName a, double v);
}  // namespace exporters

}  // namespace volmap::maps
