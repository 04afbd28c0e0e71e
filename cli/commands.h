// Subcommands of the volmap executable. Each subcommand lives in its own
// file under cli/ and registers itself with a static
// CommandRegistration; main() adds them in `order` (the order of --help).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <stdexcept>

namespace volmap::cli {

/// Runs a parsed subcommand; returns the exit status.
using Runner = std::function<int()>;
/// Adds the subcommand to the app and returns its runner.
using Registrar = std::function<Runner(CLI::App&)>;

/// A command line that cannot be run as given (an option value that does
/// not parse or does not fit the machine, two options naming one file): the
/// CLI prints its one line and exits with status 2 (cli.md), as for the
/// usage errors CLI11 finds itself.
class UsageError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct CommandRegistration {
  CommandRegistration(int order, Registrar registrar);
};

}  // namespace volmap::cli
