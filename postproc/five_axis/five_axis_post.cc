#include "postproc/five_axis/five_axis_post.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <vector>

#include "core/common/input_error.h"
#include "core/common/internal_error.h"
#include "core/common/units.h"
#include "gcode/g_codes.h"
#include "gcode/nc_path.h"
#include "gcode/nc_writer.h"
#include "postproc/five_axis/five_axis_program_post.h"
#include "postproc/five_axis/five_axis_transform.h"

namespace volmap::post {
namespace five_axis_detail {
namespace {

// apply_edit, without the trailing blanks that removed words can leave.
std::string edited(const nc::Block& b, const nc::BlockEdit& e) {
  std::string t = nc::apply_edit(b, e);
  const bool blank_end = !b.text.empty() && (b.text.back() == ' ' || b.text.back() == '\t');
  if (!blank_end)
    while (!t.empty() && (t.back() == ' ' || t.back() == '\t')) t.pop_back();
  return t;
}

}  // namespace

double FiveAxisPost::move_time_min(const FiveAxisMove& m) const {
  if (m.feed_mode == nc::kG93InverseTime) return 1.0 / m.feed;
  const double L = nc::path_length_mm(m.tip);
  if (L > 1e-9) return L / m.feed;
  double deg = 0;
  if (m.by_angles)
    deg = (m.q1 - m.q0).norm() * units::kDegPerRad;
  else
    deg = angle_between(m.a0, m.a1) * units::kDegPerRad;
  return deg / m.feed;
}

std::string FiveAxisPost::move_text(const AxisVector& c, double unit_mm, bool lower, bool spaces,
                                    int motion, double time_min, const AxisVector& from) {
  const Machine& mach = tf_->machine();
  std::string s;
  auto word = [&](char letter) {
    if (!s.empty() && spaces) s += ' ';
    s += lower ? static_cast<char>(std::tolower(static_cast<unsigned char>(letter))) : letter;
  };
  const bool feed = motion == nc::kG1Linear;
  const int want_mode =
      o_.feed == FeedOutput::kInverseTime ? nc::kG93InverseTime : nc::kG94UnitsPerMinute;
  if (feed && out_feed_mode_ != want_mode) {
    word('G');
    s += want_mode == nc::kG93InverseTime ? "93" : "94";
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
    const std::size_t at = s.size();
    if (is_rotary(n)) {
      append_number(s, c[k] * units::kDegPerRad, o_.angle_decimals);
      rot2 += std::pow((c[k] - from[k]) * units::kDegPerRad, 2);
    } else {
      append_number(s, c[k] / unit_mm, dec);
      xyz2 += std::pow((c[k] - from[k]) / unit_mm, 2);
    }
    if (fanuc_points_ && s.find('.', at) == std::string::npos) s += '.';
  }
  if (feed) {
    double f;
    // A piece of no nominal travel (a move to where the tool already is)
    // has no time of its own: it gets 6 ms, so that its F stays a sane
    // number (10 000 in inverse time) and whatever small motion the
    // correction adds is slow.
    const double t = time_min > 0 ? time_min : 1e-4;
    if (want_mode == nc::kG93InverseTime) {
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

void FiveAxisPost::change_tool(const FiveAxisLine& l) {
  try {
    tf_ = &tools_.change_to(l.tool, started_);
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  rapid_due_ = started_ && tools_.has_table();
}

void FiveAxisPost::write_line_without_move(const FiveAxisLine& l, bool lower) {
  if (l.synthetic) {
    // APT's tool change: the controller changes the tool when a table
    // gives the program's tools.
    emit(l.tool >= 0 && tools_.has_table() ? fmt::format("T{} M6 {}", l.tool, l.text) : l.text);
    return;
  }
  nc::BlockEdit edit;
  bool g91 = false;
  for (size_t k = 0; k < l.block.words.size(); ++k) {
    const nc::Word& w = l.block.words[k];
    if (w.letter == 'G' && (w.code10 == nc::kG93InverseTime || w.code10 == nc::kG94UnitsPerMinute))
      edit.remove.push_back(static_cast<int>(k));
    if (w.letter == 'G' && w.code10 == nc::kG91Incremental) {
      edit.remove.push_back(static_cast<int>(k));
      g91 = true;
    }
    if (w.letter == 'G' &&
        (w.code10 == nc::kG0Rapid || w.code10 == nc::kG1Linear || w.code10 == nc::kG2ArcClockwise ||
         w.code10 == nc::kG3ArcCounterClockwise))
      out_motion_ = w.code10;
  }
  for (int k : l.strip) edit.remove.push_back(k);
  // The output states absolute machine positions: G91 becomes G90.
  if (g91) edit.insert = lower ? "g90" : "G90";
  if (!l.strip.empty())
    edit.insert += std::string(edit.insert.empty() ? "" : " ") +
                   "(volmap post: TCP switch removed, the output commands machine axes)";
  if (edit.remove.empty()) {
    emit(l.block.text, reader_newline_);
    return;
  }
  ++report_.lines_changed;
  const std::string text = edited(l.block, edit);
  if (text.find_first_not_of(" \t") == std::string::npos) return;  // only G93/G94: moved
  emit(text, reader_newline_);
}

void FiveAxisPost::pieces_of_move(const FiveAxisMove& m) {
  if (m.rapid) {
    const NominalAt n = nominal_at(m, 1.0, u_nom_);
    if (n.singular) ++report_.singular_poses;
    pieces_.assign(1, Piece{command(n.u), 1.0});
    c_ = pieces_[0].c;
    u_nom_ = n.u;
    residual_angle_ = tf_->zero() ? 0.0 : angle_between(tf_->actual(c_).axis, n.v.axis);
  } else {
    segment(m, pieces_);
  }
}

void FiveAxisPost::merge_repeated_pieces(const AxisVector& from, double unit_mm) {
  // Pieces that would repeat the previous position at the written
  // resolution are merged into the next one (the last one stays).
  std::string last = axes_key(from, unit_mm);
  size_t kept = 0;
  for (size_t p = 0; p < pieces_.size(); ++p) {
    std::string key = axes_key(pieces_[p].c, unit_mm);
    if (key == last && p + 1 < pieces_.size()) {
      pieces_[p + 1].forced = pieces_[p + 1].forced || pieces_[p].forced;
      continue;
    }
    last = std::move(key);
    pieces_[kept++] = pieces_[p];
  }
  pieces_.resize(kept);
}

void FiveAxisPost::write_first_piece(const FiveAxisLine& l, bool lower, const std::string& words,
                                     bool newline) {
  nc::BlockEdit edit;
  bool g91 = false;
  for (size_t k = 0; k < l.block.words.size(); ++k) {
    const nc::Word& w = l.block.words[k];
    const char L = w.letter;
    const bool axis = L == 'X' || L == 'Y' || L == 'Z' || L == 'A' || L == 'B' || L == 'C' ||
                      L == 'I' || L == 'J' || L == 'K' || L == 'F';
    const bool modal =
        L == 'G' &&
        (w.code10 == nc::kG0Rapid || w.code10 == nc::kG1Linear || w.code10 == nc::kG2ArcClockwise ||
         w.code10 == nc::kG3ArcCounterClockwise || w.code10 == nc::kG93InverseTime ||
         w.code10 == nc::kG94UnitsPerMinute || w.code10 == nc::kG91Incremental);
    if (axis || modal) edit.remove.push_back(static_cast<int>(k));
    if (L == 'G' && w.code10 == nc::kG91Incremental) g91 = true;
  }
  for (int k : l.strip) edit.remove.push_back(k);
  edit.insert = g91 ? (lower ? "g90 " : "G90 ") + words : words;
  if (!l.strip.empty()) edit.insert += " (volmap post: TCP switch removed)";
  // The motion word was removed: the output's modal state before this
  // line is what move_text assumed.
  emit(edited(l.block, edit), newline);
}

void FiveAxisPost::write_line(const FiveAxisLine& l) {
  const bool lower = !l.synthetic && nc::block_uses_lowercase(l.block);
  const bool spaces = l.synthetic || nc::block_uses_spaces(l.block);
  if (!l.has_move) {
    write_line_without_move(l, lower);
    return;
  }
  const FiveAxisMove& m = l.move;
  if (rapid_due_ && !m.rapid)
    fail("a feed move right after a tool change: the new tool's first move must be a rapid");
  rapid_due_ = false;
  ++report_.moves;
  start_if_needed(m);
  const int motion = m.rapid ? nc::kG0Rapid : nc::kG1Linear;
  const AxisVector from = c_;
  pieces_of_move(m);
  const double T = m.rapid ? 0.0 : move_time_min(m);
  merge_repeated_pieces(from, l.unit_mm);
  // Time: each piece its share of the nominal path; a piece accepted at the
  // smallest span (C turning to the new azimuth as the tool leaves the
  // singular position) at least its share of the move's rotary travel, so
  // that the turn is not commanded in no time.
  const Machine& mach = tf_->machine();
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
    if (p > 0) ++report_.lines_added;
    if (p > 0 || l.synthetic)
      emit(words, newline);
    else
      write_first_piece(l, lower, words, newline);
  }
}

void FiveAxisPost::run(FiveAxisReader& reader) {
  report_.form = reader.form();
  if (reader.byte_order_mark()) out_ << "\xEF\xBB\xBF";  // the output begins as the input did
  if (reader.form() == InputForm::kApt) {
    emit("(volmap post: five-axis machine-axis program from APT/CLDATA " + file_ + ")");
    emit("G21 G90 G17 G40 G80 G94");
    out_feed_mode_ = nc::kG94UnitsPerMinute;
  }
  FiveAxisLine l;
  while (reader.next(l)) {
    line_ = l.line;
    line_ending_ = reader.line_ending();
    reader_newline_ = reader.newline();
    fanuc_points_ = reader.fanuc_head();
    ++report_.lines;
    try {
      if (l.tool >= 0) change_tool(l);
      if (l.has_move && l.move.by_angles) unwrap_turns(l.move);
      write_line(l);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw_if_unexpected(e, file_, line_);  // a bug is said to be one
      fail(e.what());
    }
  }
}

}  // namespace five_axis_detail

using five_axis_detail::angle_between;
using five_axis_detail::FiveAxisPost;

namespace {
// A program that moves nothing (empty, comments, codes without motion):
// its output would be its input, most likely not the program meant.
void refuse_motion_free(const std::string& in_name, const FiveAxisPostReport& r) {
  if (r.moves > 0) return;
  throw InputError(
      in_name, static_cast<int>(std::max<std::uint64_t>(1, r.lines)),
      (r.lines == 0 ? std::string("the file is empty") : std::to_string(r.lines) + " lines read") +
          "; no block moves the machine, so there is nothing to post: check that "
          "this is the program meant");
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
  c.outer_damping = kPostOuterDamping;
  c.iterate_below_sin = kPostIterateBelowSin;
  ToolTransforms tools(machine, options.tool_offsets_mm, [&](const Machine& m) {
    return std::make_unique<FiveAxisTransform>(m, errors, options.outside, c);
  });
  FiveAxisReader reader(in, in_name, machine, options.form, options.initial,
                        options.tolerance_mm / 4);
  FiveAxisPost post(in_name, out, tools, options);
  post.run(reader);
  refuse_motion_free(in_name, post.report_);
  return post.report_;
}

FiveAxisPostReport post_five_axis(std::istream& in, const std::string& in_name, std::ostream& out,
                                  const Machine& machine, const maps::VolumetricTable& table,
                                  const FiveAxisPostOptions& options) {
  if (const std::string why = options.invalid_reason(); !why.empty())
    throw std::invalid_argument(why);
  if (!options.tool_offsets_mm.empty())
    throw std::invalid_argument(
        "a five-axis table is for the tool it was made with: give no tool table with --table");
  ToolTransforms tools(machine, {}, [&](const Machine& m) {
    return std::make_unique<FiveAxisTransform>(m, table, options.outside);
  });
  FiveAxisReader reader(in, in_name, machine, options.form, options.initial,
                        options.tolerance_mm / 4);
  FiveAxisPost post(in_name, out, tools, options);
  post.run(reader);
  refuse_motion_free(in_name, post.report_);
  return post.report_;
}

}  // namespace volmap::post
