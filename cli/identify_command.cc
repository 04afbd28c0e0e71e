// volmap identify: location errors (ISO 230-1 or link) and squareness, optionally
// component-error curves, from recordings (docs/identify.md).
#include <fmt/format.h>

#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <stdexcept>

#include "cli/commands.h"
#include "cli/progress.h"
#include "core/common/atomic_file.h"
#include "core/common/input_error.h"
#include "core/measure/identify.h"
#include "core/measure/recordings.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"

namespace volmap::cli {
namespace {

/// identify(), its messages about a component fit in the command line's
/// terms ("--component EXX:9: ...").
IdentifyResult identify_naming_flags(const Machine& m, const Recordings& rec,
                                     const IdentifyOptions& opt) {
  try {
    return identify(m, rec, opt);
  } catch (const ComponentFitError& e) {
    throw UsageError("--component " + e.detail());
  } catch (const InputError&) {
    throw;  // the recordings' file:line
  } catch (const std::invalid_argument& e) {
    // An option the machine does not take (a --params name that is not one
    // of its errors, nothing left to estimate): a usage error (cli.md).
    throw UsageError(e.what());
  }
}

Runner register_identify(CLI::App& app) {
  struct Opts {
    std::string machine, recordings, output, known, model = "independent", params;
    std::string convention = "iso230-1";
    std::vector<std::string> components;
    bool json = false, setup_offsets = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* sub = app.add_subcommand(
      "identify",
      "Least-squares identification of location and squareness errors (ISO 230-1 meaning, or "
      "link errors), optionally component-error curves, from recordings; writes an errors CSV");
  sub->add_option("--machine", o->machine, "Machine definition (JSON, docs/machine-format.md)")
      ->required();
  sub->add_option("--recordings", o->recordings, "Recordings CSV (recordings.md)")->required();
  sub->add_option("-o,--output", o->output,
                  "Errors CSV to write (errors.md; '-' for standard output)")
      ->required();
  sub->add_option(
      "--known", o->known,
      "Errors CSV held fixed (e.g. laser-measured component errors); copied into the output");
  sub->add_option(
      "--params", o->params,
      "Comma-separated location errors to fit (default: every location error not in --known)");
  sub->add_option(
      "--component", o->components,
      "Fit a component error as a curve: NAME:DEGREE, e.g. EXX:3 (polynomial; Fourier order "
      "for a continuous rotary axis, e.g. ECC:2); repeatable");
  sub->add_flag("--setup-offsets", o->setup_offsets,
                "Fit a constant offset (x, y, z) per run: the ball or instrument setup");
  sub->add_option("--model", o->model, "independent (default) or dependent")
      ->check(CLI::IsMember({"independent", "dependent"}));
  sub->add_option("--convention", o->convention,
                  "Meaning of the location errors written: iso230-1 (default, errors.md) or link "
                  "(Lei & Hsu's link errors); --known must be in the same one")
      ->check(CLI::IsMember({"iso230-1", "link"}));
  sub->add_flag("--json", o->json, "Write the report as one JSON document to stdout");
  sub->footer(
      "Example:\n  volmap identify --machine samples/machines/lei-hsu-xyzac.json "
      "--recordings probe.csv -o identified.csv --json");
  return [o]() -> int {
    std::vector<std::string> inputs{o->machine, o->recordings};
    if (!o->known.empty()) inputs.push_back(o->known);
    refuse_output_equal_to_input(o->output, inputs);
    const Machine m = load_machine_json(o->machine);
    TerminalProgress progress("identify");
    progress.stage("reading " + o->recordings);
    const Recordings rec = load_recordings_csv(o->recordings);
    require_machine_tool_length(rec, m.tool_length_mm, m.name);
    IdentifyOptions opt;
    opt.progress = [&](const std::string& s, std::size_t d, std::size_t t) {
      progress.stage(s, d, t);
    };
    opt.formulation = o->model == "dependent" ? Formulation::kDependent : Formulation::kIndependent;
    opt.setup_offsets = o->setup_offsets;
    opt.convention = *parse_location_convention(o->convention);
    std::string known_text;
    ErrorSet known;
    if (!o->known.empty()) {
      known = load_errors_csv(o->known);
      opt.known = &known;
      std::ifstream in(o->known, std::ios::binary);
      known_text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    for (std::size_t start = 0; !o->params.empty() && start <= o->params.size();) {
      const std::size_t comma = std::min(o->params.find(',', start), o->params.size());
      const std::string name = o->params.substr(start, comma - start);
      if (!name.empty()) opt.parameters.push_back(name);
      start = comma + 1;
    }
    for (const std::string& c : o->components) {
      const std::size_t colon = c.find(':');
      int degree = 0;
      try {
        if (colon == std::string::npos) throw std::invalid_argument("");
        std::size_t used = 0;
        degree = std::stoi(c.substr(colon + 1), &used);
        if (used != c.size() - colon - 1) throw std::invalid_argument("");
      } catch (const std::exception&) {
        throw UsageError(fmt::format("--component {}: expected NAME:DEGREE, e.g. EXX:3", c));
      }
      opt.components.push_back({c.substr(0, colon), degree});
    }
    const IdentifyResult res = identify_naming_flags(m, rec, opt);
    std::map<std::string, std::string> meta{
        {"machine", o->machine},
        {"source", fmt::format("volmap identify from {} ({} observations, rms residual {:.6f} µm)",
                               o->recordings, res.equations, res.rms_after_um)}};
    if (!o->known.empty()) meta["known"] = o->known;
    meta["convention"] = o->convention;
    if (!res.warnings.empty()) meta["warning"] = res.warnings.front();
    AtomicOutput out(o->output, inputs);
    write_identified_errors_csv(out.stream(), res, meta, known_text);
    out.commit();
    // With -o - the errors CSV owns standard output; the report goes to stderr.
    std::ostream& report = o->output == "-" ? std::cerr : std::cout;
    if (o->json) {
      nlohmann::ordered_json doc = identify_report_json(res);
      doc["recordings"] = o->recordings;
      doc["convention"] = o->convention;
      doc["output"] = o->output;
      report << doc.dump(2) << "\n";
      // The JSON carries them; a script that reads only the status sees them here.
      for (const std::string& w : res.warnings) std::cerr << "volmap: warning: " << w << "\n";
    } else {
      report << identify_report_text(res);
      if (o->output != "-") report << "\nWritten: " << o->output << "\n";
    }
    return 0;
  };
}

}  // namespace

static const CommandRegistration kIdentify(61, register_identify);

}  // namespace volmap::cli
