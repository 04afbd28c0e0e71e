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
