// Canned cycles (G73 G74 G81 G82 G83 G84 G85 G86 G89) as LinuxCNC reads them: the
// checks of a cycle block, its modal R Z Q, and the holes it drills (L
// repeats, G90 or G91, polar coordinates).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/common/units.h"
#include "gcode/block_check.h"
#include "gcode/g_codes.h"

namespace volmap::nc {
namespace {

constexpr double kMaxCycleRepeats = 10000;  // L of canned cycles

}  // namespace

int BlockCheck::cycle_words(int motion_before) {
  const int mode = s_.motion;
  const bool peck = mode == kG83PeckDrill || mode == kG73PeckDrillChipBreak;
  if (s_.plane != 0)
    fail(nullptr, "canned cycles in the G18 or G19 plane are not supported; use G17");
  const Word* l = word('L');
  if (fanuc()) {
    // Fanuc 0i: K repeats (L on Haas and older controls); K0/L0 stores the
    // cycle's data and drills nothing. The return level before any G98 or
    // G99 is the control's power-on setting, unknown here.
    if (const Word* k = word('K')) {
      if (l) fail(k, "K and L in one cycle block; both give the repeats on a Fanuc control");
      l = k;
    }
    if (l && l->value == 0)
      fail(l, fmt::format("{}0: the control stores the cycle and drills no hole here, which "
                          "volmap does not follow; give the first hole's block without {}0",
                          l->letter, l->letter));
    if (!s_.return_mode_given)
      fail(g[kMotion] ? g[kMotion] : nullptr,
           "a canned cycle before any G98 or G99: a Fanuc control returns to the level its "
           "power-on setting gives, which the program does not say; add G98 (initial level) "
           "or G99 (R level) to the cycle's first block");
  }
  if (l && (l->value < 1 || l->value != std::floor(l->value) || l->value > kMaxCycleRepeats))
    fail(l, fmt::format("{} (repeats) must be a positive integer up to {}", l->letter,
                        kMaxCycleRepeats));
  const int repeats = l ? static_cast<int>(l->value) : 1;
  const bool starts = mode != motion_before;
  if (const Word* z = word('Z'))
    s_.cycle_z = z->value;
  else if (starts)
    fail(g[kMotion], "canned cycle needs a Z word (hole bottom)");
  if (const Word* r = word('R'))
    s_.cycle_r = r->value;
  else if (starts)
    fail(g[kMotion], "canned cycle needs an R word (retract plane)");
  if (peck && !word('Q') && starts) fail(g[kMotion], "peck drilling needs a Q word (peck depth)");
  // LinuxCNC (convert_cycle_g73/g83): "Negative or zero q value used".
  if (const Word* q = word('Q'); q && peck && q->value <= 0)
    fail(q, "the peck depth Q must be positive (LinuxCNC refuses a negative or zero Q)");
  if (const Word* q = word('Q'); q && peck) s_.cycle_q = q->value;
  if ((mode == kG82DrillDwell || mode == kG86BoreSpindleStop || mode == kG89BoreDwell) &&
      !word('P') && starts)
    fail(g[kMotion], "dwell cycle needs a P word (seconds)");
  if (mode == kG86BoreSpindleStop && !s_.spindle_turning)
    fail(g[kMotion] ? g[kMotion] : nullptr,
         "G86 with the spindle stopped; LinuxCNC refuses it (\"Spindle not turning in g86\"): "
         "start it "
         "with M3 or M4 first");
  // LinuxCNC (convert_cycle_g84, _g74): a tap needs the spindle turning
  // its way ("Spindle not turning in G84", "Spindle turning
  // counterclockwise in G84").
  if (mode == kG84RightHandTap || mode == kG74LeftHandTap) {
    const bool right = mode == kG84RightHandTap;
    if (!s_.spindle_turning)
      fail(g[kMotion], fmt::format("G{} with the spindle stopped; LinuxCNC refuses it (\"Spindle "
                                   "not turning in G{}\"): start it with {} first",
                                   right ? 84 : 74, right ? 84 : 74, right ? "M3" : "M4"));
    if (s_.spindle_clockwise != right)
      fail(g[kMotion],
           fmt::format("G{} with the spindle turning {}; LinuxCNC refuses it: a {}-hand tap "
                       "needs {}",
                       right ? 84 : 74, right ? "counterclockwise" : "clockwise",
                       right ? "right" : "left", right ? "M3" : "M4"));
  }
  // LinuxCNC (convert_cycle) refuses cycles under G93.
  if (s_.feed_mode == kG93InverseTime)
    fail(g[kMotion], "canned cycle under inverse time feed (G93); LinuxCNC refuses it: use G94");
  if (s_.feed <= 0.0) fail(nullptr, "canned cycle with no feed rate; add an F word");
  return repeats;
}

Eigen::Vector3d BlockCheck::cycle(Motion& mo, int motion_before, double at_x, double at_y,
                                  bool xy_known, const Eigen::Vector3d& target) {
  const int repeats = cycle_words(motion_before);
  const Eigen::Vector3d& wo = work_offset();
  const double unit = s_.unit_mm;
  mo.kind = MotionKind::kCycle;
  // LinuxCNC (interp_cycles.cc, convert_cycle_xy). G90: R and Z are
  // levels, the hole is at X Y (or @ ^ from the origin). G91: R is
  // above the initial level (State::cycle_il_mm), Z below R, and X Y (@ ^) are
  // increments applied once per repeat (L), so L holes go in a row (or
  // round a circle); under G90 the L repeats drill the same hole.
  if (!s_.cycle_il_known) {
    s_.cycle_il_known = true;
    s_.cycle_il_mm = s_.position_mm.z();
  }
  const double initial = s_.cycle_il_mm;
  const double r_mm = s_.absolute ? s_.cycle_r * unit + wo[2] : initial + s_.cycle_r * unit;
  const double bottom_mm = s_.absolute ? s_.cycle_z * unit + wo[2] : r_mm + s_.cycle_z * unit;
  if (bottom_mm > r_mm) fail(nullptr, "canned cycle with the hole bottom (Z) above the R plane");
  double aa = at_x, bb = at_y;
  double aa_step = 0, bb_step = 0, radius_step = 0, angle_step_rad = 0;
  if (s_.absolute) {
    if (polar) {
      const double radius = polar_radius ? polar_radius->value : std::hypot(bb, aa);
      const double theta =
          polar_angle ? polar_angle->value * units::kRadPerDeg : std::atan2(bb, aa);
      aa = radius * std::cos(theta);
      bb = radius * std::sin(theta);
    } else {
      aa = (target.x() - wo.x()) / unit;
      bb = (target.y() - wo.y()) / unit;
    }
  } else {
    if (const Word* x = word('X')) aa_step = x->value;
    if (const Word* y = word('Y')) bb_step = y->value;
    if (polar_radius) radius_step = polar_radius->value;
    if (polar_angle) angle_step_rad = polar_angle->value * units::kRadPerDeg;
  }
  if (polar && !xy_known)
    fail(polar_radius ? polar_radius : polar_angle,
         "polar coordinates from an unknown position: command X and Y first (or give "
         "`initial_position`)");
  mo.r_mm = r_mm;
  mo.clear_mm = s_.g98 ? std::max(initial, r_mm) : r_mm;
  Eigen::Vector3d at = s_.position_mm;
  for (int k = 0; k < repeats; ++k) {
    aa += aa_step;
    bb += bb_step;
    if ((radius_step != 0 || angle_step_rad != 0) && aa == 0 && bb == 0)
      fail(polar_radius ? polar_radius : polar_angle,
           "incremental polar coordinates (G91) at the program origin are indeterminate; move "
           "off it first");
    if (radius_step != 0) {
      const double theta = std::atan2(bb, aa), radius = std::hypot(bb, aa) + radius_step;
      aa = radius * std::cos(theta);
      bb = radius * std::sin(theta);
    }
    if (angle_step_rad != 0) {
      const double theta = std::atan2(bb, aa) + angle_step_rad, radius = std::hypot(bb, aa);
      aa = radius * std::cos(theta);
      bb = radius * std::sin(theta);
    }
    Motion& hole = k == 0 ? mo : effect_.more_holes.emplace_back(mo);
    hole.start_mm = at;
    hole.end_mm = Eigen::Vector3d(aa * unit + wo.x(), bb * unit + wo.y(), bottom_mm);
    at = Eigen::Vector3d(hole.end_mm.x(), hole.end_mm.y(), mo.clear_mm);
  }
  return at;
}

}  // namespace volmap::nc
