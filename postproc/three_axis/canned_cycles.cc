// Canned cycles that are not one block for one hole: one block per hole
// (repeats, G91, polar words), and --expand-cycles, which writes a cycle out
// as LinuxCNC's moves (docs/post.md).
#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <vector>

#include "core/common/input_error.h"
#include "gcode/g_codes.h"
#include "postproc/three_axis/program_post.h"

namespace volmap::post {

// A canned cycle that the controller would repeat (L > 1), that is
// incremental (G91) or placed by polar words: one block per hole, each with
// its own correction, the first in place of the block (its other words kept,
// L and the polar words dropped), the others after it as modal repeats
// (`X.. Y.. Z.. R..` and the block's P and Q). Under G91 every number is
// taken from where the controller stands when it reads it: X Y from over
// the hole before, R from that level (LinuxCNC: R above the level the tool
// is at, Z below R), so the rounding of each number is carried into the
// next instead of adding up. A block none of whose holes needs a change
// stays as written, L and polar words with it.
void ProgramPost::cycle_holes(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                              const Corrector& c, bool lower, bool spaces, int dec) {
  const nc::State& s = interp_.state();
  const double unit = s.unit_mm;
  const Vector3d& wo = interp_.work_offset();
  enter_cycle_run();
  // Every hole's words first, and whether the block as written takes the
  // controller within half an output unit of them: its nominal holes, moved
  // under G91 by where the controller stands off the nominal start (X Y)
  // and off the nominal initial level (Z R).
  struct Hole {
    double x, y, z, r;  // the words
    Vector3d at;        // where the controller takes them to: over the hole, at R
  };
  std::vector<Hole> holes(1 + fx.more_holes.size());
  Vector3d chain = emitted_mm_;
  const Vector3d off =
      s.absolute ? Vector3d::Zero()
                 : Vector3d(emitted_mm_.x() - fx.motion.start_mm.x(),
                            emitted_mm_.y() - fx.motion.start_mm.y(), ctrl_il_mm_ - s.cycle_il_mm);
  const double half_mm = half_unit(dec) * unit;
  bool changed = false;
  for (size_t k = 0; k < holes.size(); ++k) {
    const nc::Motion& h = k == 0 ? fx.motion : fx.more_holes[k - 1];
    // The traverse over the hole sets X and Y's approach; the feed goes down.
    ApproachDirections d;
    const Vector3d cmd = position_command(c, h.start_mm, h.end_mm, true, d);
    const Vector3d r_cmd = command(c, Vector3d(h.end_mm.x(), h.end_mm.y(), h.r_mm), d);
    check_cycle_feed(c, h, cmd, r_cmd.z(), d);
    Hole& w = holes[k];
    double bottom;  // the Z the words take the tool down to
    if (s.absolute) {
      w.x = written((cmd.x() - wo.x()) / unit, dec);
      w.y = written((cmd.y() - wo.y()) / unit, dec);
      w.r = written((r_cmd.z() - wo.z()) / unit, dec);
      w.z = written((cmd.z() - wo.z()) / unit, dec);
      w.at = Vector3d(w.x * unit + wo.x(), w.y * unit + wo.y(), w.r * unit + wo.z());
      bottom = w.z * unit + wo.z();
    } else {
      w.x = written((cmd.x() - chain.x()) / unit, dec);
      w.y = written((cmd.y() - chain.y()) / unit, dec);
      w.r = written((r_cmd.z() - ctrl_il_mm_) / unit, dec);
      w.at = Vector3d(chain.x() + w.x * unit, chain.y() + w.y * unit, ctrl_il_mm_ + w.r * unit);
      w.z = written((cmd.z() - w.at.z()) / unit, dec);
      bottom = w.at.z() + w.z * unit;
    }
    changed = changed || !(std::abs(w.at.x() - (h.end_mm.x() + off.x())) < half_mm) ||
              !(std::abs(w.at.y() - (h.end_mm.y() + off.y())) < half_mm) ||
              !(std::abs(w.at.z() - (h.r_mm + off.z())) < half_mm) ||
              !(std::abs(bottom - (h.end_mm.z() + off.z())) < half_mm);
    // After the hole: G99 at R, G98 at the initial level or R if higher.
    chain = Vector3d(w.at.x(), w.at.y(), s.g98 ? std::max(ctrl_il_mm_, w.at.z()) : w.at.z());
  }
  if (!changed) {
    write_unchanged(text, b, fx);
    if (!s.absolute) emitted_mm_ += Vector3d(off.x(), off.y(), 0.0);
    return;
  }
  std::string extra;  // the block's P and Q words, for every repeat
  for (const nc::Word& w : b.words)
    if (w.letter == 'P' || w.letter == 'Q') {
      if (spaces) extra += ' ';
      extra += b.text.substr(w.begin, w.end - w.begin);
    }
  for (size_t k = 0; k < holes.size(); ++k) {
    const Hole& h = holes[k];
    std::string words;
    const char* letters = lower ? "xyzr" : "XYZR";
    const double values[4] = {h.x, h.y, h.z, h.r};
    for (int i = 0; i < 4; ++i) {
      if (i > 0 && spaces) words += ' ';
      words += letters[i];
      words += nc::format_number(values[i], dec);
    }
    if (k == 0) {
      nc::BlockEdit edit;
      for (size_t i = 0; i < b.words.size(); ++i) {
        const char L = b.words[i].letter;
        // (K: Fanuc's repeats, as L; the interpreter refuses K in a LinuxCNC cycle.)
        if (L == 'X' || L == 'Y' || L == 'Z' || L == 'R' || L == 'L' || L == 'K' || L == '@' ||
            L == '^')
          edit.remove.push_back(static_cast<int>(i));
      }
      edit.insert = words;
      emit(nc::apply_edit(b, edit));
      ++report_.lines_changed;
    } else {
      emit(words + extra);
      ++report_.lines_added;
    }
  }
  emitted_mm_ = chain;
  emitted_exact_ = false;
  emitted_known_ = true;
}

// Pecks of one hole that --expand-cycles writes out at most.
constexpr int kMaxPecks = 10000;

void ProgramPost::write_expanded_cycle_block(const nc::Block& b, int code) {
  nc::BlockEdit edit;
  for (size_t i = 0; i < b.words.size(); ++i) {
    const nc::Word& w = b.words[i];
    const char L = w.letter;
    if (L == 'X' || L == 'Y' || L == 'Z' || L == 'R' || L == 'L' || L == 'K' || L == 'P' ||
        L == 'Q' || L == '@' || L == '^' || (L == 'G' && w.code10 == code))
      edit.remove.push_back(static_cast<int>(i));
  }
  const std::string rest = nc::apply_edit(b, edit);
  bool blank = true;
  for (char ch : rest) blank = blank && (ch == ' ' || ch == '\t');
  if (!blank) emit(rest);
  ++report_.lines_changed;
}

// --expand-cycles: a cycle block (every hole of it) becomes its moves, as
// LinuxCNC makes them (interp_cycles.cc): up to R if below it, over the hole
// at the clearance level (the first hole: at the level the tool is at, if
// higher than R), down to R, the pecks of G73 G83, the feed to the bottom, a
// dwell for G82 G89, out at feed to R for G85 G89, then to the clearance
// level. The block's
// other words (N, F, S, M...) stay on its line, with the cycle's G code,
// X Y Z R L P Q and polar words removed; the moves follow it.
void ProgramPost::expand_cycle(const nc::Block& b, const nc::BlockEffect& fx, const Corrector& c,
                               bool lower, bool spaces, int dec) {
  const nc::State& s = interp_.state();
  const int code = s.motion;
  if (code != nc::kG73PeckDrillChipBreak && code != nc::kG81Drill && code != nc::kG82DrillDwell &&
      code != nc::kG83PeckDrill && code != nc::kG85Bore && code != nc::kG89BoreDwell)
    throw InputError(
        *line_file_, current_line_,
        fmt::format(
            "`expand_cycles` writes out G73 G81 G82 G83 G85 G89 only; this is G{} (it stops "
            "or reverses the spindle at the bottom); post it without `expand_cycles` (its hole "
            "bottom and R plane are corrected)",
            code / 10));
  if (s.feed_mode == nc::kG93InverseTime)
    throw InputError(*line_file_, current_line_,
                     "`expand_cycles` under inverse time feed (G93): use G94 for the cycles");
  if (const nc::Word* p = b.find('P')) cycle_dwell_s_ = p->value;
  write_expanded_cycle_block(b, code);
  const size_t holes = 1 + fx.more_holes.size();
  Vector3d at = fx.motion.start_mm;  // nominal position of the tool
  for (size_t k = 0; k < holes; ++k) {
    const nc::Motion& h = k == 0 ? fx.motion : fx.more_holes[k - 1];
    const double x = h.end_mm.x(), y = h.end_mm.y();
    auto rapid_to = [&](const Vector3d& to) {
      expanded_rapid(c, at, to, lower, spaces);
      at = to;
    };
    if (at.z() < h.r_mm) rapid_to(Vector3d(at.x(), at.y(), h.r_mm));
    rapid_to(Vector3d(x, y, k == 0 ? at.z() : h.clear_mm));
    if (at.z() > h.r_mm) rapid_to(Vector3d(x, y, h.r_mm));
    if (code == nc::kG73PeckDrillChipBreak || code == nc::kG83PeckDrill)
      expand_pecks(c, h, code, lower, spaces, at);
    const Vector3d bottom(x, y, h.end_mm.z());
    expanded_feed(c, at, bottom, lower, spaces);
    at = bottom;
    if (code == nc::kG82DrillDwell || code == nc::kG89BoreDwell) {
      std::string dwell(1, lower ? 'p' : 'P');
      dwell += nc::format_number(cycle_dwell_s_, std::max(dec, 3));
      emit_move(4, lower, spaces, dwell);
      ++report_.lines_added;
    }
    if (code == nc::kG85Bore || code == nc::kG89BoreDwell) {
      const Vector3d r_level(x, y, h.r_mm);
      expanded_feed(c, at, r_level, lower, spaces);
      at = r_level;
    }
    if (h.clear_mm != at.z()) rapid_to(Vector3d(x, y, h.clear_mm));
  }
}

// The pecks, as LinuxCNC makes them (convert_cycle_g73/g83): levels
// R - Q, R - 2Q, ... above the bottom, by repeated subtraction in
// program units and coordinates (the same count of pecks for a bottom
// a whole number of Q below R); after each, G83 rapids out to R and
// back down to the level reached, G73 rapids up; either stops short
// of the level reached by 0.010 in (0.254 mm in a mm program).
void ProgramPost::expand_pecks(const Corrector& c, const nc::Motion& h, int code, bool lower,
                               bool spaces, Vector3d& at) {
  const nc::State& s = interp_.state();
  const double x = h.end_mm.x(), y = h.end_mm.y();
  auto rapid_to = [&](const Vector3d& to) {
    expanded_rapid(c, at, to, lower, spaces);
    at = to;
  };
  const double unit = s.unit_mm, wo_z = interp_.work_offset()[2];
  const double r_prog = s.absolute ? s.cycle_r : (h.r_mm - wo_z) / unit;
  const double bottom_prog = s.absolute ? s.cycle_z : (h.end_mm.z() - wo_z) / unit;
  const double back_off = unit == 1.0 ? 0.010 * 25.4 : 0.010;
  int pecks = 0;
  for (double depth = r_prog - s.cycle_q; depth > bottom_prog; depth -= s.cycle_q) {
    if (++pecks > kMaxPecks)
      throw InputError(
          *line_file_, current_line_,
          fmt::format("more than {} pecks in one hole (Q {:g}); `expand_cycles` would write "
                      "them all: raise Q or post without `expand_cycles`",
                      kMaxPecks, s.cycle_q));
    const Vector3d level(x, y, depth * unit + wo_z);
    expanded_feed(c, at, level, lower, spaces);
    at = level;
    if (code == nc::kG83PeckDrill) rapid_to(Vector3d(x, y, h.r_mm));
    rapid_to(Vector3d(x, y, (depth + back_off) * unit + wo_z));
  }
}

void ProgramPost::expanded_rapid(const Corrector& c, const Vector3d& from, const Vector3d& to,
                                 bool lower, bool spaces) {
  ApproachDirections d;
  const Vector3d cmd = position_command(c, from, to, false, d);
  words_.clear();
  append_axis_words(cmd, false, lower, spaces, words_);
  emit_move(0, lower, spaces, words_.view());
  ++report_.lines_added;
  set_emitted(cmd, false);
}

void ProgramPost::expanded_feed(const Corrector& c, const Vector3d& from, const Vector3d& to,
                                bool lower, bool spaces) {
  nc::Motion m;
  m.kind = nc::MotionKind::kLinear;
  m.start_mm = from;
  m.end_mm = to;
  m.feed = interp_.state().feed;
  const std::vector<Piece>& pieces = segment(c, m, emitted_mm_);
  for (const Piece& piece : pieces) {
    words_.clear();
    append_axis_words(piece.command_mm, false, lower, spaces, words_);
    emit_move(1, lower, spaces, words_.view());
    ++report_.lines_added;
    set_emitted(piece.command_mm, false);
  }
}

}  // namespace volmap::post
