// volmap post: an NC program rewritten for the real machine (three-axis).
#include <fmt/format.h>
#include <unistd.h>

#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "cli/commands.h"
#include "cli/five_axis_options.h"
#include "cli/parse_util.h"
#include "cli/program_setup.h"
#include "core/common/atomic_file.h"
#include "core/common/input_error.h"
#include "core/model/errors_csv.h"
#include "core/model/errors_import.h"
#include "core/model/machine_json.h"
#include "maps/tables/table_file.h"
#include "postproc/five_axis/five_axis_post.h"
#include "postproc/three_axis/corrector.h"
#include "postproc/three_axis/post_program.h"
#include "postproc/three_axis/post_summary.h"

namespace volmap::cli {
namespace {

// --json: what the post did as one document (docs/post.md "What the post
// did"), the summary's numbers.
nlohmann::ordered_json summary_json(const post::PostSummaryInfo& info, const post::PostReport& r) {
  nlohmann::ordered_json flattened = nullptr;
  if (r.read.flattened_from > 0)
    flattened = {{"from_line", r.read.flattened_from},
                 {"source_lines", r.read.flat_source_lines},
                 {"blocks", r.read.flat_blocks},
                 {"written_as_read", r.flattened_written_as_read}};
  nlohmann::ordered_json warnings = nlohmann::ordered_json::array();
  for (const post::PostReport::CycleWarning& w : r.cycle_warnings)
    warnings.push_back({{"file", w.file.empty() ? info.program : w.file},
                        {"line", w.line},
                        {"deviation_um", w.deviation_mm * 1e3}});
  return {
      {"program", info.program},
      {"output", info.output},
      {"tolerance_um", info.tolerance_um},
      {"lines_in", r.lines_in},
      {"lines_out", r.lines_out},
      {"lines_changed", r.lines_changed},
      {"lines_added", r.lines_added},
      {"arcs", {{"kept", r.arcs_kept}, {"cut", r.arcs_split}, {"linearized", r.arcs_linearized}}},
      {"points_corrected", r.points_corrected},
      {"max_correction_um", r.max_correction_mm * 1e3},
      {"max_deviation_um", r.max_deviation_mm * 1e3},
      {"dialect", nc::dialect_name(r.read.dialect.dialect)},
      {"flattened", flattened},
      {"cutter_compensation",
       r.comp_moves == 0 ? nlohmann::ordered_json(nullptr)
                         : nlohmann::ordered_json{{"moves", r.comp_moves},
                                                  {"max_radius_mm", r.comp_radius_mm},
                                                  {"max_bound_um", r.comp_bound_mm * 1e3}}},
      {"cycle_warning_count", r.cycle_warning_count},
      {"cycle_warnings", warnings},
      {"self_check",
       !r.self_checked ? nlohmann::ordered_json(nullptr)
                       : nlohmann::ordered_json{{"points", r.self_check.points},
                                                {"max_deviation_um", r.self_check.max_mm * 1e3}}}};
}

std::string self_check_text(const post::PostReport& r, double tolerance_um) {
  return fmt::format(
      "post: self-check: every written line read back and run on the simulated machine: {} "
      "points, the farthest {:.2f} µm from the nominal path (tolerance {:g} µm)\n",
      r.self_check.points, r.self_check.max_mm * 1e3, tolerance_um);
}

// The five-axis path (postproc/five_axis/five_axis_post.h).
template <typename Opts>
int run_five_axis(const Opts& o, const Machine& m) {
  if (o.errors.empty() && o.table.empty())
    throw std::invalid_argument("post needs --errors or --table");
  post::FiveAxisPostOptions opt;
  opt.form = o.five.form();
  opt.tolerance_mm = o.tolerance_um * 1e-3;
  opt.angle_tolerance_rad = o.five.angle_tolerance_urad * 1e-6;
  opt.decimals = o.decimals;
  opt.angle_decimals = o.five.angle_decimals;
  opt.feed = o.five.feed_output == "per-minute" ? post::FeedOutput::kPerMinute
                                                : post::FeedOutput::kInverseTime;
  opt.initial = o.five.initial(m, o.placement);
  opt.outside = o.clamp ? OutsidePolicy::kClamp : OutsidePolicy::kError;
  opt.correction_iterations = o.five.iterate ? 20 : 1;
  opt.tool_offsets_mm = FiveAxisCliOptions::tool_offsets_mm(o.placement);
  std::ifstream file_in;
  std::istream* in = &std::cin;
  std::string in_name = "<stdin>";
  if (o.in != "-") {
    file_in.open(o.in, std::ios::binary);
    if (!file_in) throw InputError(o.in, 0, "cannot open the program; check the path");
    in = &file_in;
    in_name = o.in;
  }
  AtomicOutput out(o.out, {o.in, o.machine, o.errors.empty() ? o.table : o.errors});
  post::FiveAxisPostReport r;
  if (!o.table.empty()) {
    const maps::VolumetricTable t = maps::load_table(o.table);
    r = post::post_five_axis(*in, in_name, out.stream(), m, t, opt);
  } else {
    r = post::post_five_axis(
        *in, in_name, out.stream(), m,
        load_errors_for(m, o.machine, o.errors, parse_errors_format(o.errors_format),
                        o.other_machine_errors),
        opt);
  }
  out.commit();
  if (isatty(2))
    std::cerr << fmt::format(
        "five-axis ({} input): {} lines, {} moves, {} poses ({} singular), {} lines added, "
        "max correction {:.2f} µm / {:.2f} µrad\n",
        post::input_form_name(r.form), r.lines, r.moves, r.poses, r.singular_poses, r.lines_added,
        r.max_correction_mm * 1e3, r.max_correction_rad * 1e6);
  return 0;
}

// The options of what the three-axis post writes: cycles, arcs, the
// summary as JSON and as a page.
template <typename Opts>
void add_three_axis_output_options(CLI::App& app, Opts& opts) {
  CLI::App* sub = &app;
  Opts* o = &opts;
  sub->add_flag("--expand-cycles", o->expand_cycles,
                "Write canned cycles G73 G81 G82 G83 G85 G89 out as their moves (LinuxCNC's), so "
                "the feed into the hole keeps the tolerance too (three axes)");
  auto* linearize = sub->add_flag(
      "--linearize-arcs", o->linearize_arcs,
      "Write every G2/G3 arc as straight G1 pieces within the tolerance (default: arcs stay arcs, "
      "corrected end point and centre, cut only where the error field or an axis's lost motion "
      "needs it; three axes)");
  sub->add_flag("--keep-arcs", o->keep_arcs,
                "Arcs stay arcs: the default, the flag is kept for scripts that give it")
      ->excludes(linearize);
  sub->add_flag("--json", o->json,
                "Write what the post did (lines in and out, changed, added, arcs kept, largest "
                "correction and predicted deviation) to stdout as one JSON document (three axes)");
  sub->add_flag("--no-self-check", o->no_self_check,
                "Do not read the written program back and check it on the simulated machine "
                "before it is committed (the self-check, on by default; three axes)");
  sub->add_option("--report", o->report,
                  "Write what the post did as a self-contained HTML page: the summary, canned "
                  "cycles whose feed leaves the tolerance, the changed lines as read and as "
                  "written (three axes)");
}

// The options of the three-axis post, refused with a five-axis machine.
template <typename Opts>
void refuse_three_axis_options(const Opts& o) {
  if (o.expand_cycles) throw UsageError("--expand-cycles is for three-axis programs");
  if (o.placement.dialect == "fanuc")
    throw UsageError(
        "--dialect fanuc is for three-axis programs; five-axis programs are read as LinuxCNC "
        "G-code or APT");
  if (o.keep_arcs || o.linearize_arcs)
    throw UsageError("--keep-arcs and --linearize-arcs are for three-axis programs");
  if (o.json || !o.report.empty())
    throw UsageError("--json and --report are for three-axis programs");
}

Runner register_post(CLI::App& app) {
  struct Opts {
    std::string machine, errors, errors_format = "auto", table, in, out;
    ProgramSetupOptions placement;
    FiveAxisCliOptions five;
    double tolerance_um = 1.0;
    int decimals = -1;
    bool clamp = false, expand_cycles = false, keep_arcs = false, linearize_arcs = false;
    bool json = false, other_machine_errors = false, no_self_check = false;
    std::string report;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* sub = app.add_subcommand("post",
                                     "Rewrite an NC program for the real machine (correction of "
                                     "every point, segmented within tolerance)");
  sub->add_option("--machine", o->machine, "Machine definition (JSON)")->required();
  auto* errors = sub->add_option("--errors", o->errors,
                                 "Errors file: errors.md CSV, ISG CSV or Etalon exchange format");
  sub->add_option("--errors-format", o->errors_format,
                  "Format of --errors: auto (default: detected), volmap (errors.md), isg-csv "
                  "(Beckhoff/ISG CSV), etalon (Etalon exchange format, Vendor variant)")
      ->check(CLI::IsMember({"auto", "volmap", "isg-csv", "etalon"}));
  add_other_machine_flag(*sub, o->other_machine_errors);
  auto* table = sub->add_option("--table", o->table,
                                "Compensation table (volmap map) instead of --errors (three-axis: "
                                "the machine file's tool only)");
  errors->excludes(table);
  sub->add_option("--tolerance-um", o->tolerance_um,
                  "Bound on the deviation of the actual path from the nominal one, also between "
                  "points (default 1)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--decimals", o->decimals,
                  "Decimals of rewritten numbers (default 4 in mm, 5 in inch)")
      ->check(CLI::Range(0, 9));
  o->placement.add_to(*sub);
  o->five.add_to(*sub, /*post=*/true);
  sub->add_flag("--clamp", o->clamp,
                "Hold the end value of an error table outside it (default: refuse)");
  add_three_axis_output_options(*sub, *o);
  sub->add_option("IN", o->in, "Input program (- for standard input)")->required();
  sub->add_option("-o,--output", o->out, "Output program (- for standard output)")->required();
  sub->footer(
      "Example:\n  volmap post --machine samples/machines/hsu-3axis.json --errors "
      "samples/errors/hsu-3axis.csv \\\n"
      "      --work-offset 250,200,100 samples/programs/pocket.ngc -o pocket-compensated.ngc\n"
      "  volmap post --machine samples/machines/lei-hsu-xyzac.json --errors "
      "samples/errors/lei-hsu-xyzac.csv \\\n"
      "      samples/programs/cone-vector.ngc -o cone-machine.ngc");
  return [o]() -> int {
    const Machine m = load_machine_json(o->machine);
    if (o->five.applies(m)) {
      refuse_three_axis_options(*o);
      return run_five_axis(*o, o->five.place_part(m));
    }
    if (o->errors.empty() && o->table.empty()) throw UsageError("post needs --errors or --table");
    if (o->json && o->out == "-")
      throw UsageError(
          "--json writes to standard output, where -o - puts the program: give -o a file");
    std::optional<maps::VolumetricTable> table;
    ErrorSet e;
    if (!o->table.empty()) {
      table = maps::load_table(o->table);
      try {
        post::Corrector check(m, *table, OutsidePolicy::kError);
      } catch (const std::invalid_argument& bad) {
        throw InputError(o->table, 0, bad.what());
      }
    } else {
      e = load_errors_for(m, o->machine, o->errors, parse_errors_format(o->errors_format),
                          o->other_machine_errors);
    }
    const nc::ProgramSetup setup = o->placement.load(m);
    post::PostOptions opt;
    opt.tolerance_mm = o->tolerance_um * 1e-3;
    opt.decimals = o->decimals;
    opt.outside = o->clamp ? OutsidePolicy::kClamp : OutsidePolicy::kError;
    opt.expand_cycles = o->expand_cycles;
    opt.keep_arcs = !o->linearize_arcs;
    opt.subroutine_path = o->placement.subroutine_dirs(o->in);
    if (!o->report.empty()) opt.max_recorded_changes = 2000;
    opt.self_check = !o->no_self_check;
    std::ifstream file_in;
    std::istream* in = &std::cin;
    std::string in_name = "<stdin>";
    if (o->in != "-") {
      file_in.open(o->in, std::ios::binary);
      if (!file_in) throw InputError(o->in, 0, "cannot open the program; check the path");
      in = &file_in;
      in_name = o->in;
    }
    std::vector<std::string> inputs{o->in, o->machine, table ? o->table : o->errors};
    if (!o->placement.var_file.empty()) inputs.push_back(o->placement.var_file);
    if (!o->placement.tool_table.empty()) inputs.push_back(o->placement.tool_table);
    // "-": spooled to a temporary file and copied out when complete
    // (core/common/atomic_file.h): constant memory, and nothing on failure.
    AtomicOutput out(o->out, inputs);
    // --report: opened before the work (an output onto an input is refused
    // before anything runs), committed after it.
    std::unique_ptr<AtomicOutput> report;
    if (!o->report.empty()) report = std::make_unique<AtomicOutput>(o->report, inputs);
    const post::PostReport r =
        table ? post::post_program(*in, in_name, out.stream(), m, *table, setup, opt)
              : post::post_program(*in, in_name, out.stream(), m, e, setup, opt);
    const post::PostSummaryInfo info{in_name, o->out, m.name, table ? o->table : o->errors,
                                     o->tolerance_um};
    if (report) report->stream() << post::post_report_html(info, r);
    out.commit();
    if (report) report->commit();
    print_read_notes(in_name, r.read, r.flattened_written_as_read);
    std::cerr << post::post_summary_text(info, r);
    if (r.self_checked) std::cerr << self_check_text(r, o->tolerance_um);
    if (o->json) std::cout << summary_json(info, r).dump(2) << '\n';
    return 0;
  };
}

}  // namespace

static const CommandRegistration kPost(40, register_post);

}  // namespace volmap::cli
