// ProgramPost::plain_line: the shortcut for a line of plain axis words
// (docs/post.md "Speed"); its output is byte for byte line()'s.
#include <vector>

#include "gcode/g_codes.h"
#include "gcode/nc_block.h"
#include "postproc/three_axis/program_post.h"
#include "postproc/three_axis/travel_check.h"

namespace volmap::post {

bool ProgramPost::plain_line(std::string_view text, const nc::PlainAxisWords* read) {
  const nc::State& st = interp_.state();
  // The state the line needs (the rest is execute_linear_axes's): the same
  // tool as the last line, errors, the controller's position known, G90,
  // no inverse time.
  if (!options_.shortcuts || !emitted_known_ || !st.absolute ||
      st.feed_mode == nc::kG93InverseTime || !last_corrector_ ||
      machine_.tool_length_mm + st.tool_length_mm != last_corrector_length_ ||
      last_corrector_->zero())
    return false;
  nc::PlainAxisWords parsed;
  if (!read && !nc::lex_plain_axis_words(text, parsed)) return false;
  const nc::PlainAxisWords& words = read ? *read : parsed;
  if (!interp_.execute_linear_axes(words.value, words.given, plain_motion_)) return false;
  ++report_.moves;
  if (self_check_) self_check_->nominal(plain_motion_);
  if (st.position_known)  // as line() checks every motion
    check_travel(machine_, plain_motion_, *last_corrector_, st.origin_mm, *line_file_,
                 current_line_);
  // From here on, line()'s path for a straight feed move, step by step.
  ctrl_il_known_ = false;  // the run of cycle blocks has ended
  const Corrector& c = *last_corrector_;
  const std::vector<Piece>& pieces = segment(c, plain_motion_, emitted_mm_);
  // axis_needs_word for the three axes, its constants taken once (G90, no
  // G53: program value = (machine - origin) / unit, no division in mm).
  unsigned needed = 0;
  {
    const double half = half_unit(decimals()), unit = st.unit_mm;
    const Vector3d& origin = interp_.work_offset();
    const Vector3d& cmd = pieces[0].command_mm;
    for (int a = 0; a < 3; ++a) {
      const double v = unit == 1.0 ? cmd[a] - origin[a] : (cmd[a] - origin[a]) / unit;
      const double old =
          (words.given >> a & 1u)
              ? words.value[a]
              : (unit == 1.0 ? emitted_mm_[a] - origin[a] : (emitted_mm_[a] - origin[a]) / unit);
      if (std::abs(v - old) >= half) needed |= 1u << a;
    }
  }
  if (needed == 0 && pieces.size() == 1) {
    // unchanged(): the line as written, the controller where its words say
    // (the move's end)
    emit(text);
    for (int a = 0; a < 3; ++a)
      if (words.given >> a & 1u) emitted_mm_[a] = plain_motion_.end_mm[a];
    emitted_exact_ = true;
    return true;
  }
  if (needed != 7u) {
    // Some word keeps its text: the fewest changes, through a Block
    // (first_piece_minimal; seldom with real errors, which move every axis).
    nc::lex_block_into(text, current_line_, *line_file_, block_);
    block_.file = line_file_ == &file_ ? nullptr : line_file_;
    fx_.motion = plain_motion_;
    fx_.g53 = false;
    fx_.homed_axes = 0;
    fx_.has_motion = true;
    first_piece_minimal(text, block_, fx_, block_style(block_), pieces);
    return true;
  }
  // Every axis changes: the edited line is the first piece's words alone
  // (the line's words are all axis words, X Y Z in that order).
  previous_words_.clear();
  append_axis_words(pieces[0].command_mm, false, words.lower, words.spaced, previous_words_);
  emit(previous_words_.view());
  ++report_.lines_changed;
  emitted_mm_ = pieces[0].command_mm;  // reached(): G90
  emitted_exact_ = false;
  emit_following_pieces(
      pieces, false, words.lower, words.spaced, true, [&](size_t k, CharBuffer& w) {
        w.clear();
        append_axis_words(pieces[k].command_mm, false, words.lower, words.spaced, w);
      });
  return true;
}

}  // namespace volmap::post
