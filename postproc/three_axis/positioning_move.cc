// Positioning moves: a rapid (G0) corrected at its end point, and a canned
// cycle block of one hole in G90 (hole position, bottom and R plane
// corrected). Cycles of several holes and --expand-cycles: canned_cycles.cc.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "core/common/input_error.h"
#include "gcode/g_codes.h"
#include "gcode/nc_path.h"
#include "postproc/three_axis/program_post.h"

namespace volmap::post {

Vector3d ProgramPost::position_command(const Corrector& c, const Vector3d& from, const Vector3d& to,
                                       bool z_down, ApproachDirections& d) {
  d = directions_of(from, to, last_dir_);
  if (z_down) d[2] = -1;
  if (comp_hold_xy_) {
    last_dir_ = d;
    return held_xy_command(c, to, d);
  }
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

void ProgramPost::positioning_axis_words(const nc::Block& b, const nc::BlockEffect& fx,
                                         const Vector3d& cmd, const BlockStyle& style,
                                         PositioningEdit& e) const {
  const nc::Motion& m = fx.motion;
  const nc::State& s = interp_.state();
  const int dec = decimals();
  const double half = half_unit(dec);
  // A polar block (@ ^) that needs a change is rewritten as X Y: under G91
  // the controller would apply its increments to the corrected point, not
  // the nominal one, and X Y next to @ ^ is an error.
  const bool polar = (b.has('@') || b.has('^')) && polar_needs_change(b, fx, cmd);
  if (polar)
    for (char L : {'@', '^'})
      if (const int i = word_index(b, L); i >= 0) e.edit.remove.push_back(i);
  for (int a = 0; a < 3; ++a) {
    const int idx = style.axis_index[a];
    const double new_value = program_value(a, cmd[a], fx.g53);
    // A canned cycle's Z is the hole bottom, not where the tool stays.
    const bool needed =
        m.kind == nc::MotionKind::kCycle && a == 2
            ? (idx >= 0 ? std::abs(new_value - b.words[static_cast<size_t>(idx)].value) >= half
                        : std::abs(cmd.z() - m.end_mm.z()) >= half * s.unit_mm)
            : block_needs_word(b, style, fx.g53, a, cmd) || (polar && a < 2);
    e.needed[static_cast<size_t>(a)] = needed;
    e.changed = e.changed || needed;
    if (!needed) continue;
    // The fewest changes: a word renumbered in place, an absent one added.
    const std::string number = nc::format_number(new_value, dec);
    if (idx >= 0) {
      e.edit.renumber.emplace_back(idx, number);
    } else {
      if (!e.insert.empty() && style.spaces) e.insert += ' ';
      e.insert += style.lower ? "xyz"[a] : "XYZ"[a];
      e.insert += number;
    }
  }
  int last_axis_word = -1;
  for (int a = 0; a < 3; ++a) last_axis_word = std::max(last_axis_word, style.axis_index[a]);
  e.edit.insert_after = last_axis_word;
}

double ProgramPost::cycle_r_plane(const nc::Block& b, const nc::Motion& m, const Corrector& c,
                                  const ApproachDirections& d, const Vector3d& cmd,
                                  const BlockStyle& style, PositioningEdit& e) {
  const nc::State& s = interp_.state();
  const int dec = decimals();
  const bool lower = style.lower, spaces = style.spaces;
  enter_cycle_run();
  // The R plane, corrected where the tool reaches it, stated every block
  // (the correction differs from hole to hole).
  const Vector3d r_nominal(m.end_mm.x(), m.end_mm.y(), m.r_mm);
  const Vector3d r_cmd = command(c, r_nominal, d);
  check_cycle_feed(c, m, cmd, r_cmd.z(), d);
  const double r_new = (r_cmd.z() - interp_.work_offset()[2]) / s.unit_mm;
  const double r_nom = (m.r_mm - interp_.work_offset()[2]) / s.unit_mm;
  if (e.changed || std::abs(r_new - r_nom) >= half_unit(dec)) {
    // Z too, so both modal values are this hole's.
    if (word_index(b, 'Z') < 0 && e.insert.find(lower ? 'z' : 'Z') == std::string::npos) {
      if (!e.insert.empty() && spaces) e.insert += ' ';
      e.insert += lower ? 'z' : 'Z';
      e.insert += nc::format_number(program_value(2, cmd.z(), false), dec);
    }
    if (const int ri = word_index(b, 'R'); ri >= 0) {
      e.edit.renumber.emplace_back(ri, nc::format_number(r_new, dec));
    } else {
      if (!e.insert.empty() && spaces) e.insert += ' ';
      e.insert += lower ? 'r' : 'R';
      e.insert += nc::format_number(r_new, dec);
    }
    e.changed = true;
  }
  // Where the controller ends: G99 at the R it reads, G98 at the initial
  // level or that R if higher.
  const double r_read_mm =
      e.changed ? written(r_new, dec) * s.unit_mm + interp_.work_offset()[2] : m.r_mm;
  return s.g98 ? std::max(ctrl_il_mm_, r_read_mm) : r_read_mm;
}

void ProgramPost::check_cycle_feed(const Corrector& c, const nc::Motion& hole,
                                   const Vector3d& bottom_cmd, double r_cmd_mm,
                                   const ApproachDirections& d) {
  // The controller feeds straight down from the corrected R plane to the
  // corrected bottom (and pecks back in along it; G85 G89 feed out along
  // it too, and so do the taps G84 G74 after reversing the spindle): the
  // actual tip along that line against the hole's axis.
  nc::Motion axis;
  axis.kind = nc::MotionKind::kLinear;
  axis.start_mm = Vector3d(hole.end_mm.x(), hole.end_mm.y(), hole.r_mm);
  axis.end_mm = hole.end_mm;
  const Vector3d top_cmd(bottom_cmd.x(), bottom_cmd.y(), r_cmd_mm);
  const int code = interp_.state().motion;
  const bool feeds_out = code == nc::kG85Bore || code == nc::kG89BoreDwell ||
                         code == nc::kG84RightHandTap || code == nc::kG74LeftHandTap;
  double worst = 0.0;
  for (const std::int8_t z_dir : {std::int8_t{-1}, std::int8_t{1}}) {
    if (z_dir > 0 && !feeds_out) break;
    ApproachDirections dz = d;
    dz[2] = z_dir;
    constexpr int kSamples = 16;
    for (int j = 0; j <= kSamples; ++j) {
      const Vector3d x = top_cmd + (bottom_cmd - top_cmd) * (static_cast<double>(j) / kSamples);
      worst = std::max(worst, nc::distance_to_path(axis, x + c.error_at(x, dz)));
    }
  }
  if (worst <= options_.tolerance_mm) return;
  if (report_.cycle_warnings.size() < PostReport::kMaxCycleWarnings)
    report_.cycle_warnings.push_back(
        {current_line_, worst, line_file_ == &file_ ? std::string() : *line_file_});
  ++report_.cycle_warning_count;
}

void ProgramPost::positioning_line(std::string_view text, const nc::Block& b,
                                   const nc::BlockEffect& fx, const Corrector& c,
                                   const BlockStyle& style) {
  const nc::Motion& m = fx.motion;
  const bool cycle = m.kind == nc::MotionKind::kCycle;
  ApproachDirections d;
  const Vector3d cmd = position_command(c, m.start_mm, m.end_mm, cycle, d);
  PositioningEdit e;
  positioning_axis_words(b, fx, cmd, style, e);
  const double cycle_clear_mm = cycle ? cycle_r_plane(b, m, c, d, cmd, style, e) : m.clear_mm;
  if (!e.changed) {
    write_unchanged(text, b, fx);
    return;
  }
  const nc::State& s = interp_.state();
  e.edit.insert = e.insert;
  emit(nc::apply_edit(b, e.edit));
  ++report_.lines_changed;
  emitted_exact_ = !cycle && !s.absolute;
  if (cycle) {
    emitted_mm_ = Vector3d(cmd.x(), cmd.y(), cycle_clear_mm);
  } else if (s.absolute) {
    emitted_mm_ = cmd;
  } else {
    // G91: the controller adds the increments as written (an axis not
    // named, or named unchanged, moves by what the block says).
    for (int a = 0; a < 3; ++a) {
      const int idx = word_index(b, "XYZ"[a]);
      if (e.needed[static_cast<size_t>(a)])
        emitted_mm_[a] += written(program_value(a, cmd[a], fx.g53), decimals()) * s.unit_mm;
      else if (idx >= 0)
        emitted_mm_[a] += b.words[static_cast<size_t>(idx)].value * s.unit_mm;
    }
  }
  emitted_known_ = true;
}

void ProgramPost::tap_line(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                           const Corrector& c, const BlockStyle& style) {
  const nc::Motion& m = fx.motion;
  ApproachDirections d = directions_of(m.start_mm, m.end_mm, last_dir_);
  const Vector3d cmd = command(c, m.end_mm, d);
  // The controller goes straight from where it stands to the end and back
  // (the axes turned round): the actual tip both ways against the line.
  // (the axes the tap moves turned round; the others keep their side).
  ApproachDirections back = d;
  for (int a = 0; a < 3; ++a)
    if (m.end_mm[a] != m.start_mm[a])
      back[static_cast<size_t>(a)] = static_cast<std::int8_t>(-d[a]);
  double worst = 0.0;
  for (const ApproachDirections& dir : {d, back}) {
    constexpr int kSamples = 16;
    for (int j = 0; j <= kSamples; ++j) {
      const Vector3d x = emitted_mm_ + (cmd - emitted_mm_) * (static_cast<double>(j) / kSamples);
      worst = std::max(worst, nc::distance_to_path(m, x + c.error_at(x, dir)));
    }
  }
  if (worst > options_.tolerance_mm) {
    // As a canned cycle's feed: the controller's line, said, not refused.
    if (report_.cycle_warnings.size() < PostReport::kMaxCycleWarnings)
      report_.cycle_warnings.push_back(
          {current_line_, worst, line_file_ == &file_ ? std::string() : *line_file_, true});
    ++report_.cycle_warning_count;
  } else {
    report_.max_deviation_mm = std::max(report_.max_deviation_mm, worst);
  }
  last_dir_ = back;
  PositioningEdit e;
  positioning_axis_words(b, fx, cmd, style, e);
  if (!e.changed) {
    write_unchanged(text, b, fx);
    return;
  }
  e.edit.insert = e.insert;
  emit(nc::apply_edit(b, e.edit));
  ++report_.lines_changed;
  // (The controller is back where it stood: emitted_mm_ stays.)
}

}  // namespace volmap::post
