// volmap post, five axes: a tool path in workpiece coordinates (TCP
// program, tool-vector program or APT/CLDATA; postproc/five_axis_input.h)
// in, the machine-axis program of the real machine out, corrected.
//
// Per pose (postproc/five_axis_transform.h): backward transformation
// (Lei & Hsu 2003 eq. 1) with the selection policy and C continuity of
// core/kinematics.h, the singular position held (section 4.1), then the
// correction u + du (eqs. 3-6, core/correction.h).
//
// Between poses: the controller moves its axes linearly, so a feed move is
// split until, at 1/4, 1/2 and 3/4 of every piece, the actual tool tip lies
// within tolerance_mm of the nominal tip path and the actual tool axis
// within angle_tolerance_rad of the nominal axis at that path parameter
// (nominal path: the tip along the programmed line or arc; TCP: the rotary
// angles linear along it; tool vectors: the axis along the great circle).
// Where the backward solution jumps (C leaving the singular position) the
// rotary axes turn over the jump with the tip held on the path. Rapids:
// their end point only.
//
// Feeds: each feed piece gets its time, the programmed time of the move
// (G94: nominal tip path length / F, or rotary degrees / F for a move
// without tip motion; G93: 1 / F) shared by nominal tip path length; it is
// written as G93 inverse time (default) or as G94 per minute over the
// piece's machine X Y Z length (kPerMinute).
//
// Writing: lines without a move pass byte for byte, except that G93/G94
// words move to the feed moves and LinuxCNC's kinematics switches
// (M428 M429 M430) become a comment: the output commands machine axes (run
// it in identity kinematics, G54 offset zero). A move line keeps its other
// words; its axis words become every machine axis, in the machine's axis
// order; added pieces follow as lines of their own.
// Streaming: one line at a time (the first 2000 buffered for detection).
#pragma once

#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>

#include "core/model/error_model.h"
#include "maps/tables/volumetric_table.h"
#include "postproc/five_axis/five_axis_input.h"

namespace volmap::post {

enum class FeedOutput { kInverseTime, kPerMinute };

struct FiveAxisPostOptions {
  InputForm form = InputForm::kAuto;
  double tolerance_mm = 1e-3;
  double angle_tolerance_rad = 50e-6;
  int decimals = -1;       ///< linear axes; -1: 4 in mm, 5 in inch
  int angle_decimals = 5;  ///< rotary axes, degrees
  FeedOutput feed = FeedOutput::kInverseTime;
  InitialPose initial;
  OutsidePolicy outside = OutsidePolicy::kError;
  /// One-step correction (1) or iterated to the exact solution (more).
  int correction_iterations = 1;
  /// Tool table: tool number -> how much longer than the machine file's
  /// tool (mm; LinuxCNC .tbl Z). Empty: the machine file's tool is the only
  /// one (a second tool after moves is refused).
  std::map<int, double> tool_offsets_mm;

  std::string invalid_reason() const;
};

struct FiveAxisPostReport {
  InputForm form = InputForm::kAuto;
  std::uint64_t lines = 0, lines_changed = 0, lines_added = 0;
  std::uint64_t moves = 0, poses = 0, singular_poses = 0;
  double max_correction_mm = 0.0, max_correction_rad = 0.0;
  /// Largest change of a rotary axis between consecutive written positions
  /// of feed moves (rad).
  double max_rotary_step_rad = 0.0;
};

/// `machine`: the part origin already placed (Machine::workpiece_origin_mm).
FiveAxisPostReport post_five_axis(std::istream& in, const std::string& in_name, std::ostream& out,
                                  const Machine& machine, const ErrorSet& errors,
                                  const FiveAxisPostOptions& options);

/// The same with the errors from a five-axis volumetric table (volmap map)
/// instead of the model (FiveAxisTransform's table constructor; one-step
/// correction, segmentation checks against the table's dv).
FiveAxisPostReport post_five_axis(std::istream& in, const std::string& in_name, std::ostream& out,
                                  const Machine& machine, const maps::VolumetricTable& table,
                                  const FiveAxisPostOptions& options);

/// The nominal tool axis at path parameter s of a move (unit; slerp for
/// vector moves). For by-angle moves it is not used (the angles are).
Eigen::Vector3d slerp_axis(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, double s);

}  // namespace volmap::post
