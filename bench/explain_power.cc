// The detection-power sweep of `volmap explain` (bench/explain_power.h):
// prints the table quoted in docs/explain.md and checks the goals of issue
// #20. Usage:
//   build/bench/explain_power [--reduced] [--seeds N] [--nulls N] [--threads N]
// --reduced: the form CI runs (tests/explain/explain_power_test.cc runs the
// same engine). Exit status 1 when a goal is missed.
#include "bench/explain_power.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "bench/explain_power_sweep.h"

int main(int argc, char** argv) {
  volmap::power::SweepOptions opt;
  for (int i = 1; i < argc; ++i) {
    const auto value = [&] {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "explain_power: %s needs a value\n", argv[i]);
        std::exit(2);
      }
      return std::atoi(argv[++i]);
    };
    if (!std::strcmp(argv[i], "--reduced")) {
      opt = volmap::power::reduced_options();
    } else if (!std::strcmp(argv[i], "--seeds")) {
      opt.seeds = value();
    } else if (!std::strcmp(argv[i], "--nulls")) {
      opt.nulls_per_design = value();
    } else if (!std::strcmp(argv[i], "--threads")) {
      opt.threads = value();
    } else {
      std::fprintf(stderr,
                   "usage: explain_power [--reduced] [--seeds N] [--nulls N] [--threads N]\n");
      return 2;
    }
  }
  const auto start = std::chrono::steady_clock::now();
  const volmap::power::SweepResult r =
      volmap::power::sweep(opt, [](std::int64_t done, std::int64_t all) {
        std::fprintf(stderr, "\r%lld / %lld recordings", static_cast<long long>(done),
                     static_cast<long long>(all));
      });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::fprintf(stderr, "\n");
  std::fputs(volmap::power::table(r, opt).c_str(), stdout);
  std::printf("\n%zu recordings in %.0f s\n", r.recordings, seconds);
  const std::string missed = volmap::power::missed_goals(r);
  if (!missed.empty()) {
    std::printf("goals missed:\n%s", missed.c_str());
    return 1;
  }
  std::printf("goals met\n");
  return 0;
}
