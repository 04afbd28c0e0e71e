// Backward transformation + correction per tool pose (issue target: >= 2 M
// poses/s on one core, <= 500 ns per pose) on the X'Y'ZA'C' sample with its
// sample errors; and the parts: backward alone, the Jacobian, the one-step
// and the iterated correction, and the B-C table-table sample. The pipeline
// hands the Jacobian from placing the tip (backward_selected) to correct(),
// as a post-processor does: one walk over the chains per pose, not two.
#include <benchmark/benchmark.h>

#include <random>
#include <string>
#include <vector>

#include "core/kinematics/correction.h"
#include "core/kinematics/jacobian.h"
#include "core/kinematics/kinematics.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"

namespace {

std::string sample(const std::string& rel) {
  return std::string(VOLMAP_SOURCE_DIR) + "/samples/" + rel;
}

struct Case {
  volmap::AxisVector u;  // also the previous position
  volmap::ToolPose v;
};

// Random axis positions within travel (1% inside, so that corrected
// positions stay within the error tables) and their tool poses.
std::vector<Case> cases(const volmap::Machine& m, int n) {
  std::mt19937 rng(1);
  std::vector<Case> out;
  for (int k = 0; k < n; ++k) {
    volmap::AxisVector u(m.axis_count());
    for (int i = 0; i < m.axis_count(); ++i) {
      const auto& L = m.limits[static_cast<size_t>(i)];
      const double pad = L.unlimited ? 0 : 0.01 * (L.max - L.min);
      std::uniform_real_distribution<double> d(L.unlimited ? 0 : L.min + pad,
                                               L.unlimited ? 6.28 : L.max - pad);
      u[i] = d(rng);
    }
    out.push_back({u, volmap::nominal_forward(m, u)});
  }
  return out;
}

volmap::ErrorSet errors_for(const std::string& name) {
  if (name == "lei-hsu-xyzac") return volmap::load_errors_csv(sample("errors/lei-hsu-xyzac.csv"));
  volmap::ErrorSet e;  // bc-table-table has no sample errors: location errors only
  e.location = {{"EX0C", 0.02},  {"EY0C", -0.015}, {"EA0C", 40e-6}, {"EB0C", -30e-6},
                {"EX0B", 0.025}, {"EZ0B", -0.01},  {"EA0B", 25e-6}, {"EC0B", 50e-6}};
  return e;
}

void BM_BackwardAndCorrection(benchmark::State& state, const char* name) {
  const volmap::Machine m =
      volmap::load_machine_json(sample(std::string("machines/") + name + ".json"));
  const volmap::ErrorModel model(m, errors_for(name));
  const volmap::CorrectionSolver solver(model);
  const volmap::Kinematics& kin = solver.kinematics();
  const auto cs = cases(m, 1024);
  size_t k = 0;
  for (auto _ : state) {
    const Case& c = cs[k++ & 1023];
    volmap::PoseJacobian J;
    const volmap::AxisVector u = kin.backward_selected(c.v, c.u, nullptr, &J);
    const volmap::CorrectionResult r = solver.correct(u, {}, J);
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations());
}

// The same with every solution placed (backward(), then select()).
void BM_AllSolutionsAndCorrection(benchmark::State& state) {
  const volmap::Machine m = volmap::load_machine_json(sample("machines/lei-hsu-xyzac.json"));
  const volmap::ErrorModel model(m, errors_for("lei-hsu-xyzac"));
  const volmap::CorrectionSolver solver(model);
  const volmap::Kinematics& kin = solver.kinematics();
  const auto cs = cases(m, 1024);
  size_t k = 0;
  for (auto _ : state) {
    const Case& c = cs[k++ & 1023];
    const volmap::BackwardSolutions s = kin.backward(c.v, c.u);
    const int sel = kin.select(s, c.u);
    const volmap::CorrectionResult r = solver.correct(s.u[static_cast<size_t>(sel)]);
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_Backward(benchmark::State& state) {
  const volmap::Kinematics kin(volmap::load_machine_json(sample("machines/lei-hsu-xyzac.json")));
  const auto cs = cases(kin.machine(), 1024);
  size_t k = 0;
  for (auto _ : state) {
    const Case& c = cs[k++ & 1023];
    volmap::BackwardSolutions s = kin.backward(c.v, c.u);
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_Jacobian(benchmark::State& state) {
  const volmap::Machine m = volmap::load_machine_json(sample("machines/lei-hsu-xyzac.json"));
  const auto cs = cases(m, 1024);
  size_t k = 0;
  volmap::PoseJacobian J;
  for (auto _ : state) {
    volmap::ToolPose v = volmap::nominal_forward_jacobian(m, cs[k++ & 1023].u, J);
    benchmark::DoNotOptimize(v);
    benchmark::DoNotOptimize(J);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_Correction(benchmark::State& state) {
  const volmap::Machine m = volmap::load_machine_json(sample("machines/lei-hsu-xyzac.json"));
  const volmap::ErrorModel model(m, errors_for("lei-hsu-xyzac"));
  volmap::CorrectionOptions o;
  o.max_iterations = static_cast<int>(state.range(0));
  const volmap::CorrectionSolver solver(model, o);
  const auto cs = cases(m, 1024);
  size_t k = 0;
  for (auto _ : state) {
    volmap::CorrectionResult r = solver.correct(cs[k++ & 1023].u);
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK_CAPTURE(BM_BackwardAndCorrection, five_axis, "lei-hsu-xyzac");
BENCHMARK_CAPTURE(BM_BackwardAndCorrection, bc_table_table, "bc-table-table");
BENCHMARK(BM_AllSolutionsAndCorrection);
BENCHMARK(BM_Backward);
BENCHMARK(BM_Jacobian);
BENCHMARK(BM_Correction)->Arg(1)->Arg(20)->ArgName("max_iterations");

}  // namespace

BENCHMARK_MAIN();
