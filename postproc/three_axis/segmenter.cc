// ProgramPost::segment: a move cut into pieces until the actual path stays
// within the tolerance of the nominal one (docs/post.md), and command():
// the corrected point, warm-started from the last ones.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/common/input_error.h"
#include "gcode/nc_path.h"
#include "postproc/three_axis/program_post.h"

namespace volmap::post {

// Pieces of one move at most (an arc's initial pieces, and all pieces).
constexpr int kMaxArcPieces = 1 << 16;

int ProgramPost::arc_initial_pieces(const nc::Motion& m) const {
  const double tol = path_tolerance_mm();
  // Initial pieces: arcs so that the chord error is below tol / 4.
  const nc::ArcGeometry g = nc::arc_geometry(m);
  const double r = std::max(g.radius, g.end_radius);
  const double max_step = r > tol / 4 ? 2.0 * std::acos(1.0 - (tol / 4) / r) : M_PI / 2;
  const double pieces = std::ceil(std::abs(g.sweep) / max_step);
  if (!(pieces <= kMaxArcPieces))  // also NaN: never cast to int out of range
    throw InputError(
        *line_file_, current_line_,
        fmt::format("the arc needs more than {} pieces to keep {:g} µm (radius {:g} mm); "
                    "raise `tolerance_um` or check the arc's centre",
                    kMaxArcPieces, tol * 1e3, r));
  return std::max(4, static_cast<int>(pieces));
}

double ProgramPost::start_deviation(const Corrector& c, const Vector3d& c0, const Vector3d& n0p,
                                    const ApproachDirections& d, const LastCorrected& start,
                                    double chord) {
  if (start_dev_.corrector == &c && start_dev_.command == c0 && start_dev_.nominal == n0p &&
      c.same_error(start_dev_.dir, d))
    return start_dev_.deviation;  // the same start, halved again
  // Where the controller stands near the last point corrected (at the
  // rounding of its command, or at words kept within half an output unit of
  // it: a line with the fewest changes), a bound without evaluating e. With
  // x = start.command, which solves x + e(x) = n = start.nominal to the
  // residual r (segment()'s kResidual), and e Lipschitz with L in the box:
  //   |c0 + e(c0) - n0p| <= r + (1 + L) |c0 - x| + |n - n0p|
  // (plus 1e-11 mm for the rounding of the operations). The bound stands
  // for the deviation only where it decides nothing: the piece keeps the
  // tolerance by it, and its predicted deviation, at least the exact one,
  // does not exceed the largest reported so far, which therefore stays as
  // it is. The output and the report are the exact evaluation's.
  const double residual = 2 * solve_accuracy_mm() + 1e-12;
  if (start.corrector == &c && c.same_error(start.dir, d) && c.in_bound_box(c0) &&
      c.in_bound_box(start.command)) {
    const double bound = residual + (1.0 + c.lipschitz_bound()) * (c0 - start.command).norm() +
                         (start.nominal - n0p).norm() + 1e-11;
    const double predicted = std::max(bound, residual) + chord;
    if (predicted <= path_tolerance_mm() && predicted <= report_.max_deviation_mm) return bound;
  }
  const double dev0 = (c0 + c.error_at(c0, d) - n0p).norm();
  start_dev_ = {&c, n0p, c0, d, dev0};
  return dev0;
}

Vector3d ProgramPost::command(const Corrector& c, const Vector3d& nominal,
                              const ApproachDirections& d) {
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
    throw InputError(*line_file_, current_line_,
                     "the correction is not finite here; check the errors file");
  report_.max_correction_mm = std::max(report_.max_correction_mm, corr);
  ++report_.points_corrected;
  return cmd;
}

double ProgramPost::sampled_deviation(const Corrector& c, const nc::Motion& m, double s0, double s1,
                                      const Vector3d& c0, const Vector3d& c1,
                                      const ApproachDirections& d) {
  // At 1/4, 1/2, 3/4 of the piece; the first beyond the tolerance ends it.
  double worst = 0.0;
  for (double t : {0.25, 0.5, 0.75}) {
    const Vector3d x = c0 + t * (c1 - c0);
    const Vector3d nominal = nc::point_on(m, s0 + t * (s1 - s0));
    worst = std::max(worst, (x + c.error_at(x, d) - nominal).norm());
    if (worst > path_tolerance_mm()) break;
  }
  return worst;
}

const std::vector<Piece>& ProgramPost::segment(const Corrector& c, const nc::Motion& m,
                                               const Vector3d& start_cmd) {
  const double tol = path_tolerance_mm();
  // Initial pieces: arcs so that the chord error is below tol / 4; a line whole.
  const int n0 = m.kind == nc::MotionKind::kArc ? arc_initial_pieces(m) : 1;
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
      double predicted = 0.0;  // the piece's deviation: its bound, or its largest sample
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
        const double chord = c.chord_deviation_bound(p.c0, c1);
        // The start is the last point corrected with the same directions:
        // an upper bound without evaluating e; else start_deviation.
        const bool dev0_exact = !(start_known && c.same_error(start.dir, d));
        const double dev0 = dev0_exact ? start_deviation(c, p.c0, n0p, d, start, chord)
                                       : kResidual + (start.nominal - n0p).norm();
        const double bound = std::max(dev0, kResidual) + chord;
        if (bound <= tol) {
          sample = false;
          predicted = bound;
        }
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
            if (comp_move_) refuse_comp_take_up();
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
      if (sample) {
        predicted = sampled_deviation(c, m, p.s0, p.s1, p.c0, c1, d);
        ok = predicted <= tol;
      }
      if (ok || p.s1 - p.s0 < 1e-9) {
        // (A piece that covers no path, a take-up step, leaves the tool
        // standing while the play is taken up.)
        if (ok) report_.max_deviation_mm = std::max(report_.max_deviation_mm, predicted);
        done.push_back({c1, p.s1});
        if (done.size() > kMaxPieces)
          throw InputError(
              *line_file_, current_line_,
              fmt::format("more than {} pieces needed to keep {:g} µm; raise `tolerance_um`",
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

}  // namespace volmap::post
