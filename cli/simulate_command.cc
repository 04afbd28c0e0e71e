// volmap simulate: the real machine in software (docs/simulate.md).
#include <fmt/format.h>

#include <iostream>
#include <memory>

#include "cli/commands.h"
#include "cli/parse_util.h"
#include "cli/progress.h"
#include "core/common/atomic_file.h"
#include "core/measure/effects.h"
#include "core/measure/plan.h"
#include "core/measure/recordings.h"
#include "core/measure/simulate.h"
#include "core/model/errors_csv.h"
#include "core/model/gain_evaluator.h"
#include "core/model/machine_json.h"

namespace volmap::cli {
namespace {

Runner register_simulate(CLI::App& app) {
  struct Opts {
    std::string machine, errors, effects, plan, output;
    bool other_machine_errors = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* sub = app.add_subcommand(
      "simulate",
      "Recordings (recordings.md) an instrument would produce running a plan on a machine with "
      "the given geometric errors and effects");
  sub->add_option("--machine", o->machine, "Machine definition (JSON, docs/machine-format.md)")
      ->required();
  sub->add_option("--errors", o->errors, "Component and location errors CSV (errors.md)")
      ->required();
  add_other_machine_flag(*sub, o->other_machine_errors);
  sub->add_option("--effects", o->effects,
                  "Effects beyond the geometric model (JSON volmap-effects/1, docs/simulate.md)");
  sub->add_option("--plan", o->plan, "Measurement plan (JSON volmap-plan/1, docs/simulate.md)")
      ->required();
  sub->add_option("-o,--output", o->output, "Recordings CSV to write ('-' for standard output)")
      ->required();
  sub->footer(
      "Example:\n  volmap simulate --machine samples/machines/lei-hsu-xyzac.json "
      "--errors samples/errors/lei-hsu-xyzac.csv --plan samples/plans/probe-ball.json -o "
      "probe.csv");
  return [o]() -> int {
    std::vector<std::string> inputs{o->machine, o->errors, o->plan};
    if (!o->effects.empty()) inputs.push_back(o->effects);
    refuse_output_equal_to_input(o->output, inputs);
    const Machine m = load_machine_json(o->machine);
    const ErrorModel model(m, load_errors_for(m, o->machine, o->errors, ErrorsFormat::kVolmap,
                                              o->other_machine_errors));
    const Plan plan = load_plan_json(o->plan, m);
    std::unique_ptr<EffectSet> effects;
    if (!o->effects.empty()) {
      const GainEvaluator gains(m, model.options().formulation, model.errors().convention);
      effects = std::make_unique<EffectSet>(load_effects_json(o->effects, m, gains));
    }
    std::map<std::string, std::string> meta{{"machine", o->machine},
                                            {"errors", o->errors},
                                            {"plan", o->plan},
                                            {"instrument", "volmap simulate"}};
    if (effects) meta["effects"] = o->effects;
    TerminalProgress progress("simulate");
    progress.stage(fmt::format("simulating {} targets", plan.points.size()));
    const Recordings r = simulate(model, plan, effects.get(), meta);
    progress.stage("writing " + o->output);
    AtomicOutput out(o->output, inputs);
    write_recordings_csv(out.stream(), r);
    out.commit();
    if (o->output != "-")
      std::cout << "simulate: " << r.size() << " observations written to " << o->output << "\n";
    return 0;
  };
}

}  // namespace

static const CommandRegistration kSimulate(60, register_simulate);

}  // namespace volmap::cli
