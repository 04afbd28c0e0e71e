// volmap explain: where the model and a recording disagree, the physics the
// model left out, fitted and checked on held-out runs (shared/spec/explain.md,
// docs/explain.md).
#include <iostream>
#include <memory>

#include "cli/commands.h"
#include "cli/message_wording.h"
#include "cli/progress.h"
#include "core/common/atomic_file.h"
#include "core/common/input_error.h"
#include "core/explain/explain.h"
#include "core/measure/recordings.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"

namespace volmap::cli {
namespace {

Runner register_explain(CLI::App& app) {
  struct Opts {
    std::string recordings, machine, baseline, json, report;
    int degree = 0;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* sub = app.add_subcommand("explain",
                                     "Locate where a recording departs from the model, name the "
                                     "physics left out (reversal, thermal drift, "
                                     "cyclic, servo lag, sag, setup shift, rotary errors), fit it "
                                     "and show the held-out fit improve");
  sub->add_option("--recordings", o->recordings,
                  "Recordings CSV (recordings.md; '-' for standard input)")
      ->required();
  sub->add_option(
      "--machine", o->machine,
      "Machine definition (JSON); default: a Cartesian machine with the axes of the recording");
  sub->add_option("--baseline", o->baseline,
                  "Errors CSV that fixes the simulation (errors.md); default: the rigid-body model "
                  "fitted to the "
                  "recording");
  sub->add_option("--json", o->json,
                  "Write the JSON result (volmap-explain/1) to this file ('-': standard output)");
  sub->add_option("--report", o->report,
                  "Write a self-contained HTML report with plots to this file");
  sub->add_option("--degree", o->degree,
                  "Polynomial degree of the fitted component errors of the linear axes (default 0: "
                  "automatic, "
                  "a value per target for an axis with at most 12 targets, else cubic)")
      ->check(CLI::Range(0, 12));
  sub->footer(
      "Example:\n  volmap explain --recordings samples/recordings/reversal.csv "
      "--machine samples/machines/hsu-3axis.json --json explain.json --report explain.html");
  return [o, sub, &app]() -> int {
    std::vector<std::string> inputs{o->recordings};
    if (!o->machine.empty()) inputs.push_back(o->machine);
    if (!o->baseline.empty()) inputs.push_back(o->baseline);
    if (!o->json.empty()) refuse_output_equal_to_input(o->json, inputs);
    if (!o->report.empty()) refuse_output_equal_to_input(o->report, inputs);
    if (!o->json.empty() && o->json == o->report)
      throw UsageError("--json and --report name the same file; give two files");
    TerminalProgress progress("explain");
    progress.stage("reading " + o->recordings);
    const Recordings rec = load_recordings_csv(o->recordings);
    if (rec.size() == 0)
      throw InputError(o->recordings, 0,
                       "no observations (a header and no rows); record some, or check the file");
    const Machine m =
        o->machine.empty() ? cartesian_machine_for(rec) : load_machine_json(o->machine);
    ExplainOptions opt;
    opt.degree = o->degree;
    opt.machine_assumed = o->machine.empty();
    ErrorSet baseline;
    if (!o->baseline.empty()) {
      baseline = load_errors_csv(o->baseline);
      opt.baseline = &baseline;
      opt.baseline_file = o->baseline;
    }
    opt.progress = [&](const std::string& s, std::size_t d, std::size_t t) {
      progress.stage(s, d, t);
    };
    ExplainResult res = explain(m, rec, opt);
    progress.stage("writing");
    // Notes and remedies name options by their fields (`baseline`): the
    // reader of this command's JSON and report types flags.
    for (std::string& note : res.notes) note = flag_wording(note, app, sub);
    for (Confounded& c : res.confounded) c.remedy = flag_wording(c.remedy, app, sub);
    // Both outputs are complete before either is committed.
    std::unique_ptr<AtomicOutput> json_out, html_out;
    if (!o->json.empty()) {
      json_out = std::make_unique<AtomicOutput>(o->json, inputs);
      json_out->stream() << explain_json(res).dump(2) << "\n";
    }
    if (!o->report.empty()) {
      html_out = std::make_unique<AtomicOutput>(o->report, inputs);
      html_out->stream() << explain_html(res);
    }
    if (html_out) html_out->commit();
    if (o->json != "-") std::cout << explain_text(res);
    if (json_out) json_out->commit();
    return 0;
  };
}

}  // namespace

static const CommandRegistration kExplain(62, register_explain);

}  // namespace volmap::cli
