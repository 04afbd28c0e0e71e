// volmap_conformance: the conformance engine from the command line
// (docs/conformance.md).
//
//   volmap_conformance [--seed N] [--programs N] [--minutes M] [--jobs N]
//                      [--keep-dir DIR] [--regressions-dir DIR] [--shrink-trials N]
//                      [--shrink-per-class N] [--volmap PATH] [--source DIR] [--verbose]
//   volmap_conformance --replay SEED [--print]    one program: judge it (or print it)
//   volmap_conformance --regression PATH...       re-run regression files
//   volmap_conformance --judge FILE.ngc [--field F] [--tolerance-um T]   judge a program of yours
//                      (its folder's other .ngc files are its subroutine files)
//
// Exit status: 0 when every program passed, 1 when some failed, 2 on a
// usage error.
#include <fmt/format.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "tests/conformance/engine.h"
#include "tests/conformance/process.h"
#include "tests/conformance/regression.h"

namespace fs = std::filesystem;
using namespace volmap::conformance;

namespace {

int usage(const std::string& why) {
  std::cerr << "volmap_conformance: " << why
            << "\nusage: volmap_conformance [--seed N] [--programs N] [--minutes M] [--jobs N] "
               "[--keep-dir DIR] [--regressions-dir DIR] [--shrink-trials N] "
               "[--shrink-per-class N] [--volmap PATH] [--source DIR] [--verbose] | --replay "
               "SEED [--print] | --regression PATH...\n";
  return 2;
}

int replay(EngineOptions& o, std::uint64_t seed, bool print) {
  const Program p = generate_program(seed);
  if (print) {
    std::cout << p.main;
    for (const auto& [name, bytes] : p.files) std::cout << "--- " << name << ":\n" << bytes;
    return 0;
  }
  Judge judge({o.volmap, o.source_dir, (fs::path(o.work_dir) / "replay").string()});
  const Judgement j = judge.judge(p, "p", program_fields(seed), program_tolerance_um(seed));
  std::cout << fmt::format("seed {}: rs274 {}{}; {} posts judged, worst {:.3f} um; files in {}\n",
                           seed, j.rs274_reads ? "reads it" : "refuses it: ",
                           j.rs274_reads ? "" : j.rs274_error.substr(0, j.rs274_error.find('\n')),
                           j.posted, j.worst_um, judge.last_dir());
  for (const std::string& r : j.refusals) std::cout << "  refused: " << r << "\n";
  for (const Finding& f : j.failures)
    std::cout << fmt::format("  FAIL {} [{}]: {}\n", f.kind, f.field, f.detail);
  return j.failures.empty() ? 0 : 1;
}

int judge_file(EngineOptions& o, const std::string& path, const std::string& field, double tol) {
  Program p;
  p.main = read_file(path);
  for (const auto& e : fs::directory_iterator(
           fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path()))
    if (e.path().extension() == ".ngc" && !fs::equivalent(e.path(), path))
      p.files.push_back({e.path().filename().string(), read_file(e.path().string())});
  const std::vector<FieldSpec> fields =
      field == "all" ? program_fields(1) : std::vector<FieldSpec>{FieldSpec::parse(field)};
  Judge judge({o.volmap, o.source_dir, (fs::path(o.work_dir) / "judge").string()});
  const Judgement j = judge.judge(p, "p", fields, tol);
  std::cout << fmt::format("{}: rs274 {}{}; {} posts judged, worst {:.3f} um; files in {}\n", path,
                           j.rs274_reads ? "reads it" : "refuses it: ",
                           j.rs274_reads ? "" : j.rs274_error.substr(0, j.rs274_error.find('\n')),
                           j.posted, j.worst_um, judge.last_dir());
  for (const std::string& r : j.refusals) std::cout << "  refused: " << r << "\n";
  for (const Finding& f : j.failures)
    std::cout << fmt::format("  FAIL {} [{}]: {}\n", f.kind, f.field, f.detail);
  return j.failures.empty() ? 0 : 1;
}

int regressions(EngineOptions& o, const std::vector<std::string>& paths) {
  Judge judge({o.volmap, o.source_dir, (fs::path(o.work_dir) / "regressions").string()});
  int failing = 0;
  for (const std::string& path : paths) {
    const Regression r = read_regression(path);
    const std::vector<Finding> f = rerun_regression(judge, r);
    std::cout << fmt::format("{}: {}\n", path, f.empty() ? "passes" : "FAILS");
    for (const Finding& x : f)
      std::cout << fmt::format("  {} [{}]: {}\n", x.kind, x.field, x.detail);
    failing += !f.empty();
  }
  std::cout << fmt::format("{} of {} regressions fail\n", failing, paths.size());
  return failing == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  EngineOptions o;
  o.volmap = VOLMAP_BINARY;
  o.source_dir = VOLMAP_SOURCE_DIR;
  o.regressions_dir = (fs::path(VOLMAP_SOURCE_DIR) / "tests/conformance/regressions").string();
  o.work_dir =
      (fs::temp_directory_path() / fmt::format("volmap-conformance-{}", getpid())).string();
  std::vector<std::string> regression_args;
  std::uint64_t replay_seed = 0;
  bool do_replay = false, print = false;
  std::string judge_path, field = "all";
  double tolerance = 1.0;
  try {
    for (int k = 1; k < argc; ++k) {
      const std::string a = argv[k];
      const auto next = [&]() -> std::string {
        if (k + 1 >= argc) throw std::invalid_argument(a + " needs a value");
        return argv[++k];
      };
      if (a == "--seed")
        o.seed = std::stoull(next());
      else if (a == "--programs")
        o.programs = std::stoi(next());
      else if (a == "--minutes")
        o.minutes = std::stod(next());
      else if (a == "--jobs")
        o.jobs = std::stoi(next());
      else if (a == "--keep-dir")
        o.keep_dir = next();
      else if (a == "--regressions-dir")
        o.regressions_dir = next();
      else if (a == "--shrink-trials")
        o.shrink_trials = std::stoi(next());
      else if (a == "--shrink-per-class")
        o.shrink_per_class = std::stoi(next());
      else if (a == "--volmap")
        o.volmap = next();
      else if (a == "--source")
        o.source_dir = next();
      else if (a == "--work-dir")
        o.work_dir = next();
      else if (a == "--verbose")
        o.verbose = true;
      else if (a == "--print")
        print = true;
      else if (a == "--judge")
        judge_path = next();
      else if (a == "--field")
        field = next();
      else if (a == "--tolerance-um")
        tolerance = std::stod(next());
      else if (a == "--replay")
        do_replay = true, replay_seed = std::stoull(next());
      else if (a == "--regression") {
        while (k + 1 < argc && std::string(argv[k + 1]).rfind("--", 0) != 0)
          regression_args.push_back(argv[++k]);
      } else
        return usage("unknown option " + a);
    }
    if (o.minutes > 0 && o.programs == 100) o.programs = 0;  // --minutes alone: until the time
  } catch (const std::exception& e) {
    return usage(e.what());
  }
  if (do_replay) return replay(o, replay_seed, print);
  if (!judge_path.empty()) return judge_file(o, judge_path, field, tolerance);
  if (!regression_args.empty()) return regressions(o, regression_args);
  const EngineReport r = run_engine(o, std::cerr);
  print_report(r, std::cout);
  return r.failure_counts.empty() ? 0 : 1;
}
