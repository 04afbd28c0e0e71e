// volmap verify: runs NC programs on the simulated real machine and
// measures how far the actual tool path strays from the nominal one.
//
// The nominal path is the feed moves of the nominal program (G1, G2/G3 with
// helices, the feed-in of canned cycles from R to the bottom); rapid moves
// are not cutting and are not measured. A program's commanded moves are
// interpolated as the controller does (straight in axis space for G1, arcs
// for G2/G3) and sampled at least every `sample_step_mm` and 8 times per
// move; the actual tool tip at a sample is x + e(x) (the error model,
// exact). Its deviation is the distance to the nearest point of the nominal
// path (searched around the move it belongs to).
//  before: the nominal program run uncompensated;
//  after:  the compensated program.
#pragma once

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/model/error_model.h"
#include "gcode/nc_interpreter.h"
#include "postproc/verify/deviation_profile.h"

namespace volmap::post {

struct DeviationStats {
  double max_um = 0.0;
  double rms_um = 0.0;
  std::uint64_t samples = 0;
  int worst_line = 0;        ///< line of the program where the maximum occurs
  DeviationProfile profile;  ///< along the tool path, for verify --report
};

struct VerifyResult {
  DeviationStats before, after;
  /// The largest tool radius of cutter compensation (G41/G42) in either
  /// program, mm (0: none). Verify measures the programmed contours; the
  /// controller offsets them by the radius, which adds at most what
  /// `volmap post` bounds (docs/post.md, "Cutter compensation").
  double comp_radius_mm = 0.0;
};

struct VerifyOptions {
  double sample_step_mm = 0.25;
  OutsidePolicy outside = OutsidePolicy::kError;
  /// Where `O<name> call` finds NAME.ngc (LinuxCNC's SUBROUTINE_PATH).
  std::vector<std::string> subroutine_path;
  /// Called as each move of a program is measured (the program's name, moves
  /// done, moves in all); the command line shows it on a terminal.
  std::function<void(const std::string& program, std::size_t done, std::size_t total)> progress;
};

/// Refuses (InputError) a nominal program with no feed move to measure
/// (verify measures the cutting moves: rapids only, or no motion at all),
/// and a compensated one with none, rather than a success on 0 samples.
VerifyResult verify_programs(std::istream& nominal, const std::string& nominal_name,
                             std::istream& compensated, const std::string& compensated_name,
                             const Machine& machine, const ErrorSet& errors,
                             const nc::ProgramSetup& setup, const VerifyOptions& options);

}  // namespace volmap::post
