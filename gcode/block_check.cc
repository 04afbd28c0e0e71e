#include "gcode/block_check.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>

#include "gcode/g_codes.h"

namespace volmap::nc {

BlockCheck::BlockCheck(const ProgramSetup& setup, const std::string& file, const Block& b,
                       BlockWords& words, State& s, BlockEffect& effect)
    : setup_(setup),
      file_(file),
      b_(b),
      words_(words),
      s_(s),
      effect_(effect),
      g(words.g),
      m(words.m),
      polar_radius(words.polar_radius),
      polar_angle(words.polar_angle),
      polar(words.polar()) {}

void BlockCheck::run() {
  check_polar_words();
  if (fanuc()) fanuc_words();
  if (!common_block()) general_steps();
  if (effect_.has_motion) comp_role();
}

void BlockCheck::check_polar_words() const {
  const Word* x = words_.given_word('X');
  const Word* y = words_.given_word('Y');
  if (polar && (x || y))
    fail(x ? x : y, "X or Y with polar coordinates (@ ^) in one block; use one form or the other");
  // LinuxCNC checks the plane in effect before the block (enhance_block):
  // polar words in G18/G19 are refused, and so is `G17 @..` while G18/G19
  // is active, but `G18 @..` from G17 is read (as X Y).
  if (polar && s_.plane != 0)
    fail(polar_radius ? polar_radius : polar_angle,
         "polar coordinates (@ ^) while G18 or G19 is active; LinuxCNC reads them in G17 only: "
         "select G17 in an earlier block, or use X and Y");
}

bool BlockCheck::common_block() {
  // The block of most programs: axis words (and F) only, no G or M code, in
  // G0 or G1. What the steps below do for it, and nothing else (they would
  // test every modal group in vain): F, the end of a canned-cycle run, the
  // straight move with its checks in the same order.
  constexpr std::uint32_t kAxisLetters = 1u << ('X' - 'A') | 1u << ('Y' - 'A') | 1u << ('Z' - 'A');
  constexpr std::uint32_t kFeedLetter = 1u << ('F' - 'A');
  const std::uint32_t letters = words_.letter_mask;
  if (fanuc() && !s_.group01_given) return false;  // (the general steps refuse it)
  if (!(words_.g_mask == 0 && words_.m_mask == 0 && !polar &&
        (letters & ~(kAxisLetters | kFeedLetter)) == 0 && (letters & kAxisLetters) != 0 &&
        (s_.motion == kG0Rapid || s_.motion == kG1Linear)))
    return false;
  if (const Word* f = words_.given_word('F')) {
    if (f->value < 0) fail(f, "negative feed");
    s_.feed = f->value;
  }
  double value[3] = {};
  unsigned given = 0;
  for (int a = 0; a < 3; ++a)
    if (const Word* w = words_.given_word("XYZ"[a])) {
      value[a] = w->value;
      given |= 1u << a;
    }
  bool known_after = true;
  for (int a = 0; a < 3; ++a)
    known_after = known_after &&
                  (s_.axis_known[static_cast<size_t>(a)] || ((given >> a & 1u) && s_.absolute));
  if (!known_after && s_.motion != kG0Rapid)
    fail(nullptr,
         "a feed move from an unknown position: command X, Y and Z with a rapid (G0) "
         "before the first cutting move, or give `initial_position`");
  if (s_.motion == kG1Linear && s_.feed <= 0.0 && s_.feed_mode != kG93InverseTime)
    fail(nullptr, "G1 with no feed rate; add an F word");
  straight_move(work_offset(), value, given, s_, effect_.motion);
  effect_.has_motion = true;
  return true;
}

void BlockCheck::general_steps() {
  // The general steps read every slot: those no word filled are null.
  words_.null_unfilled();
  // Rotary words are here only where the machine has the axis (step 1).
  const bool any_axis =
      word('X') || word('Y') || word('Z') || polar || word('A') || word('B') || word('C');

  // Step 3 and 4: execute in RS274NGC order.
  feed_tool_and_spindle();
  // What runs before cutter compensation's step in LinuxCNC's order (M
  // codes, the plane) meets it as it was: `G40 M6` and `G40 G18` are refused.
  if (s_.comp_side != 0) refuse_while_compensating(true);
  if (g[kPlane]) s_.plane = (g[kPlane]->code10 - kG17PlaneXY) / 10;
  if (g[kUnits]) s_.unit_mm = g[kUnits]->code10 == kG20Inch ? 25.4 : 1.0;
  if (g[kCutterComp] || s_.comp_side != 0 || word('D')) cutter_comp();
  if (g[kToolLength]) tool_length();
  distance_and_coordinate_modes();
  // Non-modal codes that set state (and use the axis words) before the motion.
  if (const Word* nm = g[kNonModal]) switch (nm->code10) {
      case kG28Home:
      case kG30SecondHome:
      case kG28_1StoreHome:
      case kG30_1StoreSecondHome:
        home(nm->code10);
        break;
      case kG10SetOffsets:
      case kG92AxisOffset:
      case kG52LocalOffset:
      case kG92_1AxisOffsetReset:
      case kG92_2AxisOffsetSuspend:
      case kG92_3AxisOffsetRestore:
        offsets(nm->code10);
        break;
      default:
        break;
    }

  // LinuxCNC asks for Z, R, P and Q only when the block starts a cycle other
  // than the modal one (a G81 restated in G81 keeps the modal values).
  const int motion_before = s_.motion;
  if (g[kMotion]) {
    const int code = g[kMotion]->code10;
    s_.motion = code;
    if (code == kG0Rapid || code == kG1Linear || is_arc(code)) {
      s_.group01 = code;
      s_.group01_given = true;
    }
    // Fanuc: G80 ends the cycle, the group 01 motion goes on.
    if (code == kG80CycleCancel && fanuc()) s_.motion = s_.group01;
    effect_.motion_code = code;
  }
  if (!is_cycle(s_.motion)) s_.cycle_il_known = false;
  const bool motion_here = motion_in_block(any_axis);
  unused_words(motion_here);
  if (motion_here) motion(motion_before);
  if (m[kMStop]) {
    effect_.stop_code = true;
    const int c = m[kMStop]->code10;
    if (c == kM2ProgramEnd || c == kM30ProgramEndRewind) {
      s_.ended = true;
      s_.spindle_turning = false;
    }
  }
}

void BlockCheck::feed_tool_and_spindle() {
  if (g[kFeedMode]) {
    // LinuxCNC (convert_feed_mode): G94 and G95 set the feed rate to zero,
    // G93 keeps it (it needs F in every feed block); F in the block comes
    // after.
    s_.feed_mode = g[kFeedMode]->code10;
    if (s_.feed_mode != kG93InverseTime) s_.feed = 0.0;
  }
  if (const Word* f = word('F')) {
    if (f->value < 0) fail(f, "negative feed");
    s_.feed = f->value;
  }
  if (const Word* t = word('T')) {
    if (t->value < 0 || t->value != std::floor(t->value) || t->value > kMaxToolNumber)
      fail(t, fmt::format("T must be a non-negative integer up to {}", kMaxToolNumber));
    s_.selected_tool = static_cast<int>(t->value);
  }
  if (m[kMTool] && m[kMTool]->code10 == kM6ToolChange) {
    s_.tool = s_.selected_tool;
    s_.tool_from_m61 = false;
    s_.tool_loaded = true;
  }
  if (m[kMTool] && m[kMTool]->code10 == kM61SetToolNumber) s_.tool_from_m61 = s_.tool_loaded = true;
  if (m[kMSpindle]) {
    s_.spindle_turning = m[kMSpindle]->code10 == kM3SpindleClockwise ||
                         m[kMSpindle]->code10 == kM4SpindleCounterClockwise;
    if (s_.spindle_turning) s_.spindle_clockwise = m[kMSpindle]->code10 == kM3SpindleClockwise;
  }
  if (g[kNonModal] && g[kNonModal]->code10 == kG4Dwell && !word('P') && !dwell_time_given_)
    fail(g[kNonModal], fanuc() ? "G04 dwell needs X (seconds) or P (milliseconds)"
                               : "G4 dwell needs a P word (seconds)");
}

void BlockCheck::tool_length() {
  const double offset_before = s_.tool_length_mm;
  const int c = g[kToolLength]->code10;
  if (c == kG49ToolLengthCancel) {
    s_.tool_length_active = false;
    s_.tool_length_mm = 0.0;
  } else if (c == kG43ToolLength) {
    const Word* h = word('H');
    if (h && (h->value < 0 || h->value != std::floor(h->value) || h->value > kMaxToolNumber))
      fail(h, fmt::format("H must be a non-negative integer up to {} (a tool number)",
                          kMaxToolNumber));
    if (!h && s_.tool_from_m61)
      fail(g[kToolLength],
           "G43 without H after M61: which tool's offset applies differs between LinuxCNC's "
           "interpreter (rs274: the tool the last M6 loaded) and a machine (the tool M61 "
           "named); give the tool with H (G43 H<tool>)");
    const int tool = h ? static_cast<int>(h->value) : s_.tool;
    auto it = setup_.tool_length_mm.find(tool);
    if (it == setup_.tool_length_mm.end())
      fail(g[kToolLength], fmt::format("G43 uses tool {}, which the tool table does not list; "
                                       "give its offset with `tool_table`",
                                       tool));
    s_.tool_length_active = true;
    s_.tool_length_mm = it->second;
  } else {  // G43.1: dynamic length from the Z word
    const Word* z = word('Z');
    if (!z) fail(g[kToolLength], "G43.1 needs a Z word (the tool length offset)");
    s_.tool_length_active = true;
    s_.tool_length_mm = z->value * s_.unit_mm;
    consumed_axes_ = true;
    if (word('X') || word('Y') || polar)
      fail(word('X')      ? word('X')
           : word('Y')    ? word('Y')
           : polar_radius ? polar_radius
                          : polar_angle,
           "G43.1 takes only Z here");
  }
  // LinuxCNC: the axes stay, the controlled point (the tip of the tool
  // now compensated) is where they put it: Z moves by minus the change
  // of offset (rs274: after G43 H1 with a -135.11 mm offset at Z50, the
  // current Z is 185.11).
  s_.position_mm.z() -= s_.tool_length_mm - offset_before;
}

void BlockCheck::distance_and_coordinate_modes() {
  if (g[kCoordSystem]) {
    for (int k = 0; k < 9; ++k)
      if (kWorkOffsetCodes[k] == g[kCoordSystem]->code10) s_.coord_system = k;
    s_.update_origin();
  }
  if (g[kDistance]) s_.absolute = g[kDistance]->code10 == kG90Absolute;
  if (g[kArcDistance]) s_.arc_absolute = g[kArcDistance]->code10 == kG90_1ArcCentreAbsolute;
  if (g[kReturnMode]) {
    s_.g98 = g[kReturnMode]->code10 == kG98ReturnToInitialLevel;
    s_.return_mode_given = true;
  }
  g53_ = g[kNonModal] && g[kNonModal]->code10 == kG53MachineCoordinates;
  effect_.g53 = g53_;
  if (g53_ && !s_.absolute) fail(g[kNonModal], "G53 needs absolute mode (G90)");
  // Fanuc: G53 positions at rapid traverse whatever group 01 holds; a
  // motion code beside it is refused (which one moves is not written).
  if (g53_ && fanuc() && g[kMotion] && g[kMotion]->code10 != kG0Rapid)
    fail(g[kMotion],
         "a motion code other than G00 beside G53; a Fanuc control positions G53 at "
         "rapid traverse: split the block");
  if (g53_ && polar)
    fail(polar_radius ? polar_radius : polar_angle,
         "polar coordinates (@ ^) with G53; use X and Y");
}

bool BlockCheck::motion_in_block(bool any_axis) {
  // A G2/G3 with centre words but no axis words is a full circle (LinuxCNC).
  static constexpr char kOffsetLetters[3][2] = {{'I', 'J'}, {'K', 'I'}, {'J', 'K'}};
  const int arc_plane = g[kPlane] ? (g[kPlane]->code10 - kG17PlaneXY) / 10 : s_.plane;
  const int arc_mode = g[kMotion] ? g[kMotion]->code10 : s_.motion;
  const bool full_circle =
      !any_axis && is_arc(arc_mode) &&
      (word(kOffsetLetters[arc_plane][0]) || word(kOffsetLetters[arc_plane][1]));
  // A tool-vector program turns the tool with I J K alone.
  const bool tool_axis_only =
      setup_.tool_axis_words && !is_arc(arc_mode) && (word('I') || word('J') || word('K'));
  const bool motion_here = (any_axis && !consumed_axes_) || full_circle || tool_axis_only ||
                           (g[kMotion] && is_cycle(g[kMotion]->code10));
  if (fanuc() && motion_here && !g[kMotion] && !s_.group01_given && !is_cycle(s_.motion) && !g53_)
    fail(any_axis ? (word('X')   ? word('X')
                     : word('Y') ? word('Y')
                                 : word('Z'))
                  : nullptr,
         "axis words before any G00, G01, G02 or G03: a Fanuc control starts in G00 or G01 as "
         "its parameter 3402#0 says, which the program does not; give the motion code");
  if (motion_here && g[kMotion] && g[kMotion]->code10 == kG80CycleCancel)
    fail(g[kMotion], "axis words with G80; remove them or use G0/G1");
  if (g53_ && motion_here && s_.motion != kG0Rapid && s_.motion != kG1Linear)
    fail(g[kNonModal], "G53 works with G0 or G1 only");
  if (motion_here && s_.motion == kG80CycleCancel && !g[kMotion])
    fail(any_axis ? (word('X')   ? word('X')
                     : word('Y') ? word('Y')
                                 : word('Z'))
                  : nullptr,
         "axis words without a motion mode (G80 active); add G0 or G1");
  // (G10's R is its own: a rotation with L2, a tool's radius with L1.)
  const bool g10 = g[kNonModal] && g[kNonModal]->code10 == kG10SetOffsets;
  if (!motion_here && (word('I') || word('J') || word('K') || (word('R') && !g10)) &&
      !is_cycle(s_.motion))
    fail(word('I')   ? word('I')
         : word('J') ? word('J')
         : word('K') ? word('K')
                     : word('R'),
         "arc words without axis words");
  if (g[kMotion] && is_arc(g[kMotion]->code10) && !motion_here)
    fail(g[kMotion],
         "G2/G3 with neither axis words nor a centre (I J K) or R; LinuxCNC refuses it: "
         "give the arc's end and centre, or select the mode in the block of the first arc");
  return motion_here;
}

void BlockCheck::unused_words(bool motion_here) {
  // A word no code of the block uses: LinuxCNC refuses the block
  // (interp_check.cc, check_other_codes, against the motion the block will
  // make), so a program that has one is not a LinuxCNC program, and its
  // post would be refused by the controller. M codes that read P Q L R
  // (spindle orientation M19, overrides M50-M53, digital and analog I/O
  // M62-M68, user M codes M100-M199) exempt the block, as in LinuxCNC.
  const int motion_to_be = g[kMotion] ? g[kMotion]->code10 : (motion_here ? s_.motion : -1);
  const bool arc = is_arc(motion_to_be);
  const bool cycle = motion_to_be >= 0 && is_cycle(motion_to_be);
  bool m_reads_words = false;
  for (const Word& w : b_.words)
    if (w.letter == 'M') {
      const int c = w.code10;
      m_reads_words = m_reads_words || c == kM19SpindleOrient ||
                      (c >= kM50FeedOverride && c <= kM53FeedStop) ||
                      (c >= kM61SetToolNumber && c <= kM68AnalogOutput) ||
                      (c >= kM100FirstUserCode && c <= kM199LastUserCode);
    }
  const bool g4 = g[kNonModal] && g[kNonModal]->code10 == kG4Dwell;
  const bool g64 = g[kPathControl] && g[kPathControl]->code10 == kG64Blending;
  const bool g10 = g[kNonModal] && g[kNonModal]->code10 == kG10SetOffsets;  // L P R
  const auto unused = [&](char L, bool used, const char* users) {
    if (const Word* w = word(L); w && !used)
      fail(w, fmt::format("{} word with no {} to use it; LinuxCNC refuses the block: remove it", L,
                          users));
  };
  if (m_reads_words) return;
  const bool straight = motion_to_be == kG0Rapid || motion_to_be == kG1Linear;
  // (Fanuc: K of a canned cycle is its repeats, canned_cycles.cc.)
  const bool tap = motion_to_be == kG33_1RigidTap;  // K the pitch, I the return's speed
  for (char L : {'I', 'J', 'K'})
    unused(L,
           arc || (tap && L != 'J') || (setup_.tool_axis_words && straight) ||
               (L == 'K' && cycle && fanuc()),
           setup_.tool_axis_words ? "G0, G1 (tool axis), G2 or G3" : "G2 or G3");
  unused('R', arc || cycle || g10, "G2, G3, G10 or canned cycle");
  // LinuxCNC's L check knows G73 and G81-G89, not G74: an L on a G74
  // block is refused there (and here).
  unused('L', (cycle && motion_to_be != kG74LeftHandTap) || g10,
         "G10 or canned cycle (G74 takes none)");
  unused('P',
         g4 || g64 || g10 || arc || motion_to_be == kG82DrillDwell ||
             motion_to_be == kG86BoreSpindleStop || motion_to_be == kG89BoreDwell ||
             motion_to_be == kG84RightHandTap || motion_to_be == kG74LeftHandTap,
         "G2, G3, G4, G10, G64, G74, G82, G84, G86 or G89");
  unused('Q', g64 || motion_to_be == kG73PeckDrillChipBreak || motion_to_be == kG83PeckDrill,
         "G64, G73 or G83");
}

}  // namespace volmap::nc
