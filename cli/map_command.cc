// volmap map: builds the gridded volumetric error / correction table of a
// machine (maps/, docs/maps.md) and writes it as a binary table file.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cli/commands.h"
#include "cli/option_checks.h"
#include "cli/parse_util.h"
#include "core/model/errors_import.h"
#include "core/model/machine_json.h"
#include "maps/tables/factorized_table.h"
#include "maps/tables/layer_name.h"
#include "maps/tables/map_job.h"
#include "maps/tables/map_report.h"
#include "maps/tables/output_wording.h"
#include "maps/tables/table_builder.h"
#include "maps/tables/table_file.h"

namespace volmap::cli {

namespace {

std::vector<double> parse_spacing(const Machine& m, const std::string& text) {
  std::vector<double> out;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    const std::string cell =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    double v = 0;
    const auto res = std::from_chars(cell.data(), cell.data() + cell.size(), v);
    if (cell.empty() || res.ec != std::errc() || res.ptr != cell.data() + cell.size() ||
        !(v > 0.0) || !std::isfinite(v))
      throw UsageError(fmt::format("--spacing {}: \"{}\" is not a positive number", text, cell));
    out.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  std::string order;
  for (AxisName a : m.axis_order) order += std::string(order.empty() ? "" : ",") + axis_char(a);
  if (static_cast<int>(out.size()) != m.axis_count())
    throw UsageError(fmt::format("--spacing {}: expected {} values ({}, mm and degrees), got {}",
                                 text, m.axis_count(), order, out.size()));
  for (int i = 0; i < m.axis_count(); ++i)
    if (is_rotary(m.axis_order[static_cast<size_t>(i)]))
      out[static_cast<size_t>(i)] *= M_PI / 180.0;
  return out;
}

// Degrees rounded to 1e-9 deg (the rad round trip of 30 deg gives
// 29.999999999999996).
double display(AxisName a, double v) {
  return is_rotary(a) ? std::round(v * 180.0 / M_PI * 1e9) / 1e9 + 0.0 : v;
}
const char* unit(AxisName a) { return is_rotary(a) ? "deg" : "mm"; }

struct MapOptions {
  std::string machine, errors, errors_format = "auto", spacing, output, interpolation = "linear",
                               model = "independent", form = "full";
  std::string report, covariance;
  double tolerance_um = 0.0, tolerance_urad = 0.0, repeatability_um = -1.0,
         repeatability_urad = -1.0, max_table_gib = 2.0;
  int threads = 0;
  bool json = false, other_machine_errors = false;
};

// The first keys of the --json summary: what was written, from what.
nlohmann::ordered_json summary_head(const MapOptions& o, const char* form,
                                    const std::string& machine, const std::string& errors) {
  nlohmann::ordered_json doc;
  doc["table"] = o.output;
  doc["form"] = form;
  doc["machine"] = machine;
  doc["errors"] = errors;
  doc["model"] = o.model;
  return doc;
}

// --form factorized: the 1-D tables and location errors, written as JSON.
int run_factorized(const MapOptions& o, const ErrorModel& model) {
  if (!o.spacing.empty() || o.tolerance_um > 0.0 || o.tolerance_urad > 0.0 || !o.report.empty())
    throw std::invalid_argument(
        "--form factorized is exact and has no grid: --spacing, --tolerance-um, "
        "--tolerance-urad and --report apply to --form full");
  const maps::FactorizedTable t = maps::factorized_table_of(o.machine, model);
  const std::string text = maps::factorized_json(t);
  if (o.output == "-") {
    std::cout << text;
    return 0;
  }
  maps::save_factorized(o.output, t);
  if (o.json) {
    nlohmann::ordered_json doc = summary_head(o, "factorized", t.machine_name, t.errors_source);
    doc["values"] = maps::factorized_values(t);
    doc["bytes"] = text.size();
    std::cout << doc.dump(2) << "\n";
  } else {
    std::cout << fmt::format(
        "Factorized table of {} ({} model, errors {}): 1-D component-error tables and "
        "location errors, {} values, exact for the rigid-body model; written {} ({} bytes)\n",
        t.machine_name, o.model, t.errors_source, maps::factorized_values(t), o.output,
        text.size());
  }
  return 0;
}

// The progress bar on a terminal's standard error.
void draw_progress(std::int64_t done, std::int64_t total) {
  const int width = 40;
  const int filled = total > 0 ? static_cast<int>(width * done / total) : width;
  std::cerr << fmt::format("\rmap [{:<{}}] {:3d}%", std::string(static_cast<size_t>(filled), '#'),
                           width, total > 0 ? static_cast<int>(100 * done / total) : 100)
            << std::flush;
  if (done == total) std::cerr << "\r" << std::string(52, ' ') << "\r" << std::flush;
}

maps::FullTableJob full_table_job(const MapOptions& o, const Machine& m, int threads,
                                  const maps::UncertaintySources& uncertainty, bool bar) {
  maps::FullTableJob job;
  if (!o.spacing.empty()) job.spacing = parse_spacing(m, o.spacing);
  job.tolerance_um = o.tolerance_um;
  job.tolerance_urad = o.tolerance_urad;
  job.build.threads = threads;
  job.build.max_bytes = static_cast<std::size_t>(o.max_table_gib * double(1 << 30));
  job.build.repeatability = uncertainty.repeatability;
  job.build.covariance = uncertainty.covariance ? &*uncertainty.covariance : nullptr;
  if (bar) job.build.progress = draw_progress;
  job.check.method = maps::parse_interpolation(o.interpolation);
  job.check.threads = threads;
  return job;
}

void print_json_summary(const MapOptions& o, const maps::FullTableResult& r,
                        const maps::TableExtremes& e, int threads) {
  const maps::VolumetricTable& table = r.table;
  const maps::CheckResult& checked = r.checked;
  const bool five = table.pose_correction();
  nlohmann::ordered_json doc = summary_head(o, "full", table.machine_name, table.errors_source);
  nlohmann::ordered_json grid = nlohmann::ordered_json::array();
  for (const maps::GridAxis& g : table.grid)
    grid.push_back({{"axis", std::string(1, axis_char(g.axis))},
                    {"unit", unit(g.axis)},
                    {"start", display(g.axis, g.start)},
                    {"end", display(g.axis, g.end)},
                    {"spacing", display(g.axis, g.spacing)},
                    {"nodes", g.count},
                    {"uniform", g.uniform()}});
  doc["grid"] = grid;
  doc["nodes"] = table.node_count();
  nlohmann::ordered_json layers = nlohmann::ordered_json::array();
  for (int l = 0; l < table.layer_count(); ++l) layers.push_back(maps::layer_name(table, l));
  doc["layers"] = layers;
  doc["channels"] = table.channels;
  doc["bytes"] = table.size_bytes();
  doc["max_dv_um"] = e.max_dv_um;
  if (e.max_du_um) doc["max_du_um"] = *e.max_du_um;
  if (e.max_dq_urad) doc["max_dq_urad"] = *e.max_dq_urad;
  if (e.max_du_rotary_urad) doc["max_du_rotary_urad"] = *e.max_du_rotary_urad;
  if (e.max_u_um) doc["max_u_um"] = *e.max_u_um;
  if (!o.report.empty()) doc["report"] = o.report;
  doc["interpolation"] = maps::interpolation_name(r.method);
  if (table.tolerance_um > 0.0) doc["tolerance_um"] = table.tolerance_um;
  doc["max_interpolation_error_um"] = r.interpolation_um();
  doc["max_interpolation_error_dv_um"] = checked.max_dv_um;
  if (e.max_du_um) doc["max_interpolation_error_du_um"] = checked.max_du_um;
  if (r.tolerance_urad > 0.0) doc["tolerance_urad"] = r.tolerance_urad;
  if (e.max_dq_urad) doc["max_interpolation_error_dq_urad"] = checked.max_dq_urad;
  if (five) {
    doc["max_interpolation_error_du_rotary_urad"] = checked.max_du_rot_urad;
    doc["du_check_points_near_singular_excluded"] = checked.du_excluded;
    doc["correction_singular_nodes"] = r.summary.correction_singular;
    doc["correction_max_residual_um"] = r.summary.correction_max_residual_mm * 1e3;
  }
  doc["check_points_per_layer"] = checked.points;
  if (r.grids_tried > 0) doc["spacing_search_grids"] = r.grids_tried;
  doc["correction_clamped_nodes"] = r.summary.correction_clamped;
  doc["build_seconds"] = r.summary.seconds;
  doc["threads"] = threads;
  std::cout << doc.dump(2) << "\n";
}

// The grid, the layers, the extremes and the interpolation error in words.
void print_table_text(const MapOptions& o, const maps::FullTableResult& r,
                      const maps::TableExtremes& e) {
  const maps::VolumetricTable& table = r.table;
  std::cout << fmt::format("Volumetric table of {} ({} model, errors {})\n",
                           table.machine_name.empty() ? o.machine : table.machine_name, o.model,
                           table.errors_source);
  for (const maps::GridAxis& g : table.grid)
    std::cout << fmt::format("  {}  {:g}..{:g} {}  spacing {:g}  {} nodes{}\n", axis_char(g.axis),
                             display(g.axis, g.start), display(g.axis, g.end), unit(g.axis),
                             display(g.axis, g.spacing), g.count,
                             g.uniform() ? "" : " (last cell shorter)");
  std::string layers;
  for (int l = 0; l < table.layer_count(); ++l)
    layers += (l ? ", " : "") + maps::layer_name(table, l);
  std::cout << fmt::format("  {} nodes x {} direction layer{} ({}), {:.1f} MiB\n",
                           table.node_count(), table.layer_count(),
                           table.layer_count() > 1 ? "s" : "", layers,
                           static_cast<double>(table.size_bytes()) / (1 << 20));
  std::cout << fmt::format("  max |dv| {:.3f} µm", e.max_dv_um);
  if (e.max_dq_urad) std::cout << fmt::format(", max |dQ| {:.3f} µrad", *e.max_dq_urad);
  if (e.max_du_um) std::cout << fmt::format(", max |du| {:.3f} µm", *e.max_du_um);
  if (e.max_du_rotary_urad)
    std::cout << fmt::format(" and {:.3f} µrad (rotary axes)", *e.max_du_rotary_urad);
  if (e.max_u_um) std::cout << fmt::format(", max uncertainty u {:.3f} µm", *e.max_u_um);
  std::cout << "\n";
  std::cout << fmt::format(
      "  interpolation error ({}) max {:.4f} µm{} over {} cell centres and random points per "
      "layer\n",
      maps::interpolation_name(r.method), r.interpolation_um(),
      table.tolerance_um > 0.0 ? fmt::format(" (tolerance {:g} µm)", table.tolerance_um) : "",
      r.checked.points);
}

// The checks of the corrections and the build in words.
void print_correction_text(const MapOptions& o, const maps::FullTableResult& r, int threads) {
  const maps::CheckResult& checked = r.checked;
  const maps::BuildSummary& summary = r.summary;
  const bool five = r.table.pose_correction();
  if (r.table.channel("ei"))
    std::cout << fmt::format(
        "  interpolation error of dQ max {:.4f} µrad{}\n", checked.max_dq_urad,
        r.tolerance_urad > 0.0 ? fmt::format(" (tolerance {:g} µrad)", r.tolerance_urad) : "");
  if (five)
    std::cout << fmt::format(
        "  interpolation error of du max {:.4f} µm, {:.4f} µrad (rotary), {} check points near "
        "the singular position not compared; {} nodes at the singular position (outer axis's "
        "correction suppressed), correction residual max {:.2g} µm\n",
        checked.max_du_um, checked.max_du_rot_urad, checked.du_excluded,
        summary.correction_singular, summary.correction_max_residual_mm * 1e3);
  if (summary.correction_clamped > 0 && five)
    std::cout << fmt::format(
        "  {} nodes' corrections reach beyond the travel of a limited axis "
        "(errors there held at the travel end)\n",
        summary.correction_clamped);
  else if (summary.correction_clamped > 0)
    std::cout << fmt::format(
        "  {} nodes' corrections reach beyond the travel (error held at the "
        "travel end)\n",
        summary.correction_clamped);
  std::cout << fmt::format("  built in {:.3f} s on {} thread{}; written {}\n", summary.seconds,
                           threads, threads > 1 ? "s" : "", o.output);
  if (!o.report.empty()) std::cout << fmt::format("  report {}\n", o.report);
}

void write_report(const MapOptions& o, const maps::FullTableResult& r) {
  maps::ReportInfo info;
  info.model = o.model;
  info.max_interpolation_um = r.interpolation_um();
  info.interpolation = maps::interpolation_name(r.method);
  info.build_seconds = r.summary.seconds;
  AtomicOutput page(o.report, {}, maps::kOutputWording);
  page.stream() << maps::map_report_html(r.table, info);
  page.commit();
}

// --form full: build on the grid given or the coarsest within the
// tolerances, check, write, report.
int run_full(const MapOptions& o, const ErrorModel& model,
             const maps::UncertaintySources& uncertainty) {
  const Machine& m = model.machine();
  const int threads = o.threads > 0
                          ? o.threads
                          : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const bool bar = isatty(2) != 0;
  const maps::FullTableJob job = full_table_job(o, m, threads, uncertainty, bar);
  const bool searching = bar && job.spacing.empty();
  if (searching)
    std::cerr << "map: searching the spacing for " << job.tolerance_um_or_default() << " µm..."
              << std::flush;
  const maps::FullTableResult r = maps::build_full_table(model, job);
  if (searching) std::cerr << "\r" << std::string(60, ' ') << "\r" << std::flush;

  if (o.output == "-") {
    maps::write_table(std::cout, r.table);
    std::cout.flush();
  } else {
    maps::save_table(o.output, r.table);
  }
  if (!o.report.empty()) write_report(o, r);
  const maps::TableExtremes extremes = maps::table_extremes(r.table);
  if (o.output == "-") return 0;  // stdout holds the table
  if (o.json) {
    print_json_summary(o, r, extremes, threads);
    return 0;
  }
  print_table_text(o, r, extremes);
  print_correction_text(o, r, threads);
  return 0;
}

int run_map(const MapOptions& o) {
  refuse_output_equal_to_input(o.output, {o.machine, o.errors, o.covariance}, maps::kOutputWording);
  if (!o.report.empty())
    refuse_output_equal_to_input(o.report, {o.machine, o.errors, o.output}, maps::kOutputWording);
  if (o.output == "-" && !o.json && isatty(1))
    throw std::invalid_argument(
        "-o -: refusing to write a binary table to a terminal; "
        "redirect standard output or give a file");
  const Machine m = load_machine_json(o.machine);
  const Formulation f =
      o.model == "dependent" ? Formulation::kDependent : Formulation::kIndependent;
  ErrorSet errors = load_errors_for(m, o.machine, o.errors, parse_errors_format(o.errors_format),
                                    o.other_machine_errors);
  const maps::UncertaintySources uncertainty = maps::uncertainty_sources(
      errors, o.repeatability_um, o.repeatability_urad, o.covariance, m, f);
  if (o.tolerance_urad > 0.0 && !m.has_rotary_axes())
    throw std::invalid_argument(fmt::format(
        "--tolerance-urad: {} has no rotary axes (its tables carry no tool-axis error); use "
        "--tolerance-um",
        m.name));
  const ErrorModel model(m, std::move(errors), ModelOptions{f, OutsidePolicy::kError});
  if (o.form == "factorized") return run_factorized(o, model);
  return run_full(o, model, uncertainty);
}

Runner register_map(CLI::App& app) {
  auto o = std::make_shared<MapOptions>();
  CLI::App* sub = app.add_subcommand(
      "map",
      "Gridded table of the tool-tip error dv and the correction du over the travel "
      "(binary table file, docs/maps.md)");
  sub->add_option("--machine", o->machine, "Machine definition (JSON, docs/machine-format.md)")
      ->required();
  sub->add_option("--errors", o->errors,
                  "Errors file: errors.md CSV, ISG CSV or Etalon exchange format")
      ->required();
  add_other_machine_flag(*sub, o->other_machine_errors);
  sub->add_option("--errors-format", o->errors_format,
                  "Format of --errors: auto (default: detected), volmap (errors.md), isg-csv "
                  "(Beckhoff/ISG CSV), etalon (Etalon exchange format, Vendor variant)")
      ->check(CLI::IsMember({"auto", "volmap", "isg-csv", "etalon"}));
  CLI::Option* spacing = sub->add_option(
      "--spacing", o->spacing,
      "Grid spacing per axis SX,SY,SZ[,SA,SC] (mm, degrees); nodes on multiples of the spacing "
      "from each travel's start, the last node at the travel's end");
  CLI::Option* tol_um = sub->add_option(
      "--tolerance-um", o->tolerance_um,
      "Automatic spacing: the coarsest grid whose interpolation error of the tool-tip error "
      "(and of the three-axis correction) against the model stays below this (µm; default 1 "
      "without --spacing)");
  tol_um->check(kFinitePositive)->excludes(spacing);
  sub->add_option("--tolerance-urad", o->tolerance_urad,
                  "Automatic spacing, machines with rotary axes: the same bound for the tool-axis "
                  "error dQ (µrad; default 1 without --spacing)")
      ->check(kFinitePositive)
      ->excludes(spacing);
  sub->add_option("--max-table-gib", o->max_table_gib,
                  "Refuse tables larger than this (GiB, default 2); the table is held in memory "
                  "whole")
      ->check(kFinitePositive);
  sub->add_option("--interpolation", o->interpolation,
                  "Interpolation the tolerance is checked with: linear (default, as controllers "
                  "do) or cubic")
      ->check(CLI::IsMember({"linear", "cubic"}));
  sub->add_option("--form", o->form,
                  "full (default): dv and du on a grid over all axes (binary table); factorized: "
                  "per-axis 1-D tables of the component errors plus the location errors, "
                  "evaluated through the HTM chain, exact for the rigid-body model (JSON, "
                  "docs/maps.md)")
      ->check(CLI::IsMember({"full", "factorized"}));
  sub->add_option("--model", o->model, "independent (Hsu Table II, default) or dependent (Table I)")
      ->check(CLI::IsMember({"independent", "dependent"}));
  sub->add_option("--threads", o->threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(1, 256));
  sub->add_option("-o,--output", o->output, "Table file to write (- for standard output)")
      ->required();
  sub->add_flag("--json", o->json, "Write the summary as one JSON document to stdout");
  sub->add_option("--report", o->report,
                  "Also write a self-contained HTML page with slices of the error field (inline "
                  "SVG, no network)");
  sub->add_option(
         "--repeatability-um", o->repeatability_um,
         "Standard uncertainty of every translational error of the errors file, µm (default: "
         "its '# repeatability_um:' metadata); adds the per-node uncertainty u")
      ->check(kFiniteNonNegative);
  sub->add_option(
         "--repeatability-urad", o->repeatability_urad,
         "Standard uncertainty of every angular error, µrad (default: '# repeatability_urad:')")
      ->check(kFiniteNonNegative);
  sub->add_option("--covariance", o->covariance,
                  "volmap identify --json report: propagate the covariance of the identified "
                  "location errors to the per-node uncertainty u (replaces their repeatability)");
  sub->footer(
      "Example:\n  volmap map --machine samples/machines/hsu-3axis.json "
      "--errors samples/errors/hsu-3axis.csv --tolerance-um 0.5 -o hsu.vmt\n"
      "  volmap map --machine samples/machines/hsu-3axis.json --errors "
      "samples/errors/hsu-3axis.csv \\\n"
      "      --spacing 10,10,10 --repeatability-um 0.5 --report map.html -o hsu-10mm.vmt\n"
      "  volmap map --machine samples/machines/lei-hsu-xyzac.json "
      "--errors samples/errors/lei-hsu-xyzac.csv --tolerance-um 2 --tolerance-urad 2 -o xyzac.vmt");

  return [o]() -> int { return run_map(*o); };
}

}  // namespace

static const CommandRegistration kMap(40, register_map);

}  // namespace volmap::cli
