// The post's self-check (docs/post.md, "Self-check"): every line the post
// writes is read back, before anything is committed, by an interpreter of
// its own, as the controller will read the text: from where the written
// program, not the post's reckoning, leaves the machine (a G91 increment, a
// polar word, a modal state). Each point it commands, and points between
// them, moved by the error model with each axis's play, must lie within
// the tolerance of the nominal moves of the line it was written for (or of
// the lines just before: a piece of a move begins where the last ended).
// A point beyond it is a refusal at that line: a bug of the post, which
// would otherwise cut the wrong part.
//
// What it samples: the end of every feed move (where the play and the
// correction are settled), straight moves every kLineStepMm between (the
// error field's curvature is all a straight move adds between its ends),
// arcs every kArcStepMm and at least kArcSamples times (an axis reverses
// inside an arc), and the bottom of each canned-cycle hole and rigid tap
// (the feed between is the controller's line, which the post warns of).
// What it does not see: a misread of the input, which fools the post and
// the check alike (the conformance engine, tests/conformance/, judges the
// reading against LinuxCNC's own).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "postproc/three_axis/corrector.h"

namespace volmap::post {

struct SelfCheckStats {
  std::uint64_t points = 0;  ///< points moved by the model and measured
  double max_mm = 0.0;       ///< the farthest from the nominal moves (an upper bound)
};

class SelfCheck {
 public:
  static constexpr double kLineStepMm = 0.25;  ///< as verify samples (VerifyOptions)
  static constexpr double kArcStepMm = 0.25;
  static constexpr int kArcSamples = 16;
  /// The model is evaluated at anchors; points near one take its
  /// first-order expansion (forward differences kAnchorStepMm apart) and
  /// the curvature bound's remainder, at most a quarter of the tolerance;
  /// a point beyond the tolerance by that bound is evaluated exactly.
  static constexpr double kAnchorStepMm = 0.1;

  /// `post`: the post's interpreter, whose dialect (the reader's choice)
  /// this one takes at the first line.
  SelfCheck(const nc::Interpreter& post, const nc::ProgramSetup& setup, const std::string& file,
            double tolerance_mm);
  /// The nominal motion of the input line being written (with a cycle's
  /// further holes): what its output is measured against.
  void nominal(const nc::Motion& m, const std::vector<nc::Motion>* more_holes = nullptr);
  /// The text written for input line `line` of `file` (its output lines,
  /// '\n' after each). Throws InputError at that line where a point leaves
  /// the tolerance or the text does not read back.
  void written(std::string_view text, const Corrector& c, const std::string& file, int line);
  /// Output lines that are not run (tape leader, trailer): counted only.
  void skipped(std::string_view text);
  const SelfCheckStats& stats() const { return stats_; }

 private:
  struct Nominal {
    nc::Motion motion;
    bool valid = false;
  };
  void read_line(std::string_view t, const Corrector& c, const std::string& file, int line);
  void feed(const nc::Motion& m, const Corrector& c, const std::string& file, int line);
  /// A straight move checked by its ends and the field's bounds; false:
  /// sample it instead.
  bool smooth_line(const nc::Motion& m, const Corrector& c);
  void hole(const nc::Motion& h, const Corrector& c, const std::string& file, int line);
  /// The actual tool tip at commanded point x (mm), with the play; how far
  /// it may be off the model's (an anchor's expansion) in bound_mm_.
  Eigen::Vector3d actual(const Corrector& c, const Eigen::Vector3d& x);
  /// The play taken up from previous_ to `to`, which becomes previous_.
  void take_up(const Corrector& c, const Eigen::Vector3d& to);
  /// The actual tip at commanded x measured (InputError beyond the tolerance).
  void measure(const Eigen::Vector3d& x, const Corrector& c, const std::string& file, int line);
  void push(const nc::Motion& m);

  const nc::Interpreter& post_;
  nc::Interpreter interp_;
  bool dialect_set_ = false;
  double tolerance_mm_;
  nc::Block block_;
  nc::BlockEffect fx_;
  nc::PlainAxisWords plain_;
  nc::Motion plain_motion_;
  std::string file_;
  /// The nominal feed moves of the line being written (a cycle's holes),
  /// and of the lines before it (newest at head_): a written piece lies on
  /// its line's move or on one just before it.
  std::vector<Nominal> current_;
  std::array<Nominal, 4> ring_{};
  std::size_t head_ = 0;
  /// The ring's move nearest p (null: the ring is empty), its distance in
  /// best_mm_; the search stops at the first within the tolerance.
  const Nominal* nearest(const Eigen::Vector3d& p);
  double best_mm_ = 0.0;
  Eigen::Vector3d last_actual_ = Eigen::Vector3d::Zero();  ///< the actual tip at previous_
  double last_bound_mm_ = 0.0;                             ///< and how far it may be off
  bool have_actual_ = false;
  double bound_mm_ = 0.0;  ///< actual()'s bound
  Eigen::Vector3d anchor_x_ = Eigen::Vector3d::Zero(), anchor_e_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d anchor_j_ = Eigen::Matrix3d::Zero();
  ApproachDirections anchor_dirs_{};
  bool anchor_valid_ = false;
  bool exact_ = false;  ///< actual() evaluates the model, no expansion
  double anchor_radius_mm_ = 0.0;
  void set_anchor_radius(const Corrector& c);
  Eigen::Vector3d previous_ = Eigen::Vector3d::Zero();  ///< where the play was last taken up to
  Eigen::Vector3d play_ = Eigen::Vector3d::Zero();      ///< each axis's play state, -1 .. 1
  bool moved_ = false;  ///< the written program moved (its first start: where the machine stood)
  long lines_with_motion_ = 0;  ///< input lines with motion so far
  bool first_line_ = true;      ///< the line being written is the input's first with motion
  bool skip_ = false;           ///< the written line is run, not measured (block delete)
  bool from_skipped_ = false;   ///< the motion before was such a line
  unsigned named_ = 0;          ///< bit a: the written program has named axis a (a word, G28/G30)
  long out_line_ = 0;           ///< lines of the written program read
  SelfCheckStats stats_;
};

}  // namespace volmap::post
