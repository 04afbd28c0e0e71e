// What an export reads beside the table (docs/exports.md): the home line
// of the one-dimensional controller tables from a machine file, and the
// errors the table was built from. The verb (cli/export_command) gives the
// paths, calls export_table and writes the files.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/model/errors_import.h"
#include "maps/tables/volumetric_table.h"

namespace volmap::maps {

/// The home position of the machine file machine_path (axis units), for a
/// table read from table_path. Throws std::invalid_argument naming both
/// files when the axis counts differ.
std::vector<double> export_home(const std::string& machine_path, const VolumetricTable& table,
                                const std::string& table_path);

/// The errors file errors_path (format `format`) when given; else the errors
/// file the table names (with the format detected), found as named (from
/// the current folder) or, a relative name, beside the table file
/// table_path; else none. `needed` (a format that exports the component
/// errors): a file the table names that is found neither way is refused
/// (std::invalid_argument naming it), never left out.
std::optional<ErrorSet> export_errors(const VolumetricTable& table, const std::string& errors_path,
                                      ErrorsFormat format, const std::string& table_path,
                                      bool needed);

}  // namespace volmap::maps
