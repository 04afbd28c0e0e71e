// volmap verify, five axes: the nominal tool path (a five-axis input
// program, postproc/five_axis_input.h) against the real machine running
//  before: the nominal program on a controller with ideal TCP (the axes at
//          every sample the nominal backward transformation of the nominal
//          pose, as a TCP controller without volumetric compensation
//          interpolates), moved by the machine's errors;
//  after:  the compensated machine-axis program (volmap post), its axes
//          interpolated linearly between the written positions, as a
//          controller in identity kinematics does, moved by the errors.
// Samples at least every sample_step_mm of tip travel, every 0.5 degree of
// rotary travel, and 8 per move. The deviation of a sample: the distance of
// the actual tip to the nearest nominal feed move (searched in a window
// around the current one) and the angle of the actual tool axis to the
// nominal axis at the nearest point. Feed moves only; rapids are not
// measured.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <map>
#include <string>

#include "core/model/error_model.h"
#include "postproc/five_axis/five_axis_input.h"
#include "postproc/verify/deviation_profile.h"

namespace volmap::post {

struct FiveAxisDeviation {
  double max_um = 0.0, rms_um = 0.0;      ///< tool tip, distance to the nominal path
  double max_urad = 0.0, rms_urad = 0.0;  ///< tool axis, angle to the nominal axis
  std::uint64_t samples = 0;
  int worst_line = 0;        ///< program line of the largest tip deviation
  int worst_angle_line = 0;  ///< program line of the largest axis deviation
  DeviationProfile profile;  ///< along the tip path, for verify --report
};

struct FiveAxisVerifyResult {
  FiveAxisDeviation before, after;
};

struct FiveAxisVerifyOptions {
  InputForm form = InputForm::kAuto;  ///< of the nominal program
  double sample_step_mm = 0.25;
  InitialPose initial;
  OutsidePolicy outside = OutsidePolicy::kError;
  /// The tool table (FiveAxisPostOptions::tool_offsets_mm).
  std::map<int, double> tool_offsets_mm;
  /// Called at each move read (the program's name, its line, 0: the total is
  /// not known while the program streams); the command line shows it.
  std::function<void(const std::string& program, std::size_t line, std::size_t total)> progress;
};

/// `machine`: the part origin already placed.
FiveAxisVerifyResult verify_five_axis(std::istream& nominal, const std::string& nominal_name,
                                      std::istream& compensated,
                                      const std::string& compensated_name, const Machine& machine,
                                      const ErrorSet& errors, const FiveAxisVerifyOptions& options);

}  // namespace volmap::post
