// ProgramPost, the three-axis post of one program line after line (internal
// to postproc/three_axis/; post_program.h is the interface). Its pieces live
// in one file each:
//   program_post.cc      line(): the dispatch, unchanged lines, feed moves;
//                        run_post and post_program
//   positioning_move.cc  rapids and single canned-cycle blocks
//   canned_cycles.cc     cycles one block per hole, --expand-cycles
//   segmenter.cc         segment(): pieces within the tolerance
//   arc_keeper.cc        keep_arc(): arcs kept as arcs
//   plain_line.cc        plain_line(): the shortcut for plain axis words
// The small helpers every line uses are inline here (the plain-line path is
// benchmarked: docs/post.md "Speed").
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "core/common/input_error.h"
#include "gcode/nc_interpreter.h"
#include "gcode/nc_writer.h"
#include "gcode/program_reader.h"
#include "postproc/three_axis/char_buffer.h"
#include "postproc/three_axis/corrector.h"
#include "postproc/three_axis/post_pieces.h"
#include "postproc/three_axis/post_program.h"
#include "postproc/three_axis/self_check.h"

namespace volmap::post {

using Eigen::Vector3d;

class ProgramPost {
 public:
  ProgramPost(const std::string& file, std::ostream& out, const Machine& machine,
              const ErrorSet& errors, const nc::ProgramSetup& setup, const PostOptions& options,
              const maps::VolumetricTable* table = nullptr)
      : file_(file),
        out_(out),
        machine_(machine),
        errors_(errors),
        table_(table),
        options_(options),
        interp_(setup, file) {
    // (Without errors the output is the input: nothing to check.)
    if (options.self_check && !corrector().zero())
      self_check_ = std::make_unique<SelfCheck>(interp_, setup, file, options.tolerance_mm);
    // Where the controller stands at the start, when given: the first move's
    // command creeps from there, which sets the direction of its play.
    if (setup.initial_position_mm) {
      emitted_mm_ = *setup.initial_position_mm;
      emitted_known_ = true;
    }
  }

  /// One line of the program as the reader hands it out (a block, or
  /// verbatim text such as tape leader).
  void line(const nc::ProgramLine& l);
  /// `plain`: the line's axis words when the reader read it as a line of
  /// axis words only (nc::lex_plain_axis_words), else nullptr.
  void line(std::string_view text, int number, bool newline,
            const nc::PlainAxisWords* plain = nullptr);
  const nc::Interpreter& interpreter() const { return interp_; }
  nc::Interpreter& interpreter() { return interp_; }  ///< the reader sets the dialect
  /// The end of the program: a flattened part in which the post changed no
  /// line goes out as it was read (`original_rest`, the reader's), not flat.
  void finish(const std::string& original_rest);
  /// Writes out what emit() gathered (also on failure: what was done).
  void flush() {
    write_out(out_buffer_.data(), out_buffer_.size());
    out_buffer_.clear();
  }
  // Output gathered in 64 KB pieces.
  static constexpr std::size_t kFlushAt = std::size_t{1} << 16;
  const PostReport& report() const { return report_; }

 private:
  const Corrector& corrector();
  // How close a commanded point is to the exact solution of x + e(x) = p:
  // 1e-9 mm, at least 1e4 times finer than the output resolution (1e-4 mm
  // or 1e-5 inch by default); 1e-12 mm for 6 decimals and more.
  double solve_accuracy_mm() const { return decimals() <= 5 ? 1e-9 : 1e-12; }
  int decimals() const {
    if (options_.decimals >= 0) return options_.decimals;
    return interp_.state().unit_mm > 1.0 ? 5 : 4;
  }
  /// The command whose actual tip is `nominal` (directions d), warm-started
  /// from the last points corrected (segmenter.cc).
  Vector3d command(const Corrector& c, const Vector3d& nominal, const ApproachDirections& d);

  // --- The line's paths (one file each, see the top) ---
  /// The line as written: the controller then stands where its words say,
  /// the axes it does not name where we left them.
  void write_unchanged(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx);
  /// G92 / G10 L20 with axis words: their values moved by where the
  /// controller stands off the nominal point.
  void offsets_line(std::string_view text, const nc::Block& b, const Vector3d& nominal_mm);
  /// A canned cycle kept as a cycle: the feed into the hole (from the R
  /// plane commanded at r_cmd_mm to bottom_cmd), which the controller
  /// computes, checked against the hole's axis; beyond the tolerance it
  /// goes into the report's cycle_warnings (--expand-cycles writes it out).
  void check_cycle_feed(const Corrector& c, const nc::Motion& hole, const Vector3d& bottom_cmd,
                        double r_cmd_mm, const ApproachDirections& d);
  /// G33.1, a rigid tap (its end corrected, there and back checked); a rapid, or a
  /// canned-cycle block of one hole in G90 (positioning_move.cc).
  void tap_line(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                const Corrector& c, const BlockStyle& style);
  void positioning_line(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                        const Corrector& c, const BlockStyle& style);
  /// The axis words of a positioning block, and whether any changed.
  struct PositioningEdit {
    nc::BlockEdit edit;
    std::string insert;
    bool changed = false;
    std::array<bool, 3> needed{};
  };
  void positioning_axis_words(const nc::Block& b, const nc::BlockEffect& fx, const Vector3d& cmd,
                              const BlockStyle& style, PositioningEdit& e) const;
  /// A cycle block's R plane (and Z with it) into e; returns the level the
  /// controller ends the hole at.
  double cycle_r_plane(const nc::Block& b, const nc::Motion& m, const Corrector& c,
                       const ApproachDirections& d, const Vector3d& cmd, const BlockStyle& style,
                       PositioningEdit& e);
  /// A feed move (lines, arcs, helices): the block as its first piece, the
  /// others after it.
  void feed_line(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                 const Corrector& c, const BlockStyle& style);
  /// The words the block's first piece replaces, ascending, into remove;
  /// returns how many.
  std::size_t feed_block_removals(const nc::Block& b, const BlockStyle& style, bool arc, bool g93,
                                  std::array<int, 12>& remove) const;
  /// Does axis a need a new word to command cmd? Compared with what the
  /// block writes (or, for an absent word, with staying put).
  bool block_needs_word(const nc::Block& b, const BlockStyle& style, bool g53, int a,
                        const Vector3d& cmd) const {
    const int idx = style.axis_index[a];
    return axis_needs_word(a, cmd, idx >= 0 ? &b.words[static_cast<size_t>(idx)].value : nullptr,
                           g53);
  }

  /// The block's X Y Z words for commanded point cmd with the fewest
  /// changes: a word is renumbered in place, or added after the block's
  /// last axis word, only where the controller would otherwise stand more
  /// than half an output unit off cmd (block_needs_word); every other word
  /// keeps its text. Adds to e; returns whether any word changed; sets
  /// *reached_mm to where the controller then stands.
  bool minimal_axis_words(const nc::Block& b, const BlockStyle& style, bool g53,
                          const Vector3d& cmd, nc::BlockEdit& e, Vector3d& reached_mm) const;
  /// Where a move as written takes the controller on an axis it names: the
  /// nominal end under G90, its increment from where it stands under G91.
  double reach_as_written_mm(const nc::Motion& m, int a) const;
  /// X Y (mm) a polar block as written reaches from where the output left
  /// the controller (nc::polar_end); whether that is more than half an
  /// output unit off cmd on any axis.
  Eigen::Vector2d polar_reach_mm(const nc::Block& b) const;
  bool polar_needs_change(const nc::Block& b, const nc::BlockEffect& fx, const Vector3d& cmd) const;
  /// A straight feed move in G94/G95 without polar words: the block as its
  /// first piece with the fewest changed words (minimal_axis_words), the
  /// other pieces after it; the block as written when it is one piece and
  /// needs no change.
  void first_piece_minimal(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                           const BlockStyle& style, const std::vector<Piece>& pieces);
  /// The largest deviation of the actual tip from the nominal path at the
  /// samples of a piece (from path parameter s0 commanded at c0 to s1 at
  /// c1, directions d); it stops at the first beyond the tolerance.
  double sampled_deviation(const Corrector& c, const nc::Motion& m, double s0, double s1,
                           const Vector3d& c0, const Vector3d& c1, const ApproachDirections& d);
  const std::vector<Piece>& segment(const Corrector& c, const nc::Motion& m,
                                    const Vector3d& start_cmd);
  /// The number of initial pieces of an arc: the chord error below tol / 4.
  int arc_initial_pieces(const nc::Motion& m) const;
  /// The last point corrected: command solves command + e(command, dir) =
  /// nominal (to solve_accuracy_mm()).
  struct LastCorrected {
    const Corrector* corrector = nullptr;
    Vector3d nominal = Vector3d::Zero(), command = Vector3d::Zero();
    ApproachDirections dir{};
  } last_, before_last_;
  /// The deviation of the actual tip at a straight piece's start (c0 commanded for nominal
  /// n0p, directions d; kept while a piece is halved), or where it decides nothing a bound
  /// of it from `start`, the last point corrected before the piece (`chord`: its bound).
  double start_deviation(const Corrector& c, const Vector3d& c0, const Vector3d& n0p,
                         const ApproachDirections& d, const LastCorrected& start, double chord);
  /// PostOptions::keep_arcs: writes the arc block `b` (its effect fx) as
  /// the corrected arc, cut only where the field needs it, when that keeps
  /// the tolerance, and returns true; false (nothing written, nothing
  /// changed) when it does not or cannot.
  bool keep_arc(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                const Corrector& c, const BlockStyle& style);
  /// A kept arc's lines, in order: arcs and take-up steps (G1), their
  /// words, the commanded end, and an arc's centre words (program values
  /// of the plane's axes).
  struct KeptLine {
    bool arc;
    std::string words;
    Vector3d end_mm;
    std::array<std::pair<bool, double>, 3> centre;
  };
  struct ArcPlan;
  /// The arc's pieces for keep_arc (docs/post.md "Arcs kept as arcs");
  /// false when the arc cannot be kept.
  bool kept_arc_lines(const nc::Motion& m, const Corrector& c, bool lower, bool spaces,
                      std::vector<KeptLine>& lines);
  /// The piece of m from path parameter s0 to s1: its lines added when it
  /// keeps the tolerance, else false (nothing added).
  bool kept_arc_piece(const nc::Motion& m, const ArcPlan& plan, const Corrector& c, double s0,
                      double s1, std::vector<KeptLine>& lines);
  /// The actual tip sampled along a kept piece (arc_keeper.cc).
  bool kept_arc_samples(const nc::Motion& m, const nc::Motion& cmd, const Corrector& c,
                        const ApproachDirections& d0, double min_samples, double& worst);
  /// A kept piece's lines: the take-up step to c0 when `step` (and not
  /// below the output's resolution), then the arc `cmd`.
  void add_kept_arc_piece_lines(const ArcPlan& plan, bool step, const Vector3d& c0,
                                const nc::Motion& cmd, const ApproachDirections& d,
                                std::vector<KeptLine>& lines);
  /// A kept arc of one line: the block with the fewest changed words
  /// (an R form becomes I J K when anything changes), or as written when
  /// none needs a change. False (nothing written) when the block relies
  /// on a modal G2/G3 that the output has left.
  bool write_kept_arc_minimal(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                              const BlockStyle& style, const KeptLine& arc);
  /// The kept arc's lines out, the first in the block's place.
  void write_kept_arc(const nc::Block& b, const nc::Motion& m, bool lower, bool spaces,
                      const std::vector<KeptLine>& lines);
  /// The output's modal motion is G1 where the program's is an arc (an arc
  /// linearised): a following arc block without G2/G3 must state it.
  bool output_left_arc_mode_ = false;
  /// The line when it is plain axis words (nc::lex_plain_axis_words) of a
  /// G1 move in G90 and G94/G95, the controller's position known, the tool
  /// the last line's: what line() does with it, without a Block, a
  /// BlockEffect or an edit (the usual line of a three-axis CAM program).
  /// Returns false, having changed nothing, for any other line.
  bool plain_line(std::string_view text, const nc::PlainAxisWords* read = nullptr);
  /// A line "G<g> <words>": the one-digit G code in the block's case, a
  /// space when the block spaces its words, the words (one writer for the
  /// added lines of feed moves, expanded cycles and kept arcs).
  void emit_move(int g, bool lower, bool spaces, std::string_view words) {
    char* l = out_buffer_.room(3 + words.size() + 2);
    *l++ = lower ? 'g' : 'G';
    *l++ = static_cast<char>('0' + g);
    if (spaces) *l++ = ' ';
    std::memcpy(l, words.data(), words.size());
    end_line(l + words.size());
  }
  /// pieces[1..] of a feed move, each as "G1 X.. Y.. Z.." (words_for(k, w)
  /// writes piece k's words into w). A piece whose words repeat the line
  /// before (a lost-motion step below the output resolution) is left out
  /// when `skip_repeats`.
  template <class WordsFor>
  void emit_following_pieces(const std::vector<Piece>& pieces, bool g53, bool lower, bool spaces,
                             bool skip_repeats, WordsFor&& words_for) {
    for (size_t k = 1; k < pieces.size(); ++k) {
      words_for(k, words_);
      // A piece below the output resolution (a lost-motion step at a
      // reversal) would repeat the line before it: the controller cannot
      // command it, so it is not written.
      if (skip_repeats && words_.view() == previous_words_.view()) continue;
      previous_words_.assign(words_.view());
      emit_move(1, lower, spaces, words_.view());
      ++report_.lines_added;
      set_emitted(pieces[k].command_mm, g53);
    }
  }
  static double half_unit(int dec) {
    static constexpr double kHalfUnit[] = {0.5,  0.05, 5e-3, 5e-4, 5e-5,
                                           5e-6, 5e-7, 5e-8, 5e-9, 5e-10};
    return dec >= 0 && dec <= 9 ? kHalfUnit[dec] : 0.5 * std::pow(10.0, -dec);
  }
  nc::Motion plain_motion_;  ///< plain_line()'s motion (only its kind and ends change)
  void cycle_holes(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                   const Corrector& c, bool lower, bool spaces, int dec);
  void expand_cycle(const nc::Block& b, const nc::BlockEffect& fx, const Corrector& c, bool lower,
                    bool spaces, int dec);
  /// The block's line without its cycle words, written unless blank.
  void write_expanded_cycle_block(const nc::Block& b, int code);
  /// The pecks of G73 G83 down to hole h's bottom, from nominal *at.
  void expand_pecks(const Corrector& c, const nc::Motion& h, int code, bool lower, bool spaces,
                    Vector3d& at);
  /// A G0 from nominal point `from` to `to` (corrected at its end), written as a line.
  void expanded_rapid(const Corrector& c, const Vector3d& from, const Vector3d& to, bool lower,
                      bool spaces);
  /// A feed move from where the tool is (nominally `from`) to `to`, segmented
  /// within tolerance, written as G1 lines.
  void expanded_feed(const Corrector& c, const Vector3d& from, const Vector3d& to, bool lower,
                     bool spaces);
  double cycle_dwell_s_ = 0.0;  ///< P of G82/G89, modal as in LinuxCNC
  /// The program value the controller reads from a number written with
  /// `dec` decimals (what format_number writes, read back).
  /// The controller's initial level of the run of cycle blocks (LinuxCNC's
  /// cycle_il, State::cycle_il_mm): the Z it stood at, as commanded, when
  /// the run began.
  void enter_cycle_run() {
    if (ctrl_il_known_) return;
    ctrl_il_known_ = true;
    ctrl_il_mm_ = emitted_mm_.z();
  }
  /// Where the controller stands after a piece's axis words (all three
  /// written) for cmd: cmd under G90 (the numbers are as near to it as the
  /// decimals allow); under G91 the last position plus the increments as
  /// written, so that the rounding of one increment is made good by the
  /// next instead of adding up along the program.
  Vector3d reached(const Vector3d& cmd, bool g53) const {
    const nc::State& st = interp_.state();
    if (st.absolute) return cmd;
    Vector3d r;
    for (int a = 0; a < 3; ++a)
      r[a] = emitted_mm_[a] + written(program_value(a, cmd[a], g53), decimals()) * st.unit_mm;
    return r;
  }
  /// The command of a positioning move (a rapid, or the traverse over a
  /// hole and down) from nominal `from` to `to`, and its approach directions
  /// in *d: an axis the nominal move moves takes its direction; one it does
  /// not move but the correction makes creep takes the creep's direction, so
  /// the command takes up its play that way (as segment() does for feed
  /// moves) instead of leaving it half taken up; `z_down` fixes Z to -1 (a
  /// cycle's feed into the hole).
  Vector3d position_command(const Corrector& c, const Vector3d& from, const Vector3d& to,
                            bool z_down, ApproachDirections& d);
  bool ctrl_il_known_ = false;
  double ctrl_il_mm_ = 0.0;
  static double written(double value, int dec) {
    return std::strtod(nc::format_number(value, dec).c_str(), nullptr);
  }
  // Program value of axis a for commanded machine position v.
  double program_value(int a, double v_mm, bool g53) const {
    const nc::State& s = interp_.state();
    const double d =
        s.absolute ? v_mm - (g53 ? 0.0 : interp_.work_offset()[a]) : v_mm - emitted_mm_[a];
    return s.unit_mm == 1.0 ? d : d / s.unit_mm;  // x / 1 is x: no division in mm (the same bits)
  }
  /// Whether axis a needs a new word to command cmd: the number written for
  /// it would differ, at the output's resolution, from `old_value` (the
  /// block's own word, program units) or, without one, from where the
  /// controller stands (G90; no increment under G91).
  bool axis_needs_word(int a, const Vector3d& cmd, const double* old_value, bool g53) const {
    const double old = old_value                  ? *old_value
                       : interp_.state().absolute ? program_value(a, emitted_mm_[a], g53)
                                                  : 0.0;
    return std::abs(program_value(a, cmd[a], g53) - old) >= half_unit(decimals());
  }
  void append_axis_words(const Vector3d& cmd, bool g53, bool lower, bool spaces, CharBuffer& s) {
    const int dec = decimals();
    const char* letters = lower ? "xyz" : "XYZ";
    // Room for the three words at once; a number the fast path does not
    // write (rare) goes in through format_number.
    constexpr std::size_t kRoom = 3 * (2 + nc::kNumberRoom);
    char* p = s.room(kRoom);
    for (int a = 0; a < 3; ++a) {
      if (a > 0 && spaces) *p++ = ' ';
      *p++ = letters[a];
      const double v = program_value(a, cmd[a], g53);
      if (char* end = nc::format_number_fast(v, dec, p)) {
        p = end;
      } else {
        s.commit(p);
        s.append(nc::format_number(v, dec));
        p = s.room(kRoom);
      }
    }
    s.commit(p);
  }
  void end_line(char* p) {
    std::memcpy(p, line_ending_, 2);  // room for both was made; only the ending's length counts
    out_buffer_.commit(p + line_ending_size_);
    // (Lines out: the '\n's written, a last line without one at finish().)
    report_.lines_out += line_ending_size_ > 0 && line_ending_[line_ending_size_ - 1] == '\n';
    if (out_buffer_.size() >= kFlushAt && !holding_ && !keep_line_) flush();
  }
  bool keep_line_ = false;  ///< the line's output stays in the buffer until the line is done
  /// PostOptions::max_recorded_changes: line l, when its output (from byte
  /// `before` of the buffer on) is not the line as read, into the report.
  void record_change(const nc::ProgramLine& l, std::size_t before);
  /// Fanuc: "X5." for "X5" the post wrote (0.005 mm without 3401#0).
  void add_decimal_points(const nc::ProgramLine& l, std::size_t before);
  /// The flattened part is held back (not flushed) until a line of it
  /// comes out other than it went in: until then, finish() may write the
  /// program as it was read instead.
  void begin_hold() {
    hold_begun_ = true;
    flush();
    holding_ = true;
  }
  /// Ends the hold when line l did not come out as it went in (from byte
  /// `before` of the buffer on).
  void check_held_line(const nc::ProgramLine& l, std::size_t before);
  void emit(std::string_view text) {
    char* p = out_buffer_.room(text.size() + 2);
    std::memcpy(p, text.data(), text.size());
    end_line(p + text.size());
  }

  std::string file_;
  const std::string* line_file_ = &file_;  ///< the line's file (a subroutine file's lines too)
  bool evaluated_ = false;                 ///< the line was evaluated by the flattener
  std::ostream& out_;
  const Machine& machine_;
  const ErrorSet& errors_;
  const maps::VolumetricTable* table_;  ///< instead of errors_ when set
  PostOptions options_;
  nc::Interpreter interp_;
  std::map<double, std::unique_ptr<Corrector>> correctors_;
  const Corrector* last_corrector_ = nullptr;  ///< corrector()'s last answer, for this tool length:
  double last_corrector_length_ = 0.0;
  nc::BlockEffect fx_;                     ///< the line's effect (storage reused line after line)
  std::unique_ptr<SelfCheck> self_check_;  ///< null: off, or a machine without errors
  PostReport report_;
  Vector3d emitted_mm_ = Vector3d::Zero();  ///< last commanded position written
  /// emitted_mm_ is the number the controller read (else the exact command
  /// whose rounding it read, G90: within half an output unit).
  bool emitted_exact_ = true;
  /// Where the controller stands on axis a as it read it (G90, program
  /// units): emitted_mm_, or the rounding written of it.
  double start_as_read(int a) const {
    const double v = program_value(a, emitted_mm_[a], false);
    return emitted_exact_ ? v : written(v, decimals());
  }
  void set_emitted(const Vector3d& cmd, bool g53) {
    emitted_mm_ = reached(cmd, g53);
    emitted_exact_ = !interp_.state().absolute;
  }
  bool emitted_known_ = false;
  // Cutter compensation kept (cutter_comp.cc): the bound of the controller's offset; the last
  // move's end tangent (XY; 0: none), length (arc: radius), corner factor g (comp_bound.h);
  // pieces kept to 3/4 of the tolerance; Z-only moves with X and Y held; the refusals.
  void check_compensation(const Corrector& c, const nc::BlockEffect& fx);
  void check_comp_pieces(const Corrector& c, double piece_lever_mm);
  void check_comp_bound(double bound_mm, const char* where, double g, double L);
  Eigen::Vector2d comp_tangent_in_ = Eigen::Vector2d::Zero();
  double comp_lever_in_ = 0.0, comp_factor_ = 2.0;
  bool comp_move_ = false, comp_hold_xy_ = false;
  double path_tolerance_mm() const { return (comp_move_ ? 0.75 : 1.0) * options_.tolerance_mm; }
  Vector3d held_xy_command(const Corrector& c, const Vector3d& nominal,
                           const ApproachDirections& d);
  [[noreturn]] void refuse_comp_take_up() const;
  [[noreturn]] void refuse_comp_split(const nc::BlockEffect& fx) const;
  double comp_travel_margin_mm() const;
  ApproachDirections last_dir_{};  ///< direction each axis last moved in (0: not yet)
  int current_line_ = 0;
  char line_ending_[2] = {};  ///< the line's ending as read: "", "\n", "\r" or "\r\n"
  std::size_t line_ending_size_ = 0;
  CharBuffer out_buffer_;
  char last_byte_ = 0;  ///< the last byte written out (0: none yet)
  void write_out(const char* data, std::size_t size) {
    if (size == 0) return;
    out_.write(data, static_cast<std::streamsize>(size));
    last_byte_ = data[size - 1];
  }
  bool hold_begun_ = false;  ///< the first flattened line came
  bool holding_ = false;     ///< every flattened line so far came out as it went in
  nc::Block block_;          ///< the line being read (storage reused line after line)
  struct Pending {
    double s0, s1;
    Vector3d c0;
    ApproachDirections dir0;  ///< axis directions on arrival at s0
    bool stepped = false;     ///< the take-up step at s0 was commanded
  };
  std::vector<Piece> pieces_;                   ///< segment()'s result (storage reused)
  std::vector<Pending> stack_;                  ///< segment()'s work list (storage reused)
  CharBuffer words_, previous_words_, insert_;  ///< scratch of the writer (storage reused)
  nc::BlockEdit edit_;                          ///< scratch of the minimal edits (storage reused)
  nc::BlockEdit& fresh_edit() {
    edit_.remove.clear();
    edit_.renumber.clear();
    edit_.insert.clear();
    edit_.insert_after = -1;
    return edit_;
  }
  std::string edited_;  ///< the edited line (storage reused)
  /// The deviation of the actual tip at a piece's start (kept while a piece
  /// is halved: the halves share their start).
  struct StartDeviation {
    const Corrector* corrector = nullptr;
    Vector3d nominal = Vector3d::Zero(), command = Vector3d::Zero();
    ApproachDirections dir{};
    double deviation = 0.0;
  } start_dev_;
};

}  // namespace volmap::post
