#include "postproc/three_axis/line_bound.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <vector>

#include "gcode/nc_interpreter.h"
#include "gcode/nc_path.h"
#include "gcode/program_reader.h"
#include "postproc/three_axis/corrector.h"
#include "postproc/three_axis/post_pieces.h"

namespace volmap::post {
namespace {

// Does the chord between the corrected points at path parameters s and t
// of the straight move m keep the tolerance (32 points along it)?
bool chord_keeps(const Corrector& c, const nc::Motion& m, double s, double t,
                 const ApproachDirections& d, double tol) {
  const Vector3d n0 = nc::point_on(m, s), n1 = nc::point_on(m, t);
  const Vector3d c0 = c.command_for(n0, d), c1 = c.command_for(n1, d);
  constexpr int kPoints = 32;
  for (int j = 1; j < kPoints; ++j) {
    const double u = static_cast<double>(j) / kPoints;
    const Vector3d x = c0 + u * (c1 - c0);
    if ((x + c.error_at(x, d) - (n0 + u * (n1 - n0))).norm() > tol) return false;
  }
  return true;
}

// The fewest chords of a straight move (greedy longest pieces).
std::uint64_t fewest_chords(const Corrector& c, const nc::Motion& m, const ApproachDirections& d,
                            double tol) {
  std::uint64_t pieces = 0;
  double s = 0.0;
  while (s < 1.0 && pieces < 100000) {
    ++pieces;
    if (chord_keeps(c, m, s, 1.0, d, tol)) break;
    double lo = s, hi = 1.0;  // lo keeps (trivially), hi does not
    for (int k = 0; k < 30 && hi - lo > 1e-9; ++k) {
      const double mid = 0.5 * (lo + hi);
      (chord_keeps(c, m, s, mid, d, tol) ? lo : hi) = mid;
    }
    s = std::max(lo, s + 1e-9);
  }
  return pieces;
}

// Lines forced by axes that turn round with more play than the tolerance:
// at the move's start (directions `from` before, `to` on it) at point p.
std::uint64_t forced_turns(const Corrector& c, const Vector3d& p, const ApproachDirections& from,
                           const ApproachDirections& to, double tol) {
  for (int a = 0; a < 3; ++a)
    if (from[static_cast<size_t>(a)] != 0 && to[static_cast<size_t>(a)] != 0 &&
        from[static_cast<size_t>(a)] != to[static_cast<size_t>(a)] &&
        c.reversal_jump_mm(p, a, to) > tol)
      return 1;
  return 0;
}

}  // namespace

LineBound fewest_lines(std::istream& in, const std::string& name, const Machine& machine,
                       const ErrorSet& errors, const nc::ProgramSetup& setup, double tolerance_mm,
                       const std::vector<std::string>& subroutine_path) {
  LineBound b;
  nc::Interpreter interp(setup, name);
  nc::ProgramReader reader(in, name, interp, subroutine_path);
  std::map<double, std::unique_ptr<Corrector>> correctors;
  auto corrector = [&]() -> const Corrector& {
    const double L = machine.tool_length_mm + interp.state().tool_length_mm;
    auto& slot = correctors[L];
    if (!slot) slot = std::make_unique<Corrector>(machine, errors, L, OutsidePolicy::kClamp);
    return *slot;
  };
  ApproachDirections last{};
  nc::ProgramLine l;
  nc::BlockEffect fx;
  while (reader.next(l)) {
    if (l.verbatim) continue;
    const bool known_before = interp.state().position_known;
    interp.execute(nc::lex_block(nc::flatten::without_cr(l.text), l.line, l.file ? *l.file : name),
                   fx);
    // (A move from an unknown position sets no direction: the post writes
    // it as it is.)
    if (!fx.has_motion || !known_before) continue;
    const nc::Motion& m = fx.motion;
    const Corrector& c = corrector();
    if (c.zero()) continue;
    if (m.kind == nc::MotionKind::kArc) {
      const nc::ArcGeometry g = nc::arc_geometry(m);
      ApproachDirections d = arc_tangent_directions(m, g, 0.0, last);
      b.turn_lines += forced_turns(c, m.start_mm, last, d, tolerance_mm);
      // Inside: every quadrant point where an axis with play turns round.
      const double quarter = M_PI / 2, lo = std::min(g.start_angle, g.start_angle + g.sweep),
                   hi = std::max(g.start_angle, g.start_angle + g.sweep);
      for (double q = std::floor(lo / quarter) + 1; q * quarter < hi; q += 1) {
        const double u = (q * quarter - g.start_angle) / g.sweep;
        if (u <= 1e-9 || u >= 1 - 1e-9) continue;
        const int a = turning_axis(g, q);
        // The arc cut there, and the play taken up between the two arcs by
        // a move of its own: two lines more.
        if (c.reversal_jump_mm(nc::point_on(m, u), a, d) > tolerance_mm) b.turn_lines += 2;
      }
      last = arc_tangent_directions(m, g, 1.0, d);
    } else {
      ApproachDirections d = directions_of(m.start_mm, m.end_mm, last);
      if (m.kind == nc::MotionKind::kLinear) {
        b.turn_lines += forced_turns(c, m.start_mm, last, d, tolerance_mm);
        // An axis the move does not move but the correction makes creep
        // moves the way it creeps (its play taken up that way); a creep
        // beyond the tolerance against the way it last moved forces a
        // take-up of its own.
        const ApproachDirections before = d;
        const Vector3d c0 = c.command_for(m.start_mm, d), c1 = c.command_for(m.end_mm, d);
        if (settle_directions(c0, c1, m.start_mm, m.end_mm, d))
          for (int a = 0; a < 3; ++a)
            if (before[static_cast<size_t>(a)] != 0 &&
                before[static_cast<size_t>(a)] != d[static_cast<size_t>(a)] && c.bidirectional(a) &&
                std::abs(c1[a] - c0[a]) > tolerance_mm) {
              ++b.turn_lines;
              break;
            }
        b.chord_lines += fewest_chords(c, m, d, tolerance_mm) - 1;
      } else if (m.kind == nc::MotionKind::kCycle) {
        // A cycle the controller repeats (L, G91, polar): a block per hole
        // once their corrections differ.
        b.hole_lines += fx.more_holes.size();
      }
      last = d;
    }
  }
  // A flattened part comes out flat once anything in it changes: its
  // blocks, not its source lines.
  const nc::ReadReport& r = reader.report();
  b.lines_in = static_cast<std::uint64_t>(
      reader.input_lines() +
      (r.flattened_from > 0 && b.turn_lines + b.chord_lines + b.hole_lines > 0
           ? r.flat_blocks - r.flat_source_lines
           : 0));
  return b;
}

}  // namespace volmap::post
