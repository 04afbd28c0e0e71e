// The conformance engine (docs/conformance.md): generated programs judged
// against rs274 (judge.h), failures shrunk to minimal programs (shrink.h)
// and written as regression files; the regression files re-run.
#pragma once

#include <cstdint>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "tests/conformance/generator.h"
#include "tests/conformance/judge.h"

namespace volmap::conformance {

struct EngineOptions {
  std::string volmap, source_dir;
  std::string work_dir;         ///< scratch folders (one per worker)
  std::string keep_dir;         ///< "" or where every failing program's folder is copied
  std::string regressions_dir;  ///< "" or where minimal programs are written
  std::uint64_t seed = 35;
  int programs = 100;    ///< how many (0: until `minutes`)
  double minutes = 0.0;  ///< a wall-clock limit (0: none)
  int jobs = 1;
  int shrink_trials = 200;   ///< judge runs per failure shrunk
  int shrink_per_class = 1;  ///< failures shrunk for each class
  bool verbose = false;
};

/// A failure found, with its minimal program.
struct FailureCase {
  Finding finding;
  std::uint64_t seed = 0;  ///< the program's generator seed
  int index = 0;           ///< its number in the run
  double tolerance_um = 1;
  Program original, minimal;
  int shrink_trials = 0;
  std::string regression_file;
};

struct EngineReport {
  int programs = 0, rs274_reads = 0, both_refused_programs = 0, user_m_programs = 0;
  int posts_judged = 0, refusals = 0;
  std::map<std::string, int> refusal_counts, failure_counts, feature_counts;
  std::vector<FailureCase> failures;  ///< the shrunk ones
  double seconds = 0, worst_passing_um = 0;
};

/// The generator seed of program `index` of a run with `seed`, its
/// tolerance and its error fields.
std::uint64_t program_seed(std::uint64_t seed, int index);
double program_tolerance_um(std::uint64_t program_seed);
std::vector<FieldSpec> program_fields(std::uint64_t program_seed);

EngineReport run_engine(const EngineOptions& options, std::ostream& log);

/// Prints the report (counts, refusals, every failure with its minimal
/// program).
void print_report(const EngineReport& report, std::ostream& out);

/// A regression file: the header the engine writes, and the program.
struct Regression {
  std::string path, kind, field, detail;
  double tolerance_um = 1;
  Program program;
};
/// Reads a regression file (`NAME.ngc`) or folder (`NAME/prog.ngc` and its
/// subroutine files); the header's lines are taken off the program.
Regression read_regression(const std::string& path);
/// Every regression under `dir`, sorted by name.
std::vector<std::string> regression_paths(const std::string& dir);
/// Judges a regression with its field and tolerance: every failure (empty:
/// it passes now).
std::vector<Finding> rerun_regression(Judge& judge, const Regression& r);

}  // namespace volmap::conformance
