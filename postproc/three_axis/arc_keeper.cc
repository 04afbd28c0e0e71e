// Arcs kept as arcs (the default; PostOptions::keep_arcs, docs/post.md
// "Arcs kept as arcs").
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "gcode/g_codes.h"
#include "gcode/nc_path.h"
#include "postproc/three_axis/program_post.h"

namespace volmap::post {

/// What keep_arc works from, the same for every piece of the arc.
struct ProgramPost::ArcPlan {
  nc::ArcGeometry g;
  double hair;      ///< rad: no cut within it of an end
  double step_rad;  ///< between two samples of the actual tip
  bool lower, spaces;
};

namespace {

// At most this many arcs for one block; beyond, the block is linearised.
constexpr int kMaxKeptPieces = 256;

// Where a piece of the arc (path parameters s0 to s1) that does not keep
// the tolerance is cut: at the quadrant point nearest its middle (where an
// axis turns round: each part moves every axis one way) when one lies in
// its middle four fifths, else at its middle.
double split_point(const nc::ArcGeometry& g, double s0, double s1) {
  const double mid = 0.5 * (s0 + s1), quarter = M_PI / 2;
  const double a_mid = g.start_angle + g.sweep * mid;
  double best = mid, best_gap = 0.4 * (s1 - s0);
  for (const double q : {std::floor(a_mid / quarter), std::ceil(a_mid / quarter)}) {
    const double s = (q * quarter - g.start_angle) / g.sweep;
    if (std::abs(s - mid) < best_gap) {
      best = s;
      best_gap = std::abs(s - mid);
    }
  }
  return best;
}

}  // namespace

// An arc stays one block where the field allows. It is cut only where it
// must be: where an axis with lost motion turns round and the jump of its
// error there exceeds a quarter of the tolerance (a take-up step, a G1 to
// the next piece's start commanded with its directions, goes between the
// pieces, never inside an arc), and where a piece does not keep the
// tolerance (halved until it does, at most kMaxKeptPieces pieces). The
// controller runs each piece from where it stands to the written end about
// the written centre, its radius going linearly from start to end
// (nc::point_on, as verify simulates it). The end is the corrected end
// point; the centre is the nominal one moved by the mean of the
// corrections at the piece's ends (for an error field affine over the
// piece, the corrected points of the nominal arc lie on a slightly
// distorted circle about it). A piece is kept only when the actual tip
// stays within the tolerance (less the rounding of the written numbers, at
// least half of it left) of the nominal path at samples as dense
// as the field's bounds require, each sample with the directions the axes
// move in there (an axis turning round inside a piece switches its error
// there: within a quarter of the tolerance, by the cuts). Otherwise the
// whole block is linearised as with --linearize-arcs, and everything tried
// is put back. Polar words, G53 and, under inverse time, an arc that needs
// more than its own line are linearised.
bool ProgramPost::keep_arc(std::string_view text, const nc::Block& b, const nc::BlockEffect& fx,
                           const Corrector& c, const BlockStyle& style) {
  const nc::Motion& m = fx.motion;
  if (b.has('@') || b.has('^') || !emitted_known_ || fx.g53) return false;
  // What the pieces change: put back if the block is not kept.
  const LastCorrected last_was = last_, before_last_was = before_last_;
  const PostReport report_was = report_;
  const Vector3d emitted_was = emitted_mm_;
  const bool exact_was = emitted_exact_;
  const ApproachDirections last_dir_was = last_dir_;
  std::vector<KeptLine> lines;
  // Under G93 every line needs its own F (inverse time): one line only.
  if (!kept_arc_lines(m, c, style.lower, style.spaces, lines) ||
      (interp_.state().feed_mode == nc::kG93InverseTime && lines.size() > 1)) {
    last_ = last_was;
    before_last_ = before_last_was;
    report_ = report_was;
    emitted_mm_ = emitted_was;
    emitted_exact_ = exact_was;
    last_dir_ = last_dir_was;
    return false;
  }
  if (lines.size() == 1) {
    ++report_.arcs_kept;
    // One arc: the block with the fewest changed words, or as written
    // (these set where the controller then stands, from the start).
    const Vector3d reached = emitted_mm_;
    const bool exact = emitted_exact_;
    emitted_mm_ = emitted_was;
    emitted_exact_ = exact_was;
    if (write_kept_arc_minimal(text, b, fx, style, lines[0])) {
      output_left_arc_mode_ = false;
      return true;
    }
    emitted_mm_ = reached;
    emitted_exact_ = exact;
  } else {
    ++report_.arcs_split;
  }
  write_kept_arc(b, m, style.lower, style.spaces, lines);
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
  const double r_max = std::max(g.radius, g.end_radius);
  // Samples close enough that the deviation grows by at most 5 % of the
  // tolerance between two: its second derivative along the arc is at most
  // M = K r^2 + 2 L r (the field's curvature and Lipschitz bounds; the
  // corrected and nominal circles differ by the correction, whose change
  // over the arc the same bounds hold), so steps of sqrt(8 * 0.05 tol / M)
  // rad. No bounds (a compensation table): linearised.
  const double M = c.curvature_bound() * r_max * r_max + 2 * c.lipschitz_bound() * r_max;
  plan.step_rad = std::min(0.05, M > 0 ? std::sqrt(0.4 * path_tolerance_mm() / M) : 0.05);
  if (!(plan.step_rad > 0) || !(std::abs(g.sweep) / plan.step_rad <= 1e6)) return false;
  // The cuts that lost motion needs: where an axis turns round and its
  // error jumps by more than a quarter of the tolerance.
  std::vector<double> cuts = {0.0};
  const double dir = g.sweep > 0 ? 1.0 : -1.0, quarter = M_PI / 2,
               margin = plan.hair / std::abs(g.sweep);
  double q =
      dir > 0 ? std::floor(g.start_angle / quarter) + 1 : std::ceil(g.start_angle / quarter) - 1;
  for (int guard = 0; guard < 4 * 1024; ++guard, q += dir) {
    const double s_cut = (q * quarter - g.start_angle) / g.sweep;
    if (s_cut >= 1.0 - margin) break;
    if (s_cut <= margin) continue;
    const int a = turning_axis(g, q);
    if (c.reversal_jump_mm(nc::point_on(m, s_cut), a, last_dir_) > 0.25 * path_tolerance_mm())
      cuts.push_back(s_cut);
    if (cuts.size() > kMaxKeptPieces) return false;
  }
  cuts.push_back(1.0);
  // The pieces in order; one that does not keep the tolerance is halved.
  std::vector<std::pair<double, double>> todo;
  for (size_t k = cuts.size() - 1; k > 0; --k) todo.emplace_back(cuts[k - 1], cuts[k]);
  int pieces = 0;
  while (!todo.empty()) {
    const auto [s0, s1] = todo.back();
    todo.pop_back();
    if (kept_arc_piece(m, plan, c, s0, s1, lines)) {
      ++pieces;
      continue;
    }
    const double mid = split_point(g, s0, s1);
    if (pieces + static_cast<int>(todo.size()) + 2 > kMaxKeptPieces ||
        !((mid - s0) * std::abs(g.sweep) > 2 * plan.hair))
      return false;
    todo.emplace_back(mid, s1);
    todo.emplace_back(s0, mid);
  }
  return true;
}

bool ProgramPost::kept_arc_piece(const nc::Motion& m, const ArcPlan& plan, const Corrector& c,
                                 double s0, double s1, std::vector<KeptLine>& lines) {
  const nc::ArcGeometry& g = plan.g;
  const nc::State& s = interp_.state();
  nc::Motion piece = m;
  // The whole block as one piece keeps its extra turns (P), a part of it
  // has none.
  const bool whole = s0 == 0.0 && s1 == 1.0;
  if (!whole) piece.extra_turns = 0;
  piece.start_mm = s0 == 0.0 ? m.start_mm : nc::point_on(m, s0);
  piece.end_mm = nc::point_on(m, s1);
  const nc::ArcGeometry pg = nc::arc_geometry(piece);
  // (A piece that arc_geometry reads as another turn, or backwards: cut.)
  if (!(std::abs(pg.sweep - g.sweep * (s1 - s0)) < 1e-6)) return false;
  // Closed in its plane (a full circle, or full turns of a helix): the
  // controller runs it only when the written end is the start in the plane.
  const bool full_circle =
      std::abs(std::remainder(std::abs(pg.sweep), 2 * M_PI)) < 1e-9 && std::abs(pg.sweep) > 1.0;
  // Its directions at its ends: the plane's axes from the tangent, the
  // normal axis from the helix, else as they were.
  const int n = g.normal;
  ApproachDirections d0 = arc_tangent_directions(piece, pg, 0.0, last_dir_);
  ApproachDirections d1 = arc_tangent_directions(piece, pg, 1.0, d0);
  // An axis that turns round here takes up its play first.
  bool step = false;
  Vector3d c0, c1;
  auto solve = [&] {
    step = !c.same_error(last_dir_, d0);
    c0 = step ? command(c, piece.start_mm, d0) : emitted_mm_;
    c1 = command(c, piece.end_mm, d1);
  };
  solve();
  // The plane's normal axis, when the arc does not move it, may still be
  // commanded to creep (the correction varies along the arc), linearly
  // over the piece: it takes the creep's direction (segment()'s
  // settle_directions), its play taken up by the step.
  if (m.end_mm[n] == m.start_mm[n] && c.bidirectional(n)) {
    const double creep = c1[n] - c0[n];
    if (creep != 0 && (creep > 0 ? 1 : -1) != d0[static_cast<size_t>(n)]) {
      d0[static_cast<size_t>(n)] = d1[static_cast<size_t>(n)] = creep > 0 ? 1 : -1;
      solve();
    }
  }
  if (step && s.feed_mode == nc::kG93InverseTime)
    return false;  // the step's own F: linearised instead
  if (full_circle) {
    // The controller runs a full circle only when the written end is the
    // start in the plane: the corrected end must round to where it stands
    // (and a take-up step too: one that would be written cuts the circle).
    for (int a = 0; a < 3 && step; ++a)
      if (axis_needs_word(a, c0, nullptr, false)) return false;
    for (int a : {g.a0, g.a1}) {
      if (axis_needs_word(a, c1, nullptr, false)) return false;
      c1[a] = c0[a];
    }
  } else if (!((c1 - c0).norm() > 40 * half_unit(decimals()) * s.unit_mm)) {
    // Ends that would coincide: a full circle to the controller.
    return false;
  }
  nc::Motion cmd = piece;
  cmd.start_mm = c0;
  cmd.end_mm = c1;
  const Vector3d shift = 0.5 * ((c0 - piece.start_mm) + (c1 - piece.end_mm));
  cmd.center_mm[g.a0] = m.center_mm[g.a0] + shift[g.a0];
  cmd.center_mm[g.a1] = m.center_mm[g.a1] + shift[g.a1];
  const nc::ArcGeometry gc = nc::arc_geometry(cmd);
  // The arc the controller reads (its numbers rounded: a unit off at most
  // on each radius) within LinuxCNC's rule for its radii, and a spiral no
  // more than 0.01 mm beyond the nominal arc's.
  if (!(std::abs(gc.sweep - pg.sweep) < 1e-3) ||
      !(std::abs(gc.end_radius - gc.radius) <= std::abs(pg.end_radius - pg.radius) + 0.01) ||
      !nc::linuxcnc_accepts_radii(gc.radius / s.unit_mm, gc.end_radius / s.unit_mm, s.unit_mm > 1.0,
                                  4 * half_unit(decimals())))
    return false;
  // The normal axis commanded the way d says (a creep against it would be
  // lost in the play of an axis with lost motion, unless that is within a
  // quarter of the tolerance).
  if (const double move = c1[n] - c0[n]; move != 0 && c.bidirectional(n) &&
                                         (move > 0 ? 1 : -1) != d0[static_cast<size_t>(n)] &&
                                         c.reversal_jump_mm(c0, n, d0) > 0.25 * path_tolerance_mm())
    return false;
  double worst = 0.0;
  if (!kept_arc_samples(m, cmd, c, d0, std::abs(pg.sweep) / plan.step_rad, worst)) return false;
  // An axis turning round inside the piece: its error's jump there within
  // a quarter of the tolerance (the cuts put the larger ones between pieces).
  {
    const double lo = std::min(gc.start_angle, gc.start_angle + gc.sweep) + 2 * plan.hair,
                 hi = std::max(gc.start_angle, gc.start_angle + gc.sweep) - 2 * plan.hair;
    for (double q = std::ceil(lo / (M_PI / 2)); q * (M_PI / 2) <= hi; q += 1) {
      const double t = (q * (M_PI / 2) - gc.start_angle) / gc.sweep;
      if (c.reversal_jump_mm(nc::point_on(cmd, t), turning_axis(gc, q), d0) >
          0.25 * path_tolerance_mm())
        return false;
    }
  }
  add_kept_arc_piece_lines(plan, step, c0, cmd, d1, lines);
  report_.max_deviation_mm = std::max(report_.max_deviation_mm, worst);
  return true;
}

// Samples of the actual tip along the commanded arc cmd (from c0 = its
// start), lost motion as play (verify's backlash operator: an axis's state
// goes from one side of its play to the other as its command travels back
// the play's width), from the side d0 took up (an axis not yet moved: the
// mean); at least `min_samples`. True, and the largest deviation from the
// nominal arc m in *worst, when every sample keeps the tolerance less what
// the written numbers may add (the end and the centre each rounded by half
// an output unit per axis; at least half the tolerance is left).
bool ProgramPost::kept_arc_samples(const nc::Motion& m, const nc::Motion& cmd, const Corrector& c,
                                   const ApproachDirections& d0, double min_samples,
                                   double& worst) {
  const int samples = std::max(16, static_cast<int>(std::ceil(min_samples)));
  Vector3d h(d0[0], d0[1], d0[2]);
  const double limit = std::max(
      0.5 * path_tolerance_mm(),
      path_tolerance_mm() - 2 * std::sqrt(3.0) * half_unit(decimals()) * interp_.state().unit_mm);
  Vector3d previous = cmd.start_mm;
  for (int j = 0; j <= samples; ++j) {
    const Vector3d x = nc::point_on(cmd, static_cast<double>(j) / samples);
    c.take_up_play(previous, x, h);
    previous = x;
    const double deviation = nc::distance_to_path(m, x + c.error_with_play(x, h));
    if (!(deviation <= limit)) return false;
    worst = std::max(worst, deviation);
  }
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
      if (comp_move_) refuse_comp_take_up();
      words_.clear();
      append_axis_words(c0, false, lower, spaces, words_);
      lines.push_back({false, std::string(words_.view()), c0, {}});
      set_emitted(c0, false);
    }
  }
  KeptLine arc{true, {}, cmd.end_mm, {}};
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
      value = centre_prog - start_as_read(a);
    else
      value = (cmd.center_mm[a] - emitted_mm_[a]) / s.unit_mm;  // where the controller stands
    append_number(w, value, dec);
    arc.centre[static_cast<size_t>(a)] = {true, value};
  }
  arc.words = std::string(w.view());
  lines.push_back(std::move(arc));
  set_emitted(cmd.end_mm, false);
  last_dir_ = d;
}

bool ProgramPost::write_kept_arc_minimal(std::string_view text, const nc::Block& b,
                                         const nc::BlockEffect& fx, const BlockStyle& style,
                                         const KeptLine& arc) {
  // The block's own motion word, or the modal one the output is still in.
  bool stated = false;
  for (const nc::Word& w : b.words)
    stated = stated || (w.letter == 'G' && (w.code10 == nc::kG2ArcClockwise ||
                                            w.code10 == nc::kG3ArcCounterClockwise));
  if (!stated && output_left_arc_mode_) return false;
  const int dec = decimals();
  nc::BlockEdit& e = fresh_edit();
  Vector3d reached_mm;
  bool changed = minimal_axis_words(b, style, false, arc.end_mm, e, reached_mm);
  // The centre words: renumbered where they would move the centre by half
  // an output unit or more; an R form, when anything changes, becomes the
  // centre's words (the controller would put R's centre elsewhere).
  const bool r_form = b.has('R');
  std::string centre_words;
  bool centre_changed = false;
  std::vector<std::pair<int, std::string>> renumber_centre;
  for (int a = 0; a < 3; ++a) {
    const auto& [in_plane, value] = arc.centre[static_cast<size_t>(a)];
    if (!in_plane) continue;
    const char letter = style.lower ? "ijk"[a] : "IJK"[a];
    const std::string word = letter + nc::format_number(value, dec);
    if (!centre_words.empty() && style.spaces) centre_words += ' ';
    centre_words += word;
    if (r_form) continue;
    const int idx = word_index(b, "IJK"[a]);
    const double old = idx >= 0                       ? b.words[static_cast<size_t>(idx)].value
                       : interp_.state().arc_absolute ? std::nan("")
                                                      : 0.0;
    if (std::abs(value - old) < half_unit(dec)) continue;
    centre_changed = true;
    if (idx >= 0) {
      renumber_centre.emplace_back(idx, word.substr(1));
    } else {
      if (!e.insert.empty() && style.spaces) e.insert += ' ';
      e.insert += word;
    }
  }
  if (r_form && !changed) {
    // Nothing else changes: the controller puts R's centre where the
    // nominal one is; is ours within half an output unit of it?
    const nc::State& st = interp_.state();
    for (int a = 0; a < 3; ++a) {
      const auto& [in_plane, value] = arc.centre[static_cast<size_t>(a)];
      if (!in_plane) continue;
      const double nominal = (fx.motion.center_mm[a] - interp_.work_offset()[a]) / st.unit_mm;
      const double start =
          st.absolute ? start_as_read(a) : (emitted_mm_[a] - interp_.work_offset()[a]) / st.unit_mm;
      const double ours = st.arc_absolute ? value : value + start;
      centre_changed = centre_changed || !(std::abs(ours - nominal) < half_unit(dec));
    }
  }
  if (!changed && !centre_changed) {
    write_unchanged(text, b, fx);
    return true;
  }
  if (r_form) {
    e.remove.push_back(word_index(b, 'R'));
    if (!e.insert.empty() && style.spaces) e.insert += ' ';
    e.insert += centre_words;
  } else {
    for (auto& rc : renumber_centre) e.renumber.push_back(std::move(rc));
  }
  nc::apply_edit(b, e, edited_);
  emit(edited_);
  ++report_.lines_changed;
  emitted_mm_ = reached_mm;
  emitted_exact_ = true;
  return true;
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
    // (P stays with a block written as one arc: the turns are its own.)
    if (L == 'X' || L == 'Y' || L == 'Z' || L == 'I' || L == 'J' || L == 'K' || L == 'R' ||
        (L == 'P' && lines.size() > 1) || (motion && !lines[0].arc))
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
  output_left_arc_mode_ = false;  // the last line is an arc
}

}  // namespace volmap::post
