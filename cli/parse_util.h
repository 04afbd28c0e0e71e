// Command-line value parsing shared by the subcommands.
#pragma once

#include <string>
#include <vector>

#include "core/model/error_set.h"
#include "core/model/errors_import.h"
#include "core/model/machine.h"

namespace CLI {
class App;
}

namespace volmap::cli {

/// "1,2.5,+3": comma-separated finite numbers (spaces around them allowed).
/// Throws std::invalid_argument naming the option and the bad cell.
std::vector<double> parse_numbers(const std::string& text, const std::string& option);

/// "250,200,150[,A,C]": one value per machine axis in axis order, mm and
/// degrees; returns internal units (mm, rad). Throws std::invalid_argument
/// naming the option on a wrong count or a non-number, and when outside travel.
AxisVector parse_axis_position(const Machine& m, const std::string& text,
                               const std::string& option);

/// The option that lets a command use errors whose "# machine:" line names
/// another machine (core/model/errors_machine.h).
inline constexpr const char* kOtherMachineErrors = "--other-machine-errors";
/// Adds kOtherMachineErrors as a flag into `flag`.
void add_other_machine_flag(CLI::App& sub, bool& flag);
/// Loads the errors for machine m (from machine_path) and refuses errors of
/// another machine unless `other_machine` is set.
ErrorSet load_errors_for(const Machine& m, const std::string& machine_path,
                         const std::string& errors_path, ErrorsFormat format, bool other_machine);

/// Internal units -> display units (mm, degrees).
double display_position(AxisName a, double value);

}  // namespace volmap::cli
