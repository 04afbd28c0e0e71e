// Identification of 30 parameters (13 location errors of the X'Y'ZA'C'
// sample and 17 component-curve terms) from 10 200 probe-ball observations
// (30 600 recorded values ex, ey, ez), Gauss-Newton on the exact model.
// Issue target: < 50 ms on one core.
#include <benchmark/benchmark.h>

#include <sstream>
#include <string>

#include "core/measure/identify.h"
#include "core/measure/plan.h"
#include "core/measure/simulate.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"

namespace {

std::string sample(const std::string& rel) {
  return std::string(VOLMAP_SOURCE_DIR) + "/samples/" + rel;
}

void BM_Identify30From10k(benchmark::State& state) {
  const volmap::Machine m = volmap::load_machine_json(sample("machines/lei-hsu-xyzac.json"));
  const volmap::ErrorModel truth(m, volmap::load_errors_csv(sample("errors/lei-hsu-xyzac.csv")));
  std::istringstream plan_text(R"({"seed": 5, "noise_um": 0.3, "tests": [{"type": "probe_ball",
      "centers_mm": [[40, 0, 0], [0, 30, 80]], "a_deg": {"from": -90, "to": 0, "step": 1.8},
      "c_deg": {"from": 0, "to": 356.4, "step": 3.6}}]})");
  const volmap::Plan plan = volmap::read_plan_json(plan_text, "bench-plan.json", m);
  const volmap::Recordings rec = volmap::simulate(truth, plan, nullptr);
  volmap::IdentifyOptions opt;
  opt.components = {{"EXX", 3}, {"EYY", 3}, {"EZZ", 3}, {"EAA", 2}, {"ECC", 2}, {"EXC", 1}};
  std::size_t params = 0;
  for (auto _ : state) {
    const volmap::IdentifyResult r = volmap::identify(m, rec, opt);
    params = r.parameters.size();
    benchmark::DoNotOptimize(r.rms_after_um);
  }
  state.counters["parameters"] = static_cast<double>(params);
  state.counters["rows"] = static_cast<double>(rec.size());
}
BENCHMARK(BM_Identify30From10k)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
