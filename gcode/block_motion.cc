// The motion of a block: its end point (axis words, G53, polar
// coordinates), the straight move and the arc; canned cycles are in
// canned_cycles.cc.
#include <fmt/format.h>

#include <cmath>

#include "core/common/units.h"
#include "gcode/block_check.h"
#include "gcode/g_codes.h"
#include "gcode/nc_path.h"

namespace volmap::nc {
namespace {

constexpr double kMaxArcTurns = 1000;  // P of G2/G3 (more would not fit in memory as pieces)

}  // namespace

void straight_move(const Eigen::Vector3d& wo, const double (&value)[3], unsigned given, State& s,
                   Motion& mo) {
  s.cycle_il_known = false;  // not a cycle: the run of cycle blocks ends
  Eigen::Vector3d target = s.position_mm;
  for (int a = 0; a < 3; ++a) {
    if (!(given >> a & 1u)) continue;
    if (s.absolute)
      target[a] = value[a] * s.unit_mm + wo[a];
    else
      target[a] = s.position_mm[a] + value[a] * s.unit_mm;
  }
  mo.kind = s.motion == kG0Rapid ? MotionKind::kRapid : MotionKind::kLinear;
  mo.start_mm = s.position_mm;
  mo.end_mm = target;
  mo.feed = s.feed;
  s.position_mm = target;
  for (int a = 0; a < 3; ++a)
    if ((given >> a & 1u) && s.absolute) s.axis_known[static_cast<size_t>(a)] = true;
  s.position_known = s.axis_known[0] && s.axis_known[1] && s.axis_known[2];
}

void BlockCheck::motion(int motion_before) {
  const Eigen::Vector3d& wo = work_offset();
  Eigen::Vector3d target = s_.position_mm;
  std::array<bool, 3> given{};
  for (int a = 0; a < 3; ++a) {
    const Word* w = word("XYZ"[a]);
    if (!w) continue;
    given[static_cast<size_t>(a)] = true;
    if (s_.absolute)
      target[a] = w->value * s_.unit_mm + (g53_ ? 0.0 : wo[a]);
    else
      target[a] = s_.position_mm[a] + w->value * s_.unit_mm;
  }
  // Program coordinates (XY plane, program units) of where the tool
  // stands: polar coordinates and canned-cycle increments start there.
  const double unit = s_.unit_mm;
  const double at_x = (s_.position_mm.x() - wo.x()) / unit,
               at_y = (s_.position_mm.y() - wo.y()) / unit;
  const bool xy_known = s_.axis_known[0] && s_.axis_known[1];
  if (polar && !is_cycle(s_.motion)) polar_target(at_x, at_y, xy_known, target, given);
  Motion& mo = effect_.motion;
  mo.start_mm = s_.position_mm;
  mo.feed = s_.feed;
  // Fanuc's G53 positions at rapid traverse (the modal motion stays).
  const int mode = g53_ && fanuc() ? kG0Rapid : s_.motion;
  bool known_after = true;
  for (int a = 0; a < 3; ++a)
    known_after = known_after && (s_.axis_known[static_cast<size_t>(a)] ||
                                  (given[static_cast<size_t>(a)] && s_.absolute));
  if (!known_after && mode != kG0Rapid)
    fail(nullptr,
         "a feed move from an unknown position: command X, Y and Z with a rapid (G0) "
         "before the first cutting move, or give `initial_position`");
  if (mode == kG0Rapid || mode == kG1Linear) {
    mo.kind = mode == kG0Rapid ? MotionKind::kRapid : MotionKind::kLinear;
    if (mode == kG1Linear && s_.feed <= 0.0 && s_.feed_mode != kG93InverseTime)
      fail(nullptr, "G1 with no feed rate; add an F word");
    mo.end_mm = target;
  } else if (is_arc(mode)) {
    arc(mo, target, given);
  } else if (is_cycle(mode)) {
    target = cycle(mo, motion_before, at_x, at_y, xy_known, target);
  } else if (mode == kG33_1RigidTap) {
    rigid_tap(mo, target);
    target = mo.start_mm;  // the tap comes back to where it started
  } else {
    fail(nullptr, "axis words without a motion mode; add G0 or G1");
  }
  if (mo.kind == MotionKind::kRapid || mo.kind == MotionKind::kLinear) straight_tool_axis();
  rotary_targets(mo.kind);
  effect_.has_motion = true;
  s_.position_mm = target;
  // An incremental word moves from where the axis is: it makes an unknown
  // axis no better known.
  for (int a = 0; a < 3; ++a)
    if ((given[static_cast<size_t>(a)] && s_.absolute) || mo.kind == MotionKind::kCycle)
      s_.axis_known[static_cast<size_t>(a)] = true;
  s_.position_known = s_.axis_known[0] && s_.axis_known[1] && s_.axis_known[2];
}

void BlockCheck::rigid_tap(Motion& mo, const Eigen::Vector3d& target) const {
  // LinuxCNC (convert_straight, G33.1; checked with rs274): K (the pitch)
  // in every block, no F, the spindle turning; RIGID_TAP to the end point
  // and back.
  const Word* code = g[kMotion];
  if (fanuc())
    fail(code,
         "G33.1 is LinuxCNC's rigid tap; on a Fanuc control tap rigidly with M29 and G84, "
         "which volmap reads as G84");
  if (!word('K')) fail(code, "K word missing with g33/g33.1 (the pitch; LinuxCNC refuses it)");
  if (const Word* f = word('F'))
    fail(f, "F word used with a g33/g33.1 (the spindle sets the feed; LinuxCNC refuses it)");
  if (!s_.spindle_turning)
    fail(code, "spindle not turning in G33.1 (LinuxCNC refuses it): start it with M3 or M4");
  if (!s_.position_known)
    fail(code, "G33.1 from an unknown position: command X, Y and Z with a rapid (G0) first");
  if (s_.comp_side != 0 && s_.comp_radius_mm > 0)
    fail(code,
         "G33.1 while cutter compensation is on (LinuxCNC refuses it: \"Bug code not g0 "
         "or g1\"); give G40 first");
  mo.kind = MotionKind::kTap;
  mo.end_mm = target;
  mo.r_mm = mo.clear_mm = mo.start_mm.z();
}

void BlockCheck::rotary_targets(MotionKind kind) {
  for (int r = 0; r < 3; ++r) {
    const Word* w = word("ABC"[r]);
    if (!w) continue;
    if (kind == MotionKind::kCycle || kind == MotionKind::kTap)
      fail(w, fmt::format(
                  "rotary axis word {} in a canned cycle or tap block; move the rotary axes in "
                  "a block of their own",
                  w->letter));
    double& q = s_.rotary_rad[static_cast<size_t>(r)];
    q = s_.absolute ? w->value * units::kRadPerDeg : q + w->value * units::kRadPerDeg;
  }
}

void BlockCheck::straight_tool_axis() {
  if (!setup_.tool_axis_words) return;
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  bool given = false;
  for (int c = 0; c < 3; ++c)
    if (const Word* w = word("IJK"[c])) {
      a[c] = w->value;
      given = true;
    }
  if (!given) return;
  if (a.norm() < 1e-9) fail(nullptr, "the tool axis I J K is zero");
  s_.tool_axis = a.normalized();
}

void BlockCheck::polar_target(double at_x, double at_y, bool xy_known, Eigen::Vector3d& target,
                              std::array<bool, 3>& given) const {
  // LinuxCNC (interp_find.cc, find_ends). G90: @ and ^ from the program
  // origin; a missing one is the current point's. G91: @ adds to the
  // current point's radius, then ^ to its angle.
  const Eigen::Vector3d& wo = work_offset();
  const double unit = s_.unit_mm;
  const Word* w = polar_radius ? polar_radius : polar_angle;
  const bool needs_current = !s_.absolute || !polar_radius || !polar_angle;
  if (needs_current && !xy_known)
    fail(w,
         "polar coordinates from an unknown position: command X and Y first (or give "
         "`initial_position`)");
  if (s_.absolute && polar_radius && !polar_angle && at_x == 0 && at_y == 0)
    fail(w, "polar radius without an angle at the origin: add a ^ word");
  if (!s_.absolute && at_x == 0 && at_y == 0)
    fail(w,
         "incremental polar coordinates (G91) at the program origin are indeterminate; move "
         "off it first");
  const double* radius = polar_radius ? &polar_radius->value : nullptr;
  const double* angle = polar_angle ? &polar_angle->value : nullptr;
  const Eigen::Vector2d p = polar_end({at_x, at_y}, s_.absolute, radius, angle);
  const double px = p.x(), py = p.y();
  target.x() = px * unit + wo.x();
  target.y() = py * unit + wo.y();
  given[0] = given[1] = s_.absolute;  // an absolute polar point fixes both axes
}

void BlockCheck::arc(Motion& mo, const Eigen::Vector3d& target, const std::array<bool, 3>& given) {
  const Eigen::Vector3d& wo = work_offset();
  if (s_.feed <= 0.0) fail(nullptr, "arc with no feed rate; add an F word");
  const int p = s_.plane;  // in-plane axes (a0, a1)
  static constexpr int kA0[3] = {0, 2, 1}, kA1[3] = {1, 0, 2};
  static constexpr char kOff0[3] = {'I', 'K', 'J'}, kOff1[3] = {'J', 'I', 'K'};
  const int a0 = kA0[p], a1 = kA1[p];
  // LinuxCNC (convert_arc): "K word given for arc in xy plane" (J in
  // xz, I in yz), and "Mixed radius ijk format for arc" for R with any
  // of I J K.
  static constexpr char kNormalOffset[3] = {'K', 'J', 'I'};
  static constexpr const char* kPlaneName[3] = {"XY (G17)", "XZ (G18)", "YZ (G19)"};
  if (const Word* w = word(kNormalOffset[p]); w && !word('R'))
    fail(w, fmt::format("{} word given for an arc in the {} plane; LinuxCNC refuses it: remove it",
                        kNormalOffset[p], kPlaneName[p]));
  if (const Word* r = word('R'); r && (word('I') || word('J') || word('K')))
    fail(r, "arc with both R and I/J/K; use one form");
  if (!given[static_cast<size_t>(a0)] && !given[static_cast<size_t>(a1)] && !word('R') &&
      !word(kOff0[p]) && !word(kOff1[p]))
    fail(nullptr, "arc without in-plane end point or centre");
  mo.kind = MotionKind::kArc;
  mo.end_mm = target;
  mo.plane = p;
  mo.clockwise = s_.motion == kG2ArcClockwise;
  const Eigen::Vector2d s2(mo.start_mm[a0], mo.start_mm[a1]);
  const Eigen::Vector2d e2(target[a0], target[a1]);
  Eigen::Vector2d c2;
  if (const Word* r = word('R')) {
    if (word(kOff0[p]) || word(kOff1[p])) fail(r, "arc with both R and I/J/K; use one form");
    const double R = r->value * s_.unit_mm;
    const Eigen::Vector2d d = e2 - s2;
    const double half = d.norm() / 2.0;
    if (half == 0.0)
      fail(r, "R-form arc with the end point at the start: a full circle needs I/J/K");
    // LinuxCNC (arc_data_r): R may fall short of half the chord by
    // RADIUS_TOLERANCE (0.00005 inch, in program units).
    if ((half - std::abs(R)) / s_.unit_mm > (s_.unit_mm > 1.0 ? 0.00005 : 0.00005 * 25.4))
      fail(r, "arc radius R is smaller than half the chord; fix R or the end point");
    const double h = std::sqrt(std::max(0.0, R * R - half * half));
    const Eigen::Vector2d mid = (s2 + e2) / 2.0;
    const Eigen::Vector2d perp(-d.y() / d.norm(), d.x() / d.norm());
    // Clockwise with positive R: centre to the right of the chord.
    const double side = (mo.clockwise ? -1.0 : 1.0) * (R > 0 ? 1.0 : -1.0);
    c2 = mid + side * h * perp;
  } else {
    const Word* i0 = word(kOff0[p]);
    const Word* i1 = word(kOff1[p]);
    if (!i0 && !i1)
      fail(nullptr, fmt::format("arc needs {} or {} (centre) or R", kOff0[p], kOff1[p]));
    if (s_.arc_absolute) {
      c2 = Eigen::Vector2d((i0 ? i0->value * s_.unit_mm + wo[a0] : mo.start_mm[a0]),
                           (i1 ? i1->value * s_.unit_mm + wo[a1] : mo.start_mm[a1]));
    } else {
      c2 = s2 +
           Eigen::Vector2d(i0 ? i0->value * s_.unit_mm : 0.0, i1 ? i1->value * s_.unit_mm : 0.0);
    }
    const double r_start = (s2 - c2).norm(), r_end = (e2 - c2).norm();
    // LinuxCNC's rule (interp_arc.cc arc_data_ijk, in program units):
    // a radius below RADIUS_TOLERANCE is a zero-radius arc; the radii as
    // linuxcnc_accepts_radii.
    const bool inch = s_.unit_mm > 1.0;
    const double r1 = r_start / s_.unit_mm, r2 = r_end / s_.unit_mm;
    const double zero_radius = inch ? 0.00005 : 0.00005 * 25.4;
    if (r1 < zero_radius || r2 < zero_radius) fail(i0 ? i0 : i1, "arc of zero radius");
    if (!linuxcnc_accepts_radii(r1, r2, inch))
      fail(i0 ? i0 : i1,
           fmt::format("radius to end of arc ({:.4f} mm) differs from radius to start "
                       "({:.4f} mm) by more than LinuxCNC allows; fix the centre or the end point",
                       r_end, r_start));
  }
  mo.center_mm = mo.start_mm;
  mo.center_mm[a0] = c2.x();
  mo.center_mm[a1] = c2.y();
  if (const Word* pw = word('P')) {
    if (pw->value < 1 || pw->value != std::floor(pw->value) || pw->value > kMaxArcTurns)
      fail(pw, fmt::format("P (turns) must be a positive integer up to {}", kMaxArcTurns));
    mo.extra_turns = static_cast<int>(pw->value) - 1;
  }
}

}  // namespace volmap::nc
