// Command-line value parsing shared by the subcommands.
#pragma once

#include <string>
#include <vector>

#include "core/model/machine.h"

namespace volmap::cli {

/// "1,2.5,+3": comma-separated finite numbers (spaces around them allowed).
/// Throws std::invalid_argument naming the option and the bad cell.
std::vector<double> parse_numbers(const std::string& text, const std::string& option);

/// "250,200,150[,A,C]": one value per machine axis in axis order, mm and
/// degrees; returns internal units (mm, rad). Throws std::invalid_argument
/// naming the option on a wrong count or a non-number, and when outside travel.
AxisVector parse_axis_position(const Machine& m, const std::string& text,
                               const std::string& option);

/// Internal units -> display units (mm, degrees).
double display_position(AxisName a, double value);

}  // namespace volmap::cli
