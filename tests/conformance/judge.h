// The engine's judge (docs/conformance.md): a program posted by the built
// `volmap post` on the sample machine with each error field, and rs274's
// reading of the input and the outputs compared:
//  - rs274 refuses the input: volmap refuses too, with file:line;
//  - rs274 reads it: volmap posts it, rs274 reads the output, and the
//    output's actual path lies within the tolerance of the input's nominal
//    path both ways (path_check.h); or volmap refuses it with file:line
//    (counted as refused, not a failure);
//  - zero errors: the output is the input, byte for byte.
// rs274 run alone knows no user M code (M100-M199: "Unknown m code used",
// with or without an INI file); where that is its only objection, input
// and output are judged on copies whose user M codes are taken out.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/conformance/generator.h"
#include "tests/conformance/process.h"
#include "tests/conformance/setup_files.h"

namespace volmap::conformance {

struct JudgeConfig {
  std::string volmap;      ///< the volmap executable
  std::string source_dir;  ///< the repository (the sample machine)
  std::string work_dir;    ///< this judge's own folder
  double timeout_s = 120;
};

/// One failure: its class (the key the shrinker keeps), what was seen, and
/// the error field it was seen with.
struct Finding {
  std::string kind;
  std::string detail;
  std::string field;
  /// A deviation's excess over its limit (um); the shrinker keeps at least
  /// half of it, so that a minimal program fails clearly.
  double excess_um = 0;
};

struct Judgement {
  bool rs274_reads = false;
  std::string rs274_error;
  bool user_m = false;  ///< judged without its user M codes
  int posted = 0;       ///< posts that were measured (or compared byte for byte)
  int both_refused = 0;
  std::vector<std::string> refusals;  ///< volmap's refusals of programs rs274 reads
  std::vector<Finding> failures;
  double worst_um = 0;  ///< the largest deviation measured
};

class Judge {
 public:
  explicit Judge(JudgeConfig config);
  /// Judges the program in a folder named after `tag` with each field.
  Judgement judge(const Program& program, const std::string& tag,
                  const std::vector<FieldSpec>& fields, double tolerance_um);
  /// Whether the program fails with the finding's class and field.
  bool reproduces(const Program& program, const Finding& finding, double tolerance_um);
  /// The folder of the last program judged (kept until the next).
  const std::string& last_dir() const { return last_dir_; }

 private:
  /// The `volmap post` run of field k's errors file `csv` into `out_name`.
  ProcessSpec post_spec(const std::filesystem::path& dir, const SetupFiles& setup,
                        const std::string& csv, const std::string& out_name, double tolerance_um,
                        size_t k) const;
  JudgeConfig config_;
  std::string last_dir_;
};

/// The program with its user M codes (M100-M199 with their P and Q words)
/// taken out, for rs274.
std::string without_user_m(const std::string& text);

}  // namespace volmap::conformance
