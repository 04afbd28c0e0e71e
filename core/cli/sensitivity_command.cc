// volmap sensitivity: the error-gain table (Hsu Tables I and II).
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/cli/commands.h"
#include "core/cli/parse_util.h"
#include "core/machine_json.h"
#include "core/sensitivity.h"

namespace volmap::cli {

Runner register_sensitivity(CLI::App& app) {
  struct Opts {
    std::string machine, at, model = "independent";
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* sub = app.add_subcommand(
      "sensitivity",
      "Error-gain table: change of the tool pose per unit of each geometric "
      "error (Hsu Table I: dependent, Table II: independent)");
  sub->add_option("--machine", o->machine, "Machine definition (JSON, docs/machine-format.md)")
      ->required();
  sub->add_option("--at", o->at,
                  "Axis position X,Y,Z[,A,C] in the machine's axis order (mm, degrees)")
      ->required();
  sub->add_option("--model", o->model,
                  "independent (Table II, default) or dependent (Table I)")
      ->check(CLI::IsMember({"independent", "dependent"}));
  sub->add_flag("--json", o->json, "Write one JSON document to stdout");
  sub->footer(
      "Example:\n  volmap sensitivity --machine samples/machines/hsu-3axis.json "
      "--at 250,200,150 --model dependent --json");

  return [o]() -> int {
    const Machine m = load_machine_json(o->machine);
    const AxisVector u = parse_axis_position(m, o->at, "--at");
    const Formulation f = o->model == "dependent" ? Formulation::kDependent
                                                  : Formulation::kIndependent;
    const std::vector<ErrorGain> gains = error_gains(m, f, u);
    auto clean = [](double x) { return std::abs(x) < 1e-12 ? 0.0 : x; };
    if (o->json) {
      nlohmann::ordered_json doc;
      doc["model"] = o->model;
      nlohmann::ordered_json at = nlohmann::ordered_json::object();
      for (int i = 0; i < m.axis_count(); ++i) {
        const AxisName a = m.axis_order[static_cast<size_t>(i)];
        at[std::string(1, axis_char(a))] = display_position(a, u[i]);
      }
      doc["at"] = at;
      nlohmann::ordered_json g = nlohmann::ordered_json::object();
      for (const ErrorGain& e : gains) {
        g[e.name] = {{"dx", clean(e.dP.x())}, {"dy", clean(e.dP.y())},
                     {"dz", clean(e.dP.z())}, {"di", clean(e.dQ.x())},
                     {"dj", clean(e.dQ.y())}, {"dk", clean(e.dQ.z())}};
      }
      doc["gains"] = g;
      std::cout << doc.dump(2) << "\n";
      return 0;
    }
    std::cout << fmt::format("Error gains of {} ({} model, {}) at {}\n",
                             m.name.empty() ? o->machine : m.name, o->model,
                             o->model == "dependent" ? "Hsu Table I" : "Hsu Table II",
                             o->at);
    std::cout << "Position gains in mm per mm (translational errors) or mm per rad "
                 "(angular);\norientation gains in rad per rad. Workpiece coordinates.\n\n";
    std::cout << fmt::format("{:<6} {:>12} {:>12} {:>12} {:>8} {:>8} {:>8}\n",
                             "error", "dx", "dy", "dz", "di", "dj", "dk");
    for (const ErrorGain& e : gains) {
      std::cout << fmt::format("{:<6} {:>12.4f} {:>12.4f} {:>12.4f} {:>8.4f} {:>8.4f} {:>8.4f}\n",
                               e.name, clean(e.dP.x()), clean(e.dP.y()), clean(e.dP.z()),
                               clean(e.dQ.x()), clean(e.dQ.y()), clean(e.dQ.z()));
    }
    return 0;
  };
}

}  // namespace volmap::cli
