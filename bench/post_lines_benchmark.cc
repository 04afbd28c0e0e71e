// Output size of `volmap post` (issue: the smallest faithful change): per
// program, the lines written at 1 um against the program's lines and
// against the fewest lines any post could write (post::fewest_lines,
// docs/post.md "How many lines"), with the sample machine and errors. The
// programs: LinuxCNC's shipped ones (when installed) and the real
// third-party corpus of tests/data/real/nc that the three-axis post takes,
// each placed at the middle of the travel. Counters: in, out, bound,
// out_per_in, out_per_bound; the time is one post of the program.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "gcode/nc_interpreter.h"
#include "gcode/program_reader.h"
#include "postproc/three_axis/line_bound.h"
#include "postproc/three_axis/post_program.h"

namespace {

namespace fs = std::filesystem;
using volmap::nc::ProgramSetup;

std::string source(const std::string& rel) { return std::string(VOLMAP_SOURCE_DIR) + "/" + rel; }

std::string bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// The program's extent (machine coordinates at a zero offset), placed at
// the middle of the sample machine's travel.
ProgramSetup placed(const std::string& text, const std::string& name, ProgramSetup setup) {
  volmap::nc::Interpreter interp(setup, name);
  std::istringstream in(text);
  volmap::nc::ProgramReader reader(in, name, interp, {source("tests/data/real/nc/subs")});
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  volmap::nc::ProgramLine l;
  volmap::nc::BlockEffect fx;
  try {
    while (reader.next(l)) {
      if (l.verbatim) continue;
      interp.execute(volmap::nc::lex_block(volmap::nc::flatten::without_cr(l.text), l.line, name),
                     fx);
      if (!fx.has_motion || !interp.state().position_known) continue;
      lo = lo.cwiseMin(fx.motion.end_mm);
      hi = hi.cwiseMax(fx.motion.end_mm);
    }
  } catch (const std::exception&) {
  }
  const Eigen::Vector3d mid =
      lo.x() <= hi.x() ? Eigen::Vector3d((lo + hi) / 2) : Eigen::Vector3d::Zero();
  setup.work_offset_mm[0] = (Eigen::Vector3d(250, 200, 150) - mid)
                                .cwiseMax(Eigen::Vector3d::Zero())
                                .cwiseMin(Eigen::Vector3d(500, 400, 300));
  return setup;
}

void BM_PostLines(benchmark::State& state, std::string path) {
  const volmap::Machine m = volmap::load_machine_json(source("samples/machines/hsu-3axis.json"));
  const volmap::ErrorSet e = volmap::load_errors_csv(source("samples/errors/hsu-3axis.csv"));
  const std::string text = bytes(path);
  ProgramSetup base;
  for (int t = 0; t <= 99; ++t) base.tool_length_mm[t] = 0.0;
  const ProgramSetup setup = placed(text, path, base);
  volmap::post::PostOptions o;
  o.outside = volmap::OutsidePolicy::kClamp;
  o.subroutine_path = {source("tests/data/real/nc/subs")};
  std::uint64_t out_lines = 0;
  try {
    for (auto _ : state) {
      std::istringstream in(text);
      std::ostringstream out;
      const volmap::post::PostReport r = volmap::post::post_program(in, path, out, m, e, setup, o);
      out_lines = r.lines_out;
      benchmark::DoNotOptimize(out_lines);
    }
  } catch (const std::exception& x) {
    state.SkipWithError(x.what());
    return;
  }
  std::istringstream in(text);
  const volmap::post::LineBound b =
      volmap::post::fewest_lines(in, path, m, e, setup, o.tolerance_mm, o.subroutine_path);
  const double lines_in = static_cast<double>(b.lines_in);
  state.counters["in"] = lines_in;
  state.counters["out"] = static_cast<double>(out_lines);
  state.counters["bound"] = static_cast<double>(b.lower_bound());
  state.counters["turns"] = static_cast<double>(b.turn_lines);
  state.counters["chords"] = static_cast<double>(b.chord_lines);
  state.counters["out_per_in"] = static_cast<double>(out_lines) / lines_in;
  state.counters["out_per_bound"] =
      static_cast<double>(out_lines) / static_cast<double>(b.lower_bound());
}

const int kRegistered = [] {
  std::vector<std::string> programs;
  for (const char* n : {"tort.ngc", "arcspiral.ngc", "3dtest.ngc", "cds.ngc", "plasmatest.ngc"}) {
    const std::string p = std::string("/usr/share/linuxcnc/ncfiles/") + n;
    if (fs::exists(p)) programs.push_back(p);
  }
  std::vector<std::string> corpus;
  for (const auto& f : fs::directory_iterator(source("tests/data/real/nc"))) {
    const std::string ext = f.path().extension().string();
    if (ext == ".ngc" || ext == ".nc" || ext == ".gcode") corpus.push_back(f.path().string());
  }
  std::sort(corpus.begin(), corpus.end());
  programs.insert(programs.end(), corpus.begin(), corpus.end());
  for (const std::string& p : programs)
    benchmark::RegisterBenchmark(("PostLines/" + fs::path(p).filename().string()).c_str(),
                                 BM_PostLines, p)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1);
  return 0;
}();

}  // namespace

BENCHMARK_MAIN();
