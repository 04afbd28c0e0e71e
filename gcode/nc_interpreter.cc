#include "gcode/nc_interpreter.h"

#include <numbers>

#include "gcode/block_check.h"
#include "gcode/block_words.h"

namespace volmap::nc {

Interpreter::Interpreter(ProgramSetup setup, std::string file)
    : setup_(std::move(setup)), file_(std::move(file)) {
  if (setup_.initial_position_mm) {
    s_.position_mm = *setup_.initial_position_mm;
    s_.position_known = true;
    s_.axis_known = {true, true, true};
  }
  s_.rotary_rad = setup_.initial_rotary_rad;
  s_.coord_offset_mm = setup_.work_offset_mm;
  // A G92 offset the parameter file keeps (LinuxCNC keeps it across runs).
  auto parameter = [&](int n) {
    const auto it = setup_.parameters.find(n);
    return it == setup_.parameters.end() ? 0.0 : it->second;
  };
  s_.g92_mm = Eigen::Vector3d(parameter(5211), parameter(5212), parameter(5213));
  s_.g92_applied = parameter(5210) != 0.0;
  s_.update_origin();
  // G28's and G30's positions, where the parameter file gives them
  // (#5161.. and #5181..: X Y Z in mm, A B C in degrees).
  for (int k = 0; k < 2; ++k)
    for (int a = 0; a < 6; ++a)
      if (const auto it = setup_.parameters.find((k == 0 ? 5161 : 5181) + a);
          it != setup_.parameters.end()) {
        s_.home[static_cast<size_t>(k)][static_cast<size_t>(a)] =
            a < 3 ? it->second : it->second * std::numbers::pi / 180.0;
        s_.home_known[static_cast<size_t>(k)][static_cast<size_t>(a)] = true;
      }
  s_.tool_axis = setup_.initial_tool_axis;
}

void Interpreter::set_dialect(Dialect d) {
  setup_.dialect = d;
  if (d != Dialect::kFanuc) return;
  // Fanuc's G28 goes to the first reference position: machine coordinates
  // from parameter 1240, zero unless the builder set it (#5161.. of a
  // parameter file give other values).
  for (int a = 0; a < 6; ++a)
    if (!s_.home_known[0][static_cast<size_t>(a)]) {
      s_.home[0][static_cast<size_t>(a)] = 0.0;
      s_.home_known[0][static_cast<size_t>(a)] = true;
    }
}

bool Interpreter::execute_linear_axes(const double (&value)[3], unsigned given, Motion& motion,
                                      bool g1) {
  // execute()'s short path, less what cannot fail here: no F word, no
  // other letter, the position known, G1 with a feed rate.
  if (s_.ended || s_.motion != kG1Linear || fanuc() || !s_.position_known || s_.comp_side != 0 ||
      s_.comp_exit_pending || (s_.feed <= 0.0 && s_.feed_mode != kG93InverseTime) || given == 0 ||
      given > 7)
    return false;
  if (g1) {  // the G1 word restates the mode (BlockCheck::general_steps)
    s_.group01 = kG1Linear;
    s_.group01_given = true;
  }
  straight_move(work_offset(), value, given, s_, motion);
  return true;
}

State Interpreter::check(const Block& b, BlockEffect& effect) const {
  // Every field as BlockEffect{} has it, without building and moving a
  // whole one (more_holes keeps its storage for the next cycle block).
  effect.has_motion = false;
  effect.motion = Motion{};
  effect.g53 = false;
  effect.stop_code = false;
  effect.motion_code = -1;
  effect.comp_role = CompRole::kNone;
  effect.tool_row = ToolTableWrite{};
  effect.comp_slack_mm = INFINITY;
  effect.more_holes.clear();
  effect.homed_axes = 0;
  effect.stores_home = false;
  effect.offsets_from_position = false;
  State after = s_;
  if (b.percent || b.words.empty()) return after;
  if (s_.ended) return after;  // after M2/M30 nothing executes (LinuxCNC ignores the rest)
  BlockWords words;
  collect_block_words(b, file_, setup_.rotary_axes, words);  // steps 1 and 2
  BlockCheck(setup_, file_, b, words, after, effect).run();  // step 3
  return after;
}

void Interpreter::execute(const Block& b, BlockEffect& effect) {
  s_ = check(b, effect);  // step 4: only a block that passed changes the state
  if (const ToolTableWrite& row = effect.tool_row; row.tool >= 0) {
    if (row.length_mm) setup_.tool_length_mm[row.tool] = *row.length_mm;
    if (row.diameter_mm) setup_.tool_diameter_mm[row.tool] = *row.diameter_mm;
  }
}

}  // namespace volmap::nc
