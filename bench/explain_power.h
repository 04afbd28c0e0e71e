// The detection-power benchmark of `volmap explain` (issue #20,
// docs/explain.md "Detection power"): recordings simulated in memory over
// several designs (bidirectional and one-direction sweeps, one and several
// runs, three and five axes, component and projection forms) and noise
// levels, each effect injected at multiples of the smallest amplitude the
// design reveals (explain's own detectable_*, quoted at the injected
// period, time constant or order), and null recordings with no effect.
// Shared by bench/explain_power.cc (the full sweep, the table of
// docs/explain.md) and tests/explain/explain_power_test.cc (the reduced
// form CI runs).
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/common/parallel.h"
#include "core/explain/axis_labels.h"
#include "core/explain/explain.h"
#include "core/measure/effects.h"
#include "core/measure/plan.h"
#include "core/measure/simulate.h"
#include "core/model/error_model.h"
#include "core/model/errors_csv.h"
#include "core/model/gain_evaluator.h"
#include "core/model/machine_json.h"

namespace volmap::power {

/// A test design: a plan (noise and seed filled in per recording) on a
/// machine, with the truth geometry and (fixed) baseline.
struct Design {
  std::string name;
  std::string machine;     ///< samples/ path
  std::string tests_json;  ///< the plan's "tests" array (and "temperature" if any)
  double step_mm = 25;     ///< target spacing of the swept axis (for the cyclic period)
  bool fixed_baseline = false;
};

/// An effect to inject: the effects-file entry with "AMP" for the amplitude,
/// the candidate key explain tests it under, the nonlinear parameter its
/// detectable size is quoted at, the parameter a finding reports it by.
struct Effect {
  std::string name;
  std::string entry;  ///< JSON object, AMP replaced by the amplitude
  std::string key;    ///< candidate key
  std::optional<double> theta;
  std::string parameter;       ///< the finding's parameter that estimates AMP
  std::string truth_location;  ///< a location error carried by the truth instead (squareness)
  double period_spacings = 0;  ///< cyclic period, spike length: in target spacings of the design
};

struct Cell {
  const Design* design;
  const Effect* effect;  ///< null: a null recording
  double noise_um;
};

/// One recording's outcome.
struct Outcome {
  bool detected = false;             ///< a finding of the injected effect and axis
  bool same_form = false;            ///< reported in the injected form (settling, not rate)
  bool within_3se = false;           ///< its parameter within 3 standard errors of the truth
  int other_findings = 0;            ///< findings of anything else
  std::optional<double> detectable;  ///< the candidate's detectable size (null recordings)
};

inline std::string sample(const std::string& rel) {
  return std::string(VOLMAP_SOURCE_DIR) + "/samples/" + rel;
}

inline std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size()))
    s.replace(p, from.size(), to);
  return s;
}

/// The designs of the sweep.
inline std::vector<Design> designs() {
  const std::string at = R"("at": {"Y": 200, "Z": 150})";
  return {
      {"X laser, bidirectional, 4 runs, ex", "machines/hsu-3axis.json",
       R"("tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 25,
          "bidirectional": true, "cycles": 4, )" +
           at + R"(, "record": ["ex"], "dwell_s": 6, "move_s": 2}])",
       25},
      {"X laser, bidirectional, 3 runs, ex ey ez", "machines/hsu-3axis.json",
       R"("tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 20,
          "bidirectional": true, "cycles": 3, )" +
           at + R"(, "record": ["ex", "ey", "ez"], "dwell_s": 6, "move_s": 2}])",
       20},
      {"X laser, one direction, 5 runs, ex", "machines/hsu-3axis.json",
       R"("tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 25,
          "cycles": 5, )" +
           at + R"(, "record": ["ex"], "dwell_s": 6, "move_s": 2}])",
       25},
      {"X laser, bidirectional, 1 run, ex", "machines/hsu-3axis.json",
       R"("tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 10,
          "bidirectional": true, "cycles": 1, )" +
           at + R"(, "record": ["ex"], "dwell_s": 6, "move_s": 2}])",
       10},
      {"X laser, bidirectional, 4 runs, beam (projection)", "machines/hsu-3axis.json",
       R"("tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 25,
          "bidirectional": true, "cycles": 4, )" +
           at + R"(, "beam": [1, 0, 0], "dwell_s": 6, "move_s": 2}])",
       25},
      {"X laser, bidirectional, 3 feeds x 2 runs, ex", "machines/hsu-3axis.json",
       R"("tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 25,
          "bidirectional": true, "cycles": 2, "feed_mm_min": [1000, 4000, 8000], )" +
           at + R"(, "record": ["ex"], "dwell_s": 1}])",
       25},
      {"X laser, bidirectional, 4 runs, screw sensor", "machines/hsu-3axis.json",
       R"("temperature": {"sensor": "x_screw", "start_c": 20.2, "rise_c": 0.8, "tau_s": 500, "rate_c_per_h": 1.0},
          "tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500, "step": 25,
          "bidirectional": true, "cycles": 4, )" +
           at + R"(, "record": ["ex"], "dwell_s": 10, "move_s": 2}])",
       25},
      {"XY grid, 3 runs, ex ey ez, fixed baseline", "machines/hsu-3axis.json",
       R"("tests": [{"type": "grid", "axes": {"X": {"from": 0, "to": 500, "step": 50},
          "Y": {"from": 0, "to": 400, "step": 100}, "Z": 150}, "cycles": 3,
          "record": ["ex", "ey", "ez"], "dwell_s": 2, "move_s": 2}])",
       50, true},
      {"probe ball, five-axis, 2 runs", "machines/lei-hsu-xyzac.json",
       R"("tests": [{"type": "probe_ball", "centers_mm": [[40, 0, 0], [0, 30, 80]],
          "a_deg": {"from": -90, "to": 0, "step": 30}, "c_deg": {"from": 0, "to": 345, "step": 15},
          "cycles": 2, "record": ["ex", "ey", "ez"], "dwell_s": 2, "move_s": 3}])",
       0},
      {"XY circle (ballbar), r 100 mm, 2000 mm/min, both directions, 2 cycles, fixed baseline",
       "machines/hsu-3axis.json",
       R"("tests": [{"type": "circular", "plane": "XY", "center": {"X": 250, "Y": 200, "Z": 150},
          "radius_mm": 100, "feed_mm_min": 2000, "cycles": 2}])",
       100 * std::numbers::pi / 180, true},
  };
}

/// The effects, each with the designs that can reveal it (by index into designs()).
struct EffectOnDesigns {
  Effect effect;
  std::vector<int> designs;
};

inline std::vector<EffectOnDesigns> effects() {
  return {
      {{"reversal X", R"({"effect": "reversal", "axis": "X", "value_um": AMP})", "reversal/X/",
        std::nullopt, "value_um", ""},
       {0, 1, 3, 4, 9}},
      {{"thermal drift X, settling 300 s",
        R"({"effect": "thermal_drift", "axis": "X", "kind": "offset", "amplitude_um": AMP, "tau_s": 300})",
        "thermal_drift/X/offset/settling", 300.0, "amplitude_um", ""},
       {0, 1, 4}},
      {{"thermal drift X, rate",
        R"({"effect": "thermal_drift", "axis": "X", "kind": "offset", "rate_um_per_h": AMP})",
        "thermal_drift/X/offset/rate", std::nullopt, "rate_um_per_h", ""},
       {0, 3}},
      {{"cyclic X, 4.7 target spacings",
        R"({"effect": "cyclic", "axis": "X", "period_mm": PERIOD, "amplitude_um": AMP, "phase_deg": 40})",
        "cyclic/X/", std::nullopt, "amplitude_um", "", 4.7},
       {0, 1, 3, 4}},
      {{"servo lag X", R"({"effect": "servo_lag", "axis": "X", "um_per_m_min": AMP})",
        "servo_lag/X/", std::nullopt, "um_per_m_min", ""},
       {5}},
      {{"setup shift X, run 2", R"({"effect": "setup_shift", "axis": "X", "per_run_um": [0, AMP]})",
        "setup_shift/X/", std::nullopt, "", ""},
       {0, 2}},
      {{"thermal drift X, um per K of the screw",
        R"({"effect": "thermal_drift", "axis": "X", "kind": "scale", "um_per_k": AMP, "sensor": "x_screw"})",
        "thermal_drift/X/scale/temp_x_screw_c", std::nullopt, "um_per_k", ""},
       {6}},
      {{"sag Z from X",
        R"({"effect": "sag", "axis": "Z", "input_axis": "X", "coefficient": -AMP, "power": 2, "origin": 250})",
        "sag/Z/X", std::nullopt, "", ""},
       {7}},
      {{"squareness EC0X missing from the baseline", "", "squareness/X/EC0X", std::nullopt,
        "value_urad", "EC0X"},
       {7}},
      {{"rotary wobble C, order 2",
        R"({"effect": "rotary_wobble", "axis": "C", "order": 2, "amplitude_urad": AMP, "phase_deg": 30})",
        "rotary_wobble/C/", 2.0, "amplitude_urad", ""},
       {8}},
      {{"reversal spike X, 1.5 target spacings",
        R"({"effect": "reversal", "axis": "X", "kind": "spike", "value_um": AMP, "length_mm": PERIOD})",
        "reversal/X/spike", std::nullopt, "value_um", "", 1.5},
       {3, 9}},
      {{"lateral play, Y with the direction of X",
        R"({"effect": "reversal", "axis": "Y", "kind": "lateral", "input_axis": "X", "value_um": AMP})",
        "reversal/Y/lateral/X", std::nullopt, "value_um", ""},
       {1, 9}},
      {{"rotary positioning C, order 3",
        R"({"effect": "rotary_positioning", "axis": "C", "order": 3, "amplitude_urad": AMP, "phase_deg": -20})",
        "rotary_positioning/C/", 3.0, "amplitude_urad", ""},
       {8}},
  };
}

/// The nonlinear parameter of an effect on a design (the cyclic period in
/// target spacings: 4.7, never a multiple of the spacing; a spike's decay
/// length: 1.5 spacings).
inline std::optional<double> theta_of(const Effect& e, const Design& d) {
  if (e.period_spacings > 0) return e.period_spacings * d.step_mm;
  return e.theta;
}

/// What one recording of a cell gives: simulated with `amplitude` of the
/// effect (0 or no effect: a null recording), explained.
class Runner {
 public:
  Outcome run(const Cell& cell, double amplitude, int seed) const {
    const Design& d = *cell.design;
    const Machine m = load_machine_json(sample(d.machine));
    ErrorSet truth_errors = load_errors_csv(sample(geometry_of(d)));
    ErrorSet baseline = truth_errors;
    const Effect* e = cell.effect;
    std::string fx_json = R"({"format": "volmap-effects/1", "effects": []})";
    if (e && !e->truth_location.empty()) {
      truth_errors.location[e->truth_location] = amplitude * 1e-6;  // urad
      baseline.location.erase(e->truth_location);
    } else if (e && amplitude != 0) {
      std::string entry = replace_all(e->entry, "AMP", fmt::format("{:.9g}", amplitude));
      entry = replace_all(entry, "PERIOD", fmt::format("{:.9g}", theta_of(*e, d).value_or(0)));
      fx_json = R"({"format": "volmap-effects/1", "effects": [)" + entry + "]}";
    }
    const std::string plan_json =
        fmt::format(R"({{"format": "volmap-plan/1", "seed": {}, "noise_um": {}, {}}})", seed,
                    cell.noise_um, d.tests_json);
    std::istringstream plan_text(plan_json);
    const Plan plan = read_plan_json(plan_text, "power-plan.json", m);
    const GainEvaluator gains(m, Formulation::kIndependent);
    std::istringstream fx_text(fx_json);
    const EffectSet fx = read_effects_json(fx_text, "power-effects.json", m, gains);
    Recordings rec = simulate(ErrorModel(m, truth_errors), plan, &fx);
    rec.file = "power.csv";
    ExplainOptions opt;
    if (d.fixed_baseline) opt.baseline = &baseline;
    if (e && theta_of(*e, d)) opt.detectable_at[e->key] = *theta_of(*e, d);
    const ExplainResult r = explain(m, rec, opt);
    return outcome(r, e, amplitude);
  }

 private:
  static std::string geometry_of(const Design& d) {
    return d.machine.find("xyzac") != std::string::npos ? "recordings/geometry-5axis.csv"
                                                        : "recordings/geometry-3axis.csv";
  }

  static std::string key_of(const CandidateResult& c) {
    return c.effect + "/" + (c.axis ? explanation::axis_letter(*c.axis) : "-") + "/" + c.variant;
  }

  static Outcome outcome(const ExplainResult& r, const Effect* e, double amplitude) {
    Outcome o;
    const std::string effect_name = e ? e->key.substr(0, e->key.find('/')) : "";
    const std::string axis = e ? e->key.substr(e->key.find('/') + 1, 1) : "";
    const std::string variant = e ? e->key.substr(e->key.find('/', e->key.find('/') + 1) + 1) : "";
    for (const Finding& f : r.findings) {
      const bool same = e && f.effect == effect_name && f.axis &&
                        explanation::axis_letter(*f.axis) == axis &&
                        (effect_name != "reversal" || reversal_form(f) == variant);
      if (!same) {
        ++o.other_findings;
        continue;
      }
      o.detected = true;
      o.same_form = e->parameter.empty() ||
                    std::any_of(f.parameters.begin(), f.parameters.end(),
                                [&](const auto& p) { return p.first == e->parameter; });
      o.within_3se = o.same_form && within_3se(f, *e, amplitude);
    }
    if (e)
      for (const CandidateResult& c : r.candidates)
        if (key_of(c) == e->key) o.detectable = c.detectable;
    return o;
  }

  /// A reversal finding's form as its candidate's variant: "" (a step),
  /// "spike", "lateral/J".
  static std::string reversal_form(const Finding& f) {
    std::string kind, input;
    for (const auto& [k, v] : f.parameters) {
      if (k == "kind") kind = v.get<std::string>();
      if (k == "input_axis") input = v.get<std::string>();
    }
    return kind == "lateral" ? "lateral/" + input : kind;
  }

  static bool within_3se(const Finding& f, const Effect& e, double amplitude) {
    if (e.parameter.empty()) {
      // sag: the coefficient (sign as injected); setup shift: run 2's offset
      if (f.effect == "sag") return near(f, "coefficient", -amplitude);
      for (const auto& [k, v] : f.parameters)
        if (k == "per_run_um" && v.size() >= 2)
          for (const auto& [sk, se] : f.std_errors)
            if (sk == "per_run_um/1") return std::abs(v[1].get<double>() - amplitude) <= 3 * se;
      return false;
    }
    return near(f, e.parameter, amplitude);
  }

  static bool near(const Finding& f, const std::string& name, double truth) {
    std::optional<double> value, se;
    for (const auto& [k, v] : f.parameters)
      if (k == name && v.is_number()) value = v.get<double>();
    for (const auto& [k, s] : f.std_errors)
      if (k == name) se = s;
    return value && se && std::abs(*value - truth) <= 3 * *se;
  }
};

}  // namespace volmap::power
