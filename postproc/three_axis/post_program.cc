#include "postproc/three_axis/post_program.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <istream>
#include <map>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/common/input_error.h"
#include "gcode/nc_path.h"
#include "gcode/nc_writer.h"
#include "maps/tables/volumetric_table.h"
#include "postproc/three_axis/corrector.h"

namespace volmap::post {
namespace {

using Eigen::Vector3d;

// The direction each axis approaches `to` from `from`; an axis that does not
// move keeps the direction it last moved in (it stands where its last move
// left it, lost motion taken up that way).
ApproachDirections directions_of(const Vector3d& from, const Vector3d& to,
                                 const ApproachDirections& last) {
  ApproachDirections d = last;
  for (int a = 0; a < 3; ++a) {
    const double delta = to[a] - from[a];
    if (delta > 0) d[static_cast<size_t>(a)] = 1;
    if (delta < 0) d[static_cast<size_t>(a)] = -1;
  }
  return d;
}

// An axis the nominal path does not move may still be commanded to creep
// (the correction varies along the path). A creep against the direction the
// axis last moved in is eaten by lost motion unless the command takes it up:
// such an axis gets the direction of its commanded motion, so the command
// for it includes the take-up step (and the piece containing the step is
// split until the step stands alone). Returns whether d changed.
bool settle_directions(const Vector3d& c0, const Vector3d& c1, const Vector3d& n0,
                       const Vector3d& n1, ApproachDirections& d) {
  bool changed = false;
  for (int a = 0; a < 3; ++a) {
    if (n1[a] != n0[a]) continue;  // the nominal motion sets the direction
    const double creep = c1[a] - c0[a];
    const std::int8_t want = creep > 0 ? 1 : (creep < 0 ? -1 : d[static_cast<size_t>(a)]);
    if (want != d[static_cast<size_t>(a)]) {
      d[static_cast<size_t>(a)] = want;
      changed = true;
    }
  }
  return changed;
}

// One commanded point of the output and the nominal path parameter it ends.
struct Piece {
  Vector3d command_mm;
  double s_end;
};

// A growable byte buffer written through a pointer: room(n) makes n bytes
// writable at the end without initialising them (std::string::resize would
// zero them), commit(end) keeps what was written up to end. The writer's
// numbers and edited lines go straight into it, no string per piece.
class CharBuffer {
 public:
  char* room(std::size_t n) {
    if (cap_ - size_ < n) grow(n);
    return data_.get() + size_;
  }
  void commit(const char* end) { size_ = static_cast<std::size_t>(end - data_.get()); }
  void append(std::string_view s) {
    std::memcpy(room(s.size()), s.data(), s.size());
    size_ += s.size();
  }
  void assign(std::string_view s) {
    size_ = 0;
    append(s);
  }
  void clear() { size_ = 0; }
  std::size_t size() const { return size_; }
  const char* data() const { return data_.get(); }
  std::string_view view() const { return {data_.get(), size_}; }

 private:
  void grow(std::size_t n) {
    const std::size_t cap = std::max(2 * cap_, size_ + n);
    std::unique_ptr<char[]> bigger(new char[cap]);  // uninitialised, as room() promises
    if (size_) std::memcpy(bigger.get(), data_.get(), size_);
    data_ = std::move(bigger);
    cap_ = cap;
  }
  std::unique_ptr<char[]> data_;
  std::size_t size_ = 0, cap_ = 0;
};

// format_number(value, dec) appended to w.
void append_number(CharBuffer& w, double value, int dec) {
  char* p = w.room(nc::kNumberRoom);
  if (const char* end = nc::format_number_fast(value, dec, p))
    w.commit(end);
  else
    w.append(nc::format_number(value, dec));
}

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
        interp_(setup, file) {}

  void line(std::string_view text, int number, bool newline);
  /// Writes out what emit() gathered (also on failure: what was done).
  void flush() {
    out_.write(out_buffer_.data(), static_cast<std::streamsize>(out_buffer_.size()));
    out_buffer_.clear();
  }
  // Output gathered in 64 KB pieces.
  static constexpr std::size_t kFlushAt = std::size_t{1} << 16;
  const PostReport& report() const { return report_; }

 private:
  const Corrector& corrector() {
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
            file_, current_line_,
            fmt::format(
                "the tool length offset here is {:g} mm, but a compensation table holds the "
                "errors of the machine file's {:g} mm tool only; post with --errors instead",
                offset, machine_.tool_length_mm));
      it = correctors_
               .emplace(
                   L, table_ ? std::make_unique<Corrector>(machine_, *table_, options_.outside)
                             : std::make_unique<Corrector>(machine_, errors_, L, options_.outside))
               .first;
    }
    last_corrector_length_ = L;
    last_corrector_ = it->second.get();  // map nodes stay put: the pointer stays valid
    return *it->second;
  }
  // How close a commanded point is to the exact solution of x + e(x) = p:
  // 1e-9 mm, at least 1e4 times finer than the output resolution (1e-4 mm
  // or 1e-5 inch by default); 1e-12 mm for 6 decimals and more.
  double solve_accuracy_mm() const { return decimals() <= 5 ? 1e-9 : 1e-12; }
  int decimals() const {
    if (options_.decimals >= 0) return options_.decimals;
    return interp_.state().unit_mm > 1.0 ? 5 : 4;
  }
  Vector3d command(const Corrector& c, const Vector3d& nominal, const ApproachDirections& d) {
    // Warm start from the correction of the last point corrected, moved on
    // along the line through the last two (the fixed point is the same, to
    // solve_accuracy_mm(); it takes a third to a half of the evaluations).
    Vector3d cmd;
    if (last_.corrector == &c) {
      Vector3d guess = last_.command - last_.nominal;
      if (before_last_.corrector == &c && c.same_error(before_last_.dir, last_.dir) &&
          c.same_error(last_.dir, d)) {
        const Vector3d a = last_.nominal - before_last_.nominal;
        const double a2 = a.squaredNorm();
        if (a2 > 0) {
          const double t = std::clamp((nominal - last_.nominal).dot(a) / a2, 0.0, 2.0);
          guess += t * (guess - (before_last_.command - before_last_.nominal));
        }
      }
      cmd = c.command_for(nominal, d, guess, solve_accuracy_mm());
    } else {
      cmd = c.command_for(nominal, d);
    }
    before_last_ = last_;
    last_ = {&c, nominal, cmd, d};
    const double corr = (cmd - nominal).norm();
    if (!std::isfinite(corr))
      throw InputError(file_, current_line_,
                       "the correction is not finite here; check the errors file");
    report_.max_correction_mm = std::max(report_.max_correction_mm, corr);
    ++report_.points_corrected;
    return cmd;
  }
  const std::vector<Piece>& segment(const Corrector& c, const nc::Motion& m,
                                    const Vector3d& start_cmd);
  /// PostOptions::keep_arcs: writes the arc block `b` (motion m) as the
  /// corrected arc when that arc keeps the tolerance, and returns true;
  /// false (nothing written, nothing changed) when it does not or cannot.
  bool keep_arc(const nc::Block& b, const nc::Motion& m, const Corrector& c, bool lower,
                bool spaces);
  /// The line when it is plain axis words (nc::lex_plain_axis_words) of a
  /// G1 move in G90 and G94/G95, the controller's position known, the tool
  /// the last line's: what line() does with it, without a Block, a
  /// BlockEffect or an edit (the usual line of a three-axis CAM program).
  /// Returns false, having changed nothing, for any other line.
  bool plain_line(std::string_view text);
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
      char* l = out_buffer_.room(3 + words_.size() + 2);
      *l++ = lower ? 'g' : 'G';
      *l++ = '1';
      if (spaces) *l++ = ' ';
      std::memcpy(l, words_.data(), words_.size());
      end_line(l + words_.size());
      ++report_.lines_added;
      emitted_mm_ = reached(pieces[k].command_mm, g53);
    }
  }
  static double half_unit(int dec) {
    static constexpr double kHalfUnit[] = {0.5,  0.05, 5e-3, 5e-4, 5e-5,
                                           5e-6, 5e-7, 5e-8, 5e-9, 5e-10};
    return dec >= 0 && dec <= 9 ? kHalfUnit[dec] : 0.5 * std::pow(10.0, -dec);
  }
  nc::Motion plain_motion_;  ///< plain_line()'s motion (only its kind and ends change)
  void cycle_holes(const nc::Block& b, const nc::BlockEffect& fx, const Corrector& c, bool lower,
                   bool spaces, int dec);
  void expand_cycle(const nc::Block& b, const nc::BlockEffect& fx, const Corrector& c, bool lower,
                    bool spaces, int dec);
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
                            bool z_down, ApproachDirections& d) {
    d = directions_of(from, to, last_dir_);
    if (z_down) d[2] = -1;
    Vector3d cmd = command(c, to, d);
    if (emitted_known_) {
      ApproachDirections settled = d;
      Vector3d to_flat = to, from_flat = from;
      if (z_down) from_flat.z() = to_flat.z() = 0.0;  // Z's direction is the feed's
      if (settle_directions(emitted_mm_, cmd, from_flat, to_flat, settled)) {
        const bool again = !c.same_error(d, settled);
        d = settled;
        if (again) cmd = command(c, to, d);
      }
    }
    last_dir_ = d;
    return cmd;
  }
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
    if (out_buffer_.size() >= kFlushAt) flush();
  }
  void emit(std::string_view text) {
    char* p = out_buffer_.room(text.size() + 2);
    std::memcpy(p, text.data(), text.size());
    end_line(p + text.size());
  }

  std::string file_;
  std::ostream& out_;
  const Machine& machine_;
  const ErrorSet& errors_;
  const maps::VolumetricTable* table_;  ///< instead of errors_ when set
  PostOptions options_;
  nc::Interpreter interp_;
  std::map<double, std::unique_ptr<Corrector>> correctors_;
  const Corrector* last_corrector_ = nullptr;  ///< corrector()'s last answer, for this tool length:
  double last_corrector_length_ = 0.0;
  nc::BlockEffect fx_;  ///< the line's effect (storage reused line after line)
  PostReport report_;
  Vector3d emitted_mm_ = Vector3d::Zero();  ///< last commanded position written
  bool emitted_known_ = false;
  ApproachDirections last_dir_{};  ///< direction each axis last moved in (0: not yet)
  int current_line_ = 0;
  char line_ending_[2] = {};  ///< the line's ending as read: "", "\n", "\r" or "\r\n"
  std::size_t line_ending_size_ = 0;
  CharBuffer out_buffer_;
  nc::Block block_;  ///< the line being read (storage reused line after line)
  struct Pending {
    double s0, s1;
    Vector3d c0;
    ApproachDirections dir0;  ///< axis directions on arrival at s0
    bool stepped = false;     ///< the take-up step at s0 was commanded
  };
  std::vector<Piece> pieces_;                   ///< segment()'s result (storage reused)
  std::vector<Pending> stack_;                  ///< segment()'s work list (storage reused)
  CharBuffer words_, previous_words_, insert_;  ///< scratch of the writer (storage reused)
  CharBuffer expanded_line_;                    ///< a line of an expanded cycle (storage reused)
  /// The last point corrected: command solves command + e(command, dir) =
  /// nominal (to solve_accuracy_mm()).
  struct LastCorrected {
    const Corrector* corrector = nullptr;
    Vector3d nominal = Vector3d::Zero(), command = Vector3d::Zero();
    ApproachDirections dir{};
  } last_, before_last_;
  /// The deviation of the actual tip at a piece's start (kept while a piece
  /// is halved: the halves share their start).
  struct StartDeviation {
    const Corrector* corrector = nullptr;
    Vector3d nominal = Vector3d::Zero(), command = Vector3d::Zero();
    ApproachDirections dir{};
    double deviation = 0.0;
  } start_dev_;
};

// Pieces of one move at most (an arc's initial pieces, and all pieces).
constexpr int kMaxArcPieces = 1 << 16;

const std::vector<Piece>& ProgramPost::segment(const Corrector& c, const nc::Motion& m,
                                               const Vector3d& start_cmd) {
  const double tol = options_.tolerance_mm;
  // Initial pieces: arcs so that the chord error is below tol / 4.
  int n0 = 1;
  if (m.kind == nc::MotionKind::kArc) {
    const nc::ArcGeometry g = nc::arc_geometry(m);
    const double r = std::max(g.radius, g.end_radius);
    const double max_step = r > tol / 4 ? 2.0 * std::acos(1.0 - (tol / 4) / r) : M_PI / 2;
    const double pieces = std::ceil(std::abs(g.sweep) / max_step);
    if (!(pieces <= kMaxArcPieces))  // also NaN: never cast to int out of range
      throw InputError(
          file_, current_line_,
          fmt::format("the arc needs more than {} pieces to keep {:g} um (radius {:g} mm); "
                      "raise --tolerance-um or check the arc's centre",
                      kMaxArcPieces, tol * 1e3, r));
    n0 = std::max(4, static_cast<int>(pieces));
  }
  std::vector<Piece>& done = pieces_;
  std::vector<Pending>& stack = stack_;
  done.clear();
  stack.clear();
  Vector3d c_prev = start_cmd;
  double s_prev = 0.0;
  constexpr int kMaxPieces = kMaxArcPieces;
  for (int k = 1; k <= n0; ++k) {
    stack.push_back({s_prev, static_cast<double>(k) / n0, c_prev, last_dir_, false});
    while (!stack.empty()) {
      const Pending p = stack.back();
      stack.pop_back();
      const Vector3d n0p = nc::point_on(m, p.s0), n1p = nc::point_on(m, p.s1);
      // Is the piece's start the last point corrected? Then its actual
      // deviation is known without evaluating e (below).
      const bool start_known = last_.corrector == &c && p.c0 == last_.command;
      const LastCorrected start = last_;
      ApproachDirections d = directions_of(n0p, n1p, p.dir0);
      Vector3d c1 = command(c, n1p, d);
      const ApproachDirections d_before = d;
      if (settle_directions(p.c0, c1, n0p, n1p, d)) {
        // A direction that changes the error (an axis with lost motion)
        // needs the point again; others only change the bookkeeping.
        if (c.same_error(d_before, d))
          last_.dir = d;
        else
          c1 = command(c, n1p, d);
      }
      bool ok = true;
      bool sample = true;
      if (m.kind == nc::MotionKind::kLinear) {
        // The deviation of the actual path from the nominal line,
        // dev(t) = x(t) + e(x(t)) - n(t) with x and n linear in t, is the
        // chord of its end values plus a part whose second derivative is
        // D2e[c1 - c0, c1 - c0]: |dev(t)| <= max(|dev(0)|, |dev(1)|) +
        // K |c1 - c0|^2 / 8 (Corrector::chord_deviation_bound). |dev(1)| is
        // the fixed point's residual; |dev(0)| too when the start is the last
        // point corrected with the same directions. Only when that bound
        // exceeds the tolerance is the piece sampled at 1/4, 1/2, 3/4.
        const double kResidual = 2 * solve_accuracy_mm() + 1e-12;
        double dev0;
        bool dev0_exact = true;  // else an upper bound only
        if (start_known && c.same_error(start.dir, d)) {
          dev0 = kResidual + (start.nominal - n0p).norm();
          dev0_exact = false;
        } else if (start_dev_.corrector == &c && start_dev_.command == p.c0 &&
                   start_dev_.nominal == n0p && c.same_error(start_dev_.dir, d)) {
          dev0 = start_dev_.deviation;  // the same start, halved again
        } else {
          dev0 = (p.c0 + c.error_at(p.c0, d) - n0p).norm();
          start_dev_ = {&c, n0p, p.c0, d, dev0};
        }
        const double chord = c.chord_deviation_bound(p.c0, c1);
        const double bound = std::max(dev0, kResidual) + chord;
        if (bound <= tol) sample = false;
        // The other way round: at t = 1/4 the deviation is at least
        // 3/4 |dev(0)| - 1/4 |dev(1)| - 3/32 K |c1 - c0|^2. When that exceeds
        // the tolerance (a lost-motion step at the start), the sample at 1/4
        // would fail: the piece is split without evaluating it.
        if (sample && dev0_exact && 0.75 * dev0 - kResidual - 0.75 * chord - 1e-12 > tol) {
          sample = false;
          ok = false;
          if (!p.stepped) {
            // The step stands at the start (lost motion taken up at a
            // reversal): halving would close in on it in some thirty levels
            // to a piece shorter than 1e-9 of the move. The take-up is
            // commanded at once instead, at the start point with the new
            // directions (the actual tip stays on the start point while the
            // play is taken up), and the piece goes on from there.
            const Vector3d c_step = command(c, n0p, d);
            done.push_back({c_step, p.s0});
            c_prev = c_step;
            s_prev = p.s0;
            last_dir_ = d;
            Pending rest = p;
            rest.c0 = c_step;
            rest.dir0 = d;
            rest.stepped = true;
            stack.push_back(rest);
            continue;
          }
        }
      }
      for (double t : {0.25, 0.5, 0.75}) {
        if (!sample) break;
        const Vector3d x = p.c0 + t * (c1 - p.c0);
        const Vector3d actual = x + c.error_at(x, d);
        const Vector3d nominal = nc::point_on(m, p.s0 + t * (p.s1 - p.s0));
        if ((actual - nominal).norm() > tol) {
          ok = false;
          break;
        }
      }
      if (ok || p.s1 - p.s0 < 1e-9) {
        done.push_back({c1, p.s1});
        if (done.size() > kMaxPieces)
          throw InputError(
              file_, current_line_,
              fmt::format("more than {} pieces needed to keep {:g} um; raise --tolerance-um",
                          kMaxPieces, tol * 1e3));
        c_prev = c1;
        s_prev = p.s1;
        last_dir_ = d;
        // Continue with all that is left of this initial piece as one piece
        // (split again only where needed): after a lost-motion step the
        // rest need not stay cut into ever smaller halves.
        if (!stack.empty()) {
          const double end = stack.front().s1;
          stack.clear();
          stack.push_back({p.s1, end, c1, d, false});
        }
      } else {
        const double mid = 0.5 * (p.s0 + p.s1);
        stack.push_back({mid, p.s1, Vector3d::Zero(), p.dir0, false});  // c0, dir0 set when reached
        stack.push_back({p.s0, mid, p.c0, p.dir0, p.stepped});
      }
    }
  }
  return done;
}

// A canned cycle that the controller would repeat (L > 1), that is
// incremental (G91) or placed by polar words: one block per hole, each with
// its own correction, the first in place of the block (its other words kept,
// L and the polar words dropped), the others after it as modal repeats
// (`X.. Y.. Z.. R..` and the block's P and Q). Under G91 every number is
// taken from where the controller stands when it reads it: X Y from over
// the hole before, R from that level (LinuxCNC: R above the level the tool
// is at, Z below R), so the rounding of each number is carried into the
// next instead of adding up.
void ProgramPost::cycle_holes(const nc::Block& b, const nc::BlockEffect& fx, const Corrector& c,
                              bool lower, bool spaces, int dec) {
  const nc::State& s = interp_.state();
  const double unit = s.unit_mm;
  const Vector3d& wo = interp_.work_offset();
  std::string extra;  // the block's P and Q words, for every repeat
  for (const nc::Word& w : b.words)
    if (w.letter == 'P' || w.letter == 'Q') {
      if (spaces) extra += ' ';
      extra += b.text.substr(w.begin, w.end - w.begin);
    }
  enter_cycle_run();
  const size_t holes = 1 + fx.more_holes.size();
  for (size_t k = 0; k < holes; ++k) {
    const nc::Motion& h = k == 0 ? fx.motion : fx.more_holes[k - 1];
    // The traverse over the hole sets X and Y's approach; the feed goes down.
    ApproachDirections d;
    const Vector3d cmd = position_command(c, h.start_mm, h.end_mm, true, d);
    const Vector3d r_cmd = command(c, Vector3d(h.end_mm.x(), h.end_mm.y(), h.r_mm), d);
    double x, y, r, z;  // the words
    Vector3d at;        // where the controller takes them to: over the hole, at R
    if (s.absolute) {
      x = written((cmd.x() - wo.x()) / unit, dec);
      y = written((cmd.y() - wo.y()) / unit, dec);
      r = written((r_cmd.z() - wo.z()) / unit, dec);
      z = written((cmd.z() - wo.z()) / unit, dec);
      at = Vector3d(x * unit + wo.x(), y * unit + wo.y(), r * unit + wo.z());
    } else {
      x = written((cmd.x() - emitted_mm_.x()) / unit, dec);
      y = written((cmd.y() - emitted_mm_.y()) / unit, dec);
      r = written((r_cmd.z() - ctrl_il_mm_) / unit, dec);
      at = Vector3d(emitted_mm_.x() + x * unit, emitted_mm_.y() + y * unit, ctrl_il_mm_ + r * unit);
      z = written((cmd.z() - at.z()) / unit, dec);
    }
    std::string words;
    const char* letters = lower ? "xyzr" : "XYZR";
    const double values[4] = {x, y, z, r};
    for (int i = 0; i < 4; ++i) {
      if (i > 0 && spaces) words += ' ';
      words += letters[i];
      words += nc::format_number(values[i], dec);
    }
    if (k == 0) {
      nc::BlockEdit edit;
      for (size_t i = 0; i < b.words.size(); ++i) {
        const char L = b.words[i].letter;
        if (L == 'X' || L == 'Y' || L == 'Z' || L == 'R' || L == 'L' || L == '@' || L == '^')
          edit.remove.push_back(static_cast<int>(i));
      }
      edit.insert = words;
      emit(nc::apply_edit(b, edit));
      ++report_.lines_changed;
    } else {
      emit(words + extra);
      ++report_.lines_added;
    }
    // After the hole: G99 at R, G98 at the initial level or R if higher.
    emitted_mm_ = Vector3d(at.x(), at.y(), s.g98 ? std::max(ctrl_il_mm_, at.z()) : at.z());
  }
  emitted_known_ = true;
}

// Pecks of one hole that --expand-cycles writes out at most.
constexpr int kMaxPecks = 10000;

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
  if (code != 730 && code != 810 && code != 820 && code != 830 && code != 850 && code != 890)
    throw InputError(
        file_, current_line_,
        fmt::format(
            "--expand-cycles writes out G73 G81 G82 G83 G85 G89 only; this is G{} (it stops "
            "the spindle); post it without --expand-cycles (its hole bottom and R plane are "
            "corrected)",
            code / 10));
  if (s.feed_mode == 930)
    throw InputError(file_, current_line_,
                     "--expand-cycles under inverse time feed (G93): use G94 for the cycles");
  if (const nc::Word* p = b.find('P')) cycle_dwell_s_ = p->value;
  nc::BlockEdit edit;
  for (size_t i = 0; i < b.words.size(); ++i) {
    const nc::Word& w = b.words[i];
    const char L = w.letter;
    if (L == 'X' || L == 'Y' || L == 'Z' || L == 'R' || L == 'L' || L == 'P' || L == 'Q' ||
        L == '@' || L == '^' || (L == 'G' && w.code10 == code))
      edit.remove.push_back(static_cast<int>(i));
  }
  const std::string rest = nc::apply_edit(b, edit);
  bool blank = true;
  for (char ch : rest) blank = blank && (ch == ' ' || ch == '\t');
  if (!blank) emit(rest);
  ++report_.lines_changed;
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
    if (code == 730 || code == 830) {
      // The pecks, as LinuxCNC makes them (convert_cycle_g73/g83): levels
      // R - Q, R - 2Q, ... above the bottom, by repeated subtraction in
      // program units and coordinates (the same count of pecks for a bottom
      // a whole number of Q below R); after each, G83 rapids out to R and
      // back down to the level reached, G73 rapids up; either stops short
      // of the level reached by 0.010 in (0.254 mm in a mm program).
      const double unit = s.unit_mm, wo_z = interp_.work_offset()[2];
      const double r_prog = s.absolute ? s.cycle_r : (h.r_mm - wo_z) / unit;
      const double bottom_prog = s.absolute ? s.cycle_z : (h.end_mm.z() - wo_z) / unit;
      const double back_off = unit == 1.0 ? 0.010 * 25.4 : 0.010;
      int pecks = 0;
      for (double depth = r_prog - s.cycle_q; depth > bottom_prog; depth -= s.cycle_q) {
        if (++pecks > kMaxPecks)
          throw InputError(
              file_, current_line_,
              fmt::format("more than {} pecks in one hole (Q {:g}); --expand-cycles would write "
                          "them all: raise Q or post without --expand-cycles",
                          kMaxPecks, s.cycle_q));
        const Vector3d level(x, y, depth * unit + wo_z);
        expanded_feed(c, at, level, lower, spaces);
        at = level;
        if (code == 830) rapid_to(Vector3d(x, y, h.r_mm));
        rapid_to(Vector3d(x, y, (depth + back_off) * unit + wo_z));
      }
    }
    const Vector3d bottom(x, y, h.end_mm.z());
    expanded_feed(c, at, bottom, lower, spaces);
    at = bottom;
    if (code == 820 || code == 890) {
      std::string dwell = lower ? "g4" : "G4";
      if (spaces) dwell += ' ';
      dwell += lower ? 'p' : 'P';
      dwell += nc::format_number(cycle_dwell_s_, std::max(dec, 3));
      emit(dwell);
      ++report_.lines_added;
    }
    if (code == 850 || code == 890) {
      const Vector3d r_level(x, y, h.r_mm);
      expanded_feed(c, at, r_level, lower, spaces);
      at = r_level;
    }
    if (h.clear_mm != at.z()) rapid_to(Vector3d(x, y, h.clear_mm));
  }
}

void ProgramPost::expanded_rapid(const Corrector& c, const Vector3d& from, const Vector3d& to,
                                 bool lower, bool spaces) {
  ApproachDirections d;
  const Vector3d cmd = position_command(c, from, to, false, d);
  CharBuffer& l = expanded_line_;
  l.assign(lower ? "g0" : "G0");
  if (spaces) l.append(" ");
  append_axis_words(cmd, false, lower, spaces, l);
  emit(l.view());
  ++report_.lines_added;
  emitted_mm_ = reached(cmd, false);
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
    CharBuffer& l = expanded_line_;
    l.assign(lower ? "g1" : "G1");
    if (spaces) l.append(" ");
    append_axis_words(piece.command_mm, false, lower, spaces, l);
    emit(l.view());
    ++report_.lines_added;
    emitted_mm_ = reached(piece.command_mm, false);
  }
}

void ProgramPost::line(std::string_view raw, int number, bool newline) {
  current_line_ = number;
  ++report_.lines;
  // The line ending goes out as it came in (CRLF stays CRLF; a last line
  // without a newline stays without one).
  const bool cr = !raw.empty() && raw.back() == '\r';
  const std::string_view text = cr ? raw.substr(0, raw.size() - 1) : raw;
  line_ending_size_ = 0;
  if (cr) line_ending_[line_ending_size_++] = '\r';
  if (newline) line_ending_[line_ending_size_++] = '\n';
  if (plain_line(text)) return;
  nc::lex_block_into(text, number, file_, block_);
  const nc::Block& b = block_;
  const bool known_before = interp_.state().position_known;
  const double offset_before = interp_.state().tool_length_mm;
  nc::BlockEffect& fx = fx_;
  interp_.execute(b, fx);
  // A change of tool length offset moves the controlled point where the
  // controller stands, as it moves the interpreter's (LinuxCNC).
  if (const double offset = interp_.state().tool_length_mm; offset != offset_before)
    emitted_mm_.z() -= offset - offset_before;
  if (!interp_.state().cycle_il_known) ctrl_il_known_ = false;
  const Corrector& c = corrector();
  // The line goes out as written: the controller then stands where its
  // words say, the axes it does not name where we left them.
  auto unchanged = [&] {
    emit(text);
    if (fx.has_motion) {
      if (!emitted_known_ || fx.motion.kind == nc::MotionKind::kCycle) {
        emitted_mm_ = interp_.state().position_mm;
      } else {
        const nc::State& st = interp_.state();
        for (int a = 0; a < 3; ++a) {
          const nc::Word* w = b.find("XYZ"[a]);
          if (!w) continue;
          emitted_mm_[a] = st.absolute
                               ? w->value * st.unit_mm + (fx.g53 ? 0.0 : interp_.work_offset()[a])
                               : emitted_mm_[a] + w->value * st.unit_mm;
        }
      }
    }
    emitted_known_ = interp_.state().position_known;
  };
  if (!fx.has_motion || c.zero() || b.block_delete) {
    // Block delete: the line may or may not run on the machine; it is
    // written unchanged and the correction goes on from its nominal end.
    unchanged();
    return;
  }
  const nc::Motion& m = fx.motion;
  // One pass over the words: the indices of X, Y and Z (asked for again and
  // again below), and the block's style, as nc::block_uses_lowercase (the
  // case of the first letter, '@' and '^' have none) and
  // nc::block_uses_spaces (a gap between two words; a lone word: spaces).
  int axis_index[3] = {-1, -1, -1};
  bool lower = false, case_known = false, spaced = false;
  {
    const size_t n = b.words.size();
    std::uint32_t prev_end = 0;
    for (size_t k = 0; k < n; ++k) {
      const nc::Word& w = b.words[k];
      const char L = w.letter;
      if (L >= 'X' && L <= 'Z' && axis_index[L - 'X'] < 0)
        axis_index[L - 'X'] = static_cast<int>(k);
      if (!case_known && L != '@' && L != '^') {
        case_known = true;
        lower = b.text[w.begin] >= 'a';
      }
      if (k > 0 && w.begin > prev_end) spaced = true;
      prev_end = w.end;
    }
    spaced = spaced || n <= 1;
  }
  const bool spaces = spaced;
  const int dec = decimals();
  const double half_unit = ProgramPost::half_unit(dec);

  // Indices of the words this block states.
  auto index_of = [&](char L) {
    for (size_t k = 0; k < b.words.size(); ++k)
      if (b.words[k].letter == L) return static_cast<int>(k);
    return -1;
  };
  // Does axis a need a new word to command cmd? Compared with what the block
  // writes (or, for an absent word, with staying put).
  auto needs_word = [&](int a, const Vector3d& cmd) {
    const int idx = axis_index[a];
    return axis_needs_word(a, cmd, idx >= 0 ? &b.words[static_cast<size_t>(idx)].value : nullptr,
                           fx.g53);
  };

  if (m.kind == nc::MotionKind::kRapid) {
    if (!known_before && !interp_.state().position_known) {
      unchanged();  // partial rapid from an unknown position: nothing to correct
      return;
    }
  }
  if (!emitted_known_) emitted_mm_ = m.start_mm;

  if (m.kind == nc::MotionKind::kCycle && options_.expand_cycles) {
    expand_cycle(b, fx, c, lower, spaces, dec);
    return;
  }
  if (m.kind == nc::MotionKind::kCycle &&
      (!fx.more_holes.empty() || !interp_.state().absolute || b.find('@') || b.find('^'))) {
    cycle_holes(b, fx, c, lower, spaces, dec);
    return;
  }
  if (m.kind == nc::MotionKind::kRapid || m.kind == nc::MotionKind::kCycle) {
    ApproachDirections d;
    const Vector3d cmd =
        position_command(c, m.start_mm, m.end_mm, m.kind == nc::MotionKind::kCycle, d);
    nc::BlockEdit edit;
    std::string insert;
    bool changed = false;
    const nc::State& s = interp_.state();
    std::array<bool, 3> needed{};
    // A polar block (@ ^) is always rewritten as X Y: under G91 the
    // controller would apply its increments to the corrected point, not the
    // nominal one, and X Y next to @ ^ is an error.
    const bool polar = b.has('@') || b.has('^');
    if (polar)
      for (char L : {'@', '^'})
        if (const int i = index_of(L); i >= 0) edit.remove.push_back(i);
    for (int a = 0; a < 3; ++a) {
      const int idx = index_of("XYZ"[a]);
      const double new_value = program_value(a, cmd[a], fx.g53);
      // A canned cycle's Z is the hole bottom, not where the tool stays.
      needed[static_cast<size_t>(a)] =
          m.kind == nc::MotionKind::kCycle && a == 2
              ? (idx >= 0
                     ? std::abs(new_value - b.words[static_cast<size_t>(idx)].value) >= half_unit
                     : std::abs(cmd.z() - m.end_mm.z()) >= half_unit * s.unit_mm)
              : needs_word(a, cmd) || (polar && a < 2);
      changed = changed || needed[static_cast<size_t>(a)];
    }
    // When any axis changes, the axis words are written together in X Y Z
    // order; an unchanged one keeps its original text.
    for (int a = 0; a < 3 && changed; ++a) {
      const int idx = index_of("XYZ"[a]);
      if (!needed[static_cast<size_t>(a)] && idx < 0) continue;
      if (idx >= 0) edit.remove.push_back(idx);
      if (!insert.empty() && spaces) insert += ' ';
      if (needed[static_cast<size_t>(a)]) {
        insert += lower ? "xyz"[a] : "XYZ"[a];
        insert += nc::format_number(program_value(a, cmd[a], fx.g53), dec);
      } else {
        const nc::Word& w = b.words[static_cast<size_t>(idx)];
        insert += b.text.substr(w.begin, w.end - w.begin);
      }
    }
    double cycle_clear_mm = m.clear_mm;
    if (m.kind == nc::MotionKind::kCycle) {
      enter_cycle_run();
      // The R plane, corrected where the tool reaches it, stated every block
      // (the correction differs from hole to hole).
      const Vector3d r_nominal(m.end_mm.x(), m.end_mm.y(), m.r_mm);
      const Vector3d r_cmd = command(c, r_nominal, d);
      const double r_new = (r_cmd.z() - interp_.work_offset()[2]) / s.unit_mm;
      const double r_nom = (m.r_mm - interp_.work_offset()[2]) / s.unit_mm;
      if (changed || std::abs(r_new - r_nom) >= half_unit) {
        // Z too, so both modal values are this hole's.
        if (index_of('Z') < 0 && insert.find(lower ? 'z' : 'Z') == std::string::npos) {
          if (!insert.empty() && spaces) insert += ' ';
          insert += lower ? 'z' : 'Z';
          insert += nc::format_number(program_value(2, cmd.z(), false), dec);
        }
        if (const int ri = index_of('R'); ri >= 0) edit.remove.push_back(ri);
        if (!insert.empty() && spaces) insert += ' ';
        insert += lower ? 'r' : 'R';
        insert += nc::format_number(r_new, dec);
        changed = true;
      }
      // Where the controller ends: G99 at the R it reads, G98 at the initial
      // level or that R if higher.
      const double r_read_mm =
          changed ? written(r_new, dec) * s.unit_mm + interp_.work_offset()[2] : m.r_mm;
      cycle_clear_mm = s.g98 ? std::max(ctrl_il_mm_, r_read_mm) : r_read_mm;
    }
    if (!changed) {
      unchanged();
      return;
    }
    edit.insert = insert;
    emit(nc::apply_edit(b, edit));
    ++report_.lines_changed;
    if (m.kind == nc::MotionKind::kCycle) {
      emitted_mm_ = Vector3d(cmd.x(), cmd.y(), cycle_clear_mm);
    } else if (s.absolute) {
      emitted_mm_ = cmd;
    } else {
      // G91: the controller adds the increments as written (an axis not
      // named, or named unchanged, moves by what the block says).
      for (int a = 0; a < 3; ++a) {
        const int idx = index_of("XYZ"[a]);
        if (needed[static_cast<size_t>(a)])
          emitted_mm_[a] += written(program_value(a, cmd[a], fx.g53), dec) * s.unit_mm;
        else if (idx >= 0)
          emitted_mm_[a] += b.words[static_cast<size_t>(idx)].value * s.unit_mm;
      }
    }
    emitted_known_ = true;
    return;
  }

  // Feed moves: lines, arcs and helices.
  if (fx.stop_code)
    throw InputError(file_, number,
                     "a feed move and a stop code (M0/M1/M2/M30/M60) in one block; "
                     "put the stop code on its own line");
  const Vector3d start_cmd = emitted_mm_;
  if (m.kind == nc::MotionKind::kArc && options_.keep_arcs && keep_arc(b, m, c, lower, spaces))
    return;
  const std::vector<Piece>& pieces = segment(c, m, start_cmd);
  const bool arc = m.kind == nc::MotionKind::kArc;
  // A straight move whose end needs no change stays as written.
  const bool polar = b.has('@') || b.has('^');  // always rewritten as X Y (see the rapids)
  if (!arc && pieces.size() == 1 && !polar) {
    bool needed = false;
    for (int a = 0; a < 3; ++a) needed = needed || needs_word(a, pieces[0].command_mm);
    if (!needed) {
      unchanged();
      return;
    }
  }
  const nc::State& s = interp_.state();
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
  // The block itself becomes the first piece: its X Y Z words, its polar
  // words @ ^ (a corrected point goes out as X Y: LinuxCNC refuses @ ^
  // beside X Y), and an arc's I J K R P and G2/G3, G93's F give way to the
  // piece's words. At most 3 + 2 + 5 + 1 + 1 distinct words (a letter
  // twice, or two motion G codes, the interpreter refused).
  std::array<int, 12> remove;
  std::size_t removed = 0;
  for (int a = 0; a < 3; ++a)
    if (axis_index[a] >= 0) remove[removed++] = axis_index[a];
  for (char L : {'@', '^'})
    if (const int i = index_of(L); i >= 0) remove[removed++] = i;
  if (arc) {
    for (char L : {'I', 'J', 'K', 'R', 'P'})
      if (const int i = index_of(L); i >= 0) remove[removed++] = i;
    for (size_t k = 0; k < b.words.size(); ++k)
      if (b.words[k].letter == 'G' && (b.words[k].code10 == 20 || b.words[k].code10 == 30))
        remove[removed++] = static_cast<int>(k);
  }
  const bool g93 = s.feed_mode == 930;
  if (g93)
    if (const int i = index_of('F'); i >= 0) remove[removed++] = i;
  // Ascending, as apply_edit_to wants (insertion sort: a handful, nearly
  // always in order already).
  for (std::size_t r = 1; r < removed; ++r)
    for (std::size_t q = r; q > 0 && remove[q - 1] > remove[q]; --q)
      std::swap(remove[q - 1], remove[q]);
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
  emitted_mm_ = reached(pieces[0].command_mm, g53);
  emit_following_pieces(pieces, g53, lower, spaces, !g93 && s.absolute,
                        [&](size_t k, CharBuffer& w) {
                          words_for(pieces[k].command_mm, pieces[k - 1].s_end, pieces[k].s_end, w);
                        });
  emitted_known_ = true;
}

// Arcs kept as arcs (PostOptions::keep_arcs, docs/post.md). An arc is cut
// at the points where an axis of its plane turns round (its quadrant
// points): on each piece every axis moves one way, and a lost-motion step
// can be taken up between pieces (a G1 to the piece's start commanded with
// its directions), never inside an arc. The controller runs each piece from
// where it stands to the written end about the written centre, its radius
// going linearly from start to end (nc::point_on, as verify simulates it).
// The end is the corrected end point; the centre is the nominal one moved
// by the mean of the corrections at the piece's ends (for an error field
// affine over the piece, the corrected points of the nominal arc lie on a
// slightly distorted circle about it). Kept only when, for every piece, the
// actual tip stays within half the tolerance of the nominal path at samples
// as dense as the field's bounds require; otherwise the whole block is
// linearised as without the option, and everything tried is put back.
// Polar words, G53 and, under inverse time, an arc that needs more than its
// own line are linearised.
bool ProgramPost::keep_arc(const nc::Block& b, const nc::Motion& m, const Corrector& c, bool lower,
                           bool spaces) {
  if (b.has('@') || b.has('^') || !emitted_known_) return false;
  for (const nc::Word& w : b.words)
    if (w.letter == 'G' && w.code10 == 530) return false;
  const nc::ArcGeometry g = nc::arc_geometry(m);
  if (!(std::abs(g.sweep) > 1e-9)) return false;
  // The pieces: cut where the angle passes a multiple of pi/2, but not
  // within a hair of an end (a = sqrt(2e-7 mm / r): an axis backs up by
  // r (1 - cos a) < 1e-7 mm past such a point, inside any play and the
  // numbers' rounding); no sliver pieces.
  const double hair =
      std::min(1e-3, std::sqrt(2e-7 / std::max(std::min(g.radius, g.end_radius), 1e-9)));
  std::vector<double> cuts = {0.0};
  {
    const double dir = g.sweep > 0 ? 1.0 : -1.0, quarter = M_PI / 2,
                 margin = hair / std::abs(g.sweep);
    double q =
        dir > 0 ? std::floor(g.start_angle / quarter) + 1 : std::ceil(g.start_angle / quarter) - 1;
    for (int guard = 0; guard < 4 * 1024; ++guard, q += dir) {
      const double s_cut = (q * quarter - g.start_angle) / g.sweep;
      if (s_cut >= 1.0 - margin) break;
      if (s_cut > margin) cuts.push_back(s_cut);
    }
    cuts.push_back(1.0);
    if (cuts.size() > 4 * 1024) return false;
  }
  const nc::State& s = interp_.state();
  const int dec = decimals();
  const double r_max = std::max(g.radius, g.end_radius);
  // Samples close enough that the deviation grows by at most 5 % of the
  // tolerance between two: its second derivative along the arc is at most
  // M = K r^2 + 2 L r (the field's curvature and Lipschitz bounds; the
  // corrected and nominal circles differ by the correction, whose change
  // over the arc the same bounds hold), so steps of sqrt(8 * 0.05 tol / M)
  // rad. No bounds (a compensation table): linearised.
  const double M = c.curvature_bound() * r_max * r_max + 2 * c.lipschitz_bound() * r_max;
  const double step_rad = std::min(0.05, M > 0 ? std::sqrt(0.4 * options_.tolerance_mm / M) : 0.05);
  if (!(step_rad > 0) || !(std::abs(g.sweep) / step_rad <= 1e6)) return false;
  // What the pieces change: put back if the block is not kept.
  const LastCorrected last_was = last_, before_last_was = before_last_;
  const PostReport report_was = report_;
  const Vector3d emitted_was = emitted_mm_;
  const ApproachDirections last_dir_was = last_dir_;
  auto give_up = [&] {
    last_ = last_was;
    before_last_ = before_last_was;
    report_ = report_was;
    emitted_mm_ = emitted_was;
    last_dir_ = last_dir_was;
    return false;
  };
  const char* arc_code = lower ? (m.clockwise ? "g2" : "g3") : (m.clockwise ? "G2" : "G3");
  // The lines, in order: arcs and take-up steps (G1), their words.
  struct Line {
    bool arc;
    std::string words;
  };
  std::vector<Line> lines;
  for (size_t k = 0; k + 1 < cuts.size(); ++k) {
    nc::Motion piece = m;
    piece.extra_turns = 0;
    piece.start_mm = k == 0 ? m.start_mm : nc::point_on(m, cuts[k]);
    piece.end_mm = nc::point_on(m, cuts[k + 1]);
    const nc::ArcGeometry pg = nc::arc_geometry(piece);
    // (A piece that arc_geometry reads as a full turn, or backwards: give up.)
    if (!(std::abs(pg.sweep - g.sweep * (cuts[k + 1] - cuts[k])) < 1e-6)) return give_up();
    // Its directions: the plane's axes from the tangent at its middle, the
    // normal axis from the helix, else as they were.
    const Vector3d mid_tangent = nc::point_on(piece, 0.5 + 1e-3) - nc::point_on(piece, 0.5 - 1e-3);
    ApproachDirections d = last_dir_;
    for (int a : {g.a0, g.a1})
      if (mid_tangent[a] != 0) d[static_cast<size_t>(a)] = mid_tangent[a] > 0 ? 1 : -1;
    if (m.end_mm[g.normal] != m.start_mm[g.normal])
      d[static_cast<size_t>(g.normal)] = m.end_mm[g.normal] > m.start_mm[g.normal] ? 1 : -1;
    // An axis that turns round here takes up its play first.
    bool step = false;
    Vector3d c0, c1;
    auto solve = [&] {
      step = !c.same_error(last_dir_, d);
      c0 = step ? command(c, piece.start_mm, d) : emitted_mm_;
      c1 = command(c, piece.end_mm, d);
    };
    solve();
    // The plane's normal axis, when the arc does not move it, may still be
    // commanded to creep (the correction varies along the arc), linearly
    // over the piece: it takes the creep's direction (segment()'s
    // settle_directions), its play taken up by the step.
    if (const int n = g.normal; m.end_mm[n] == m.start_mm[n] && c.bidirectional(n)) {
      const double creep = c1[n] - c0[n];
      if (creep != 0 && (creep > 0 ? 1 : -1) != d[static_cast<size_t>(n)]) {
        d[static_cast<size_t>(n)] = creep > 0 ? 1 : -1;
        solve();
      }
    }
    if (step && s.feed_mode == 930) return give_up();  // the step's own F: linearised instead
    nc::Motion cmd = piece;
    cmd.start_mm = c0;
    cmd.end_mm = c1;
    const Vector3d shift = 0.5 * ((c0 - piece.start_mm) + (c1 - piece.end_mm));
    cmd.center_mm[g.a0] = m.center_mm[g.a0] + shift[g.a0];
    cmd.center_mm[g.a1] = m.center_mm[g.a1] + shift[g.a1];
    const nc::ArcGeometry gc = nc::arc_geometry(cmd);
    if (!(std::abs(gc.sweep - pg.sweep) < 1e-3) || !(std::abs(gc.radius - gc.end_radius) < 0.01))
      return give_up();
    // Every axis commanded the way d says (a creep against it would be lost
    // in the play of an axis with lost motion). The corrected piece may
    // begin or end a hair past the quadrant point the nominal one begins or
    // ends at: the axis backs up by r (1 - cos a), under 1e-7 mm for
    // a = sqrt(2e-7 mm / r), inside any play and the numbers' rounding.
    for (int a = 0; a < 3; ++a) {
      const double move = c1[a] - c0[a];
      if (move != 0 && c.bidirectional(a) && (move > 0 ? 1 : -1) != d[static_cast<size_t>(a)])
        return give_up();
    }
    {
      const double lo = std::min(gc.start_angle, gc.start_angle + gc.sweep) + 2 * hair,
                   hi = std::max(gc.start_angle, gc.start_angle + gc.sweep) - 2 * hair;
      if (std::floor(lo / (M_PI / 2)) * (M_PI / 2) + M_PI / 2 < hi) return give_up();
    }
    // An arc whose written ends would coincide is a full circle to the
    // controller: such a piece is not written as an arc.
    if (!((c1 - c0).norm() > 40 * half_unit(dec) * s.unit_mm)) return give_up();
    const int samples = std::max(16, static_cast<int>(std::ceil(std::abs(pg.sweep) / step_rad)));
    for (int j = 0; j <= samples; ++j) {
      const Vector3d x = nc::point_on(cmd, static_cast<double>(j) / samples);
      if (!(nc::distance_to_path(m, x + c.error_at(x, d)) <= 0.5 * options_.tolerance_mm))
        return give_up();
    }
    // The piece's lines: the take-up step (unless below the output's
    // resolution, as in segment()), then the arc.
    if (step) {
      bool needed = false;
      for (int a = 0; a < 3; ++a) needed = needed || axis_needs_word(a, c0, nullptr, false);
      if (needed) {
        CharBuffer& l = expanded_line_;
        l.clear();
        append_axis_words(c0, false, lower, spaces, l);
        lines.push_back({false, std::string(l.view())});
        emitted_mm_ = reached(c0, false);
      }
    }
    CharBuffer& w = words_;
    w.clear();
    append_axis_words(c1, false, lower, spaces, w);
    // The centre: from where the controller starts (G91.1: the start as
    // written under G90, where it stands under G91), or in program
    // coordinates (G90.1).
    for (int a : std::array<int, 2>{std::min(g.a0, g.a1), std::max(g.a0, g.a1)}) {
      const char letter = lower ? "ijk"[a] : "IJK"[a];
      if (spaces) w.append(" ");
      w.append(std::string_view(&letter, 1));
      const double centre_prog = (cmd.center_mm[a] - interp_.work_offset()[a]) / s.unit_mm;
      double value;
      if (s.arc_absolute)
        value = centre_prog;
      else if (s.absolute)
        value = centre_prog -
                written(program_value(a, emitted_mm_[a], false), dec);  // the start as written
      else
        value = (cmd.center_mm[a] - emitted_mm_[a]) / s.unit_mm;  // where the controller stands
      append_number(w, value, dec);
    }
    lines.push_back({true, std::string(w.view())});
    emitted_mm_ = reached(c1, false);
    last_dir_ = d;
  }
  // Under G93 every line needs its own F (inverse time): one line only.
  if (s.feed_mode == 930 && lines.size() > 1) return give_up();
  // Kept: the lines out. The first takes the block's place: the block keeps
  // its other words (its modes apply to all that follows), its end point and
  // centre words are replaced (an R form becomes I J K, a P gives way to
  // the pieces), and the motion is stated: the arc's G2/G3 (the block may
  // rely on the modal one, and an arc linearised before it left the output
  // in G1), or G1 for a take-up step, in place of the block's G2/G3.
  nc::BlockEdit edit;
  bool stated = false;
  for (size_t k = 0; k < b.words.size(); ++k) {
    const nc::Word& word = b.words[k];
    const char L = word.letter;
    const bool motion = L == 'G' && (word.code10 == 20 || word.code10 == 30);
    if (L == 'X' || L == 'Y' || L == 'Z' || L == 'I' || L == 'J' || L == 'K' || L == 'R' ||
        L == 'P' || (motion && !lines[0].arc))
      edit.remove.push_back(static_cast<int>(k));
    stated = stated || motion;
  }
  const char* first_code = lines[0].arc ? (stated ? "" : arc_code) : (lower ? "g1" : "G1");
  edit.insert = std::string(first_code) + (*first_code && spaces ? " " : "") + lines[0].words;
  emit(nc::apply_edit(b, edit));
  ++report_.lines_changed;
  for (size_t k = 1; k < lines.size(); ++k) {
    emit(std::string(lines[k].arc ? arc_code : (lower ? "g1" : "G1")) + (spaces ? " " : "") +
         lines[k].words);
    ++report_.lines_added;
  }
  return true;
}

bool ProgramPost::plain_line(std::string_view text) {
  const nc::State& st = interp_.state();
  // The state the line needs (the rest is execute_linear_axes's): the same
  // tool as the last line, errors, the controller's position known, G90,
  // no inverse time.
  if (!options_.shortcuts || !emitted_known_ || !st.absolute || st.feed_mode == 930 ||
      !last_corrector_ || machine_.tool_length_mm + st.tool_length_mm != last_corrector_length_ ||
      last_corrector_->zero())
    return false;
  nc::PlainAxisWords words;
  if (!nc::lex_plain_axis_words(text, words)) return false;
  if (!interp_.execute_linear_axes(words.value, words.given, plain_motion_)) return false;
  // From here on, line()'s path for a straight feed move, step by step.
  ctrl_il_known_ = false;  // the run of cycle blocks has ended
  const Corrector& c = *last_corrector_;
  const std::vector<Piece>& pieces = segment(c, plain_motion_, emitted_mm_);
  if (pieces.size() == 1) {
    bool needed = false;
    for (int a = 0; a < 3; ++a)
      needed =
          needed || axis_needs_word(a, pieces[0].command_mm,
                                    (words.given >> a & 1u) ? &words.value[a] : nullptr, false);
    if (!needed) {  // unchanged(): the line as written, the controller where its words say (the
                    // move's end)
      emit(text);
      for (int a = 0; a < 3; ++a)
        if (words.given >> a & 1u) emitted_mm_[a] = plain_motion_.end_mm[a];
      return true;
    }
  }
  // The line's words are all axis words: the edited line is the first
  // piece's words alone (apply_edit_to removes every word, separating
  // spaces with them, and puts the insert in their place).
  previous_words_.clear();
  append_axis_words(pieces[0].command_mm, false, words.lower, words.spaced, previous_words_);
  emit(previous_words_.view());
  ++report_.lines_changed;
  emitted_mm_ = pieces[0].command_mm;  // reached(): G90
  emit_following_pieces(
      pieces, false, words.lower, words.spaced, true, [&](size_t k, CharBuffer& w) {
        w.clear();
        append_axis_words(pieces[k].command_mm, false, words.lower, words.spaced, w);
      });
  return true;
}

}  // namespace

namespace {
PostReport run_post(std::istream& in, const std::string& in_name, std::ostream& out,
                    const Machine& machine, const ErrorSet& errors,
                    const maps::VolumetricTable* table, const nc::ProgramSetup& setup,
                    const PostOptions& options) {
  if (!(options.tolerance_mm > 0) || !std::isfinite(options.tolerance_mm))
    throw std::invalid_argument("--tolerance-um must be a positive finite number");
  if (table)
    Corrector check(machine, *table, options.outside);  // a wrong table fails before any output
  ProgramPost post(in_name, out, machine, errors, setup, options, table);
  // Lines out of a large buffer (getline's per-line work and copies avoided);
  // the buffer grows only to hold the longest line.
  std::vector<char> buf(1 << 16);
  std::size_t begin = 0, end = 0;
  bool eof = false;
  int number = 0;
  try {
    for (;;) {
      const char* nl = static_cast<const char*>(std::memchr(buf.data() + begin, '\n', end - begin));
      if (nl) {
        const auto at = static_cast<std::size_t>(nl - buf.data());
        post.line(std::string_view(buf.data() + begin, at - begin), ++number, true);
        begin = at + 1;
        continue;
      }
      if (eof) {
        if (begin < end)
          post.line(std::string_view(buf.data() + begin, end - begin), ++number, false);
        break;
      }
      const std::size_t rest = end - begin;
      std::memmove(buf.data(), buf.data() + begin, rest);
      begin = 0;
      end = rest;
      if (end == buf.size()) buf.resize(2 * buf.size());
      in.read(buf.data() + end, static_cast<std::streamsize>(buf.size() - end));
      const auto got = static_cast<std::size_t>(in.gcount());
      end += got;
      if (got == 0) eof = true;
    }
  } catch (const std::out_of_range& e) {
    // An error table's range (the message names the table's file:line):
    // the block that left it is the program's line (docs/model.md).
    post.flush();
    throw InputError(in_name, number,
                     std::string("this block leaves the error tables: ") + e.what() +
                         " (volmap post --clamp holds the end values)");
  } catch (...) {
    post.flush();
    throw;
  }
  post.flush();
  return post.report();
}

}  // namespace

PostReport post_program(std::istream& in, const std::string& in_name, std::ostream& out,
                        const Machine& machine, const ErrorSet& errors,
                        const nc::ProgramSetup& setup, const PostOptions& options) {
  return run_post(in, in_name, out, machine, errors, nullptr, setup, options);
}

PostReport post_program(std::istream& in, const std::string& in_name, std::ostream& out,
                        const Machine& machine, const maps::VolumetricTable& table,
                        const nc::ProgramSetup& setup, const PostOptions& options) {
  static const ErrorSet kNoErrors;
  return run_post(in, in_name, out, machine, kNoErrors, &table, setup, options);
}

}  // namespace volmap::post
