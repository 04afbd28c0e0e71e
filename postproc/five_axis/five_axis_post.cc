#include "postproc/five_axis/five_axis_post.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <vector>

#include "core/common/input_error.h"
#include "gcode/nc_path.h"
#include "gcode/nc_writer.h"
#include "postproc/five_axis/five_axis_transform.h"

namespace volmap::post {
namespace {

using Eigen::Vector3d;

// apply_edit, without the trailing blanks that removed words can leave.
std::string edited(const nc::Block& b, const nc::BlockEdit& e) {
  std::string t = nc::apply_edit(b, e);
  const bool blank_end = !b.text.empty() && (b.text.back() == ' ' || b.text.back() == '\t');
  if (!blank_end)
    while (!t.empty() && (t.back() == ' ' || t.back() == '\t')) t.pop_back();
  return t;
}

constexpr double kRadToDeg = 180.0 / M_PI;

double angle_between(const Vector3d& a, const Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// The nominal pose of a move at path parameter s and its nominal axes.
struct NominalAt {
  ToolPose v;
  AxisVector u;
  bool singular = false;
};

class FiveAxisPost {
 public:
  FiveAxisPost(const std::string& file, std::ostream& out, const FiveAxisTransform& tf,
               const FiveAxisPostOptions& o)
      : file_(file), out_(out), o_(o), tf_(tf) {
    const Machine& m = tf_.machine();
    u_nom_ = m.home;
    for (int k = 0; k < m.axis_count(); ++k)
      if (is_rotary(m.axis_order[static_cast<size_t>(k)]) && o.initial.q.size() == m.axis_count())
        u_nom_[k] = o.initial.q[k];
  }

  void run(FiveAxisReader& reader);
  FiveAxisPostReport report_;

 private:
  NominalAt nominal_at(const FiveAxisMove& m, double s, const AxisVector& previous) const {
    NominalAt n;
    n.v.tip_mm = nc::point_on(m.tip, s);
    if (m.by_angles) {
      const AxisVector q = m.q0 + s * (m.q1 - m.q0);
      n.u = tf_.axes_for_angles(q, n.v.tip_mm);
      n.v.axis = tf_.nominal(n.u).axis;
    } else {
      n.v.axis = slerp_axis(m.a0, m.a1, s);
      n.u = tf_.axes_for_pose(n.v, previous, &n.singular);
    }
    return n;
  }
  AxisVector command(const AxisVector& u_nom) {
    const Machine& m = tf_.machine();
    try {
      check_within_travel(m, u_nom);
    } catch (const std::invalid_argument& e) {
      fail(std::string(e.what()) + "; place the part elsewhere on the table (--part-origin)");
    }
    const AxisVector c = tf_.command(u_nom);
    double lin = 0, rot = 0;
    for (int k = 0; k < m.axis_count(); ++k) {
      const double d = c[k] - u_nom[k];
      (is_rotary(m.axis_order[static_cast<size_t>(k)]) ? rot : lin) += d * d;
    }
    if (!std::isfinite(lin + rot)) fail("the correction is not finite here; check the errors file");
    report_.max_correction_mm = std::max(report_.max_correction_mm, std::sqrt(lin));
    report_.max_correction_rad = std::max(report_.max_correction_rad, std::sqrt(rot));
    try {
      check_within_travel(m, c);
    } catch (const std::invalid_argument& e) {
      fail(std::string(e.what()) + "; place the part elsewhere on the table (--part-origin)");
    }
    ++report_.poses;
    return c;
  }
  [[noreturn]] void fail(const std::string& msg) const { throw InputError(file_, line_, msg); }

  struct Piece {
    AxisVector c;  ///< commanded
    double s1;
    bool forced = false;  ///< accepted at the smallest span (a turn at the singular position)
  };
  // The written axis words of c without letters (to find repeated lines).
  std::string axes_key(const AxisVector& c, double unit_mm) const {
    const Machine& mach = tf_.machine();
    const int dec = o_.decimals >= 0 ? o_.decimals : (unit_mm > 1.0 ? 5 : 4);
    std::string k;
    for (int i = 0; i < mach.axis_count(); ++i) {
      if (is_rotary(mach.axis_order[static_cast<size_t>(i)]))
        append_number(k, c[i] * kRadToDeg, o_.angle_decimals);
      else
        append_number(k, c[i] / unit_mm, dec);
      k += ' ';
    }
    return k;
  }
  void segment(const FiveAxisMove& m, std::vector<Piece>& pieces);
  void start_if_needed(const FiveAxisMove& m);
  double move_time_min(const FiveAxisMove& m) const;
  void write_line(const FiveAxisLine& l);
  std::string move_text(const AxisVector& c, double unit_mm, bool lower, bool spaces, int motion,
                        double feed_for_piece, const AxisVector& from);
  void emit(const std::string& text, bool newline = true) {
    out_ << text;
    if (newline) out_ << line_ending_;
  }

  std::string file_;
  std::ostream& out_;
  FiveAxisPostOptions o_;
  const FiveAxisTransform& tf_;
  int line_ = 0;
  std::string line_ending_ = "\n";
  bool reader_newline_ = true;
  bool started_ = false;
  AxisVector u_nom_;  ///< nominal axes at the end of the last move
  /// Whole turns added to the programmed angles of each unlimited rotary
  /// axis (TCP input): see unwrap_turns.
  AxisVector turns_;

  // A TCP program may send an unlimited rotary axis round by a turn or more
  // on a rapid (LinuxCNC's demos end with G0 C0 after C-399.8, unwinding a
  // counter); the pose is the same at the nearest equivalent angle. At a
  // rapid the programmed angle is taken as the representative within half
  // a turn of where the axis is, and the whole turns so added stay with
  // every later programmed angle, so feed moves sweep exactly as
  // programmed: C never jumps by 180 degrees or more between two lines.
  void unwrap_turns(FiveAxisMove& m) {
    const Machine& mach = tf_.machine();
    if (turns_.size() != mach.axis_count()) turns_ = AxisVector::Zero(mach.axis_count());
    if (m.q1.size() != mach.axis_count()) return;
    for (int k = 0; k < mach.axis_count(); ++k) {
      if (!is_rotary(mach.axis_order[static_cast<size_t>(k)]) ||
          !mach.limits[static_cast<size_t>(k)].unlimited)
        continue;
      if (m.rapid) {
        const double d = m.q1[k] + turns_[k] - u_nom_[k];
        if (std::abs(d) >= M_PI) turns_[k] -= 2.0 * M_PI * std::nearbyint(d / (2.0 * M_PI));
      }
      if (m.q0.size() == mach.axis_count()) m.q0[k] += turns_[k];
      m.q1[k] += turns_[k];
    }
  }
  AxisVector c_;                 ///< commanded axes at the end of the last move
  double residual_angle_ = 0.0;  ///< tool-axis error left there (rad)
  int out_motion_ = -1;          ///< modal motion of the output (x10), -1 unknown
  int out_feed_mode_ = 940;      ///< modal feed mode of the output
  std::vector<Piece> pieces_;
  std::vector<std::pair<double, double>> stack_;  ///< segmentation work list (reused)
  std::vector<Piece> turn_;                       ///< pieces of one accepted step (reused)
};

void FiveAxisPost::start_if_needed(const FiveAxisMove& m) {
  if (started_) return;
  // The first move starts where the reader's initial pose is.
  const NominalAt n = nominal_at(m, 0.0, u_nom_);
  u_nom_ = n.u;
  c_ = tf_.command(n.u);
  residual_angle_ = tf_.zero() ? 0.0 : angle_between(tf_.actual(c_).axis, n.v.axis);
  started_ = true;
}

void FiveAxisPost::segment(const FiveAxisMove& m, std::vector<Piece>& pieces) {
  pieces.clear();
  // The checks aim at 3/4 of the tolerances: the rest is for the rounding of
  // the written numbers and for the deviation between the checked points.
  const double tol = 0.75 * o_.tolerance_mm, atol = 0.75 * o_.angle_tolerance_rad;
  int n0 = 1;
  if (m.tip.kind == nc::MotionKind::kArc) {
    const nc::ArcGeometry g = nc::arc_geometry(m.tip);
    const double r = std::max(g.radius, g.end_radius);
    const double max_step = r > tol / 4 ? 2.0 * std::acos(1.0 - (tol / 4) / r) : M_PI / 2;
    n0 = std::max(4, static_cast<int>(std::ceil(std::abs(g.sweep) / max_step)));
  }
  if (!m.by_angles && angle_between(m.a0, m.a1) > M_PI - 1e-6)
    fail(
        "the tool axis turns by 180 degrees in one move; its path is undefined: add a point "
        "between");
  const Machine& mach = tf_.machine();
  constexpr int kMaxPieces = 1 << 16;
  std::vector<std::pair<double, double>>& stack = stack_;
  stack.clear();
  double s_prev = 0.0;
  for (int k = 1; k <= n0; ++k) {
    stack.push_back({s_prev, static_cast<double>(k) / n0});
    while (!stack.empty()) {
      const auto [s0, s1] = stack.back();
      stack.pop_back();
      const NominalAt n1 = nominal_at(m, s1, u_nom_);
      const AxisVector c1 = command(n1.u);
      // What the correction leaves of the tool-axis error at the ends (the
      // singular position: the part only the outer axis could turn) is
      // allowed between them too.
      const double r1 = tf_.zero() ? 0.0 : angle_between(tf_.actual(c1).axis, n1.v.axis);
      const double allowed_angle = atol + std::max(residual_angle_, r1);
      bool ok = true;
      for (int k2 = 0; k2 < mach.axis_count() && ok; ++k2)
        if (is_rotary(mach.axis_order[static_cast<size_t>(k2)]) &&
            std::abs(c1[k2] - c_[k2]) >= M_PI / 2)
          ok = false;  // C continuity: never half a turn in one piece
      for (double t : {0.25, 0.5, 0.75}) {
        if (!ok) break;
        const AxisVector u = c_ + t * (c1 - c_);
        const ToolPose a = tf_.actual(u);
        const double s = s0 + t * (s1 - s0);
        const Vector3d q_nom =
            m.by_angles
                ? tf_.nominal(tf_.axes_for_angles(m.q0 + s * (m.q1 - m.q0), nc::point_on(m.tip, s)))
                      .axis
                : slerp_axis(m.a0, m.a1, s);
        if (nc::distance_to_path(m.tip, a.tip_mm) > tol ||
            angle_between(a.axis, q_nom) > allowed_angle)
          ok = false;
      }
      if (ok || s1 - s0 < 1e-7) {
        if (n1.singular) ++report_.singular_poses;
        if (ok) {
          turn_.assign(1, Piece{c1, s1, false});
        } else {
          // The backward solution jumps here (C turning to the new azimuth
          // as the tool leaves the singular position): turn the rotary
          // axes over the jump with the tip held on the path — linear in
          // the rotary axes, each position placing the tip (and corrected)
          // — in as many pieces as the tip tolerance needs.
          const AxisVector u0 = u_nom_;
          for (int n = 2;; n *= 2) {
            turn_.clear();
            bool pass = true;
            AxisVector cprev = c_;
            for (int k = 1; k <= n && pass; ++k) {
              const double t = static_cast<double>(k) / n, s = s0 + t * (s1 - s0);
              const AxisVector uk =
                  k == n ? n1.u : tf_.axes_for_angles(u0 + t * (n1.u - u0), nc::point_on(m.tip, s));
              const AxisVector ck = k == n ? c1 : command(uk);
              for (double tt : {0.25, 0.5, 0.75})
                if (nc::distance_to_path(m.tip, tf_.actual(cprev + tt * (ck - cprev)).tip_mm) > tol)
                  pass = false;
              turn_.push_back({ck, s, true});
              cprev = ck;
            }
            if (pass || n >= 4096) break;
          }
        }
        for (const Piece& pc : turn_) {
          for (int k2 = 0; k2 < mach.axis_count(); ++k2)
            if (is_rotary(mach.axis_order[static_cast<size_t>(k2)]))
              report_.max_rotary_step_rad =
                  std::max(report_.max_rotary_step_rad, std::abs(pc.c[k2] - c_[k2]));
          pieces.push_back(pc);
          c_ = pc.c;
        }
        if (pieces.size() > kMaxPieces)
          fail(fmt::format(
              "more than {} pieces needed to keep {:g} um and {:g} urad; raise the tolerances",
              kMaxPieces, o_.tolerance_mm * 1e3, o_.angle_tolerance_rad * 1e6));
        u_nom_ = n1.u;
        residual_angle_ = r1;
        s_prev = s1;
        if (!stack.empty()) {
          const double end = stack.front().second;
          stack.clear();
          stack.push_back({s1, end});
        }
      } else {
        const double mid = 0.5 * (s0 + s1);
        stack.push_back({mid, s1});
        stack.push_back({s0, mid});
      }
    }
  }
}

double FiveAxisPost::move_time_min(const FiveAxisMove& m) const {
  if (m.feed_mode == 930) return 1.0 / m.feed;
  const double L = nc::path_length_mm(m.tip);
  if (L > 1e-9) return L / m.feed;
  double deg = 0;
  if (m.by_angles)
    deg = (m.q1 - m.q0).norm() * kRadToDeg;
  else
    deg = angle_between(m.a0, m.a1) * kRadToDeg;
  return deg / m.feed;
}

std::string FiveAxisPost::move_text(const AxisVector& c, double unit_mm, bool lower, bool spaces,
                                    int motion, double time_min, const AxisVector& from) {
  const Machine& mach = tf_.machine();
  std::string s;
  auto word = [&](char letter) {
    if (!s.empty() && spaces) s += ' ';
    s += lower ? static_cast<char>(std::tolower(static_cast<unsigned char>(letter))) : letter;
  };
  const bool feed = motion == 10;
  const int want_mode = o_.feed == FeedOutput::kInverseTime ? 930 : 940;
  if (feed && out_feed_mode_ != want_mode) {
    word('G');
    s += want_mode == 930 ? "93" : "94";
    out_feed_mode_ = want_mode;
  }
  if (out_motion_ != motion) {
    word('G');
    s += feed ? "1" : "0";
    out_motion_ = motion;
  }
  const int dec = o_.decimals >= 0 ? o_.decimals : (unit_mm > 1.0 ? 5 : 4);
  double xyz2 = 0, rot2 = 0;
  for (int k = 0; k < mach.axis_count(); ++k) {
    const AxisName n = mach.axis_order[static_cast<size_t>(k)];
    word(axis_char(n));
    if (is_rotary(n)) {
      append_number(s, c[k] * kRadToDeg, o_.angle_decimals);
      rot2 += std::pow((c[k] - from[k]) * kRadToDeg, 2);
    } else {
      append_number(s, c[k] / unit_mm, dec);
      xyz2 += std::pow((c[k] - from[k]) / unit_mm, 2);
    }
  }
  if (feed) {
    double f;
    // A piece of no nominal travel (a move to where the tool already is)
    // has no time of its own: it gets 6 ms, so that its F stays a sane
    // number (10 000 in inverse time) and whatever small motion the
    // correction adds is slow.
    const double t = time_min > 0 ? time_min : 1e-4;
    if (want_mode == 930) {
      f = 1.0 / t;
    } else {
      const double len = std::sqrt(xyz2) > 1e-9 ? std::sqrt(xyz2) : std::sqrt(rot2);
      f = len > 0 ? len / t : 1.0;
    }
    word('F');
    // Four decimals, more for a slow feed so that F never reads 0 (G93
    // F0 is an error; a feed of 1e-5 per minute is a program's business).
    int f_decimals = 4;
    while (f_decimals < 9 && f > 0 && f * std::pow(10.0, f_decimals) < 1000) ++f_decimals;
    append_number(s, f, f_decimals);
  }
  return s;
}

void FiveAxisPost::write_line(const FiveAxisLine& l) {
  const bool lower = !l.synthetic && nc::block_uses_lowercase(l.block);
  const bool spaces = l.synthetic || nc::block_uses_spaces(l.block);
  if (!l.has_move) {
    if (l.synthetic) {
      emit(l.text);
      return;
    }
    nc::BlockEdit edit;
    bool g91 = false;
    for (size_t k = 0; k < l.block.words.size(); ++k) {
      const nc::Word& w = l.block.words[k];
      if (w.letter == 'G' && (w.code10 == 930 || w.code10 == 940))
        edit.remove.push_back(static_cast<int>(k));
      if (w.letter == 'G' && w.code10 == 910) {
        edit.remove.push_back(static_cast<int>(k));
        g91 = true;
      }
      if (w.letter == 'G' && (w.code10 == 0 || w.code10 == 10 || w.code10 == 20 || w.code10 == 30))
        out_motion_ = w.code10;
    }
    for (int k : l.strip) edit.remove.push_back(k);
    // The output states absolute machine positions: G91 becomes G90.
    if (g91) edit.insert = lower ? "g90" : "G90";
    if (!l.strip.empty())
      edit.insert +=
          std::string(edit.insert.empty() ? "" : " ") +
          "(volmap post: LinuxCNC kinematics switch removed, the output commands machine axes)";
    if (edit.remove.empty()) {
      emit(l.block.text, reader_newline_);
      return;
    }
    ++report_.lines_changed;
    const std::string text = edited(l.block, edit);
    if (text.find_first_not_of(" \t") == std::string::npos) return;  // only G93/G94: moved
    emit(text, reader_newline_);
    return;
  }
  const FiveAxisMove& m = l.move;
  ++report_.moves;
  start_if_needed(m);
  const int motion = m.rapid ? 0 : 10;
  const AxisVector from = c_;
  if (m.rapid) {
    const NominalAt n = nominal_at(m, 1.0, u_nom_);
    if (n.singular) ++report_.singular_poses;
    pieces_.assign(1, Piece{command(n.u), 1.0});
    c_ = pieces_[0].c;
    u_nom_ = n.u;
    residual_angle_ = tf_.zero() ? 0.0 : angle_between(tf_.actual(c_).axis, n.v.axis);
  } else {
    segment(m, pieces_);
  }
  const double T = m.rapid ? 0.0 : move_time_min(m);
  // Pieces that would repeat the previous position at the written
  // resolution are merged into the next one (the last one stays).
  {
    std::string last = axes_key(from, l.unit_mm);
    size_t kept = 0;
    for (size_t p = 0; p < pieces_.size(); ++p) {
      std::string key = axes_key(pieces_[p].c, l.unit_mm);
      if (key == last && p + 1 < pieces_.size()) {
        pieces_[p + 1].forced = pieces_[p + 1].forced || pieces_[p].forced;
        continue;
      }
      last = std::move(key);
      pieces_[kept++] = pieces_[p];
    }
    pieces_.resize(kept);
  }
  // Time: each piece its share of the nominal path; a piece accepted at the
  // smallest span (C turning to the new azimuth as the tool leaves the
  // singular position) at least its share of the move's rotary travel, so
  // that the turn is not commanded in no time.
  const Machine& mach = tf_.machine();
  auto rotary_travel = [&](const AxisVector& a, const AxisVector& b) {
    double r = 0;
    for (int k = 0; k < mach.axis_count(); ++k)
      if (is_rotary(mach.axis_order[static_cast<size_t>(k)]))
        r = std::max(r, std::abs(b[k] - a[k]));
    return r;
  };
  double rot_total = 0;
  {
    AxisVector a = from;
    for (const Piece& pc : pieces_) {
      rot_total += rotary_travel(a, pc.c);
      a = pc.c;
    }
  }
  AxisVector prev = from;
  double s_prev = 0.0;
  ++report_.lines_changed;
  for (size_t p = 0; p < pieces_.size(); ++p) {
    double share = pieces_[p].s1 - s_prev;
    if (pieces_[p].forced && rot_total > 0)
      share = std::max(share, rotary_travel(prev, pieces_[p].c) / rot_total);
    const std::string words =
        move_text(pieces_[p].c, l.unit_mm, lower, spaces, motion, T * share, prev);
    prev = pieces_[p].c;
    s_prev = pieces_[p].s1;
    const bool newline = p + 1 < pieces_.size() || reader_newline_;
    if (p > 0) {
      ++report_.lines_added;
      emit(words, newline);
      continue;
    }
    if (l.synthetic) {
      emit(words, newline);
      continue;
    }
    nc::BlockEdit edit;
    bool g91 = false;
    for (size_t k = 0; k < l.block.words.size(); ++k) {
      const nc::Word& w = l.block.words[k];
      const char L = w.letter;
      const bool axis = L == 'X' || L == 'Y' || L == 'Z' || L == 'A' || L == 'B' || L == 'C' ||
                        L == 'I' || L == 'J' || L == 'K' || L == 'F';
      const bool modal =
          L == 'G' && (w.code10 == 0 || w.code10 == 10 || w.code10 == 20 || w.code10 == 30 ||
                       w.code10 == 930 || w.code10 == 940 || w.code10 == 910);
      if (axis || modal) edit.remove.push_back(static_cast<int>(k));
      if (L == 'G' && w.code10 == 910) g91 = true;
    }
    for (int k : l.strip) edit.remove.push_back(k);
    edit.insert = g91 ? (lower ? "g90 " : "G90 ") + words : words;
    if (!l.strip.empty()) edit.insert += " (volmap post: LinuxCNC kinematics switch removed)";
    // The motion word was removed: the output's modal state before this
    // line is what move_text assumed.
    emit(edited(l.block, edit), newline);
  }
}

void FiveAxisPost::run(FiveAxisReader& reader) {
  report_.form = reader.form();
  if (reader.form() == InputForm::kApt) {
    emit("(volmap post: five-axis machine-axis program from APT/CLDATA " + file_ + ")");
    emit("G21 G90 G17 G40 G80 G94");
    out_feed_mode_ = 940;
  }
  FiveAxisLine l;
  while (reader.next(l)) {
    line_ = l.line;
    line_ending_ = reader.line_ending();
    reader_newline_ = reader.newline();
    ++report_.lines;
    try {
      if (l.has_move && l.move.by_angles) unwrap_turns(l.move);
      write_line(l);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      fail(e.what());
    }
  }
}

}  // namespace

std::string FiveAxisPostOptions::invalid_reason() const {
  if (!(tolerance_mm > 0)) return "the position tolerance must be positive";
  if (!(angle_tolerance_rad > 0)) return "the angle tolerance must be positive";
  if (decimals > 9 || angle_decimals < 0 || angle_decimals > 9) return "decimals must be 0 to 9";
  if (correction_iterations < 1) return "correction iterations must be at least 1";
  return "";
}

Eigen::Vector3d slerp_axis(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, double s) {
  const double theta = angle_between(a0, a1);
  if (theta < 1e-12) return a0;
  const double st = std::sin(theta);
  return ((std::sin((1.0 - s) * theta) / st) * a0 + (std::sin(s * theta) / st) * a1).normalized();
}

FiveAxisPostReport post_five_axis(std::istream& in, const std::string& in_name, std::ostream& out,
                                  const Machine& machine, const ErrorSet& errors,
                                  const FiveAxisPostOptions& options) {
  if (const std::string why = options.invalid_reason(); !why.empty())
    throw std::invalid_argument(why);
  CorrectionOptions c;
  c.max_iterations = options.correction_iterations;
  const FiveAxisTransform tf(machine, errors, options.outside, c);
  FiveAxisReader reader(in, in_name, machine, options.form, options.initial);
  FiveAxisPost post(in_name, out, tf, options);
  post.run(reader);
  return post.report_;
}

FiveAxisPostReport post_five_axis(std::istream& in, const std::string& in_name, std::ostream& out,
                                  const Machine& machine, const maps::VolumetricTable& table,
                                  const FiveAxisPostOptions& options) {
  if (const std::string why = options.invalid_reason(); !why.empty())
    throw std::invalid_argument(why);
  const FiveAxisTransform tf(machine, table, options.outside);
  FiveAxisReader reader(in, in_name, machine, options.form, options.initial);
  FiveAxisPost post(in_name, out, tf, options);
  post.run(reader);
  return post.report_;
}

}  // namespace volmap::post
