#include "postproc/post_program.h"

#include <array>
#include <cmath>
#include <istream>
#include <map>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "core/input_error.h"
#include "gcode/nc_path.h"
#include "gcode/nc_writer.h"
#include "postproc/corrector.h"

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

class ProgramPost {
 public:
  ProgramPost(const std::string& file, std::ostream& out, const Machine& machine,
              const ErrorSet& errors, const nc::ProgramSetup& setup, const PostOptions& options)
      : file_(file), out_(out), machine_(machine), errors_(errors), options_(options),
        interp_(setup, file) {}

  void line(const std::string& text, int number, bool newline);
  const PostReport& report() const { return report_; }

 private:
  const Corrector& corrector() {
    const double L = interp_.state().tool_length_active ? interp_.state().tool_length_mm
                                                        : machine_.tool_length_mm;
    auto it = correctors_.find(L);
    if (it == correctors_.end())
      it = correctors_.emplace(L, std::make_unique<Corrector>(machine_, errors_, L, options_.outside)).first;
    return *it->second;
  }
  int decimals() const {
    if (options_.decimals >= 0) return options_.decimals;
    return interp_.state().unit_mm > 1.0 ? 5 : 4;
  }
  Vector3d command(const Corrector& c, const Vector3d& nominal, const ApproachDirections& d) {
    const Vector3d cmd = c.command_for(nominal, d);
    const double corr = (cmd - nominal).norm();
    if (!std::isfinite(corr))
      throw InputError(file_, current_line_, "the correction is not finite here; check the errors file");
    report_.max_correction_mm = std::max(report_.max_correction_mm, corr);
    ++report_.points_corrected;
    return cmd;
  }
  std::vector<Piece> segment(const Corrector& c, const nc::Motion& m, const Vector3d& start_cmd);
  // Program value of axis a for commanded machine position v.
  double program_value(int a, double v_mm, bool g53) const {
    const nc::State& s = interp_.state();
    if (s.absolute) return (v_mm - (g53 ? 0.0 : interp_.work_offset()[a])) / s.unit_mm;
    return (v_mm - emitted_mm_[a]) / s.unit_mm;
  }
  std::string axis_words(const Vector3d& cmd, bool g53, bool lower, bool spaces) {
    std::string s;
    for (int a = 0; a < 3; ++a) {
      if (!s.empty() && spaces) s += ' ';
      s += lower ? "xyz"[a] : "XYZ"[a];
      s += nc::format_number(program_value(a, cmd[a], g53), decimals());
    }
    return s;
  }
  void emit(const std::string& text) {
    out_ << text;
    if (!line_ending_.empty()) out_ << line_ending_;
  }

  std::string file_;
  std::ostream& out_;
  const Machine& machine_;
  const ErrorSet& errors_;
  PostOptions options_;
  nc::Interpreter interp_;
  std::map<double, std::unique_ptr<Corrector>> correctors_;
  PostReport report_;
  Vector3d emitted_mm_ = Vector3d::Zero();  ///< last commanded position written
  bool emitted_known_ = false;
  ApproachDirections last_dir_{};  ///< direction each axis last moved in (0: not yet)
  int current_line_ = 0;
  std::string line_ending_;
};

// Pieces of one move at most (an arc's initial pieces, and all pieces).
constexpr int kMaxArcPieces = 1 << 16;

std::vector<Piece> ProgramPost::segment(const Corrector& c, const nc::Motion& m,
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
      throw InputError(file_, current_line_,
                       fmt::format("the arc needs more than {} pieces to keep {:g} um (radius {:g} mm); "
                                   "raise --tolerance-um or check the arc's centre",
                                   kMaxArcPieces, tol * 1e3, r));
    n0 = std::max(4, static_cast<int>(pieces));
  }
  std::vector<Piece> done;
  struct Pending {
    double s0, s1;
    Vector3d c0;
    ApproachDirections dir0;  ///< axis directions on arrival at s0
  };
  std::vector<Pending> stack;
  Vector3d c_prev = start_cmd;
  double s_prev = 0.0;
  constexpr int kMaxPieces = kMaxArcPieces;
  for (int k = 1; k <= n0; ++k) {
    stack.push_back({s_prev, static_cast<double>(k) / n0, c_prev, last_dir_});
    while (!stack.empty()) {
      const Pending p = stack.back();
      stack.pop_back();
      const Vector3d n0p = nc::point_on(m, p.s0), n1p = nc::point_on(m, p.s1);
      ApproachDirections d = directions_of(n0p, n1p, p.dir0);
      Vector3d c1 = command(c, n1p, d);
      if (settle_directions(p.c0, c1, n0p, n1p, d)) c1 = command(c, n1p, d);
      bool ok = true;
      for (double t : {0.25, 0.5, 0.75}) {
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
          throw InputError(file_, current_line_,
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
          stack.push_back({p.s1, end, c1, d});
        }
      } else {
        const double mid = 0.5 * (p.s0 + p.s1);
        stack.push_back({mid, p.s1, Vector3d::Zero(), p.dir0});  // c0, dir0 set when reached
        stack.push_back({p.s0, mid, p.c0, p.dir0});
      }
    }
  }
  return done;
}

void ProgramPost::line(const std::string& raw, int number, bool newline) {
  current_line_ = number;
  ++report_.lines;
  // The line ending goes out as it came in (CRLF stays CRLF; a last line
  // without a newline stays without one).
  const bool cr = !raw.empty() && raw.back() == '\r';
  const std::string text = cr ? raw.substr(0, raw.size() - 1) : raw;
  line_ending_.clear();
  if (cr) line_ending_.push_back('\r');
  if (newline) line_ending_.push_back('\n');
  const nc::Block b = nc::lex_block(text, number, file_);
  const bool known_before = interp_.state().position_known;
  nc::BlockEffect fx;
  interp_.execute(b, fx);
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
          emitted_mm_[a] = st.absolute ? w->value * st.unit_mm + (fx.g53 ? 0.0 : interp_.work_offset()[a])
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
  const bool lower = nc::block_uses_lowercase(b);
  const bool spaces = nc::block_uses_spaces(b);
  const int dec = decimals();
  const double half_unit = 0.5 * std::pow(10.0, -dec);

  // Indices of the words this block states.
  auto index_of = [&](char L) {
    for (size_t k = 0; k < b.words.size(); ++k)
      if (b.words[k].letter == L) return static_cast<int>(k);
    return -1;
  };
  // Does axis a need a new word to command cmd? Compared with what the block
  // writes (or, for an absent word, with staying put).
  auto needs_word = [&](int a, const Vector3d& cmd) {
    const int idx = index_of("XYZ"[a]);
    double old_value;
    if (idx >= 0)
      old_value = b.words[static_cast<size_t>(idx)].value;
    else
      old_value = interp_.state().absolute ? program_value(a, emitted_mm_[a], fx.g53) : 0.0;
    return std::abs(program_value(a, cmd[a], fx.g53) - old_value) >= half_unit;
  };

  if (m.kind == nc::MotionKind::kRapid) {
    if (!known_before && !interp_.state().position_known) {
      unchanged();  // partial rapid from an unknown position: nothing to correct
      return;
    }
  }
  if (!emitted_known_) emitted_mm_ = m.start_mm;

  if (m.kind == nc::MotionKind::kRapid || m.kind == nc::MotionKind::kCycle) {
    const ApproachDirections d = m.kind == nc::MotionKind::kCycle
                                     ? ApproachDirections{last_dir_[0], last_dir_[1], -1, 0, 0, 0}
                                     : directions_of(m.start_mm, m.end_mm, last_dir_);
    last_dir_ = d;
    const Vector3d cmd = command(c, m.end_mm, d);
    nc::BlockEdit edit;
    std::string insert;
    bool changed = false;
    const nc::State& s = interp_.state();
    std::array<bool, 3> needed{};
    for (int a = 0; a < 3; ++a) {
      const int idx = index_of("XYZ"[a]);
      const double new_value = program_value(a, cmd[a], fx.g53);
      // A canned cycle's Z is the hole bottom, not where the tool stays.
      needed[static_cast<size_t>(a)] =
          m.kind == nc::MotionKind::kCycle && a == 2
              ? (idx >= 0 ? std::abs(new_value - b.words[static_cast<size_t>(idx)].value) >= half_unit
                          : std::abs(cmd.z() - m.end_mm.z()) >= half_unit * s.unit_mm)
              : needs_word(a, cmd);
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
    if (m.kind == nc::MotionKind::kCycle) {
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
    }
    if (!changed) {
      unchanged();
      return;
    }
    edit.insert = insert;
    emit(nc::apply_edit(b, edit));
    ++report_.lines_changed;
    if (m.kind == nc::MotionKind::kCycle)
      emitted_mm_ = Vector3d(cmd.x(), cmd.y(), m.clear_mm);  // returns to the nominal clearance
    else
      emitted_mm_ = cmd;
    emitted_known_ = true;
    return;
  }

  // Feed moves: lines, arcs and helices.
  if (fx.stop_code)
    throw InputError(file_, number, "a feed move and a stop code (M0/M1/M2/M30/M60) in one block; "
                                    "put the stop code on its own line");
  const Vector3d start_cmd = emitted_mm_;
  const std::vector<Piece> pieces = segment(c, m, start_cmd);
  const bool arc = m.kind == nc::MotionKind::kArc;
  // A straight move whose end needs no change stays as written.
  if (!arc && pieces.size() == 1) {
    bool needed = false;
    for (int a = 0; a < 3; ++a) needed = needed || needs_word(a, pieces[0].command_mm);
    if (!needed) {
      unchanged();
      return;
    }
  }
  const nc::State& s = interp_.state();
  const double length = nc::path_length_mm(m);
  auto g93_feed = [&](double s0, double s1) {
    // Inverse time: the piece takes its share of the block's time.
    const double share = std::max(1e-12, s1 - s0);
    return nc::format_number(s.feed / share, 4);
  };
  // The block itself becomes the first piece.
  nc::BlockEdit edit;
  for (char L : {'X', 'Y', 'Z'})
    if (const int i = index_of(L); i >= 0) edit.remove.push_back(i);
  if (arc) {
    for (char L : {'I', 'J', 'K', 'R', 'P'})
      if (const int i = index_of(L); i >= 0) edit.remove.push_back(i);
    for (size_t k = 0; k < b.words.size(); ++k)
      if (b.words[k].letter == 'G' && (b.words[k].code10 == 20 || b.words[k].code10 == 30))
        edit.remove.push_back(static_cast<int>(k));
  }
  const bool g93 = s.feed_mode == 930;
  if (g93)
    if (const int i = index_of('F'); i >= 0) edit.remove.push_back(i);
  std::string insert = arc ? (lower ? "g1" : "G1") : "";
  const bool g53 = fx.g53;
  auto words_for = [&](const Vector3d& cmd, double s0, double s1) {
    std::string w = axis_words(cmd, g53, lower, spaces);
    if (g93) {
      if (spaces) w += ' ';
      w += lower ? 'f' : 'F';
      w += g93_feed(s0, s1);
    }
    return w;
  };
  if (!insert.empty() && spaces) insert += ' ';
  insert += words_for(pieces[0].command_mm, 0.0, pieces[0].s_end);
  edit.insert = insert;
  emit(nc::apply_edit(b, edit));
  ++report_.lines_changed;
  emitted_mm_ = pieces[0].command_mm;
  std::string previous_words = words_for(pieces[0].command_mm, 0.0, pieces[0].s_end);
  for (size_t k = 1; k < pieces.size(); ++k) {
    const std::string w = words_for(pieces[k].command_mm, pieces[k - 1].s_end, pieces[k].s_end);
    // A piece below the output resolution (a lost-motion step at a
    // reversal) would repeat the line before it: the controller cannot
    // command it, so it is not written.
    if (w == previous_words && !g93 && s.absolute) continue;
    previous_words = w;
    std::string l = lower ? "g1" : "G1";
    if (spaces) l += ' ';
    l += w;
    emit(l);
    ++report_.lines_added;
    emitted_mm_ = pieces[k].command_mm;
  }
  emitted_known_ = true;
  (void)length;
}

}  // namespace

PostReport post_program(std::istream& in, const std::string& in_name, std::ostream& out,
                        const Machine& machine, const ErrorSet& errors,
                        const nc::ProgramSetup& setup, const PostOptions& options) {
  if (!(options.tolerance_mm > 0) || !std::isfinite(options.tolerance_mm))
    throw std::invalid_argument("--tolerance-um must be a positive finite number");
  ProgramPost post(in_name, out, machine, errors, setup, options);
  std::string text;
  int number = 0;
  while (std::getline(in, text)) {
    ++number;
    try {
      post.line(text, number, !in.eof());
    } catch (const std::out_of_range& e) {
      // An error table's range (the message names the table's file:line):
      // the block that left it is the program's line (docs/model.md).
      throw InputError(in_name, number,
                       std::string("this block leaves the error tables: ") + e.what() +
                           " (volmap post --clamp holds the end values)");
    }
  }
  return post.report();
}

}  // namespace volmap::post
