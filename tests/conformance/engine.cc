#include "tests/conformance/engine.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <mutex>
#include <random>
#include <thread>

#include "tests/conformance/regression.h"
#include "tests/conformance/shrink.h"

namespace volmap::conformance {

namespace fs = std::filesystem;

std::uint64_t program_seed(std::uint64_t seed, int index) {
  // splitmix64 of the run's seed and the index.
  std::uint64_t z = seed * 1000003ULL + static_cast<std::uint64_t>(index) + 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return (z ^ (z >> 31)) % 1000000000000ULL;
}

double program_tolerance_um(std::uint64_t s) {
  const std::uint64_t k = (s / 7) % 10;
  double tol = k < 8 ? 1.0 : k == 8 ? 2.0 : 5.0;
  // Cutter compensation is kept where the field's slope times the radius
  // is within a quarter of the tolerance (docs/post.md): 5 um for most of
  // the programs that have it, so that it is posted and judged.
  const Program p = generate_program(s);
  for (const std::string& f : p.features)
    if (f == "cutter comp" && (s / 11) % 10 < 7) tol = 5.0;
  return tol;
}

std::vector<FieldSpec> program_fields(std::uint64_t s) {
  FieldSpec lost{FieldSpec::kLostMotion, s % 100000 + 1};
  FieldSpec smooth{FieldSpec::kSmooth, (s / 3) % 100000 + 2};
  FieldSpec zero{FieldSpec::kZero, s % 2};
  return {lost, smooth, zero};
}

namespace {

struct Result {
  int index = 0;
  std::uint64_t seed = 0;
  Judgement judgement;
  std::vector<std::string> features;
};

void tally(EngineReport& report, const Result& r) {
  const Judgement& j = r.judgement;
  ++report.programs;
  report.rs274_reads += j.rs274_reads;
  report.both_refused_programs += !j.rs274_reads;
  report.user_m_programs += j.user_m;
  report.posts_judged += j.posted;
  report.refusals += static_cast<int>(j.refusals.size());
  for (const std::string& k : j.refusals) ++report.refusal_counts[k];
  for (const std::string& f : r.features) ++report.feature_counts[f];
  std::vector<std::string> kinds;
  for (const Finding& f : j.failures)
    if (std::find(kinds.begin(), kinds.end(), f.kind) == kinds.end()) kinds.push_back(f.kind);
  for (const std::string& k : kinds) ++report.failure_counts[k];
  if (j.failures.empty()) report.worst_passing_um = std::max(report.worst_passing_um, j.worst_um);
}

// The programs of the run, judged by `jobs` workers; results in order.
std::vector<Result> judge_all(const EngineOptions& o, std::ostream& log) {
  const auto start = std::chrono::steady_clock::now();
  const auto out_of_time = [&] {
    return o.minutes > 0 &&
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
               60 * o.minutes;
  };
  std::atomic<int> next{0};
  std::mutex m;
  std::vector<Result> results;
  const auto worker = [&](int id) {
    JudgeConfig c{o.volmap, o.source_dir, (fs::path(o.work_dir) / fmt::format("w{}", id)).string()};
    Judge judge(c);
    for (;;) {
      const int i = next++;
      if ((o.programs > 0 && i >= o.programs) || out_of_time()) return;
      Result r;
      r.index = i;
      r.seed = program_seed(o.seed, i);
      const Program p = generate_program(r.seed);
      r.features = p.features;
      r.judgement = judge.judge(p, "p", program_fields(r.seed), program_tolerance_um(r.seed));
      if (!r.judgement.failures.empty() && !o.keep_dir.empty()) {
        const fs::path keep = fs::path(o.keep_dir) / fmt::format("program-{}", r.seed);
        fs::remove_all(keep);
        fs::create_directories(keep.parent_path());
        fs::copy(judge.last_dir(), keep, fs::copy_options::recursive);
      }
      const std::lock_guard<std::mutex> lock(m);
      if (o.verbose || !r.judgement.failures.empty()) {
        log << fmt::format("program {} (seed {}): {}", i, r.seed,
                           r.judgement.failures.empty() ? "ok" : "FAILS");
        for (const Finding& f : r.judgement.failures)
          log << fmt::format("\n  {} [{}]: {}", f.kind, f.field, f.detail);
        log << std::endl;
      }
      results.push_back(std::move(r));
    }
  };
  std::vector<std::thread> threads;
  for (int k = 0; k < std::max(1, o.jobs); ++k) threads.emplace_back(worker, k);
  for (std::thread& t : threads) t.join();
  std::sort(results.begin(), results.end(),
            [](const Result& a, const Result& b) { return a.index < b.index; });
  return results;
}

}  // namespace

EngineReport run_engine(const EngineOptions& o, std::ostream& log) {
  const auto start = std::chrono::steady_clock::now();
  EngineReport report;
  const std::vector<Result> results = judge_all(o, log);
  for (const Result& r : results) tally(report, r);
  // Shrink the first failures of each class.
  std::map<std::string, int> shrunk;
  Judge judge({o.volmap, o.source_dir, (fs::path(o.work_dir) / "shrink").string()});
  for (const Result& r : results) {
    std::vector<std::string> done;  // a class once per program (not once per field)
    for (const Finding& f : r.judgement.failures) {
      if (shrunk[f.kind] >= o.shrink_per_class ||
          std::find(done.begin(), done.end(), f.kind) != done.end())
        continue;
      ++shrunk[f.kind];
      done.push_back(f.kind);
      FailureCase fc;
      fc.finding = f;
      fc.seed = r.seed;
      fc.index = r.index;
      fc.tolerance_um = program_tolerance_um(r.seed);
      fc.original = generate_program(r.seed);
      log << fmt::format("shrinking program {} (seed {}): {} [{}] ...", r.index, r.seed, f.kind,
                         f.field)
          << std::endl;
      const ShrinkResult s = shrink(
          fc.original, [&](const Program& p) { return judge.reproduces(p, f, fc.tolerance_um); },
          o.shrink_trials);
      fc.minimal = s.program;
      fc.shrink_trials = s.trials;
      // The minimal program's own numbers.
      const Judgement again =
          judge.judge(fc.minimal, "shrink", {FieldSpec::parse(f.field)}, fc.tolerance_um);
      for (const Finding& g : again.failures)
        if (g.kind == f.kind) fc.finding.detail = g.detail;
      if (!o.regressions_dir.empty()) fc.regression_file = write_regression(o.regressions_dir, fc);
      report.failures.push_back(std::move(fc));
    }
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

void print_report(const EngineReport& r, std::ostream& out) {
  out << fmt::format(
      "conformance: {} programs in {:.0f} s: rs274 reads {} ({} judged without their user M "
      "codes), refuses {}; {} posts judged, {} refused by volmap with file:line; worst passing "
      "deviation {:.2f} um\n",
      r.programs, r.seconds, r.rs274_reads, r.user_m_programs, r.both_refused_programs,
      r.posts_judged, r.refusals, r.worst_passing_um);
  if (!r.refusal_counts.empty()) out << "volmap's refusals of programs rs274 reads:\n";
  for (const auto& [k, n] : r.refusal_counts) out << fmt::format("  {:4} {}\n", n, k);
  out << fmt::format("failure classes: {}\n", r.failure_counts.size());
  for (const auto& [k, n] : r.failure_counts) out << fmt::format("  {:4} programs: {}\n", n, k);
  for (const FailureCase& f : r.failures) {
    out << fmt::format("\n== {} [{}], program {} (seed {}), tolerance {} um\n   {}\n",
                       f.finding.kind, f.finding.field, f.index, f.seed, f.tolerance_um,
                       f.finding.detail);
    out << fmt::format("   minimal program ({} judge runs){}:\n", f.shrink_trials,
                       f.regression_file.empty() ? "" : ", kept as " + f.regression_file);
    out << f.minimal.main;
    if (!f.minimal.main.empty() && f.minimal.main.back() != '\n') out << "\n(no final newline)\n";
    for (const auto& [name, bytes] : f.minimal.files) out << "--- " << name << ":\n" << bytes;
  }
}

}  // namespace volmap::conformance
