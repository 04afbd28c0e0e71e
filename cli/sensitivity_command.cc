// volmap sensitivity: the error-gain table (Hsu Tables I and II).
#include <fmt/format.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "cli/commands.h"
#include "cli/parse_util.h"
#include "core/common/units.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "core/model/sensitivity.h"

namespace volmap::cli {

namespace {

double clean(double x) { return std::abs(x) < 1e-12 ? 0.0 : x; }

double display_value(const ErrorGain& g, double v) {
  return v * (g.angular ? units::kUradPerRad : units::kUmPerMm);
}

/// An error's contribution to the tool-tip error (um).
Eigen::Vector3d contribution_um(const ErrorGain& g, double value) {
  return g.dP * value * units::kUmPerMm;
}

nlohmann::ordered_json um3(const Eigen::Vector3d& v) {
  return nlohmann::ordered_json::array({clean(v.x()), clean(v.y()), clean(v.z())});
}

struct SensitivityOptions {
  std::string machine, errors, at, model = "independent", convention = "iso230-1";
  bool json = false, other_machine_errors = false;
};

/// The gains at u and, with --errors, the model and each error's value.
struct SensitivityResult {
  const Machine& machine;
  AxisVector u;
  std::vector<ErrorGain> gains;
  std::optional<ErrorModel> model;
  std::vector<double> values;
  LocationConvention convention = LocationConvention::kIso230;
};

/// --json: one document with the gains and, with --errors, each error's
/// value and contribution and the total.
void print_sensitivity_json(const SensitivityOptions& o, const SensitivityResult& r) {
  nlohmann::ordered_json doc;
  doc["model"] = o.model;
  doc["convention"] = location_convention_name(r.convention);
  nlohmann::ordered_json at = nlohmann::ordered_json::object();
  for (int i = 0; i < r.machine.axis_count(); ++i) {
    const AxisName a = r.machine.axis_order[static_cast<size_t>(i)];
    at[std::string(1, axis_char(a))] = display_position(a, r.u[i]);
  }
  doc["at"] = at;
  nlohmann::ordered_json g = nlohmann::ordered_json::object();
  for (const ErrorGain& e : r.gains) {
    g[e.name] = {{"dx", clean(e.dP.x())}, {"dy", clean(e.dP.y())}, {"dz", clean(e.dP.z())},
                 {"di", clean(e.dQ.x())}, {"dj", clean(e.dQ.y())}, {"dk", clean(e.dQ.z())}};
  }
  doc["gains"] = g;
  if (r.model) {
    nlohmann::ordered_json c = nlohmann::ordered_json::object();
    for (size_t k = 0; k < r.gains.size(); ++k) {
      const Eigen::Vector3d d = contribution_um(r.gains[k], r.values[k]);
      c[r.gains[k].name] = {{"value", clean(display_value(r.gains[k], r.values[k]))},
                            {"dx_um", clean(d.x())},
                            {"dy_um", clean(d.y())},
                            {"dz_um", clean(d.z())}};
    }
    const PoseError fo = r.model->first_order(r.u), ex = r.model->exact(r.u);
    doc["errors"] = {{"file", o.errors},
                     {"contributions", c},
                     {"first_order_um", um3(fo.dP_mm * units::kUmPerMm)},
                     {"exact_um", um3(ex.dP_mm * units::kUmPerMm)},
                     {"exact_axis_urad", um3(ex.dQ * units::kUradPerRad)}};
  }
  std::cout << doc.dump(2) << "\n";
}

/// The table for people.
void print_sensitivity_text(const SensitivityOptions& o, const SensitivityResult& r) {
  std::cout << fmt::format("Error gains of {} ({} model, {}; location errors: {}) at {}\n",
                           r.machine.name.empty() ? o.machine : r.machine.name, o.model,
                           o.model == "dependent" ? "Hsu Table I" : "Hsu Table II",
                           location_convention_name(r.convention), o.at);
  std::cout << "Position gains in mm per mm (translational errors) or mm per rad "
               "(angular);\norientation gains in rad per rad. Workpiece coordinates.\n\n";
  std::cout << fmt::format("{:<6} {:>10} {:>10} {:>10} {:>7} {:>7} {:>7}", "error", "dx", "dy",
                           "dz", "di", "dj", "dk");
  if (r.model)
    std::cout << fmt::format(" | {:>11} {:>8} {:>8} {:>8}", "value", "dx µm", "dy µm", "dz µm");
  std::cout << "\n";
  for (size_t k = 0; k < r.gains.size(); ++k) {
    const ErrorGain& e = r.gains[k];
    std::cout << fmt::format("{:<6} {:>10.3f} {:>10.3f} {:>10.3f} {:>7.3f} {:>7.3f} {:>7.3f}",
                             e.name, clean(e.dP.x()), clean(e.dP.y()), clean(e.dP.z()),
                             clean(e.dQ.x()), clean(e.dQ.y()), clean(e.dQ.z()));
    if (r.model) {
      const Eigen::Vector3d d = contribution_um(r.gains[k], r.values[k]);
      std::cout << fmt::format(" | {:>6.2f} {:<4} {:>8.3f} {:>8.3f} {:>8.3f}",
                               clean(display_value(e, r.values[k])), e.angular ? "µrad" : "µm",
                               clean(d.x()), clean(d.y()), clean(d.z()));
    }
    std::cout << "\n";
  }
  if (r.model) {
    const PoseError fo = r.model->first_order(r.u), ex = r.model->exact(r.u);
    std::cout << fmt::format(
        "\nTool-tip error at {} (workpiece coordinates, actual - nominal):\n"
        "  first order  dx {:8.3f} µm  dy {:8.3f} µm  dz {:8.3f} µm\n"
        "  exact HTM    dx {:8.3f} µm  dy {:8.3f} µm  dz {:8.3f} µm  |dP| {:.3f} µm\n"
        "  tool axis    di {:8.3f} µrad  dj {:8.3f} µrad  dk {:8.3f} µrad\n"
        "(value: µm for translational errors, µrad for angular ones; mean of both\n"
        " directions for bidirectional tables)\n",
        o.at, clean(fo.dP_mm.x() * units::kUmPerMm), clean(fo.dP_mm.y() * units::kUmPerMm),
        clean(fo.dP_mm.z() * units::kUmPerMm), clean(ex.dP_mm.x() * units::kUmPerMm),
        clean(ex.dP_mm.y() * units::kUmPerMm), clean(ex.dP_mm.z() * units::kUmPerMm),
        ex.dP_mm.norm() * units::kUmPerMm, clean(ex.dQ.x() * units::kUradPerRad),
        clean(ex.dQ.y() * units::kUradPerRad), clean(ex.dQ.z() * units::kUradPerRad));
  }
}

Runner register_sensitivity(CLI::App& app) {
  auto o = std::make_shared<SensitivityOptions>();
  CLI::App* sub =
      app.add_subcommand("sensitivity",
                         "Error-gain table: change of the tool pose per unit of each geometric "
                         "error (Hsu Table I: dependent, Table II: independent)");
  sub->add_option("--machine", o->machine, "Machine definition (JSON, docs/machine-format.md)")
      ->required();
  sub->add_option("--at", o->at,
                  "Axis position X,Y,Z[,A,C] in the machine's axis order (mm, degrees)")
      ->required();
  sub->add_option("--model", o->model, "independent (Table II, default) or dependent (Table I)")
      ->check(CLI::IsMember({"independent", "dependent"}));
  sub->add_option("--errors", o->errors,
                  "Errors CSV (errors.md): adds each error's value and its contribution "
                  "to the tool-tip error at --at, and the total (first order and exact)");
  CLI::Option* sub_convention =
      sub->add_option(
             "--convention", o->convention,
             "Meaning of the location errors' gains without --errors: iso230-1 (default) or "
             "link (with --errors: the file's)")
          ->check(CLI::IsMember({"iso230-1", "link"}));
  add_other_machine_flag(*sub, o->other_machine_errors);
  sub->add_flag("--json", o->json, "Write one JSON document to stdout");
  sub->footer(
      "Example:\n  volmap sensitivity --machine samples/machines/hsu-3axis.json "
      "--at 250,200,150 --model dependent --json");

  return [o, sub_convention]() -> int {
    const Machine m = load_machine_json(o->machine);
    const AxisVector u = parse_axis_position(m, o->at, "--at");
    const Formulation f =
        o->model == "dependent" ? Formulation::kDependent : Formulation::kIndependent;
    SensitivityResult r{m, u, {}, std::nullopt, {}};
    // With --errors: value of each error at u and its contribution (um);
    // the gains of location errors in the file's meaning.
    LocationConvention convention = *parse_location_convention(o->convention);
    if (!o->errors.empty()) {
      r.model.emplace(
          m,
          load_errors_for(m, o->machine, o->errors, ErrorsFormat::kVolmap, o->other_machine_errors),
          ModelOptions{f, OutsidePolicy::kError});
      r.values = error_values(m, r.model->errors(), u, OutsidePolicy::kError);
      if (sub_convention->count() > 0 && r.model->errors().convention != convention)
        throw UsageError(fmt::format(
            "--convention {}: {} gives its location errors in the {} convention; leave "
            "--convention out (the file's meaning is used), or convert the file (volmap convert)",
            o->convention, o->errors, location_convention_name(r.model->errors().convention)));
      convention = r.model->errors().convention;
    }
    r.gains = error_gains(m, f, u, convention);
    r.convention = convention;
    if (o->json) {
      print_sensitivity_json(*o, r);
      return 0;
    }
    print_sensitivity_text(*o, r);
    return 0;
  };
}

}  // namespace

static const CommandRegistration kSensitivity(10, register_sensitivity);

}  // namespace volmap::cli
