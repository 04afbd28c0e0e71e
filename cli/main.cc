// volmap: geometric error models, compensation tables and NC post-processing
// for machine tools. Exit status: 0 success, 2 usage error, 1 anything else
// (one line on stderr naming the file and line and what is wrong).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <exception>
#include <iostream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "cli/commands.h"
#include "cli/installed_samples.h"
#include "cli/message_wording.h"
#include "core/common/internal_error.h"

namespace volmap::cli {
namespace {
std::vector<std::pair<int, Registrar>>& registry() {
  static std::vector<std::pair<int, Registrar>> r;
  return r;
}
}  // namespace
CommandRegistration::CommandRegistration(int order, Registrar registrar) {
  registry().emplace_back(order, std::move(registrar));
}
}  // namespace volmap::cli

int main(int argc, char** argv) {
  CLI::App app{
      "volmap: machine-tool geometric error models, compensation tables and "
      "NC post-processing (Hsu; Lei & Hsu 2003)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("volmap 0.1.0"));
  std::map<const CLI::App*, volmap::cli::Runner> runners;
  auto commands = volmap::cli::registry();
  std::stable_sort(commands.begin(), commands.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [order, registrar] : commands) {
    volmap::cli::Runner r = registrar(app);
    runners[app.get_subcommands({}).back()] = std::move(r);
  }

  // An installed volmap finds its samples from any folder (cli/installed_samples.h).
  std::vector<std::string> notes;
  const std::vector<std::string> args = volmap::cli::with_installed_samples(
      std::vector<std::string>(argv, argv + argc), volmap::cli::installed_samples_dir(), &notes);
  std::vector<char*> arg_ptrs;
  for (const std::string& a : args) arg_ptrs.push_back(const_cast<char*>(a.c_str()));
  argv = arg_ptrs.data();
  for (const std::string& n : notes) std::cerr << "volmap: " << n << "\n";
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string hint = volmap::cli::misspelling_hint(app, argc, argv);
    if (hint.empty())
      hint = volmap::cli::flag_value_hint(
          app, argc, argv,
          dynamic_cast<const CLI::ExtrasError*>(&e) ? std::string(e.what()) : std::string());
    std::cerr << "volmap: " << (hint.empty() ? volmap::cli::plain_range(e.what()) : hint)
              << " (see volmap --help)\n";
    return 2;
  }
  const CLI::App* verb = app.get_subcommands().empty() ? nullptr : app.get_subcommands().front();
  // The libraries name fields (`tolerance_um`); the user types flags.
  const auto wording = [&](const char* message) {
    return volmap::cli::flag_wording(message, app, verb);
  };
  try {
    for (const CLI::App* sub : app.get_subcommands()) return runners.at(sub)();
  } catch (const volmap::cli::UsageError& e) {
    std::cerr << "volmap: " << wording(e.what()) << " (see volmap "
              << (app.get_subcommands().empty() ? ""
                                                : app.get_subcommands().front()->get_name() + " ")
              << "--help)\n";
    return 2;
  } catch (const std::exception& e) {
    // Every exception that reaches here and is not an error volmap raises
    // on purpose (core/common/internal_error.h) is a bug: said so, with the
    // input's file:line when the code that caught it knew them.
    if (!volmap::is_expected_error(e)) {
      std::cerr << "volmap: " << volmap::internal_error_message(e) << "\n";
      return 1;
    }
    std::string msg = wording(e.what());
    for (char& c : msg)
      if (c == '\n') c = ' ';
    std::cerr << "volmap: " << msg << "\n";
    return 1;
  } catch (...) {
    std::cerr << "volmap: internal error: an exception that is not a std::exception; this is a "
                 "bug in volmap, not a fault of the input: please report it with the command "
                 "line and its input files\n";
    return 1;
  }
  return 2;
}
