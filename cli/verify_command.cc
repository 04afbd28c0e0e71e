// volmap verify: nominal and compensated programs on the simulated machine.
#include <fmt/format.h>

#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/five_axis_options.h"
#include "cli/option_checks.h"
#include "cli/parse_util.h"
#include "cli/program_setup.h"
#include "cli/progress.h"
#include "core/common/atomic_file.h"
#include "core/common/input_error.h"
#include "core/model/errors_csv.h"
#include "core/model/errors_import.h"
#include "core/model/machine_json.h"
#include "postproc/five_axis/five_axis_verify.h"
#include "postproc/verify/verify.h"
#include "postproc/verify/verify_report.h"

namespace volmap::cli {
namespace {

// --report: opened before the work (an output onto an input is refused
// before anything runs), committed after it.
template <typename Opts>
std::unique_ptr<AtomicOutput> open_report(const Opts& o) {
  if (o.report.empty()) return nullptr;
  return std::make_unique<AtomicOutput>(
      o.report, std::vector<std::string>{o.machine, o.errors, o.nominal, o.program});
}

template <typename Stats>
post::VerifyReportRun report_run(const char* label, const std::string& program, const Stats& s) {
  post::VerifyReportRun r;
  r.label = label;
  r.program = program;
  r.max_um = s.max_um;
  r.rms_um = s.rms_um;
  if constexpr (requires { s.max_urad; }) {
    r.max_urad = s.max_urad;
    r.rms_urad = s.rms_urad;
  }
  r.samples = s.samples;
  r.worst_line = s.worst_line;
  r.profile = &s.profile;
  return r;
}

template <typename Opts, typename Result>
void write_report(AtomicOutput* report, const Opts& o, const Machine& m, const Result& r,
                  bool five_axis) {
  if (!report) return;
  post::VerifyReportInfo info{m.name, o.errors, five_axis};
  report->stream() << post::verify_report_html(info, report_run("before", o.nominal, r.before),
                                               report_run("after", o.program, r.after));
  report->commit();
}

// cli.md: with --tolerance-um T, exit status 3 and one line on stderr when
// the actual path of the compensated program leaves T; without it, a
// warning on stderr whenever the compensated program deviates more than the
// nominal one (a post and a verify given different machines, errors or
// placements is the usual cause). Runs after the results are written.
template <typename Opts, typename Stats>
int verdict(const Opts& o, const Stats& before, const Stats& after) {
  if (o.tolerance_um > 0) {
    if (!(after.max_um > o.tolerance_um)) return 0;
    std::cerr << fmt::format(
        "volmap: {}: the actual tool path leaves the tolerance: max {:.3f} µm from the nominal "
        "path (at line {}), more than --tolerance-um {:g}\n",
        o.program, after.max_um, after.worst_line, o.tolerance_um);
    return 3;
  }
  if (after.max_um > before.max_um)
    std::cerr << fmt::format(
        "volmap: warning: {} deviates more from the nominal path than the uncompensated {} "
        "({:.3f} µm against {:.3f} µm): were post and verify given the same machine, errors and "
        "placement (--work-offset, --part-origin)?\n",
        o.program, o.nominal, after.max_um, before.max_um);
  return 0;
}

// Five axes: tip deviation (um) and tool-axis deviation (urad), before and
// after (postproc/five_axis/five_axis_verify.h).
template <typename Opts>
int run_five_axis(const Opts& o, const Machine& m, const ErrorSet& e) {
  const std::unique_ptr<AtomicOutput> report = open_report(o);
  std::ifstream a(o.nominal, std::ios::binary), b(o.program, std::ios::binary);
  if (!a) throw InputError(o.nominal, 0, "cannot open the nominal program; check the path");
  if (!b) throw InputError(o.program, 0, "cannot open the compensated program; check the path");
  post::FiveAxisVerifyOptions opt;
  opt.form = o.five.form();
  opt.sample_step_mm = o.step_mm;
  opt.initial = o.five.initial(m, o.placement);
  opt.outside = o.clamp ? OutsidePolicy::kClamp : OutsidePolicy::kError;
  opt.tool_offsets_mm = FiveAxisCliOptions::tool_offsets_mm(o.placement);
  post::FiveAxisVerifyResult r;
  {
    TerminalProgress progress("verify");
    opt.progress = [&](const std::string& p, std::size_t d, std::size_t t) { progress(p, d, t); };
    r = post::verify_five_axis(a, o.nominal, b, o.program, m, e, opt);
  }
  write_report(report.get(), o, m, r, true);
  if (o.json) {
    nlohmann::ordered_json doc;
    auto stats = [](const post::FiveAxisDeviation& s) {
      return nlohmann::ordered_json{{"max_um", s.max_um},
                                    {"rms_um", s.rms_um},
                                    {"max_urad", s.max_urad},
                                    {"rms_urad", s.rms_urad},
                                    {"samples", s.samples},
                                    {"worst_line", s.worst_line},
                                    {"worst_angle_line", s.worst_angle_line}};
    };
    doc["before"] = stats(r.before);
    doc["after"] = stats(r.after);
    std::cout << doc.dump(2) << "\n";
    return verdict(o, r.before, r.after);
  }
  std::cout << fmt::format(
      "deviation of the actual tool pose from the nominal path (five axes, feed moves)\n"
      "  before (nominal program, ideal TCP, uncompensated): tip max {:8.3f} µm rms {:8.3f} µm, "
      "axis max {:8.2f} µrad rms {:8.2f} µrad ({} samples, worst at line {})\n"
      "  after  (compensated machine-axis program):          tip max {:8.3f} µm rms {:8.3f} µm, "
      "axis max {:8.2f} µrad rms {:8.2f} µrad ({} samples, worst at line {})\n",
      r.before.max_um, r.before.rms_um, r.before.max_urad, r.before.rms_urad, r.before.samples,
      r.before.worst_line, r.after.max_um, r.after.rms_um, r.after.max_urad, r.after.rms_urad,
      r.after.samples, r.after.worst_line);
  return verdict(o, r.before, r.after);
}

Runner register_verify(CLI::App& app) {
  struct Opts {
    std::string machine, errors, errors_format = "auto", nominal, program, report;
    ProgramSetupOptions placement;
    FiveAxisCliOptions five;
    double step_mm = 0.25;
    double tolerance_um = 0.0;  ///< 0: not given
    bool json = false, clamp = false, other_machine_errors = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* sub =
      app.add_subcommand("verify",
                         "Run a nominal program (uncompensated) and its compensated version on the "
                         "simulated real machine; report the deviation of the actual tool path");
  sub->add_option("--machine", o->machine, "Machine definition (JSON)")->required();
  sub->add_option("--errors", o->errors,
                  "Errors file: errors.md CSV, ISG CSV or Etalon exchange format")
      ->required();
  add_other_machine_flag(*sub, o->other_machine_errors);
  sub->add_option("--errors-format", o->errors_format,
                  "Format of --errors: auto (default: detected), volmap (errors.md), isg-csv "
                  "(Beckhoff/ISG CSV), etalon (Etalon exchange format, Vendor variant)")
      ->check(CLI::IsMember({"auto", "volmap", "isg-csv", "etalon"}));
  sub->add_option("--nominal", o->nominal, "The program as written for the ideal machine")
      ->required();
  sub->add_option("--program", o->program, "The compensated program (volmap post)")->required();
  o->placement.add_to(*sub);
  o->five.add_to(*sub, /*post=*/false);
  sub->add_option(
         "--sample-step-mm", o->step_mm,
         "Largest distance between samples along a move (default 0.25; at least 8 per move)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--clamp", o->clamp,
                "Hold the end value of an error table outside it (default: refuse)");
  sub->add_option("--tolerance-um", o->tolerance_um,
                  "Exit with status 3 (one line on stderr) when the compensated program's actual "
                  "tool path is farther than this from the nominal path (µm; the tip on five "
                  "axes). Without it, a warning when it is farther than the uncompensated one")
      ->check(kFinitePositive);
  sub->add_flag("--json", o->json, "Write one JSON document to stdout");
  sub->add_option("--report", o->report,
                  "Also write a self-contained HTML page: the deviation along the whole path "
                  "before and after, the worst lines");
  sub->footer(
      "Example:\n  volmap verify --machine samples/machines/hsu-3axis.json --errors "
      "samples/errors/hsu-3axis.csv \\\n"
      "      --work-offset 250,200,100 --nominal samples/programs/pocket.ngc \\\n"
      "      --program pocket-compensated.ngc --tolerance-um 1 --json --report verify.html\n"
      "  volmap verify --machine samples/machines/lei-hsu-xyzac.json --errors "
      "samples/errors/lei-hsu-xyzac.csv \\\n"
      "      --nominal samples/programs/cone-vector.ngc --program cone-machine.ngc\n"
      "(the same machine, errors and placement as the post that wrote the program)");
  return [o]() -> int {
    const Machine m = load_machine_json(o->machine);
    const ErrorSet e = load_errors_for(
        m, o->machine, o->errors, parse_errors_format(o->errors_format), o->other_machine_errors);
    if (o->five.applies(m)) return run_five_axis(*o, o->five.place_part(m), e);
    const nc::ProgramSetup setup = o->placement.load(m);
    const std::unique_ptr<AtomicOutput> report = open_report(*o);
    std::ifstream a(o->nominal, std::ios::binary), b(o->program, std::ios::binary);
    if (!a) throw InputError(o->nominal, 0, "cannot open the nominal program; check the path");
    if (!b) throw InputError(o->program, 0, "cannot open the compensated program; check the path");
    post::VerifyOptions opt;
    opt.sample_step_mm = o->step_mm;
    opt.outside = o->clamp ? OutsidePolicy::kClamp : OutsidePolicy::kError;
    opt.subroutine_path = o->placement.subroutine_dirs(o->nominal);
    post::VerifyResult r;
    {
      TerminalProgress progress("verify");
      opt.progress = [&](const std::string& p, std::size_t d, std::size_t t) { progress(p, d, t); };
      r = post::verify_programs(a, o->nominal, b, o->program, m, e, setup, opt);
    }
    write_report(report.get(), *o, m, r, false);
    if (r.comp_radius_mm > 0)
      std::cerr << fmt::format(
          "note: the programs keep cutter compensation (G41/G42, tool radius up to {:g} mm): "
          "verify measures their programmed contours; the controller offsets them by the "
          "radius, which adds at most the bound `volmap post` checked (a quarter of its "
          "tolerance; docs/post.md)\n",
          r.comp_radius_mm);
    if (o->json) {
      nlohmann::ordered_json doc;
      auto stats = [](const post::DeviationStats& s) {
        return nlohmann::ordered_json{{"max_um", s.max_um},
                                      {"rms_um", s.rms_um},
                                      {"samples", s.samples},
                                      {"worst_line", s.worst_line}};
      };
      doc["before"] = stats(r.before);
      doc["after"] = stats(r.after);
      if (r.comp_radius_mm > 0) doc["cutter_compensation_radius_mm"] = r.comp_radius_mm;
      std::cout << doc.dump(2) << "\n";
      return verdict(*o, r.before, r.after);
    }
    std::cout << fmt::format(
        "deviation of the actual tool path from the nominal one (feed moves)\n"
        "  before (nominal program, uncompensated): max {:8.3f} µm  rms {:8.3f} µm  ({} samples, "
        "worst at line {})\n"
        "  after  (compensated program):           max {:8.3f} µm  rms {:8.3f} µm  ({} samples, "
        "worst at line {})\n",
        r.before.max_um, r.before.rms_um, r.before.samples, r.before.worst_line, r.after.max_um,
        r.after.rms_um, r.after.samples, r.after.worst_line);
    return verdict(*o, r.before, r.after);
  };
}

}  // namespace

static const CommandRegistration kVerify(50, register_verify);

}  // namespace volmap::cli
