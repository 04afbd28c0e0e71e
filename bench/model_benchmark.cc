// The exact five-axis model at one axis position, every component error
// interpolated (issue target: <= 200 ns on one core), and the three-axis
// model and the first-order form beside it.
#include <benchmark/benchmark.h>

#include <array>
#include <random>
#include <vector>

#include "core/model/error_model.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"

namespace {

std::string sample(const std::string& rel) {
  return std::string(VOLMAP_SOURCE_DIR) + "/samples/" + rel;
}

std::vector<volmap::AxisVector> poses(const volmap::Machine& m, int n) {
  std::mt19937 rng(1);
  std::vector<volmap::AxisVector> out;
  for (int k = 0; k < n; ++k) {
    volmap::AxisVector u(m.axis_count());
    for (int i = 0; i < m.axis_count(); ++i) {
      const auto& L = m.limits[static_cast<size_t>(i)];
      std::uniform_real_distribution<double> d(L.unlimited ? 0 : L.min, L.unlimited ? 6.28 : L.max);
      u[i] = d(rng);
    }
    out.push_back(u);
  }
  return out;
}

template <bool kExact>
void BM_Model(benchmark::State& state, const char* name) {
  const volmap::Machine m =
      volmap::load_machine_json(sample(std::string("machines/") + name + ".json"));
  const volmap::ErrorModel model(
      m, volmap::load_errors_csv(sample(std::string("errors/") + name + ".csv")));
  const auto us = poses(m, 1024);
  size_t k = 0;
  for (auto _ : state) {
    const auto& u = us[k++ & 1023];
    volmap::PoseError e = kExact ? model.exact(u) : model.first_order(u);
    benchmark::DoNotOptimize(e);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_ExactModel(benchmark::State& s, const char* name) { BM_Model<true>(s, name); }
void BM_FirstOrderModel(benchmark::State& s, const char* name) { BM_Model<false>(s, name); }
BENCHMARK_CAPTURE(BM_ExactModel, five_axis, "lei-hsu-xyzac");
BENCHMARK_CAPTURE(BM_ExactModel, three_axis, "hsu-3axis");
BENCHMARK_CAPTURE(BM_FirstOrderModel, five_axis, "lei-hsu-xyzac");

// The three-axis post-processor's hot path: the tool tip error of an
// all-linear machine, once per NC line, positions inside the travel and
// approach directions varying (+1, -1, 0) as along a program.
void BM_TipErrorLinear(benchmark::State& state, const char* name) {
  const volmap::Machine m =
      volmap::load_machine_json(sample(std::string("machines/") + name + ".json"));
  const volmap::ErrorModel model(
      m, volmap::load_errors_csv(sample(std::string("errors/") + name + ".csv")));
  const auto us = poses(m, 1024);
  std::mt19937 rng(2);
  std::uniform_int_distribution<int> die(-1, 1);
  std::vector<std::array<double, 3>> u3(1024);
  std::vector<volmap::ApproachDirections> dirs(1024);
  for (size_t k = 0; k < 1024; ++k) {
    for (int i = 0; i < 3; ++i) {
      u3[k][static_cast<size_t>(i)] = us[k][i];
      dirs[k][static_cast<size_t>(i)] = static_cast<std::int8_t>(die(rng));
    }
  }
  size_t k = 0;
  for (auto _ : state) {
    const size_t j = k++ & 1023;
    Eigen::Vector3d e = model.tip_error_linear(u3[j].data(), dirs[j]);
    benchmark::DoNotOptimize(e);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_TipErrorLinear, three_axis, "hsu-3axis");

}  // namespace

BENCHMARK_MAIN();
