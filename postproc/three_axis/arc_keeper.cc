// Arcs kept as arcs (PostOptions::keep_arcs, docs/post.md "Arcs kept as
// arcs").
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "gcode/g_codes.h"
#include "gcode/nc_path.h"
#include "postproc/three_axis/program_post.h"

namespace volmap::post {

/// What keep_arc works from, the same for every piece of the arc.
struct ProgramPost::ArcPlan {
  nc::ArcGeometry g;
  std::vector<double> cuts;  ///< the pieces' ends as path parameters: 0, ..., 1
  double hair;               ///< rad: no cut within it of an end
  double step_rad;           ///< between two samples of the actual tip
  bool lower, spaces;
};

namespace {

// The pieces: cut where the angle passes a multiple of pi/2, but not
// within a hair of an end; no sliver pieces. False for more than 4096
// pieces.
bool quadrant_cuts(const nc::ArcGeometry& g, double hair, std::vector<double>& cuts) {
  cuts = {0.0};
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
  return cuts.size() <= 4 * 1024;
}

}  // namespace

// An arc is cut at the points where an axis of its plane turns round (its
// quadrant points): on each piece every axis moves one way, and a
// lost-motion step can be taken up between pieces (a G1 to the piece's
// start commanded with its directions), never inside an arc. The controller
// runs each piece from where it stands to the written end about the
// written centre, its radius going linearly from start to end
// (nc::point_on, as verify simulates it). The end is the corrected end
// point; the centre is the nominal one moved by the mean of the corrections
// at the piece's ends (for an error field affine over the piece, the
// corrected points of the nominal arc lie on a slightly distorted circle
// about it). Kept only when, for every piece, the actual tip stays within
// half the tolerance of the nominal path at samples as dense as the field's
// bounds require; otherwise the whole block is linearised as without the
// option, and everything tried is put back. Polar words, G53 and, under
// inverse time, an arc that needs more than its own line are linearised.
bool ProgramPost::keep_arc(const nc::Block& b, const nc::Motion& m, const Corrector& c, bool lower,
                           bool spaces) {
  if (b.has('@') || b.has('^') || !emitted_known_) return false;
  for (const nc::Word& w : b.words)
    if (w.letter == 'G' && w.code10 == nc::kG53MachineCoordinates) return false;
  // What the pieces change: put back if the block is not kept.
  const LastCorrected last_was = last_, before_last_was = before_last_;
  const PostReport report_was = report_;
  const Vector3d emitted_was = emitted_mm_;
  const ApproachDirections last_dir_was = last_dir_;
  std::vector<KeptLine> lines;
  // Under G93 every line needs its own F (inverse time): one line only.
  if (!kept_arc_lines(m, c, lower, spaces, lines) ||
      (interp_.state().feed_mode == nc::kG93InverseTime && lines.size() > 1)) {
    last_ = last_was;
    before_last_ = before_last_was;
    report_ = report_was;
    emitted_mm_ = emitted_was;
    last_dir_ = last_dir_was;
    return false;
  }
  write_kept_arc(b, m, lower, spaces, lines);
  return true;
}

bool ProgramPost::kept_arc_lines(const nc::Motion& m, const Corrector& c, bool lower, bool spaces,
                                 std::vector<KeptLine>& lines) {
  ArcPlan plan;
  plan.g = nc::arc_geometry(m);
  plan.lower = lower;
  plan.spaces = spaces;
  const nc::ArcGeometry& g = plan.g;
  if (!(std::abs(g.sweep) > 1e-9)) return false;
  // Not within a hair of an end: a = sqrt(2e-7 mm / r), an axis backs up
  // by r (1 - cos a) < 1e-7 mm past such a point, inside any play and the
  // numbers' rounding.
  plan.hair = std::min(1e-3, std::sqrt(2e-7 / std::max(std::min(g.radius, g.end_radius), 1e-9)));
  if (!quadrant_cuts(g, plan.hair, plan.cuts)) return false;
  const double r_max = std::max(g.radius, g.end_radius);
  // Samples close enough that the deviation grows by at most 5 % of the
  // tolerance between two: its second derivative along the arc is at most
  // M = K r^2 + 2 L r (the field's curvature and Lipschitz bounds; the
  // corrected and nominal circles differ by the correction, whose change
  // over the arc the same bounds hold), so steps of sqrt(8 * 0.05 tol / M)
  // rad. No bounds (a compensation table): linearised.
  const double M = c.curvature_bound() * r_max * r_max + 2 * c.lipschitz_bound() * r_max;
  plan.step_rad = std::min(0.05, M > 0 ? std::sqrt(0.4 * options_.tolerance_mm / M) : 0.05);
  if (!(plan.step_rad > 0) || !(std::abs(g.sweep) / plan.step_rad <= 1e6)) return false;
  for (size_t k = 0; k + 1 < plan.cuts.size(); ++k)
    if (!kept_arc_piece(m, plan, c, k, lines)) return false;
  return true;
}

bool ProgramPost::kept_arc_piece(const nc::Motion& m, const ArcPlan& plan, const Corrector& c,
                                 std::size_t k, std::vector<KeptLine>& lines) {
  const nc::ArcGeometry& g = plan.g;
  const std::vector<double>& cuts = plan.cuts;
  const nc::State& s = interp_.state();
  nc::Motion piece = m;
  piece.extra_turns = 0;
  piece.start_mm = k == 0 ? m.start_mm : nc::point_on(m, cuts[k]);
  piece.end_mm = nc::point_on(m, cuts[k + 1]);
  const nc::ArcGeometry pg = nc::arc_geometry(piece);
  // (A piece that arc_geometry reads as a full turn, or backwards: give up.)
  if (!(std::abs(pg.sweep - g.sweep * (cuts[k + 1] - cuts[k])) < 1e-6)) return false;
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
  if (step && s.feed_mode == nc::kG93InverseTime)
    return false;  // the step's own F: linearised instead
  nc::Motion cmd = piece;
  cmd.start_mm = c0;
  cmd.end_mm = c1;
  const Vector3d shift = 0.5 * ((c0 - piece.start_mm) + (c1 - piece.end_mm));
  cmd.center_mm[g.a0] = m.center_mm[g.a0] + shift[g.a0];
  cmd.center_mm[g.a1] = m.center_mm[g.a1] + shift[g.a1];
  const nc::ArcGeometry gc = nc::arc_geometry(cmd);
  if (!(std::abs(gc.sweep - pg.sweep) < 1e-3) || !(std::abs(gc.radius - gc.end_radius) < 0.01))
    return false;
  // Every axis commanded the way d says (a creep against it would be lost
  // in the play of an axis with lost motion). The corrected piece may
  // begin or end a hair past the quadrant point the nominal one begins or
  // ends at: the axis backs up by r (1 - cos a), under 1e-7 mm for
  // a = sqrt(2e-7 mm / r), inside any play and the numbers' rounding.
  for (int a = 0; a < 3; ++a) {
    const double move = c1[a] - c0[a];
    if (move != 0 && c.bidirectional(a) && (move > 0 ? 1 : -1) != d[static_cast<size_t>(a)])
      return false;
  }
  {
    const double lo = std::min(gc.start_angle, gc.start_angle + gc.sweep) + 2 * plan.hair,
                 hi = std::max(gc.start_angle, gc.start_angle + gc.sweep) - 2 * plan.hair;
    if (std::floor(lo / (M_PI / 2)) * (M_PI / 2) + M_PI / 2 < hi) return false;
  }
  // An arc whose written ends would coincide is a full circle to the
  // controller: such a piece is not written as an arc.
  if (!((c1 - c0).norm() > 40 * half_unit(decimals()) * s.unit_mm)) return false;
  const int samples = std::max(16, static_cast<int>(std::ceil(std::abs(pg.sweep) / plan.step_rad)));
  for (int j = 0; j <= samples; ++j) {
    const Vector3d x = nc::point_on(cmd, static_cast<double>(j) / samples);
    if (!(nc::distance_to_path(m, x + c.error_at(x, d)) <= 0.5 * options_.tolerance_mm))
      return false;
  }
  add_kept_arc_piece_lines(plan, step, c0, cmd, d, lines);
  return true;
}

void ProgramPost::add_kept_arc_piece_lines(const ArcPlan& plan, bool step, const Vector3d& c0,
                                           const nc::Motion& cmd, const ApproachDirections& d,
                                           std::vector<KeptLine>& lines) {
  const nc::ArcGeometry& g = plan.g;
  const nc::State& s = interp_.state();
  const int dec = decimals();
  const bool lower = plan.lower, spaces = plan.spaces;
  // The piece's lines: the take-up step (unless below the output's
  // resolution, as in segment()), then the arc.
  if (step) {
    bool needed = false;
    for (int a = 0; a < 3; ++a) needed = needed || axis_needs_word(a, c0, nullptr, false);
    if (needed) {
      words_.clear();
      append_axis_words(c0, false, lower, spaces, words_);
      lines.push_back({false, std::string(words_.view())});
      emitted_mm_ = reached(c0, false);
    }
  }
  CharBuffer& w = words_;
  w.clear();
  append_axis_words(cmd.end_mm, false, lower, spaces, w);
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
  emitted_mm_ = reached(cmd.end_mm, false);
  last_dir_ = d;
}

// Kept: the lines out. The first takes the block's place: the block keeps
// its other words (its modes apply to all that follows), its end point and
// centre words are replaced (an R form becomes I J K, a P gives way to
// the pieces), and the motion is stated: the arc's G2/G3 (the block may
// rely on the modal one, and an arc linearised before it left the output
// in G1), or G1 for a take-up step, in place of the block's G2/G3.
void ProgramPost::write_kept_arc(const nc::Block& b, const nc::Motion& m, bool lower, bool spaces,
                                 const std::vector<KeptLine>& lines) {
  const char* arc_code = lower ? (m.clockwise ? "g2" : "g3") : (m.clockwise ? "G2" : "G3");
  nc::BlockEdit edit;
  bool stated = false;
  for (size_t k = 0; k < b.words.size(); ++k) {
    const nc::Word& word = b.words[k];
    const char L = word.letter;
    const bool motion = L == 'G' && (word.code10 == nc::kG2ArcClockwise ||
                                     word.code10 == nc::kG3ArcCounterClockwise);
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
    emit_move(lines[k].arc ? (m.clockwise ? 2 : 3) : 1, lower, spaces, lines[k].words);
    ++report_.lines_added;
  }
}

}  // namespace volmap::post
