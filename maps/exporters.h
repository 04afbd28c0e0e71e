// Exports of a VolumetricTable for people and controllers (docs/exports.md
// for each format's layout, sign convention, units and limits).
//
// An exporter returns its files as (name, text) pairs; write_export puts
// them into a folder atomically per file (temporary name, then rename, all
// renames after every file is complete). A table that does not fit a
// controller's limits is refused with ExportError (nothing written).
//
// One-dimensional controller tables (LinuxCNC, Siemens LEC / CEC) take the
// table along one axis with the other axes at the grid nodes nearest the
// machine's home position ("the home line"); see docs/exports.md.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "maps/volumetric_table.h"

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

/// Index of the grid node nearest the home position on each axis.
std::vector<std::int64_t> home_line_nodes(const VolumetricTable& t, const ExportOptions& o);
/// Channel c along axis `axis` through the home line, for approach
/// direction dir of that axis (+1, -1; 0: mean over its layers), averaged
/// over the direction layers of the other bidirectional axes. Internal units.
std::vector<double> along_axis(const VolumetricTable& t, const std::vector<std::int64_t>& home,
                               int axis, int channel, int dir);
/// Refuses tables without the three-axis correction channels.
void require_three_axis(const VolumetricTable& t, const std::string& format);
}  // namespace exporters

}  // namespace volmap::maps
