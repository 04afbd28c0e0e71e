// Step 3 of the interpreter's validation (nc_interpreter.h) for one block:
// the values checked against the state, in RS274NGC order, and the state
// the block leads to computed into a copy. Internal to the interpreter.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>

#include "gcode/block_words.h"
#include "gcode/nc_interpreter.h"

namespace volmap::nc {

/// The straight move (G0 or G1) of a block of axis words (program units by
/// axis, bit a of `given` for each word) from state `s` with `work_offset_mm`
/// active: the end point, `motion`'s kind, ends and feed; `s`'s position
/// and the axes known.
void straight_move(const Eigen::Vector3d& work_offset_mm, const double (&value)[3], unsigned given,
                   State& s, Motion& motion);

class BlockCheck {
 public:
  /// `s` is the state before the block, and after run() the state after it.
  BlockCheck(const ProgramSetup& setup, const std::string& file, const Block& b, BlockWords& words,
             State& s, BlockEffect& effect);
  void run();

 private:
  [[noreturn]] void fail(const Word* w, const std::string& msg) const {
    refuse_block(file_, b_, w, msg);
  }
  const Word* word(char L) const { return words_.letter[static_cast<size_t>(L - 'A')]; }
  /// Work offset of the coordinate system active in s_, mm.
  const Eigen::Vector3d& work_offset() const { return s_.origin_mm; }

  // block_check.cc
  void check_polar_words() const;
  /// The block of most programs (axis words and F in G0 or G1): true when
  /// this was one and has been done.
  bool common_block();
  void general_steps();
  void feed_tool_and_spindle();
  void tool_length();
  void distance_and_coordinate_modes();
  /// G28 G30 (a rapid through the axis words' point to the stored
  /// position) and G28.1 G30.1 (store where the axes are): home.cc.
  void home(int code10);
  /// G10 L2/L20 and G92 G92.1 G92.2 G92.3: offsets.cc.
  void offsets(int code10);
  /// G10 L1: a row of the tool table (offsets.cc), into effect_.tool_row.
  void tool_table_row();
  /// What Fanuc's offsets refuse (offsets.cc).
  void fanuc_offsets(int code10);
  /// Whether the block moves, and the refusals of words that need a motion.
  bool motion_in_block(bool any_axis);
  /// LinuxCNC's check_other_codes: a word no code of the block uses.
  void unused_words(bool motion_here);

  // block_motion.cc
  void motion(int motion_before);
  void polar_target(double at_x, double at_y, bool xy_known, Eigen::Vector3d& target,
                    std::array<bool, 3>& given) const;
  void arc(Motion& mo, const Eigen::Vector3d& target, const std::array<bool, 3>& given);
  /// G33.1: a rigid tap to `target` and back (block_motion.cc).
  void rigid_tap(Motion& mo, const Eigen::Vector3d& target) const;
  /// The rotary axes' end (A B C words) of a motion of `kind`.
  void rotary_targets(MotionKind kind);
  /// A tool-vector program's new tool axis (I J K of a straight move).
  void straight_tool_axis();

  // cutter_comp.cc
  /// G40 G41 G42 G41.1 G42.1 and D: the side and radius into the state.
  void cutter_comp();
  /// The diameter (mm) a G41/G42's D names, or the spindle's tool's.
  double comp_diameter_mm(const Word* code, const Word* d) const;
  /// G41 G42 G41.1 G42.1: the side, the radius, the entry to come.
  void turn_compensation_on(const Word* code, const Word* d, bool on_before);
  /// Refuses what may not happen while cutter compensation is on: what
  /// runs before its step in LinuxCNC's order (before_step), or after.
  void refuse_while_compensating(bool before_step) const;
  /// The motion's part in cutter compensation (effect_.comp_role).
  void comp_role();
  /// A straight side cut back by two inside corners: refused where the
  /// tool cannot reach it, its slack into effect_ (cutter_comp.cc).
  void comp_side_reach(CompRole role);
  // fanuc_rules.cc
  /// The Fanuc dialect's checks of the words (decimal points, G04's X).
  void fanuc_words();
  bool fanuc() const { return setup_.dialect == Dialect::kFanuc; }

  // canned_cycles.cc
  /// The checks of a cycle block and its modal R Z Q; returns the repeats (L).
  int cycle_words(int motion_before);
  /// A canned cycle's holes into effect_ (motion and more_holes); returns
  /// where the tool ends.
  Eigen::Vector3d cycle(Motion& mo, int motion_before, double at_x, double at_y, bool xy_known,
                        const Eigen::Vector3d& target);

  const ProgramSetup& setup_;
  const std::string& file_;
  const Block& b_;
  BlockWords& words_;
  State& s_;
  BlockEffect& effect_;
  // The slots of words_, by their names in the steps.
  const std::array<const Word*, kGroupCount>& g;
  const std::array<const Word*, kMGroupCount>& m;
  const Word* const polar_radius;
  const Word* const polar_angle;
  const bool polar;
  bool consumed_axes_ = false;  ///< G43.1 took the Z word
  bool g53_ = false;
  bool dwell_time_given_ = false;  ///< Fanuc: G04 X (seconds)
};

}  // namespace volmap::nc
