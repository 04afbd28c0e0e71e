// Subcommands of the volmap executable. Each register_* adds its subcommand
// to the app and returns the function that runs it after parsing.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace volmap::cli {

using Runner = std::function<int()>;

Runner register_sensitivity(CLI::App& app);

}  // namespace volmap::cli
