// Subcommands of the volmap executable. Each subcommand lives in its own
// file under core/cli/ and registers itself with a static
// CommandRegistration; main() adds them in `order` (the order of --help).
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace volmap::cli {

/// Runs a parsed subcommand; returns the exit status.
using Runner = std::function<int()>;
/// Adds the subcommand to the app and returns its runner.
using Registrar = std::function<Runner(CLI::App&)>;

struct CommandRegistration {
  CommandRegistration(int order, Registrar registrar);
};

}  // namespace volmap::cli
