// FiveAxisPost, the five-axis post of one program (internal to
// postproc/five_axis/; five_axis_post.h is the interface and says what it
// does). five_axis_post.cc writes the lines, five_axis_segmenter.cc cuts a
// move into pieces within the tolerances.
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "core/common/input_error.h"
#include "core/common/units.h"
#include "gcode/g_codes.h"
#include "gcode/nc_path.h"
#include "gcode/nc_writer.h"
#include "postproc/five_axis/five_axis_post.h"
#include "postproc/five_axis/five_axis_transform.h"

namespace volmap::post::five_axis_detail {

using Eigen::Vector3d;

inline double angle_between(const Vector3d& a, const Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// The nominal pose of a move at path parameter s and its nominal axes.
struct NominalAt {
  ToolPose v;
  AxisVector u;
  bool singular = false;
};

class FiveAxisPost {
 public:
  FiveAxisPost(const std::string& file, std::ostream& out, ToolTransforms& tools,
               const FiveAxisPostOptions& o)
      : file_(file), out_(out), o_(o), tools_(tools), tf_(&tools.get(-1)) {
    const Machine& m = tf_->machine();
    u_nom_ = m.home;
    for (int k = 0; k < m.axis_count(); ++k)
      if (is_rotary(m.axis_order[static_cast<size_t>(k)]) && o.initial.q.size() == m.axis_count())
        u_nom_[k] = o.initial.q[k];
  }

  void run(FiveAxisReader& reader);
  FiveAxisPostReport report_;

 private:
  NominalAt nominal_at(const FiveAxisMove& m, double s, const AxisVector& previous) const {
    NominalAt n;
    n.v.tip_mm = nc::point_on(m.tip, s);
    if (m.by_angles) {
      const AxisVector q = m.q0 + s * (m.q1 - m.q0);
      n.u = tf_->axes_for_angles(q, n.v.tip_mm);
      n.v.axis = tf_->nominal(n.u).axis;
    } else {
      n.v.axis = slerp_axis(m.a0, m.a1, s);
      n.u = tf_->axes_for_pose(n.v, previous, &n.singular);
    }
    return n;
  }
  AxisVector command(const AxisVector& u_nom) {
    const Machine& m = tf_->machine();
    try {
      check_within_travel(m, u_nom);
    } catch (const std::invalid_argument& e) {
      fail(std::string(e.what()) + "; place the part elsewhere on the table (`part_origin`)");
    }
    const AxisVector c = tf_->command(u_nom);
    double lin = 0, rot = 0;
    for (int k = 0; k < m.axis_count(); ++k) {
      const double d = c[k] - u_nom[k];
      (is_rotary(m.axis_order[static_cast<size_t>(k)]) ? rot : lin) += d * d;
    }
    if (!std::isfinite(lin + rot)) fail("the correction is not finite here; check the errors file");
    report_.max_correction_mm = std::max(report_.max_correction_mm, std::sqrt(lin));
    report_.max_correction_rad = std::max(report_.max_correction_rad, std::sqrt(rot));
    try {
      check_within_travel(m, c);
    } catch (const std::invalid_argument& e) {
      fail(std::string(e.what()) + "; place the part elsewhere on the table (`part_origin`)");
    }
    ++report_.poses;
    return c;
  }
  [[noreturn]] void fail(const std::string& msg) const { throw InputError(file_, line_, msg); }

  struct Piece {
    AxisVector c;  ///< commanded
    double s1;
    bool forced = false;  ///< accepted at the smallest span (a turn at the singular position)
  };
  // The written axis words of c without letters (to find repeated lines).
  std::string axes_key(const AxisVector& c, double unit_mm) const {
    const Machine& mach = tf_->machine();
    const int dec = o_.decimals >= 0 ? o_.decimals : (unit_mm > 1.0 ? 5 : 4);
    std::string k;
    for (int i = 0; i < mach.axis_count(); ++i) {
      if (is_rotary(mach.axis_order[static_cast<size_t>(i)]))
        append_number(k, c[i] * units::kDegPerRad, o_.angle_decimals);
      else
        append_number(k, c[i] / unit_mm, dec);
      k += ' ';
    }
    return k;
  }
  void segment(const FiveAxisMove& m, std::vector<Piece>& pieces);
  /// Where the backward solution jumps between s0 and s1 (C leaving the
  /// singular position): the pieces that turn the rotary axes over the jump
  /// into turn_.
  void turn_over_jump(const FiveAxisMove& m, double s0, double s1, const NominalAt& n1,
                      const AxisVector& c1, double tol);
  void start_if_needed(const FiveAxisMove& m);
  double move_time_min(const FiveAxisMove& m) const;
  void write_line(const FiveAxisLine& l);
  /// A line without a move: G93/G94 moved to the feed moves, G91 made G90,
  /// kinematics switches made a comment.
  void write_line_without_move(const FiveAxisLine& l, bool lower);
  /// The commanded pieces of move m into pieces_.
  void pieces_of_move(const FiveAxisMove& m);
  /// pieces_ without those that would repeat the position before them at
  /// the written resolution.
  void merge_repeated_pieces(const AxisVector& from, double unit_mm);
  /// The block of a move line with its first piece's words.
  void write_first_piece(const FiveAxisLine& l, bool lower, const std::string& words, bool newline);
  std::string move_text(const AxisVector& c, double unit_mm, bool lower, bool spaces, int motion,
                        double feed_for_piece, const AxisVector& from);
  void emit(const std::string& text, bool newline = true) {
    out_ << text;
    if (newline) out_ << line_ending_;
  }

  std::string file_;
  std::ostream& out_;
  FiveAxisPostOptions o_;
  /// A tool change (FiveAxisLine::tool): the transform of the new tool
  /// from the tool table; without one, a second tool after moves is
  /// refused.
  void change_tool(const FiveAxisLine& l);
  ToolTransforms& tools_;
  const FiveAxisTransform* tf_;  ///< the tool in the spindle's
  bool rapid_due_ = false;       ///< a tool was changed: the next move must be a rapid
  int line_ = 0;
  std::string line_ending_ = "\n";
  bool reader_newline_ = true;
  bool fanuc_points_ = false;  ///< every number written with its point (FiveAxisReader::fanuc_head)
  bool started_ = false;
  AxisVector u_nom_;  ///< nominal axes at the end of the last move
  /// Whole turns added to the programmed angles of each unlimited rotary
  /// axis (TCP input): see unwrap_turns.
  AxisVector turns_;

  // A TCP program may send an unlimited rotary axis round by a turn or more
  // on a rapid (LinuxCNC's demos end with G0 C0 after C-399.8, unwinding a
  // counter); the pose is the same at the nearest equivalent angle. At a
  // rapid the programmed angle is taken as the representative within half
  // a turn of where the axis is, and the whole turns so added stay with
  // every later programmed angle, so feed moves sweep exactly as
  // programmed: C never jumps by 180 degrees or more between two lines.
  void unwrap_turns(FiveAxisMove& m) {
    const Machine& mach = tf_->machine();
    if (turns_.size() != mach.axis_count()) turns_ = AxisVector::Zero(mach.axis_count());
    if (m.q1.size() != mach.axis_count()) return;
    for (int k = 0; k < mach.axis_count(); ++k) {
      if (!is_rotary(mach.axis_order[static_cast<size_t>(k)]) ||
          !mach.limits[static_cast<size_t>(k)].unlimited)
        continue;
      if (m.rapid) {
        const double d = m.q1[k] + turns_[k] - u_nom_[k];
        if (std::abs(d) >= M_PI) turns_[k] -= 2.0 * M_PI * std::nearbyint(d / (2.0 * M_PI));
      }
      if (m.q0.size() == mach.axis_count()) m.q0[k] += turns_[k];
      m.q1[k] += turns_[k];
    }
  }
  AxisVector c_;                                ///< commanded axes at the end of the last move
  double residual_angle_ = 0.0;                 ///< tool-axis error left there (rad)
  int out_motion_ = -1;                         ///< modal motion of the output (x10), -1 unknown
  int out_feed_mode_ = nc::kG94UnitsPerMinute;  ///< modal feed mode of the output
  std::vector<Piece> pieces_;
  std::vector<std::pair<double, double>> stack_;  ///< segmentation work list (reused)
  std::vector<Piece> turn_;                       ///< pieces of one accepted step (reused)
};

}  // namespace volmap::post::five_axis_detail
