// The five-axis post's per-pose work (issue 6 target: >= 1 M tool poses/s on
// one core through backward transformation, correction and formatting) on
// the X'Y'ZA'C' sample with its errors: a smooth tool path (consecutive
// poses 0.1 mm and ~0.3 degree apart, as a CAM program has them), each pose
// transformed after the previous one (selection and C continuity), corrected
// (one step, eq. 6) and written as "X.. Y.. Z.. A.. C.." into a reused
// buffer. Parts: backward alone, backward + correction, formatting alone,
// and the zero-error path (no model). BM_PostProgram posts a whole TCP
// program (segmentation with checks between points, G93 feeds) from memory.
#include <benchmark/benchmark.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "postproc/five_axis/five_axis_post.h"
#include "postproc/five_axis/five_axis_transform.h"

namespace {

using volmap::AxisVector;
using volmap::ToolPose;

std::string sample(const std::string& rel) {
  return std::string(VOLMAP_SOURCE_DIR) + "/samples/" + rel;
}

// A spiral of the tool tip over a dome with the tool axis tilting around
// (A from about -10 to -60 degrees, C turning): 4096 poses.
std::vector<ToolPose> path() {
  std::vector<ToolPose> v;
  for (int i = 0; i < 4096; ++i) {
    const double t = i * 0.005, tilt = (10 + 50.0 * i / 4096) * M_PI / 180;
    ToolPose p;
    p.tip_mm = Eigen::Vector3d(40 * std::cos(t), 40 * std::sin(t), 20 + 0.005 * i);
    p.axis =
        Eigen::Vector3d(std::sin(tilt) * std::cos(t), std::sin(tilt) * std::sin(t), std::cos(tilt));
    v.push_back(p);
  }
  return v;
}

struct Setup {
  volmap::Machine m = volmap::load_machine_json(sample("machines/lei-hsu-xyzac.json"));
  volmap::ErrorSet e = volmap::load_errors_csv(sample("errors/lei-hsu-xyzac.csv"));
  std::vector<ToolPose> poses = path();
};

void append_words(std::string& out, const AxisVector& c) {
  static constexpr char kLetters[] = "XYZAC";
  for (int k = 0; k < 5; ++k) {
    if (k) out += ' ';
    out += kLetters[k];
    volmap::post::append_number(out, k < 3 ? c[k] : c[k] * (180.0 / M_PI), k < 3 ? 4 : 5);
  }
  out += '\n';
}

// backward + correction + formatting: the figure.
void BM_PosePipeline(benchmark::State& state) {
  const Setup s;
  const volmap::post::FiveAxisTransform tf(s.m, state.range(0) ? s.e : volmap::ErrorSet{},
                                           volmap::OutsidePolicy::kError);
  std::string out;
  out.reserve(1 << 20);
  AxisVector prev = s.m.home;
  size_t i = 0;
  for (auto _ : state) {
    const AxisVector u = tf.axes_for_pose(s.poses[i], prev);
    const AxisVector c = tf.command(u);
    append_words(out, c);
    prev = u;
    if (++i == s.poses.size()) {
      i = 0;
      prev = s.m.home;
    }
    if (out.size() > (1 << 19)) out.clear();
  }
  benchmark::DoNotOptimize(out.data());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PosePipeline)->Arg(1)->Arg(0)->ArgName("errors");

void BM_Backward(benchmark::State& state) {
  const Setup s;
  const volmap::post::FiveAxisTransform tf(s.m, s.e, volmap::OutsidePolicy::kError);
  AxisVector prev = s.m.home;
  size_t i = 0;
  for (auto _ : state) {
    prev = tf.axes_for_pose(s.poses[i], prev);
    benchmark::DoNotOptimize(prev.data());
    if (++i == s.poses.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Backward);

void BM_BackwardAndCorrection(benchmark::State& state) {
  const Setup s;
  const volmap::post::FiveAxisTransform tf(s.m, s.e, volmap::OutsidePolicy::kError);
  AxisVector prev = s.m.home;
  size_t i = 0;
  for (auto _ : state) {
    const AxisVector u = tf.axes_for_pose(s.poses[i], prev);
    const AxisVector c = tf.command(u);
    benchmark::DoNotOptimize(c.data());
    prev = u;
    if (++i == s.poses.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_BackwardAndCorrection);

void BM_Formatting(benchmark::State& state) {
  AxisVector c(5);
  c << 12.34567, -123.4567, 250.00012, -0.7123456, 2.3456789;
  std::string out;
  out.reserve(1 << 20);
  for (auto _ : state) {
    append_words(out, c);
    c[0] += 1e-4;
    if (out.size() > (1 << 19)) out.clear();
  }
  benchmark::DoNotOptimize(out.data());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Formatting);

// A whole TCP program through volmap's five-axis post (reading, per pose
// work, segmentation with three model evaluations per checked piece, G93
// feeds, writing): items are input moves.
void BM_PostProgram(benchmark::State& state) {
  const Setup s;
  std::ostringstream prog;
  prog << "G21 G90 G94\nG0 X40 Y0 Z20 A-10 C0\n";
  for (int i = 1; i < 2000; ++i) {
    const double t = i * 0.005;
    prog << "G1 X" << 40 * std::cos(t) << " Y" << 40 * std::sin(t) << " Z" << 20 + 0.005 * i << " A"
         << -(10 + 50.0 * i / 2000) << " C" << t * 180 / M_PI << " F1000\n";
  }
  const std::string text = prog.str();
  volmap::post::FiveAxisPostOptions o;
  for (auto _ : state) {
    std::istringstream in(text);
    std::ostringstream out;
    volmap::post::post_five_axis(in, "bench.ngc", out, s.m, s.e, o);
    benchmark::DoNotOptimize(out.str().data());
  }
  state.SetItemsProcessed(state.iterations() * 2000);
}
BENCHMARK(BM_PostProgram)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
