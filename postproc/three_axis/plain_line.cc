// ProgramPost::plain_line: the shortcut for a line of plain axis words
// (docs/post.md "Speed"); its output is byte for byte line()'s.
#include <cstdlib>
#include <string>
#include <vector>

#include "gcode/g_codes.h"
#include "gcode/nc_block.h"
#include "postproc/three_axis/program_post.h"
#include "postproc/three_axis/travel_check.h"

namespace volmap::post {
namespace {

// A number written with `dec` decimals at w's end (format_number's text),
// and the program value the controller reads from it (strtod's).
double append_read_number(CharBuffer& w, double value, int dec) {
  double read;
  if (const char* end = nc::format_number_fast(value, dec, w.room(nc::kNumberRoom), &read)) {
    w.commit(end);
    return read;
  }
  // format_number's general path (large values, near a tie, many decimals)
  const std::string number = nc::format_number(value, dec);
  w.append(number);
  return std::strtod(number.c_str(), nullptr);
}

// The plain line `text` (its words w) with the fewest changes, byte for
// byte as minimal_axis_words and apply_edit write it through a Block: the
// word of each axis in `needed` renumbered in place for command cmd (its
// letter and the separators kept), the needed axes the line does not name
// added after its last word in X Y Z order (a space before each when the
// line spaces its words), every other word (and a G1) as it is. Into out;
// read_mm[a]: where the controller stands on axis a after it (G90, machine
// frame), for every axis the line names or needs.
void write_plain_minimal(std::string_view text, const nc::PlainAxisWords& w, unsigned needed,
                         const Vector3d& cmd, const Vector3d& origin, double unit, int dec,
                         CharBuffer& out, double (&read_mm)[3]) {
  // program value = (machine - origin) / unit, no division in mm (as program_value)
  const auto program = [&](int a) {
    return unit == 1.0 ? cmd[a] - origin[a] : (cmd[a] - origin[a]) / unit;
  };
  for (int a = 0; a < 3; ++a)
    if (w.given >> a & 1u) read_mm[a] = origin[a] + w.value[a] * unit;
  // The words as lex_plain_axis_words read them, after a G1 word: a
  // letter, its number up to a space or the next letter.
  const char* const begin = text.data();
  const char* const end = begin + text.size();
  const char* kept = begin;  // copied up to here
  for (const char* p = begin + w.g1; p != end;) {
    const int a = (*p | 0x20) - 'x';
    const char* const letter = p++;
    while (p != end && *p != ' ' && static_cast<unsigned>((*p | 0x20) - 'x') > 2u) ++p;
    if (needed >> a & 1u) {
      out.append(std::string_view(kept, static_cast<std::size_t>(letter + 1 - kept)));
      read_mm[a] = origin[a] + append_read_number(out, program(a), dec) * unit;
      kept = p;
    }
    if (p != end && *p == ' ') ++p;
  }
  out.append(std::string_view(kept, static_cast<std::size_t>(end - kept)));
  for (int a = 0; a < 3; ++a) {
    if (!(needed >> a & 1u) || (w.given >> a & 1u)) continue;
    if (w.spaced) out.append(" ");
    out.append(std::string_view(&(w.lower ? "xyz" : "XYZ")[a], 1));
    read_mm[a] = origin[a] + append_read_number(out, program(a), dec) * unit;
  }
}

}  // namespace

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
  if (!interp_.execute_linear_axes(words.value, words.given, plain_motion_, words.g1 != 0))
    return false;
  ++report_.moves;
  if (self_check_) self_check_->nominal(plain_motion_);
  // What line()'s check_compensation does for a move outside cutter
  // compensation (the shortcut runs only there): after a G40 exit, the
  // lines that follow are no compensated moves.
  comp_move_ = false;
  comp_tangent_in_.setZero();
  comp_factor_ = 2.0;
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
  if (needed != 7u || words.g1) {
    // Some word keeps its text (a line of X and Y words whose Z correction
    // has not moved half an output unit: every line of a circle in the XY
    // plane), or the G1 word: the fewest changes, as first_piece_minimal
    // writes them.
    double read_mm[3];
    words_.clear();
    write_plain_minimal(text, words, needed, pieces[0].command_mm, interp_.work_offset(),
                        st.unit_mm, decimals(), words_, read_mm);
    emit(words_.view());
    if (needed != 0) ++report_.lines_changed;
    // Where the controller stands: the numbers it reads, and on an axis the
    // line does not name, where it stood.
    for (int a = 0; a < 3; ++a)
      if ((words.given | needed) >> a & 1u) emitted_mm_[a] = read_mm[a];
    emitted_exact_ = true;
    if (pieces.size() > 1) {
      previous_words_.clear();
      append_axis_words(pieces[0].command_mm, false, words.lower, words.spaced, previous_words_);
      emit_following_pieces(
          pieces, false, words.lower, words.spaced, true, [&](size_t k, CharBuffer& w) {
            w.clear();
            append_axis_words(pieces[k].command_mm, false, words.lower, words.spaced, w);
          });
    }
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
