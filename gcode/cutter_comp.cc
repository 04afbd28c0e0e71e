// Cutter radius compensation (G40, G41, G42, G41.1, G42.1) as the
// interpreter reads it: the side and radius the controller will offset the
// programmed path by, the D word's rules, what may not happen while it is
// on, and each motion's part in it (CompRole). The post keeps the codes and
// corrects the programmed contour (postproc/three_axis/cutter_comp.cc,
// docs/post.md "Cutter compensation").
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "gcode/block_check.h"
#include "gcode/g_codes.h"
#include "gcode/nc_path.h"

namespace volmap::nc {

void BlockCheck::cutter_comp() {
  const Word* d = word('D');
  const Word* code = g[kCutterComp];
  const bool on_before = s_.comp_side != 0;
  if (fanuc() && code && code->code10 != kG40CutterCompOff)
    fail(code,
         "cutter compensation in a Fanuc program: how the control starts it and goes round "
         "corners depends on its parameters (5003 start-up type, 5008 interference check, "
         "5010 vector omission limit), which an offline post cannot know; output the tool "
         "centre path from CAM (G40)");
  if (d && (!code || code->code10 == kG40CutterCompOff))
    fail(d, fanuc() ? "D (the cutter compensation offset) without G41 or G42; give it in the "
                      "block of G41/G42"
                    : "D word with no G41, G42, G41.1 or G42.1 to use it; LinuxCNC refuses the "
                      "block: remove it");
  // (What runs before this step was checked in general_steps; what runs
  // after meets the compensation as the block leaves it: `G40 G55` is read.)
  if (code && code->code10 != kG40CutterCompOff) turn_compensation_on(code, d, on_before);
  if (code && code->code10 == kG40CutterCompOff) {
    // The next move leaves the offset path, if the compensation moved.
    s_.comp_exit_pending =
        (on_before && !s_.comp_entry_pending && s_.comp_radius_mm > 0) || s_.comp_exit_pending;
    s_.comp_arc_not_allowed = s_.comp_arc_not_allowed || s_.comp_exit_pending;
    s_.comp_side = 0;
    s_.comp_entry_pending = false;
  }
  if (s_.comp_side != 0) refuse_while_compensating(false);
}

void BlockCheck::turn_compensation_on(const Word* code, const Word* d, bool on_before) {
  if (s_.plane != 0)
    fail(code,
         "cutter compensation in G18 or G19: volmap reads it in the XY plane (G17) only; "
         "output the tool centre path from CAM");
  if (on_before)
    fail(code,
         "cutter compensation is on already; the controller refuses a second G41/G42 "
         "(LinuxCNC: cannot turn cutter radius comp on when on): give G40 first");
  const bool dynamic =
      code->code10 == kG41_1DynamicCutterCompLeft || code->code10 == kG42_1DynamicCutterCompRight;
  double diameter_mm = 0.0;
  if (dynamic) {
    if (fanuc())
      fail(code,
           "G41.1/G42.1 is normal direction control on a Fanuc control, not cutter "
           "compensation; it is not supported");
    if (!d) fail(code, "G41.1/G42.1 needs D (the tool's diameter)");
    if (const Word* l = word('L'))
      fail(l,
           "L (a lathe tool's orientation) with G41.1/G42.1 needs G18; volmap reads cutter "
           "compensation in G17 only");
    diameter_mm = d->value * s_.unit_mm;
  } else {
    diameter_mm = comp_diameter_mm(code, d);
  }
  const bool left =
      code->code10 == kG41CutterCompLeft || code->code10 == kG41_1DynamicCutterCompLeft;
  // LinuxCNC: a negative diameter switches the side and keeps the size.
  s_.comp_side = (left != (diameter_mm < 0)) ? 1 : 2;
  s_.comp_radius_mm = std::abs(diameter_mm) / 2;
  s_.comp_entry_pending = true;
  s_.comp_exit_pending = false;
}

double BlockCheck::comp_diameter_mm(const Word* code, const Word* d) const {
  int tool = 0;
  if (d) {
    // LinuxCNC: a D within 1e-4 of a whole number is that number.
    const double nearest = std::floor(d->value + 0.5);
    if (std::abs(d->value - nearest) >= 1e-4 || nearest < 0 || nearest > kMaxToolNumber)
      fail(d, fanuc() ? "D must be an offset number (a whole number, 0 or more)"
                      : "G41/G42 requires D to be a whole number, 0 or more (a tool number)");
    tool = static_cast<int>(nearest);
  }
  if (tool == 0) {  // no D, or D0: the tool in the spindle (LinuxCNC's pocket 0)
    if (!s_.tool_loaded || s_.tool_from_m61)
      fail(d ? d : code,
           "G41/G42 without D (or with D0) uses the diameter of the tool in the spindle, which "
           "this program has not loaded with M6 here; give D (the tool number)");
    tool = s_.tool;
  }
  if (setup_.tool_orientation.contains(tool))
    fail(d ? d : code, fmt::format("G41/G42 with lathe tool {} (orientation {} in the tool table), "
                                   "but plane is not G18; LinuxCNC refuses it",
                                   tool, setup_.tool_orientation.at(tool)));
  const auto it = setup_.tool_diameter_mm.find(tool);
  if (it == setup_.tool_diameter_mm.end())
    fail(d ? d : code,
         fmt::format("G41/G42 uses {} {}, whose diameter the tool table does not give; give "
                     "it with `tool_table` (the row T{} with a D column)",
                     fanuc() ? "offset" : "tool", tool, tool));
  return it->second;
}

void BlockCheck::refuse_while_compensating(bool before_step) const {
  // What LinuxCNC's interpreter refuses with cutter compensation on (each
  // checked with rs274), and what volmap does not read under it (a change
  // of units, offsets that rs274 2.9 ignores there: G92.1 G92.2 G92.3).
  const char* what = nullptr;
  const Word* at = nullptr;
  auto refuse = [&](const Word* w, const char* text) {
    if (!what && w) what = text, at = w;
  };
  if (before_step) {
    if (g[kPlane] && (g[kPlane]->code10 - kG17PlaneXY) / 10 != s_.plane)
      refuse(g[kPlane], "a change of plane");
    refuse(m[kMTool] && m[kMTool]->code10 == kM6ToolChange ? m[kMTool] : nullptr,
           "a tool change (M6)");
    refuse(g[kUnits], "a change of units");
    for (const Word& w : b_.words)
      if (w.letter == 'M' && ((w.code10 >= kM48OverridesOn && w.code10 <= kM53FeedStop) ||
                              (w.code10 >= kM62FirstMotionOutput && w.code10 <= kM68AnalogOutput)))
        refuse(&w, "an override or I/O code (M48-M53, M62-M68)");
  } else {
    if (const Word* nm = g[kNonModal]; nm && nm->code10 != kG4Dwell)
      refuse(nm->code10 == kG53MachineCoordinates && s_.comp_radius_mm == 0 ? nullptr : nm,
             nm->code10 == kG53MachineCoordinates ? "G53"
             : nm->code10 == kG28Home || nm->code10 == kG30SecondHome ||
                     nm->code10 == kG28_1StoreHome || nm->code10 == kG30_1StoreSecondHome
                 ? "G28/G30"
                 : "a change of offsets (G10, G52, G92)");
    refuse(g[kCoordSystem], "a coordinate system code (G54-G59.3)");
    refuse(g[kToolLength], "a change of tool length offset (G43, G49)");
    refuse(g[kPathControl], "a change of path control (G61, G64)");
    refuse(g[kReturnMode], "a change of retract mode (G98, G99)");
    if (g[kMotion] && is_cycle(g[kMotion]->code10)) refuse(g[kMotion], "a canned cycle");
    if (!g[kMotion] && is_cycle(s_.motion) && (word('X') || word('Y') || word('Z')))
      refuse(word('X') ? word('X') : word('Y') ? word('Y') : word('Z'), "a canned cycle");
  }
  if (what)
    fail(at, fmt::format("{} while cutter compensation is on; the controller refuses it or "
                         "volmap does not read it there: give G40 first",
                         what));
}

void BlockCheck::comp_role() {
  const Motion& mo = effect_.motion;
  if (mo.kind == MotionKind::kCycle) return;  // (refused while compensating)
  const bool arc = mo.kind == MotionKind::kArc;
  const double r = s_.comp_radius_mm;
  CompRole role = CompRole::kNone;
  if (s_.comp_side != 0 && r > 0) {
    role = s_.comp_entry_pending ? CompRole::kEntry : CompRole::kCompensated;
    s_.comp_entry_pending = false;
  } else if (s_.comp_exit_pending) {
    role = CompRole::kExit;
    s_.comp_exit_pending = false;
  }
  if (arc && s_.comp_arc_not_allowed)
    fail(g[kMotion],
         "the move just after exiting cutter compensation mode must be straight, not an arc "
         "(LinuxCNC refuses it); add a straight move after G40");
  if (mo.kind != MotionKind::kArc && mo.kind != MotionKind::kCycle)
    s_.comp_arc_not_allowed = false;  // G0 G1 G33.1 (a cycle leaves it: rs274)
  if (role == CompRole::kExit && mo.kind == MotionKind::kTap)
    fail(g[kMotion],
         "a rigid tap (G33.1) as the move after G40: LinuxCNC taps from the offset "
         "point, across; add a straight move after G40");
  if (role == CompRole::kEntry) {
    // LinuxCNC: the tool goes from where it stands to the offset of the
    // end, which must be further than the radius (a Z move alone too).
    const double d = std::hypot(mo.end_mm.x() - mo.start_mm.x(), mo.end_mm.y() - mo.start_mm.y());
    if (d <= r)
      fail(g[kMotion],
           fmt::format("{} of cutter compensation entry move is not greater than the tool radius "
                       "({:g} mm, the move {:g} mm; LinuxCNC refuses it): start further away",
                       arc ? "Radius" : "Length", r, d));
  }
  if (arc && role != CompRole::kNone && role != CompRole::kExit) {
    // The tool inside the arc (G41 with G3, G42 with G2) needs a larger arc.
    const bool inside = (s_.comp_side == 1) != mo.clockwise;
    const double radius =
        std::hypot(mo.end_mm.x() - mo.center_mm.x(), mo.end_mm.y() - mo.center_mm.y());
    if (inside && radius <= r)
      fail(g[kMotion], fmt::format("tool radius not less than arc radius with comp (tool {:g} "
                                   "mm, arc {:g} mm; LinuxCNC refuses it)",
                                   r, radius));
  }
  effect_.comp_role = role;
  comp_side_reach(role);
}

void BlockCheck::comp_side_reach(CompRole role) {
  // LinuxCNC cuts a straight side back at an inside corner (turn above
  // 0.05 rad) by r tan(turn / 2) and refuses a side its two cuts reverse
  // ("Straight feed in concave corner cannot be reached by the tool without
  // gouging"). Arcs' corners and the entry's are not followed here.
  const Motion& mo = effect_.motion;
  const bool line = mo.kind != MotionKind::kArc;  // (a tap is refused under compensation)
  const Eigen::Vector2d d(mo.end_mm.x() - mo.start_mm.x(), mo.end_mm.y() - mo.start_mm.y());
  if (role != CompRole::kCompensated) {
    s_.comp_side_dir.setZero();
    return;
  }
  if (!line) {  // (a side into an arc is cut to the offset arc: not followed)
    s_.comp_side_dir.setZero();
    return;
  }
  if (d.isZero(0.0)) return;  // a move along Z: the side stays the last one
  const Eigen::Vector2d t_out = xy_tangent(mo, false);
  double trim = 0.0, rate = 0.0;
  if (!s_.comp_side_dir.isZero(0.0)) {
    bool inside = false;
    const double turn = xy_turn_rad(s_.comp_side_dir, t_out, s_.comp_side, inside);
    if (inside && turn > kLinuxCncCornerTurnRad) {
      const double r = s_.comp_radius_mm, c = std::cos(turn / 2);
      trim = r * std::tan(turn / 2);
      rate = r / (2 * c * c);
      const double slack = s_.comp_side_len_mm - s_.comp_side_trim_mm - trim;
      if (slack < 0)
        fail(g[kMotion],
             fmt::format("straight feed in concave corner cannot be reached by the tool without "
                         "gouging (LinuxCNC refuses it): the side before this corner is {:g} mm, "
                         "the tool needs {:g} mm of it",
                         s_.comp_side_len_mm, s_.comp_side_trim_mm + trim));
      effect_.comp_slack_mm = slack;
      effect_.comp_slack_len_mm = s_.comp_side_len_mm;
      effect_.comp_slack_rate = s_.comp_side_trim_rate + rate;
    }
  }
  s_.comp_side_dir = t_out;
  s_.comp_side_len_mm = d.norm();
  s_.comp_side_trim_mm = trim;
  s_.comp_side_trim_rate = rate;
}

}  // namespace volmap::nc
