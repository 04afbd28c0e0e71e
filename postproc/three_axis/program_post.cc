// ProgramPost::line: one line of the program read, executed and written;
// the dispatch to the paths of program_post.h, lines left unchanged, and
// feed moves (lines, arcs, helices) cut into pieces.
#include "postproc/three_axis/program_post.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "core/common/input_error.h"
#include "gcode/g_codes.h"
#include "gcode/nc_path.h"
#include "maps/tables/volumetric_table.h"
#include "postproc/three_axis/travel_check.h"

namespace volmap::post {

const Corrector& ProgramPost::corrector() {
  // The tool's length: the machine file's tool (the one of offset zero)
  // plus the active tool length offset.
  const double offset = interp_.state().tool_length_mm;
  const double L = machine_.tool_length_mm + offset;
  // The same tool as the line before (almost always): no map search.
  if (last_corrector_ && L == last_corrector_length_) return *last_corrector_;
  auto it = correctors_.find(L);
  if (it == correctors_.end()) {
    if (table_ && offset != 0.0)
      // The table's errors are those of the machine file's tool; angular
      // errors act on another tool through another lever.
      throw InputError(
          *line_file_, current_line_,
          fmt::format("the tool length offset here is {:g} mm, but a compensation table holds the "
                      "errors of the machine file's {:g} mm tool only; post with `errors` instead",
                      offset, machine_.tool_length_mm));
    it = correctors_
             .emplace(L, table_
                             ? std::make_unique<Corrector>(machine_, *table_, options_.outside)
                             : std::make_unique<Corrector>(machine_, errors_, L, options_.outside))
             .first;
  }
  last_corrector_length_ = L;
  last_corrector_ = it->second.get();  // map nodes stay put: the pointer stays valid
  return *it->second;
}

BlockStyle block_style(const nc::Block& b) {
  // One pass over the words: the indices of X, Y and Z (asked for again and
  // again by the writer), the case of the first letter and any gap.
  BlockStyle style;
  bool case_known = false, spaced = false;
  const size_t n = b.words.size();
  std::uint32_t prev_end = 0;
  for (size_t k = 0; k < n; ++k) {
    const nc::Word& w = b.words[k];
    const char L = w.letter;
    if (L >= 'X' && L <= 'Z' && style.axis_index[L - 'X'] < 0)
      style.axis_index[L - 'X'] = static_cast<int>(k);
    if (!case_known && L != '@' && L != '^') {
      case_known = true;
      style.lower = b.text[w.begin] >= 'a';
    }
    if (k > 0 && w.begin > prev_end) spaced = true;
    prev_end = w.end;
  }
  style.spaces = spaced || n <= 1;
  return style;
}

void ProgramPost::write_unchanged(std::string_view text, const nc::Block& b,
                                  const nc::BlockEffect& fx) {
  emit(text);
  if (fx.homed_axes != 0) {
    // The controller stands at the stored position on those axes exactly;
    // the block's axis words were the point on the way.
    for (int a = 0; a < 3; ++a)
      if (fx.homed_axes & (1u << a)) emitted_mm_[a] = interp_.state().position_mm[a];
  } else if (fx.has_motion && fx.motion.kind == nc::MotionKind::kTap) {
    // A rigid tap comes back to where the controller stood.
  } else if (fx.has_motion) {
    if (!emitted_known_ || fx.motion.kind == nc::MotionKind::kCycle) {
      emitted_mm_ = interp_.state().position_mm;
    } else {
      const nc::State& st = interp_.state();
      const bool polar = b.has('@') || b.has('^');
      // @ ^ name X and Y, from where the output left the controller.
      const Eigen::Vector2d polar_xy = polar ? polar_reach_mm(b) : Eigen::Vector2d::Zero();
      for (int a = 0; a < 3; ++a) {
        const nc::Word* w = b.find("XYZ"[a]);
        if (polar && a < 2) {
          emitted_mm_[a] = polar_xy[a];
          continue;
        }
        if (!w) continue;
        emitted_mm_[a] = st.absolute
                             ? w->value * st.unit_mm + (fx.g53 ? 0.0 : interp_.work_offset()[a])
                             : emitted_mm_[a] + w->value * st.unit_mm;
      }
    }
  }
  if (fx.has_motion) emitted_exact_ = true;
  emitted_known_ = interp_.state().position_known;
}

void ProgramPost::line(std::string_view raw, int number, bool newline,
                       const nc::PlainAxisWords* plain) {
  current_line_ = number;
  ++report_.lines;
  // The line ending goes out as it came in (CRLF stays CRLF; a last line
  // without a newline stays without one).
  const bool cr = !raw.empty() && raw.back() == '\r';
  const std::string_view text = cr ? raw.substr(0, raw.size() - 1) : raw;
  line_ending_size_ = 0;
  if (cr) line_ending_[line_ending_size_++] = '\r';
  if (newline) line_ending_[line_ending_size_++] = '\n';
  if (plain_line(text, plain)) return;
  nc::lex_block_into(text, number, *line_file_, block_);
  block_.file = line_file_ == &file_ ? nullptr : line_file_;
  block_.evaluated = evaluated_;
  const nc::Block& b = block_;
  const bool known_before = interp_.state().position_known;
  const Vector3d position_before = interp_.state().position_mm;
  const double offset_before = interp_.state().tool_length_mm;
  nc::BlockEffect& fx = fx_;
  interp_.execute(b, fx);
  if (fx.has_motion) {
    ++report_.moves;
    if (self_check_) self_check_->nominal(fx.motion, &fx.more_holes);
  }
  // A change of tool length offset moves the controlled point where the
  // controller stands, as it moves the interpreter's (LinuxCNC).
  if (const double offset = interp_.state().tool_length_mm; offset != offset_before)
    emitted_mm_.z() -= offset - offset_before;
  if (!interp_.state().cycle_il_known) ctrl_il_known_ = false;
  const Corrector& c = corrector();
  check_compensation(c, fx);
  if (fx.has_motion && interp_.state().position_known)
    check_travel(machine_, fx.motion, c, interp_.state().origin_mm, *line_file_, number,
                 fx.comp_role == nc::CompRole::kNone ? 0.0 : comp_travel_margin_mm());
  if (fx.stores_home && !c.zero())
    throw InputError(*line_file_, number,
                     "G28.1/G30.1 store where the controller stands, which the correction "
                     "moves off the nominal point: give the stored position in the parameter "
                     "file (`var_file`) instead");
  if (fx.offsets_from_position && !c.zero()) {
    offsets_line(text, b, position_before);
    return;
  }
  // G28/G30 go to the stored position whatever is corrected: written as
  // they are (rapids, through their intermediate point).
  if (!fx.has_motion || c.zero() || b.block_delete || fx.homed_axes != 0) {
    // Block delete: the line may or may not run on the machine; it is
    // written unchanged and the correction goes on from its nominal end.
    write_unchanged(text, b, fx);
    return;
  }
  const nc::Motion& m = fx.motion;
  const BlockStyle style = block_style(b);
  if (m.kind == nc::MotionKind::kRapid) {
    if (!known_before && !interp_.state().position_known) {
      write_unchanged(text, b, fx);  // partial rapid from an unknown position: nothing to correct
      return;
    }
  }
  if (!emitted_known_) emitted_mm_ = m.start_mm;

  if (m.kind == nc::MotionKind::kCycle && options_.expand_cycles) {
    expand_cycle(b, fx, c, style.lower, style.spaces, decimals());
    return;
  }
  if (m.kind == nc::MotionKind::kCycle &&
      (!fx.more_holes.empty() || !interp_.state().absolute || b.find('@') || b.find('^'))) {
    cycle_holes(text, b, fx, c, style.lower, style.spaces, decimals());
    return;
  }
  if (m.kind == nc::MotionKind::kRapid || m.kind == nc::MotionKind::kCycle) {
    positioning_line(text, b, fx, c, style);
    return;
  }
  if (m.kind == nc::MotionKind::kTap) {
    tap_line(text, b, fx, c, style);
    return;
  }
  // Feed moves: lines, arcs and helices.
  if (fx.stop_code)
    throw InputError(*line_file_, number,
                     "a feed move and a stop code (M0/M1/M2/M30/M60) in one block; "
                     "put the stop code on its own line");
  feed_line(text, b, fx, c, style);
}

bool ProgramPost::minimal_axis_words(const nc::Block& b, const BlockStyle& style, bool g53,
                                     const Vector3d& cmd, nc::BlockEdit& e,
                                     Vector3d& reached_mm) const {
  const nc::State& s = interp_.state();
  const int dec = decimals();
  bool changed = false;
  int last_axis_word = -1;
  for (int a = 0; a < 3; ++a) last_axis_word = std::max(last_axis_word, style.axis_index[a]);
  for (int a = 0; a < 3; ++a) {
    const int idx = style.axis_index[a];
    const double origin = s.absolute ? (g53 ? 0.0 : interp_.work_offset()[a]) : emitted_mm_[a];
    double value;  // what the controller reads for this axis, program units
    if (block_needs_word(b, style, g53, a, cmd)) {
      // The number and the value the controller reads from it (strtod's;
      // format_number_fast gives it without reading the text back).
      char buf[nc::kNumberRoom];
      const double v = program_value(a, cmd[a], g53);
      std::string_view number;
      std::string general;  // format_number's general path (seldom)
      if (const char* end = nc::format_number_fast(v, dec, buf, &value)) {
        number = std::string_view(buf, static_cast<std::size_t>(end - buf));
      } else {
        general = nc::format_number(v, dec);
        value = std::strtod(general.c_str(), nullptr);
        number = general;
      }
      if (idx >= 0) {
        e.renumber.emplace_back(idx, number);
      } else {
        if (!e.insert.empty() && style.spaces) e.insert += ' ';
        e.insert += style.lower ? "xyz"[a] : "XYZ"[a];
        e.insert += number;
      }
      changed = true;
    } else if (idx >= 0) {
      value = b.words[static_cast<size_t>(idx)].value;
    } else {
      reached_mm[a] = emitted_mm_[a];  // not named: it stays
      continue;
    }
    reached_mm[a] = origin + value * s.unit_mm;
  }
  if (e.remove.empty() && last_axis_word >= 0) e.insert_after = last_axis_word;
  return changed;
}

double ProgramPost::reach_as_written_mm(const nc::Motion& m, int a) const {
  return interp_.state().absolute ? m.end_mm[a] : emitted_mm_[a] + (m.end_mm[a] - m.start_mm[a]);
}

Eigen::Vector2d ProgramPost::polar_reach_mm(const nc::Block& b) const {
  const nc::State& s = interp_.state();
  const Vector3d& wo = interp_.work_offset();
  const nc::Word* r = b.find('@');
  const nc::Word* t = b.find('^');
  const Eigen::Vector2d at((emitted_mm_.x() - wo.x()) / s.unit_mm,
                           (emitted_mm_.y() - wo.y()) / s.unit_mm);
  const Eigen::Vector2d p =
      nc::polar_end(at, s.absolute, r ? &r->value : nullptr, t ? &t->value : nullptr);
  return {p.x() * s.unit_mm + wo.x(), p.y() * s.unit_mm + wo.y()};
}

bool ProgramPost::polar_needs_change(const nc::Block& b, const nc::BlockEffect& fx,
                                     const Vector3d& cmd) const {
  // Where the block as written takes the controller: X and Y by its polar
  // words from where the output left it (under G91, and under G90 with one
  // word, that depends on the correction already written); Z by its word,
  // as any block's.
  const nc::Motion& m = fx.motion;
  const nc::State& s = interp_.state();
  const Eigen::Vector2d xy = polar_reach_mm(b);
  for (int a = 0; a < 3; ++a) {
    const double as_written = a < 2                       ? xy[a]
                              : b.has('Z') || !s.absolute ? reach_as_written_mm(m, a)
                                                          : emitted_mm_[a];
    if (std::abs(cmd[a] - as_written) / s.unit_mm >= half_unit(decimals())) return true;
  }
  return false;
}

void ProgramPost::first_piece_minimal(std::string_view text, const nc::Block& b,
                                      const nc::BlockEffect& fx, const BlockStyle& style,
                                      const std::vector<Piece>& pieces) {
  nc::BlockEdit& e = fresh_edit();
  Vector3d reached_mm;
  // A line of axis words only, all three of which change, is the piece's
  // three words (what plain_line() writes for such a line, to the byte).
  bool all_axes = true;
  for (int a = 0; a < 3; ++a)
    all_axes = all_axes && block_needs_word(b, style, fx.g53, a, pieces[0].command_mm);
  if (all_axes) {
    std::size_t axis_words = 0;
    for (int a = 0; a < 3; ++a) axis_words += style.axis_index[a] >= 0 ? 1 : 0;
    all_axes = axis_words == b.words.size();
  }
  if (all_axes) {
    for (int a = 0; a < 3; ++a)
      if (style.axis_index[a] >= 0) e.remove.push_back(style.axis_index[a]);
    std::sort(e.remove.begin(), e.remove.end());
    previous_words_.clear();
    append_axis_words(pieces[0].command_mm, fx.g53, style.lower, style.spaces, previous_words_);
    e.insert.assign(previous_words_.view());
    nc::apply_edit(b, e, edited_);
    emit(edited_);
    ++report_.lines_changed;
    set_emitted(pieces[0].command_mm, fx.g53);
  } else if (!minimal_axis_words(b, style, fx.g53, pieces[0].command_mm, e, reached_mm)) {
    if (pieces.size() == 1) {
      write_unchanged(text, b, fx);
      return;
    }
    emit(text);
    emitted_mm_ = reached_mm;
    emitted_exact_ = true;
  } else {
    nc::apply_edit(b, e, edited_);
    emit(edited_);
    ++report_.lines_changed;
    emitted_mm_ = reached_mm;
    emitted_exact_ = true;
  }
  if (pieces.size() == 1) {
    emitted_known_ = true;
    return;
  }
  previous_words_.clear();
  append_axis_words(pieces[0].command_mm, fx.g53, style.lower, style.spaces, previous_words_);
  const bool g53 = fx.g53;
  emit_following_pieces(pieces, g53, style.lower, style.spaces, interp_.state().absolute,
                        [&](size_t k, CharBuffer& w) {
                          w.clear();
                          append_axis_words(pieces[k].command_mm, g53, style.lower, style.spaces,
                                            w);
                        });
  emitted_known_ = true;
}

void ProgramPost::offsets_line(std::string_view text, const nc::Block& b,
                               const Vector3d& nominal_mm) {
  // G92 / G10 L20 take where the controller stands, which is where the post
  // commanded it, not the nominal point: each value moves by the
  // difference, so the controller sets the nominal offset.
  if (!emitted_known_)
    throw InputError(*line_file_, current_line_,
                     "an offset set from where the tool stands (G92, G10 L20) before the post "
                     "knows where the controller stands; command X, Y and Z first");
  std::string out(text);
  const double unit = interp_.state().unit_mm;
  const int dec = decimals();
  bool changed = false;
  for (std::size_t k = b.words.size(); k-- > 0;) {
    const nc::Word& w = b.words[k];
    if (w.letter < 'X' || w.letter > 'Z') continue;
    const int a = w.letter - 'X';
    const double v = w.value + (emitted_mm_[a] - nominal_mm[a]) / unit;
    if (std::abs(v - w.value) < half_unit(dec)) continue;
    out.replace(w.begin + 1, w.end - w.begin - 1, nc::format_number(v, dec));
    changed = true;
  }
  if (changed) ++report_.lines_changed;
  emit(out);
}

std::size_t ProgramPost::feed_block_removals(const nc::Block& b, const BlockStyle& style, bool arc,
                                             bool g93, std::array<int, 12>& remove) const {
  // The block itself becomes the first piece: its X Y Z words, its polar
  // words @ ^ (a corrected point goes out as X Y: LinuxCNC refuses @ ^
  // beside X Y), and an arc's I J K R P and G2/G3, G93's F give way to the
  // piece's words. At most 3 + 2 + 5 + 1 + 1 distinct words (a letter
  // twice, or two motion G codes, the interpreter refused).
  std::size_t removed = 0;
  for (int a = 0; a < 3; ++a)
    if (style.axis_index[a] >= 0) remove[removed++] = style.axis_index[a];
  for (char L : {'@', '^'})
    if (const int i = word_index(b, L); i >= 0) remove[removed++] = i;
  if (arc) {
    for (char L : {'I', 'J', 'K', 'R', 'P'})
      if (const int i = word_index(b, L); i >= 0) remove[removed++] = i;
    for (size_t k = 0; k < b.words.size(); ++k)
      if (b.words[k].letter == 'G' && (b.words[k].code10 == nc::kG2ArcClockwise ||
                                       b.words[k].code10 == nc::kG3ArcCounterClockwise))
        remove[removed++] = static_cast<int>(k);
  }
  if (g93)
    if (const int i = word_index(b, 'F'); i >= 0) remove[removed++] = i;
  // Ascending, as apply_edit_to wants (insertion sort: a handful, nearly
  // always in order already).
  for (std::size_t r = 1; r < removed; ++r)
    for (std::size_t q = r; q > 0 && remove[q - 1] > remove[q]; --q)
      std::swap(remove[q - 1], remove[q]);
  return removed;
}

void ProgramPost::feed_line(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                            const Corrector& c, const BlockStyle& style) {
  const nc::Motion& m = fx.motion;
  const bool lower = style.lower, spaces = style.spaces;
  const Vector3d start_cmd = emitted_mm_;
  // The entry and exit moves of cutter compensation stay one move: the
  // controller computes them from their start, which a split would move.
  const bool one_piece =
      fx.comp_role == nc::CompRole::kEntry || fx.comp_role == nc::CompRole::kExit;
  const std::uint64_t arcs_split_before = report_.arcs_split;
  const bool compensated = fx.comp_role != nc::CompRole::kNone && !c.zero();
  if (m.kind == nc::MotionKind::kArc && options_.keep_arcs && keep_arc(text, b, fx, c, style)) {
    if (one_piece && report_.arcs_split != arcs_split_before) refuse_comp_split(fx);
    if (compensated && report_.arcs_split != arcs_split_before)
      check_comp_pieces(c,
                        std::hypot(m.end_mm.x() - m.center_mm.x(), m.end_mm.y() - m.center_mm.y()));
    return;
  }
  if (one_piece && m.kind == nc::MotionKind::kArc) refuse_comp_split(fx);
  if (compensated && m.kind == nc::MotionKind::kArc)
    throw InputError(*line_file_, current_line_,
                     "an arc under cutter compensation that volmap would write as straight "
                     "pieces (--linearize-arcs, or an arc it cannot keep): the controller "
                     "would not trim their inside corners below 0.05 rad, and the tool would "
                     "cut into the part; keep arcs as arcs, or output the tool centre path "
                     "from CAM (G40)");
  if (m.kind == nc::MotionKind::kArc) {
    ++report_.arcs_linearized;
    output_left_arc_mode_ = true;
  }
  if (comp_hold_xy_ && m.kind != nc::MotionKind::kArc) {
    const ApproachDirections d = directions_of(m.start_mm, m.end_mm, last_dir_);
    last_dir_ = d;
    pieces_.assign(1, Piece{held_xy_command(c, m.end_mm, d), 1.0});
  }
  const std::vector<Piece>& pieces =
      comp_hold_xy_ && m.kind != nc::MotionKind::kArc ? pieces_ : segment(c, m, start_cmd);
  if (one_piece && pieces.size() > 1) refuse_comp_split(fx);
  if (compensated && pieces.size() > 1) {
    double shortest = 1.0, s_prev = 0.0;  // (of the move, 0 .. 1)
    for (const Piece& p : pieces) shortest = std::min(shortest, p.s_end - s_prev), s_prev = p.s_end;
    check_comp_pieces(
        c, shortest * std::hypot(m.end_mm.x() - m.start_mm.x(), m.end_mm.y() - m.start_mm.y()));
  }
  const bool arc = m.kind == nc::MotionKind::kArc;
  const bool polar = b.has('@') || b.has('^');  // rewritten as X Y when changed (see the rapids)
  const nc::State& s = interp_.state();
  const bool g93 = s.feed_mode == nc::kG93InverseTime;
  if (!arc && !g93) {
    // A straight move: its block is the first piece, with the fewest
    // changed words; a block that needs none stays as written.
    if (!polar) {
      first_piece_minimal(text, b, fx, style, pieces);
      return;
    }
    if (pieces.size() == 1 && !polar_needs_change(b, fx, pieces[0].command_mm)) {
      write_unchanged(text, b, fx);
      return;
    }
  }
  auto g93_share = [&](double s0, double s1, double step_mm) {
    // Inverse time: the piece takes its share of the block's time. A
    // take-up step at a reversal covers no nominal path: it takes the time
    // of its own length at the block's nominal speed.
    double share = s1 - s0;
    if (share < 1e-9) {
      const double length = nc::path_length_mm(m);
      share = length > 0 ? step_mm / length : 0.0;
    }
    return std::max(1e-12, share);
  };
  std::array<int, 12> remove;
  const std::size_t removed = feed_block_removals(b, style, arc, g93, remove);
  const bool g53 = fx.g53;
  // The words of a piece into w (storage reused: no allocation per line).
  auto words_for = [&](const Vector3d& cmd, double s0, double s1, CharBuffer& w) {
    w.clear();
    append_axis_words(cmd, g53, lower, spaces, w);
    if (g93) {
      char* p = w.room(2);
      if (spaces) *p++ = ' ';
      *p++ = lower ? 'f' : 'F';
      w.commit(p);
      append_number(w, s.feed / g93_share(s0, s1, (cmd - emitted_mm_).norm()), 4);
    }
  };
  CharBuffer& previous_words = previous_words_;
  words_for(pieces[0].command_mm, 0.0, pieces[0].s_end, previous_words);
  std::string_view insert = previous_words.view();
  if (arc) {
    insert_.assign(lower ? "g1" : "G1");
    if (spaces) insert_.append(" ");
    insert_.append(insert);
    insert = insert_.view();
  }
  // Straight into the output: the line can grow by the insert and a space.
  char* out = out_buffer_.room(text.size() + insert.size() + 1 + 2);
  end_line(nc::apply_edit_to(b, remove.data(), removed, insert, spaces, out));
  ++report_.lines_changed;
  set_emitted(pieces[0].command_mm, g53);
  emit_following_pieces(pieces, g53, lower, spaces, !g93 && s.absolute,
                        [&](size_t k, CharBuffer& w) {
                          words_for(pieces[k].command_mm, pieces[k - 1].s_end, pieces[k].s_end, w);
                        });
  emitted_known_ = true;
}

}  // namespace volmap::post
