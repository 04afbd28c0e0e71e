// volmap explain on 100 000 observations (issue #7: under 10 s on this
// machine). Two recordings made in memory by simulate():
//  - LaserX100k: bidirectional X laser runs on the three-axis sample, 100 098
//    readings (ex) in 249 runs, with backlash, a settling drift and a
//    screw-pitch error; fitted rigid-body baseline.
//  - ProbeBall100k: probe-ball test on the X'Y'ZA'C' sample, 35 712 poses x
//    (ex, ey, ez) = 107 136 readings in 16 runs, with a C wobble; fitted
//    baseline (57 identifiable parameters).
#include <benchmark/benchmark.h>

#include <sstream>
#include <string>

#include "core/explain/explain.h"
#include "core/measure/effects.h"
#include "core/measure/plan.h"
#include "core/measure/simulate.h"
#include "core/model/errors_csv.h"
#include "core/model/gain_evaluator.h"
#include "core/model/machine_json.h"

namespace {

std::string sample(const std::string& rel) {
  return std::string(VOLMAP_SOURCE_DIR) + "/samples/" + rel;
}

volmap::Recordings make(const volmap::Machine& m, const std::string& errors,
                        const std::string& plan_json, const std::string& effects_json) {
  const volmap::ErrorModel truth(m, volmap::load_errors_csv(sample(errors)));
  std::istringstream plan_text(plan_json);
  const volmap::Plan plan = volmap::read_plan_json(plan_text, "bench-plan.json", m);
  const volmap::GainEvaluator gains(m, volmap::Formulation::kIndependent);
  std::istringstream fx_text(effects_json);
  const volmap::EffectSet fx = volmap::read_effects_json(fx_text, "bench-effects.json", m, gains);
  volmap::Recordings rec = volmap::simulate(truth, plan, &fx);
  rec.file = "bench.csv";
  return rec;
}

void run(benchmark::State& state, const volmap::Machine& m, const volmap::Recordings& rec) {
  const volmap::ExplainOptions opt;
  std::size_t findings = 0, observations = 0;
  for (auto _ : state) {
    const volmap::ExplainResult r = volmap::explain(m, rec, opt);
    findings = r.findings.size();
    observations = r.observations;
    benchmark::DoNotOptimize(r.final_rms_um);
  }
  state.counters["observations"] = static_cast<double>(observations);
  state.counters["findings"] = static_cast<double>(findings);
}

void BM_ExplainLaserX100k(benchmark::State& state) {
  const volmap::Machine m = volmap::load_machine_json(sample("machines/hsu-3axis.json"));
  const volmap::Recordings rec = make(
      m, "recordings/geometry-3axis.csv",
      R"({"seed": 3, "noise_um": 0.5, "tests": [{"type": "laser", "axis": "X", "from": 0, "to": 500,
          "step": 2.5, "bidirectional": true, "cycles": 249, "at": {"Y": 200, "Z": 150}, "record": ["ex"],
          "dwell_s": 1, "move_s": 1}]})",
      R"({"effects": [{"effect": "reversal", "axis": "X", "value_um": 2.0},
          {"effect": "thermal_drift", "axis": "X", "amplitude_um": 4.0, "tau_s": 20000},
          {"effect": "cyclic", "axis": "X", "period_mm": 16, "amplitude_um": 0.5}]})");
  run(state, m, rec);
}
BENCHMARK(BM_ExplainLaserX100k)->Unit(benchmark::kMillisecond)->Iterations(1);

void BM_ExplainProbeBall100k(benchmark::State& state) {
  const volmap::Machine m = volmap::load_machine_json(sample("machines/lei-hsu-xyzac.json"));
  const volmap::Recordings rec = make(
      m, "recordings/geometry-5axis.csv",
      R"({"seed": 4, "noise_um": 0.3, "tests": [{"type": "probe_ball", "centers_mm": [[40, 0, 0], [0, 30, 80]],
          "a_deg": {"from": -90, "to": 0, "step": 3.0}, "c_deg": {"from": 0, "to": 355, "step": 5},
          "cycles": 8, "record": ["ex", "ey", "ez"]}]})",
      R"({"effects": [{"effect": "rotary_wobble", "axis": "C", "order": 2, "amplitude_urad": 20}]})");
  run(state, m, rec);
}
BENCHMARK(BM_ExplainProbeBall100k)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
