// volmap kinematics: the nominal forward and backward transformations
// (Lei & Hsu 2003, eqs. 1-2), and with --errors the correction du of eq. 4.
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/parse_util.h"
#include "core/kinematics/correction.h"
#include "core/kinematics/kinematics.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"

namespace volmap::cli {

namespace {

double clean(double x) { return std::abs(x) < 1e-12 ? 0.0 : x; }

nlohmann::ordered_json axes_json(const Machine& m, const AxisVector& u) {
  nlohmann::ordered_json o = nlohmann::ordered_json::object();
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisName a = m.axis_order[static_cast<size_t>(i)];
    o[std::string(1, axis_char(a))] = clean(display_position(a, u[i]));
  }
  return o;
}

std::string axes_text(const Machine& m, const AxisVector& u) {
  std::string s;
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisName a = m.axis_order[static_cast<size_t>(i)];
    s += fmt::format("{}{} {:.6f}", s.empty() ? "" : "  ", axis_char(a),
                     clean(display_position(a, u[i])));
  }
  return s;
}

std::string outside_travel(const Machine& m, const AxisVector& u) {
  std::string s;
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisLimits& L = m.limits[static_cast<size_t>(i)];
    if (L.unlimited || (u[i] >= L.min - 1e-9 && u[i] <= L.max + 1e-9)) continue;
    s += fmt::format("{}{}", s.empty() ? "" : ",", axis_char(m.axis_order[static_cast<size_t>(i)]));
  }
  return s;
}

// The correction at u: JSON and text.
struct CorrectionOut {
  nlohmann::ordered_json json;
  std::string text;
};
CorrectionOut correction_out(const Machine& m, const CorrectionSolver& corr, const AxisVector& u,
                             const std::string& errors_file) {
  const CorrectionResult r = corr.correct(u);
  CorrectionOut out;
  nlohmann::ordered_json du = nlohmann::ordered_json::object();
  std::string du_text;
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisName a = m.axis_order[static_cast<size_t>(i)];
    const bool rot = is_rotary(a);
    const double v = clean(r.du[i] * (rot ? 1e6 : 1e3));
    du[fmt::format("{}_{}", axis_char(a), rot ? "urad" : "um")] = v;
    du_text += fmt::format("{}d{} {:.3f} {}", du_text.empty() ? "" : "  ", axis_char(a), v,
                           rot ? "µrad" : "µm");
  }
  const AxisVector corrected = u + r.du;
  out.json = {{"errors", errors_file},
              {"method", corr.options().max_iterations > 1 ? "iterated" : "one-step"},
              {"du", du},
              {"corrected", axes_json(m, corrected)},
              {"singular", r.singular},
              {"iterations", r.iterations},
              {"residual_um", clean(r.residual_mm * 1e3)},
              {"residual_axis_urad", clean(r.residual_axis * 1e6)}};
  out.text = fmt::format(
      "Correction ({}, {}): du = -J^-1 dv, dv = actual - nominal{}\n  {}\n  command  {}\n"
      "  residual tool-tip error {:.6f} µm, tool axis {:.6f} µrad\n",
      errors_file, corr.options().max_iterations > 1 ? "iterated to eq. 4" : "one step, eq. 6",
      r.singular ? " (singular: outer rotary correction suppressed)" : "", du_text,
      axes_text(m, corrected), r.residual_mm * 1e3, r.residual_axis * 1e6);
  return out;
}

struct KinematicsOptions {
  std::string machine, forward, backward, previous, errors;
  bool json = false, iterate = false, other_machine_errors = false;
};

// --forward: the nominal tool pose at an axis position, and the correction
// there with --errors.
int run_forward(const KinematicsOptions& o, const Machine& m, const std::string& name,
                const CorrectionSolver* corrector) {
  const AxisVector u = parse_axis_position(m, o.forward, "--forward");
  const ToolPose v = nominal_forward(m, u);
  std::optional<CorrectionOut> c;
  if (corrector) c = correction_out(m, *corrector, u, o.errors);
  if (o.json) {
    nlohmann::ordered_json doc;
    doc["tip_mm"] = {clean(v.tip_mm.x()), clean(v.tip_mm.y()), clean(v.tip_mm.z())};
    doc["axis"] = {clean(v.axis.x()), clean(v.axis.y()), clean(v.axis.z())};
    if (c) doc["correction"] = c->json;
    std::cout << doc.dump(2) << "\n";
    return 0;
  }
  std::cout << fmt::format(
      "Nominal tool pose of {} at {} (mm, deg), workpiece coordinates:\n"
      "  tip   x {:.6f}  y {:.6f}  z {:.6f} mm\n  axis  i {:.9f}  j {:.9f}  k {:.9f}\n",
      name, axes_text(m, u), clean(v.tip_mm.x()), clean(v.tip_mm.y()), clean(v.tip_mm.z()),
      clean(v.axis.x()), clean(v.axis.y()), clean(v.axis.z()));
  if (c) std::cout << "\n" << c->text;
  return 0;
}

// The tool pose of --backward: x,y,z,i,j,k, or x,y,z along the machine's
// tool axis on a three-axis machine.
ToolPose backward_pose(const KinematicsOptions& o, const Machine& m, const Kinematics& kin) {
  const std::vector<double> x = parse_numbers(o.backward, "--backward");
  if (x.size() == 6) return {{x[0], x[1], x[2]}, {x[3], x[4], x[5]}};
  if (x.size() == 3 && !kin.has_rotary_axes()) return {{x[0], x[1], x[2]}, m.tool_axis};
  throw std::invalid_argument(
      fmt::format("--backward {}: expected 6 values (x,y,z,i,j,k){}, got {}", o.backward,
                  kin.has_rotary_axes() ? "" : " or 3 (x,y,z)", x.size()));
}

void print_solutions(const Machine& m, const std::string& name, const ToolPose& v,
                     const BackwardSolutions& s, int k) {
  std::cout << fmt::format(
      "{} axis position{} of {} for the tool tip ({:g}, {:g}, {:g}) mm along ({:g}, {:g}, {:g}), "
      "workpiece coordinates (mm, deg):\n",
      s.count, s.count == 1 ? "" : "s", name, v.tip_mm.x(), v.tip_mm.y(), v.tip_mm.z(), v.axis.x(),
      v.axis.y(), v.axis.z());
  for (int i = 0; i < s.count; ++i) {
    const AxisVector& u = s.u[static_cast<size_t>(i)];
    const std::string out = outside_travel(m, u);
    std::cout << fmt::format("  {}: {}{}{}\n", i + 1, axes_text(m, u),
                             i == k ? "   (selected)" : "",
                             out.empty() ? "" : "   (outside travel: " + out + ")");
  }
  if (s.singular)
    std::cout << "Singular: the tool axis lies along the outer rotary axis; it is held at its "
                 "previous position.\n";
}

// --backward: every axis position of a tool pose, the one selected, and
// the correction of that one with --errors.
int run_backward(const KinematicsOptions& o, const Machine& m, const std::string& name,
                 const Kinematics& kin, const AxisVector& previous,
                 const CorrectionSolver* corrector) {
  const ToolPose v = backward_pose(o, m, kin);
  BackwardSolutions s;
  try {
    s = kin.backward(v, previous);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("--backward {}: {}", o.backward, e.what()));
  }
  if (s.count == 0)
    throw std::invalid_argument(fmt::format(
        "--backward {}: no axis position of {} reaches this tool axis within the rotary travel",
        o.backward, name));
  const int k = kin.select(s, previous);
  std::optional<CorrectionOut> c;
  if (corrector) c = correction_out(m, *corrector, s.u[static_cast<size_t>(k)], o.errors);
  if (o.json) {
    nlohmann::ordered_json doc;
    nlohmann::ordered_json sols = nlohmann::ordered_json::array();
    for (int i = 0; i < s.count; ++i) sols.push_back(axes_json(m, s.u[static_cast<size_t>(i)]));
    doc["solutions"] = sols;
    doc["selected"] = k;
    doc["singular"] = s.singular;
    if (c) doc["correction"] = c->json;
    std::cout << doc.dump(2) << "\n";
    return 0;
  }
  print_solutions(m, name, v, s, k);
  if (c) std::cout << "\n" << c->text;
  return 0;
}

int run_kinematics(const KinematicsOptions& o) {
  if (o.forward.empty() == o.backward.empty()) {
    std::cerr << "volmap kinematics: give one of --forward or --backward (see volmap kinematics "
                 "--help)\n";
    return 2;
  }
  const Machine m = load_machine_json(o.machine);
  const Kinematics kin(m);
  const AxisVector previous =
      o.previous.empty() ? m.home : parse_axis_position(m, o.previous, "--previous");
  std::optional<ErrorModel> model;
  std::optional<CorrectionSolver> corrector;
  if (!o.errors.empty()) {
    model.emplace(
        m, load_errors_for(m, o.machine, o.errors, ErrorsFormat::kVolmap, o.other_machine_errors));
    CorrectionOptions co;
    co.residual = true;
    if (o.iterate) co.max_iterations = 20;
    corrector.emplace(*model, co);
  }
  const std::string name = m.name.empty() ? o.machine : m.name;
  const CorrectionSolver* solver = corrector ? &*corrector : nullptr;
  if (!o.forward.empty()) return run_forward(o, m, name, solver);
  return run_backward(o, m, name, kin, previous, solver);
}

Runner register_kinematics(CLI::App& app) {
  auto o = std::make_shared<KinematicsOptions>();
  CLI::App* sub = app.add_subcommand(
      "kinematics",
      "Nominal forward (axis position -> tool pose) and backward (tool pose -> all axis "
      "positions) transformations, workpiece coordinates (Lei & Hsu eqs. 1-2)");
  sub->add_option("--machine", o->machine, "Machine definition (JSON, docs/machine-format.md)")
      ->required();
  CLI::Option* fwd =
      sub->add_option("--forward", o->forward,
                      "Axis position X,Y,Z[,A,C] in the machine's axis order (mm, degrees)");
  CLI::Option* bwd =
      sub->add_option("--backward", o->backward,
                      "Tool pose x,y,z,i,j,k in workpiece coordinates: tip (mm) and unit tool axis "
                      "(x,y,z alone on a three-axis machine)");
  fwd->excludes(bwd);
  sub->add_option("--previous", o->previous,
                  "Previous axis position (default: home): picks the solution with the least "
                  "rotary travel, unwraps unlimited rotary axes next to it, holds the free "
                  "rotary axis at the singular position");
  CLI::Option* err = sub->add_option(
      "--errors", o->errors,
      "Errors CSV (errors.md): also print the correction du (µm, µrad) and the corrected axis "
      "position for the real machine (Lei & Hsu eq. 4); for --backward, of the selected solution");
  sub->add_flag("--iterate", o->iterate,
                "With --errors: iterate to the exact solution of eq. 4 instead of the one-step "
                "du = -J^-1 dv of eq. 6")
      ->needs(err);
  add_other_machine_flag(*sub, o->other_machine_errors);
  sub->add_flag("--json", o->json, "Write one JSON document to stdout");
  sub->footer(
      "Example:\n  volmap kinematics --machine samples/machines/lei-hsu-xyzac.json "
      "--backward 10,20,30,0.5,0,0.8660254037844386 --previous 0,0,0,-30,90 --json");

  return [o]() -> int { return run_kinematics(*o); };
}

}  // namespace

static const CommandRegistration kKinematics(20, register_kinematics);

}  // namespace volmap::cli
