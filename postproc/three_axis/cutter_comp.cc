// ProgramPost::check_compensation: cutter radius compensation (G41/G42)
// kept in the output. The controller offsets the corrected contour by the
// tool radius; the post accepts a move only where that leaves the tool
// within a quarter of the tolerance of where the nominal program puts it
// (comp_bound.h), and refuses it with the numbers otherwise.
#include <fmt/format.h>

#include <cmath>

#include "core/common/input_error.h"
#include "postproc/three_axis/comp_bound.h"
#include "postproc/three_axis/program_post.h"

namespace volmap::post {

namespace {

// The length over which a rounding of the output turns a move's tangent:
// a line's length in XY, an arc's radius (mm).
double tangent_lever_mm(const nc::Motion& m) {
  if (m.kind == nc::MotionKind::kArc)
    return std::hypot(m.end_mm.x() - m.center_mm.x(), m.end_mm.y() - m.center_mm.y());
  return std::hypot(m.end_mm.x() - m.start_mm.x(), m.end_mm.y() - m.start_mm.y());
}

}  // namespace

void ProgramPost::check_compensation(const Corrector& c, const nc::BlockEffect& fx) {
  if (!fx.has_motion) return;  // the last tangent stays: a block that does not move
  const nc::CompRole role = fx.comp_role;
  comp_move_ = role != nc::CompRole::kNone && !c.zero();
  if (role == nc::CompRole::kNone) {
    comp_tangent_in_.setZero();
    comp_factor_ = 2.0;
    return;
  }
  const nc::Motion& m = fx.motion;
  const nc::State& s = interp_.state();
  const double r = s.comp_radius_mm;
  const double L = c.zero() ? 0.0 : c.lipschitz_bound();
  const Eigen::Vector2d t_out = nc::xy_tangent(m, false);
  const double lever = tangent_lever_mm(m);
  double g = 2.0, extra_mm = 0.0;
  if (role == nc::CompRole::kEntry && m.kind == nc::MotionKind::kArc && comp_move_)
    // LinuxCNC (convert_arc_comp1) builds a new arc through the start and
    // the offset end, its centre on the line to the programmed one: how far
    // the correction moves that arc is not bounded here.
    throw InputError(*line_file_, current_line_,
                     "an arc as the entry move of cutter compensation: the controller builds "
                     "a new arc from the start, which volmap does not bound on a machine with "
                     "errors; enter with a straight move");
  if (role == nc::CompRole::kEntry) {
    // LinuxCNC (convert_straight_comp1) ends the entry at the end offset
    // square to the move: the end's offset, as on a smooth path.
    g = 2.0;
  } else if (role == nc::CompRole::kCompensated) {
    g = comp_corner_factor(comp_tangent_in_, t_out, s.comp_side);
    // The turn the controller sees: the nominal one, moved by the
    // correction (at most L on each side) and by the output's rounding
    // (half a unit on each axis at both ends: up to 2 units across a move,
    // over its lever).
    const double unit_mm = 2 * half_unit(decimals()) * s.unit_mm;
    const double margin = 2 * L + 2 * unit_mm / std::max(comp_lever_in_, 1e-300) +
                          2 * unit_mm / std::max(lever, 1e-300);
    extra_mm = comp_threshold_term_mm(comp_tangent_in_, t_out, s.comp_side, r, margin);
    if (comp_move_ && std::isfinite(fx.comp_slack_mm)) {
      // The side before this corner, cut back by both its inside corners,
      // must stay reachable on the output: its length changes by at most
      // L times it and the rounding, the cuts by their rate times the turn.
      const double use_mm = L * fx.comp_slack_len_mm + 4 * unit_mm + fx.comp_slack_rate * margin;
      if (fx.comp_slack_mm < use_mm)
        throw InputError(*line_file_, current_line_,
                         fmt::format("the side before this inside corner of cutter compensation "
                                     "leaves the tool {:.3g} µm to spare, and the correction can "
                                     "use up {:.3g} µm of it: LinuxCNC would refuse the output "
                                     "(cannot be reached without gouging); lengthen the side or "
                                     "use a smaller tool",
                                     fx.comp_slack_mm * 1e3, use_mm * 1e3));
    }
  }
  comp_factor_ = g;
  // The correction of a move along Z alone would move X and Y a little: a
  // move in the plane, which the controller would offset as a corner.
  comp_hold_xy_ = comp_move_ && role == nc::CompRole::kCompensated && t_out.isZero(0.0);
  const Eigen::Vector2d t_end = nc::xy_tangent(m, true);
  if (!t_end.isZero(0.0)) comp_tangent_in_ = t_end, comp_lever_in_ = lever;
  if (role == nc::CompRole::kExit) comp_tangent_in_.setZero();
  ++report_.comp_moves;
  report_.comp_radius_mm = std::max(report_.comp_radius_mm, r);
  if (c.zero()) return;
  if (!std::isfinite(L))
    throw InputError(*line_file_, current_line_,
                     "cutter compensation (G41/G42) is kept only with an errors file: the "
                     "controller offsets the corrected contour, and a compensation table gives "
                     "no bound on how the errors change over the tool's radius; post with "
                     "`errors`, or output the tool centre path from CAM (G40)");
  check_comp_bound(g * r * L + extra_mm,
                   role == nc::CompRole::kEntry  ? "the entry move of "
                   : role == nc::CompRole::kExit ? "the exit move of "
                   : extra_mm > 0                ? "a corner near LinuxCNC's 0.05 rad limit under "
                   : g > 2.0                     ? "an inside corner of "
                                                 : "",
                   g, L);
}

void ProgramPost::check_comp_pieces(const Corrector& c, double piece_lever_mm) {
  // Pieces the post wrote for one move turn by at most 2 L and the
  // rounding: the controller jumps between their offsets (below 0.05 rad),
  // overshooting by up to r (1 - cos turn) inside.
  const nc::State& s = interp_.state();
  const double L = c.lipschitz_bound();
  const double turn =
      2 * L + 4 * half_unit(decimals()) * s.unit_mm / std::max(piece_lever_mm, 1e-300);
  check_comp_bound(comp_factor_ * s.comp_radius_mm * L + s.comp_radius_mm * (1 - std::cos(turn)),
                   "the pieces of ", comp_factor_, L);
}

void ProgramPost::check_comp_bound(double bound_mm, const char* where, double g, double L) {
  report_.comp_bound_mm = std::max(report_.comp_bound_mm, bound_mm);
  const double allowed_mm = options_.tolerance_mm / 4;
  if (bound_mm <= allowed_mm) return;
  const double r = interp_.state().comp_radius_mm;
  if (!std::isfinite(bound_mm))
    throw InputError(*line_file_, current_line_,
                     fmt::format("{}cutter compensation (G41/G42, tool radius {:g} mm): the path "
                                 "turns back on itself here, an inside corner where the "
                                 "controller's offset has no bound; output the tool centre path "
                                 "from CAM (G40)",
                                 where, r));
  throw InputError(
      *line_file_, current_line_,
      fmt::format("{}cutter compensation (G41/G42, tool radius {:g} mm): the controller offsets "
                  "the corrected contour, which can leave the tool up to {:.3g} µm off ({:.3g} "
                  "x radius x the error field's slope bound {:.3g}, and the corner's terms), "
                  "more than a quarter of the tolerance ({:g} µm); post with --tolerance-um "
                  "{:g} or more, or output the tool centre path from CAM (G40)",
                  where, r, bound_mm * 1e3, g, L, allowed_mm * 1e3,
                  std::ceil(bound_mm * 4e3 * 100) / 100));
}

double ProgramPost::comp_travel_margin_mm() const {
  // r / c at a corner (g / 2 >= 1 / c), at least sqrt 2 r.
  return interp_.state().comp_radius_mm * std::max(M_SQRT2, comp_factor_ / 2);
}

Vector3d ProgramPost::held_xy_command(const Corrector& c, const Vector3d& nominal,
                                      const ApproachDirections& d) {
  Vector3d cmd(emitted_mm_.x(), emitted_mm_.y(), nominal.z());
  for (int k = 0; k < 20; ++k) {  // a contraction by about L: a few steps
    const double z = nominal.z() - c.error_at(cmd, d).z();
    const bool done = std::abs(z - cmd.z()) < solve_accuracy_mm();
    cmd.z() = z;
    if (done) break;
  }
  // X and Y stay off by how much their errors change over the Z travel.
  const double off_mm = (cmd + c.error_at(cmd, d) - nominal).norm();
  report_.max_deviation_mm = std::max(report_.max_deviation_mm, off_mm);
  if (off_mm > path_tolerance_mm())
    throw InputError(*line_file_, current_line_,
                     fmt::format("a move along Z alone under cutter compensation: X and Y stay "
                                 "where they are (a move in the plane would be a corner for the "
                                 "controller), and their errors change by {:.3g} µm over the Z "
                                 "travel, more than the tolerance allows ({:g} µm); give G40 "
                                 "before the Z move and G41/G42 after it, or output the tool "
                                 "centre path from CAM (G40)",
                                 off_mm * 1e3, path_tolerance_mm() * 1e3));
  return cmd;
}

void ProgramPost::refuse_comp_take_up() const {
  throw InputError(*line_file_, current_line_,
                   "an axis with lost motion turns round here under cutter compensation, and "
                   "keeping the tolerance needs a short step that takes up its play, of which "
                   "the controller would make a corner of the offset path; raise "
                   "--tolerance-um (the play is then left within it), or output the tool "
                   "centre path from CAM (G40)");
}

void ProgramPost::refuse_comp_split(const nc::BlockEffect& fx) const {
  const bool entry = fx.comp_role == nc::CompRole::kEntry;
  throw InputError(*line_file_, current_line_,
                   fmt::format("the {} move of cutter compensation ({}) needs more than one piece "
                               "to keep the tolerance on this machine, and a split would move "
                               "the controller's {} (it computes it from the move's start); "
                               "make the move shorter, or raise --tolerance-um",
                               entry ? "entry" : "exit",
                               entry ? "the first move after G41/G42" : "the first after G40",
                               entry ? "entry" : "exit"));
}

}  // namespace volmap::post
