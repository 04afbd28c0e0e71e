#include "gcode/nc_interpreter.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <optional>
#include <sstream>

#include "core/common/input_error.h"

namespace volmap::nc {
namespace {

// Bounds of integer words (beyond them a number would overflow int, or a
// helix would need more pieces than memory holds).
constexpr double kMaxToolNumber = 99999;    // T, H and tool table numbers
constexpr double kMaxArcTurns = 1000;       // P of G2/G3
constexpr double kMaxCycleRepeats = 10000;  // L of canned cycles
constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

// Modal groups of G codes (code x 10), RS274NGC / LinuxCNC numbering.
enum GGroup {
  kNonModal = 0,
  kMotion = 1,
  kPlane = 2,
  kDistance = 3,
  kArcDistance = 4,
  kFeedMode = 5,
  kUnits = 6,
  kCutterComp = 7,
  kToolLength = 8,
  kReturnMode = 10,
  kCoordSystem = 12,
  kPathControl = 13,
  kSpindleMode = 14,
  kGroupCount = 16
};

// Returns the group of a supported G code, or -1 with `why` set for one
// volmap refuses.
int g_group(int code10, const char** why) {
  switch (code10) {
    case 0:
    case 10:
    case 20:
    case 30:
    case 730:
    case 800:
    case 810:
    case 820:
    case 830:
    case 850:
    case 860:
    case 890:
      return kMotion;
    case 170:
    case 180:
    case 190:
      return kPlane;
    case 900:
    case 910:
      return kDistance;
    case 901:
    case 911:
      return kArcDistance;
    case 930:
    case 940:
    case 950:
      return kFeedMode;
    case 200:
    case 210:
      return kUnits;
    case 400:
      return kCutterComp;
    case 430:
    case 431:
    case 490:
      return kToolLength;
    case 980:
    case 990:
      return kReturnMode;
    case 540:
    case 550:
    case 560:
    case 570:
    case 580:
    case 590:
    case 591:
    case 592:
    case 593:
      return kCoordSystem;
    case 610:
    case 611:
    case 640:
      return kPathControl;
    case 960:
    case 970:
      return kSpindleMode;
    case 40:
    case 530:
      return kNonModal;
    case 410:
    case 420:
    case 411:
    case 421:
      *why =
          "cutter radius compensation (G41/G42) is not supported: the post-processor "
          "needs the tool centre path; output it from CAM with G40";
      return -1;
    case 280:
    case 281:
    case 300:
    case 301:
      *why =
          "G28/G30 move to stored positions the program does not state; replace them "
          "with explicit G53 moves";
      return -1;
    case 920:
    case 921:
    case 922:
    case 923:
    case 520:
      *why =
          "G92/G52 coordinate offsets are not supported; use G54-G59.3 work offsets "
          "(--work-offset or --var-file)";
      return -1;
    case 100:
      *why =
          "G10 (setting offsets or tools from the program) is not supported; give them "
          "with --var-file / --tool-table";
      return -1;
    case 382:
    case 383:
    case 384:
    case 385:
      *why = "probing moves (G38.x) cannot be compensated; run them uncompensated";
      return -1;
    case 330:
    case 331:
    case 760:
    case 840:
    case 740:
    case 870:
    case 880:
      *why =
          "threading and tapping cycles (G33, G76, G84, G74) and G87/G88 are not "
          "supported; compensation would break spindle synchronisation";
      return -1;
    case 50:
    case 51:
    case 52:
    case 70:
    case 80:
    case 150:
    case 160:
    case 680:
    case 690:
      *why = "splines, lathe diameter mode, polar and rotated coordinates are not supported";
      return -1;
    default:
      *why = "unknown G code";
      return -1;
  }
}

enum MGroup {
  kMStop = 0,
  kMTool = 1,
  kMSpindle = 2,
  kMCoolant = 3,
  kMOverride = 4,
  kMOther = 5,
  kMGroupCount = 6
};

int m_group(int code10, const char** why) {
  if (code10 % 10 != 0) {
    *why = "M codes have no decimals";
    return -1;
  }
  const int m = code10 / 10;
  switch (m) {
    case 0:
    case 1:
    case 2:
    case 30:
    case 60:
      return kMStop;
    case 6:
      return kMTool;
    case 3:
    case 4:
    case 5:
    case 19:
      return kMSpindle;
    case 7:
    case 8:
    case 9:
      return kMCoolant;
    case 48:
    case 49:
    case 50:
    case 51:
    case 52:
    case 53:
      return kMOverride;
    case 98:
    case 99:
      *why = "M98/M99 subroutine calls are not supported; expand them in CAM";
      return -1;
    default:
      if ((m >= 61 && m <= 68) || (m >= 70 && m <= 73) || (m >= 100 && m <= 199)) return kMOther;
      *why = "unknown M code";
      return -1;
  }
}

// Letters whose words need nothing but "not twice in a block": all of A-Z
// except G and M (modal groups), N (may repeat), the axes the three-axis
// post refuses (A B C U V W) and D E (refused); '@' '^' are handled apart.
constexpr std::array<bool, 256> kPlainLetter = [] {
  std::array<bool, 256> t{};
  for (char c = 'A'; c <= 'Z'; ++c) t[static_cast<unsigned char>(c)] = true;
  for (char c : {'G', 'M', 'N', 'A', 'B', 'C', 'U', 'V', 'W', 'D', 'E'})
    t[static_cast<unsigned char>(c)] = false;
  return t;
}();

bool is_cycle(int motion) { return motion == 730 || (motion >= 810 && motion <= 890); }

}  // namespace

Interpreter::Interpreter(ProgramSetup setup, std::string file)
    : setup_(std::move(setup)), file_(std::move(file)) {
  if (setup_.initial_position_mm) {
    s_.position_mm = *setup_.initial_position_mm;
    s_.position_known = true;
    s_.axis_known = {true, true, true};
  }
}

void Interpreter::fail(const Block& b, const Word* w, const std::string& msg) const {
  throw InputError(file_, b.line, w ? static_cast<int>(w->begin) + 1 : 0, msg);
}

void Interpreter::straight_move(const double (&value)[3], unsigned given, Motion& mo) {
  s_.cycle_il_known = false;  // not a cycle: the run of cycle blocks ends
  const Eigen::Vector3d& wo = work_offset();
  Eigen::Vector3d target = s_.position_mm;
  for (int a = 0; a < 3; ++a) {
    if (!(given >> a & 1u)) continue;
    if (s_.absolute)
      target[a] = value[a] * s_.unit_mm + wo[a];
    else
      target[a] = s_.position_mm[a] + value[a] * s_.unit_mm;
  }
  mo.kind = s_.motion == 0 ? MotionKind::kRapid : MotionKind::kLinear;
  mo.start_mm = s_.position_mm;
  mo.end_mm = target;
  mo.feed = s_.feed;
  s_.position_mm = target;
  for (int a = 0; a < 3; ++a)
    if ((given >> a & 1u) && s_.absolute) s_.axis_known[static_cast<size_t>(a)] = true;
  s_.position_known = s_.axis_known[0] && s_.axis_known[1] && s_.axis_known[2];
}

bool Interpreter::execute_linear_axes(const double (&value)[3], unsigned given, Motion& motion) {
  // execute()'s short path, less what cannot fail here: no F word, no
  // other letter, the position known, G1 with a feed rate.
  if (s_.ended || s_.motion != 10 || !s_.position_known ||
      (s_.feed <= 0.0 && s_.feed_mode != 930) || given == 0 || given > 7)
    return false;
  straight_move(value, given, motion);
  return true;
}

void Interpreter::execute(const Block& b, BlockEffect& effect) {
  // Every field as BlockEffect{} has it, without building and moving a
  // whole one (more_holes keeps its storage for the next cycle block).
  effect.has_motion = false;
  effect.motion = Motion{};
  effect.g53 = false;
  effect.stop_code = false;
  effect.motion_code = -1;
  effect.more_holes.clear();
  if (b.percent || b.words.empty()) return;
  if (s_.ended) return;  // after M2/M30 nothing executes (LinuxCNC ignores the rest)

  // Step 1 and 2: every word known; one G code per modal group, one M code
  // per group; no letter twice (except G and M).
  // The slots are filled as the words come; only those a word filled are
  // valid (the masks say which) until the general steps below null the
  // others: clearing all 48 slots first would cost the common block more
  // than everything else the interpreter does for it.
  std::array<const Word*, kGroupCount> g;
  std::array<const Word*, kMGroupCount> m;
  std::array<const Word*, 26> letter;
  const Word* polar_radius = nullptr;  // @: LinuxCNC polar coordinates in the XY plane
  const Word* polar_angle = nullptr;   // ^: degrees, counter-clockwise from +X
  unsigned g_mask = 0, m_mask = 0;
  std::uint32_t letter_mask = 0;  // bit L - 'A' for each letter of letter[] set
  for (const Word& w : b.words) {
    // Most words are plain letters (X Y Z F ...): one test sends them on.
    if (kPlainLetter[static_cast<unsigned char>(w.letter)]) {
      const size_t L = static_cast<size_t>(w.letter - 'A');
      if (letter_mask & (1u << L))
        fail(b, &w, fmt::format("word {} appears twice in one block", w.letter));
      letter[L] = &w;
      letter_mask |= 1u << L;
      continue;
    }
    if (w.letter == 'G') {
      const char* why = nullptr;
      const int grp = w.code10 < 0 ? -1 : g_group(w.code10, &why);
      if (grp < 0)
        fail(
            b, &w,
            fmt::format("G{} is not supported: {}", b.text.substr(w.begin + 1, w.end - w.begin - 1),
                        why ? why : "unknown G code"));
      if (g_mask & (1u << grp))
        fail(b, &w,
             "two G codes of the same modal group in one block; put them in separate blocks");
      // (A second non-modal code failed just above: the group's bit was set.)
      if (grp == kNonModal && (g_mask & (1u << kNonModal)) && g[kNonModal]->code10 != w.code10)
        fail(b, &w, "two non-modal G codes in one block; split the block");
      g_mask |= 1u << grp;
      g[static_cast<size_t>(grp)] = &w;
      continue;
    }
    if (w.letter == 'M') {
      const char* why = nullptr;
      const int grp = w.code10 < 0 ? -1 : m_group(w.code10, &why);
      if (grp < 0)
        fail(b, &w, fmt::format("M code is not supported: {}", why ? why : "unknown M code"));
      if (grp != kMOther && (m_mask & (1u << grp)))
        fail(b, &w, "two M codes of the same modal group in one block; split the block");
      m_mask |= 1u << grp;
      m[static_cast<size_t>(grp)] = &w;
      continue;
    }
    if (w.letter == '@' || w.letter == '^') {
      const Word*& slot = w.letter == '@' ? polar_radius : polar_angle;
      if (slot) fail(b, &w, fmt::format("word {} appears twice in one block", w.letter));
      slot = &w;
      continue;
    }
    const char L = w.letter;
    if (L == 'A' || L == 'B' || L == 'C' || L == 'U' || L == 'V' || L == 'W')
      fail(b, &w,
           fmt::format("axis word {} is not supported by the three-axis post-processor; "
                       "use a five-axis machine definition",
                       L));
    if (L == 'D' || L == 'E')
      fail(b, &w, fmt::format("word {} is not supported (cutter compensation, lathe)", L));
    if (L != 'N' && (letter_mask & (1u << (L - 'A'))))
      fail(b, &w, fmt::format("word {} appears twice in one block", L));
    letter[static_cast<size_t>(L - 'A')] = &w;
    letter_mask |= 1u << (L - 'A');
  }
  // Until the general steps, a slot is read only when its bit is set.
  auto given_word = [&](char L) -> const Word* {
    const size_t k = static_cast<size_t>(L - 'A');
    return (letter_mask & (1u << k)) ? letter[k] : nullptr;
  };
  const bool polar = polar_radius || polar_angle;
  if (polar && (given_word('X') || given_word('Y')))
    fail(b, given_word('X') ? given_word('X') : given_word('Y'),
         "X or Y with polar coordinates (@ ^) in one block; use one form or the other");
  // LinuxCNC checks the plane in effect before the block (enhance_block):
  // polar words in G18/G19 are refused, and so is `G17 @..` while G18/G19
  // is active, but `G18 @..` from G17 is read (as X Y).
  if (polar && s_.plane != 0)
    fail(b, polar_radius ? polar_radius : polar_angle,
         "polar coordinates (@ ^) while G18 or G19 is active; LinuxCNC reads them in G17 only: "
         "select G17 in an earlier block, or use X and Y");

  // The block of most programs: axis words (and F) only, no G or M code, in
  // G0 or G1. What the steps below do for it, and nothing else (they would
  // test every modal group in vain): F, the end of a canned-cycle run, the
  // straight move with its checks in the same order.
  constexpr std::uint32_t kAxisLetters = 1u << ('X' - 'A') | 1u << ('Y' - 'A') | 1u << ('Z' - 'A');
  constexpr std::uint32_t kFeedLetter = 1u << ('F' - 'A');
  if (g_mask == 0 && m_mask == 0 && !polar && (letter_mask & ~(kAxisLetters | kFeedLetter)) == 0 &&
      (letter_mask & kAxisLetters) != 0 && (s_.motion == 0 || s_.motion == 10)) {
    if (const Word* f = given_word('F')) {
      if (f->value < 0) fail(b, f, "negative feed");
      s_.feed = f->value;
    }
    double value[3] = {};
    unsigned given = 0;
    for (int a = 0; a < 3; ++a)
      if (const Word* w = given_word("XYZ"[a])) {
        value[a] = w->value;
        given |= 1u << a;
      }
    bool known_after = true;
    for (int a = 0; a < 3; ++a)
      known_after = known_after &&
                    (s_.axis_known[static_cast<size_t>(a)] || ((given >> a & 1u) && s_.absolute));
    if (!known_after && s_.motion != 0)
      fail(b, nullptr,
           "a feed move from an unknown position: command X, Y and Z with a rapid (G0) "
           "before the first cutting move, or give --initial-position");
    if (s_.motion == 10 && s_.feed <= 0.0 && s_.feed_mode != 930)
      fail(b, nullptr, "G1 with no feed rate; add an F word");
    straight_move(value, given, effect.motion);
    effect.has_motion = true;
    return;
  }

  // The general steps read every slot: those no word filled are null.
  for (size_t k = 0; k < letter.size(); ++k)
    if (!(letter_mask & (1u << k))) letter[k] = nullptr;
  for (size_t k = 0; k < g.size(); ++k)
    if (!(g_mask & (1u << k))) g[k] = nullptr;
  for (size_t k = 0; k < m.size(); ++k)
    if (!(m_mask & (1u << k))) m[k] = nullptr;
  auto word = [&](char L) { return letter[static_cast<size_t>(L - 'A')]; };
  const bool any_axis = word('X') || word('Y') || word('Z') || polar;

  // Step 3 and 4: execute in RS274NGC order.
  if (g[kFeedMode]) s_.feed_mode = g[kFeedMode]->code10;
  if (const Word* f = word('F')) {
    if (f->value < 0) fail(b, f, "negative feed");
    s_.feed = f->value;
  }
  if (const Word* t = word('T')) {
    if (t->value < 0 || t->value != std::floor(t->value) || t->value > kMaxToolNumber)
      fail(b, t, fmt::format("T must be a non-negative integer up to {}", kMaxToolNumber));
    s_.selected_tool = static_cast<int>(t->value);
  }
  if (m[kMTool]) s_.tool = s_.selected_tool;
  if (m[kMSpindle]) s_.spindle_turning = m[kMSpindle]->code10 == 30 || m[kMSpindle]->code10 == 40;
  if (g[kNonModal] && g[kNonModal]->code10 == 40 && !word('P'))
    fail(b, g[kNonModal], "G4 dwell needs a P word (seconds)");
  if (g[kPlane]) s_.plane = (g[kPlane]->code10 - 170) / 10;
  if (g[kUnits]) s_.unit_mm = g[kUnits]->code10 == 200 ? 25.4 : 1.0;
  bool consumed_axes = false;
  if (g[kToolLength]) {
    const double offset_before = s_.tool_length_mm;
    const int c = g[kToolLength]->code10;
    if (c == 490) {
      s_.tool_length_active = false;
      s_.tool_length_mm = 0.0;
    } else if (c == 430) {
      const Word* h = word('H');
      if (h && (h->value < 0 || h->value != std::floor(h->value) || h->value > kMaxToolNumber))
        fail(b, h,
             fmt::format("H must be a non-negative integer up to {} (a tool number)",
                         kMaxToolNumber));
      const int tool = h ? static_cast<int>(h->value) : s_.tool;
      auto it = setup_.tool_length_mm.find(tool);
      if (it == setup_.tool_length_mm.end())
        fail(b, g[kToolLength],
             fmt::format("G43 uses tool {}, which the tool table does not list; "
                         "give its offset with --tool-table",
                         tool));
      s_.tool_length_active = true;
      s_.tool_length_mm = it->second;
    } else {  // G43.1: dynamic length from the Z word
      const Word* z = word('Z');
      if (!z) fail(b, g[kToolLength], "G43.1 needs a Z word (the tool length offset)");
      s_.tool_length_active = true;
      s_.tool_length_mm = z->value * s_.unit_mm;
      consumed_axes = true;
      if (word('X') || word('Y') || polar)
        fail(b,
             word('X')      ? word('X')
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
  if (g[kCoordSystem]) {
    static constexpr int kCodes[9] = {540, 550, 560, 570, 580, 590, 591, 592, 593};
    for (int k = 0; k < 9; ++k)
      if (kCodes[k] == g[kCoordSystem]->code10) s_.coord_system = k;
  }
  if (g[kDistance]) s_.absolute = g[kDistance]->code10 == 900;
  if (g[kArcDistance]) s_.arc_absolute = g[kArcDistance]->code10 == 901;
  if (g[kReturnMode]) s_.g98 = g[kReturnMode]->code10 == 980;
  const bool g53 = g[kNonModal] && g[kNonModal]->code10 == 530;
  effect.g53 = g53;
  if (g53 && !s_.absolute) fail(b, g[kNonModal], "G53 needs absolute mode (G90)");
  if (g53 && polar)
    fail(b, polar_radius ? polar_radius : polar_angle,
         "polar coordinates (@ ^) with G53; use X and Y");

  // LinuxCNC asks for Z, R, P and Q only when the block starts a cycle other
  // than the modal one (a G81 restated in G81 keeps the modal values).
  const int motion_before = s_.motion;
  if (g[kMotion]) {
    s_.motion = g[kMotion]->code10;
    effect.motion_code = s_.motion;
  }
  if (!is_cycle(s_.motion)) s_.cycle_il_known = false;
  // A G2/G3 with centre words but no axis words is a full circle (LinuxCNC).
  static constexpr char kOffsetLetters[3][2] = {{'I', 'J'}, {'K', 'I'}, {'J', 'K'}};
  const int arc_plane = g[kPlane] ? (g[kPlane]->code10 - 170) / 10 : s_.plane;
  const int arc_mode = g[kMotion] ? g[kMotion]->code10 : s_.motion;
  const bool full_circle =
      !any_axis && (arc_mode == 20 || arc_mode == 30) &&
      (word(kOffsetLetters[arc_plane][0]) || word(kOffsetLetters[arc_plane][1]));
  const bool motion_here =
      (any_axis && !consumed_axes) || full_circle || (g[kMotion] && is_cycle(g[kMotion]->code10));
  if (motion_here && g[kMotion] && g[kMotion]->code10 == 800)
    fail(b, g[kMotion], "axis words with G80; remove them or use G0/G1");
  if (g53 && motion_here && s_.motion != 0 && s_.motion != 10)
    fail(b, g[kNonModal], "G53 works with G0 or G1 only");
  if (motion_here && s_.motion == 800 && !g[kMotion])
    fail(b,
         any_axis ? (word('X')   ? word('X')
                     : word('Y') ? word('Y')
                                 : word('Z'))
                  : nullptr,
         "axis words without a motion mode (G80 active); add G0 or G1");
  if (!motion_here && (word('I') || word('J') || word('K') || word('R')) && !is_cycle(s_.motion))
    fail(b,
         word('I')   ? word('I')
         : word('J') ? word('J')
         : word('K') ? word('K')
                     : word('R'),
         "arc words without axis words");
  if (g[kMotion] && (g[kMotion]->code10 == 20 || g[kMotion]->code10 == 30) && !motion_here)
    fail(b, g[kMotion],
         "G2/G3 with neither axis words nor a centre (I J K) or R; LinuxCNC refuses it: "
         "give the arc's end and centre, or select the mode in the block of the first arc");
  // A word no code of the block uses: LinuxCNC refuses the block
  // (interp_check.cc, check_other_codes, against the motion the block will
  // make), so a program that has one is not a LinuxCNC program, and its
  // post would be refused by the controller. M codes that read P Q L R
  // (spindle orientation M19, overrides M50-M53, digital and analog I/O
  // M62-M68, user M codes M100-M199) exempt the block, as in LinuxCNC.
  {
    const int motion_to_be = g[kMotion] ? g[kMotion]->code10 : (motion_here ? s_.motion : -1);
    const bool arc = motion_to_be == 20 || motion_to_be == 30;
    const bool cycle = motion_to_be >= 0 && is_cycle(motion_to_be);
    bool m_reads_words = false;
    for (const Word& w : b.words)
      if (w.letter == 'M') {
        const int c = w.code10 / 10;
        m_reads_words = m_reads_words || c == 19 || (c >= 50 && c <= 53) || (c >= 61 && c <= 68) ||
                        (c >= 100 && c <= 199);
      }
    const bool g4 = g[kNonModal] && g[kNonModal]->code10 == 40;
    const bool g64 = g[kPathControl] && g[kPathControl]->code10 == 640;
    const auto unused = [&](char L, bool used, const char* users) {
      if (const Word* w = word(L); w && !used)
        fail(b, w,
             fmt::format("{} word with no {} to use it; LinuxCNC refuses the block: remove it", L,
                         users));
    };
    if (!m_reads_words) {
      for (char L : {'I', 'J', 'K'}) unused(L, arc, "G2 or G3");
      unused('R', arc || cycle, "G2, G3 or canned cycle");
      unused('L', cycle, "canned cycle");
      unused('P',
             g4 || g64 || arc || motion_to_be == 820 || motion_to_be == 860 || motion_to_be == 890,
             "G2, G3, G4, G64, G82, G86 or G89");
      unused('Q', g64 || motion_to_be == 730 || motion_to_be == 830, "G64, G73 or G83");
    }
  }

  if (motion_here) {
    const Eigen::Vector3d& wo = work_offset();
    Eigen::Vector3d target = s_.position_mm;
    std::array<bool, 3> given{};
    for (int a = 0; a < 3; ++a) {
      const Word* w = word("XYZ"[a]);
      if (!w) continue;
      given[static_cast<size_t>(a)] = true;
      if (s_.absolute)
        target[a] = w->value * s_.unit_mm + (g53 ? 0.0 : wo[a]);
      else
        target[a] = s_.position_mm[a] + w->value * s_.unit_mm;
    }
    // Program coordinates (XY plane, program units) of where the tool
    // stands: polar coordinates and canned-cycle increments start there.
    const double unit = s_.unit_mm;
    const double at_x = (s_.position_mm.x() - wo.x()) / unit,
                 at_y = (s_.position_mm.y() - wo.y()) / unit;
    const bool xy_known = s_.axis_known[0] && s_.axis_known[1];
    if (polar && !is_cycle(s_.motion)) {
      // LinuxCNC (interp_find.cc, find_ends). G90: @ and ^ from the program
      // origin; a missing one is the current point's. G91: @ adds to the
      // current point's radius, then ^ to its angle.
      const Word* w = polar_radius ? polar_radius : polar_angle;
      const bool needs_current = !s_.absolute || !polar_radius || !polar_angle;
      if (needs_current && !xy_known)
        fail(b, w,
             "polar coordinates from an unknown position: command X and Y first (or give "
             "--initial-position)");
      double px = at_x, py = at_y;
      if (s_.absolute) {
        if (polar_radius && !polar_angle && px == 0 && py == 0)
          fail(b, w, "polar radius without an angle at the origin: add a ^ word");
        const double radius = polar_radius ? polar_radius->value : std::hypot(py, px);
        const double theta = polar_angle ? polar_angle->value * kDegToRad : std::atan2(py, px);
        px = radius * std::cos(theta);
        py = radius * std::sin(theta);
      } else {
        if (px == 0 && py == 0)
          fail(b, w,
               "incremental polar coordinates (G91) at the program origin are indeterminate; move "
               "off it first");
        if (polar_radius) {
          const double theta = std::atan2(py, px),
                       radius = std::hypot(py, px) + polar_radius->value;
          px = radius * std::cos(theta);
          py = radius * std::sin(theta);
        }
        if (polar_angle) {
          const double theta = std::atan2(py, px) + polar_angle->value * kDegToRad,
                       radius = std::hypot(py, px);
          px = radius * std::cos(theta);
          py = radius * std::sin(theta);
        }
      }
      target.x() = px * unit + wo.x();
      target.y() = py * unit + wo.y();
      given[0] = given[1] = s_.absolute;  // an absolute polar point fixes both axes
    }
    Motion& mo = effect.motion;
    mo.start_mm = s_.position_mm;
    mo.feed = s_.feed;
    const int mode = s_.motion;
    bool known_after = true;
    for (int a = 0; a < 3; ++a)
      known_after = known_after && (s_.axis_known[static_cast<size_t>(a)] ||
                                    (given[static_cast<size_t>(a)] && s_.absolute));
    if (!known_after && mode != 0)
      fail(b, nullptr,
           "a feed move from an unknown position: command X, Y and Z with a rapid (G0) "
           "before the first cutting move, or give --initial-position");
    if (mode == 0 || mode == 10) {
      mo.kind = mode == 0 ? MotionKind::kRapid : MotionKind::kLinear;
      if (mode == 10 && s_.feed <= 0.0 && s_.feed_mode != 930)
        fail(b, nullptr, "G1 with no feed rate; add an F word");
      mo.end_mm = target;
    } else if (mode == 20 || mode == 30) {
      if (s_.feed <= 0.0) fail(b, nullptr, "arc with no feed rate; add an F word");
      const int p = s_.plane;  // in-plane axes (a0, a1) and normal axis n
      static constexpr int kA0[3] = {0, 2, 1}, kA1[3] = {1, 0, 2}, kN[3] = {2, 1, 0};
      static constexpr char kOff0[3] = {'I', 'K', 'J'}, kOff1[3] = {'J', 'I', 'K'};
      const int a0 = kA0[p], a1 = kA1[p];
      // LinuxCNC (convert_arc): "K word given for arc in xy plane" (J in
      // xz, I in yz), and "Mixed radius ijk format for arc" for R with any
      // of I J K.
      static constexpr char kNormalOffset[3] = {'K', 'J', 'I'};
      static constexpr const char* kPlaneName[3] = {"XY (G17)", "XZ (G18)", "YZ (G19)"};
      if (const Word* w = word(kNormalOffset[p]); w && !word('R'))
        fail(b, w,
             fmt::format("{} word given for an arc in the {} plane; LinuxCNC refuses it: remove it",
                         kNormalOffset[p], kPlaneName[p]));
      if (const Word* r = word('R'); r && (word('I') || word('J') || word('K')))
        fail(b, r, "arc with both R and I/J/K; use one form");
      if (!given[static_cast<size_t>(a0)] && !given[static_cast<size_t>(a1)] && !word('R') &&
          !word(kOff0[p]) && !word(kOff1[p]))
        fail(b, nullptr, "arc without in-plane end point or centre");
      mo.kind = MotionKind::kArc;
      mo.end_mm = target;
      mo.plane = p;
      mo.clockwise = mode == 20;
      const Eigen::Vector2d s2(mo.start_mm[a0], mo.start_mm[a1]);
      const Eigen::Vector2d e2(target[a0], target[a1]);
      Eigen::Vector2d c2;
      if (const Word* r = word('R')) {
        if (word(kOff0[p]) || word(kOff1[p])) fail(b, r, "arc with both R and I/J/K; use one form");
        const double R = r->value * s_.unit_mm;
        const Eigen::Vector2d d = e2 - s2;
        const double half = d.norm() / 2.0;
        if (half == 0.0)
          fail(b, r, "R-form arc with the end point at the start: a full circle needs I/J/K");
        // LinuxCNC (arc_data_r): R may fall short of half the chord by
        // RADIUS_TOLERANCE (0.00005 inch, in program units).
        if ((half - std::abs(R)) / s_.unit_mm > (s_.unit_mm > 1.0 ? 0.00005 : 0.00005 * 25.4))
          fail(b, r, "arc radius R is smaller than half the chord; fix R or the end point");
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
          fail(b, nullptr, fmt::format("arc needs {} or {} (centre) or R", kOff0[p], kOff1[p]));
        if (s_.arc_absolute) {
          c2 = Eigen::Vector2d((i0 ? i0->value * s_.unit_mm + wo[a0] : mo.start_mm[a0]),
                               (i1 ? i1->value * s_.unit_mm + wo[a1] : mo.start_mm[a1]));
        } else {
          c2 = s2 + Eigen::Vector2d(i0 ? i0->value * s_.unit_mm : 0.0,
                                    i1 ? i1->value * s_.unit_mm : 0.0);
        }
        const double r_start = (s2 - c2).norm(), r_end = (e2 - c2).norm();
        // LinuxCNC's rule (interp_arc.cc arc_data_ijk, in program units):
        // a radius below RADIUS_TOLERANCE is a zero-radius arc; the two
        // radii may differ by CENTER_ARC_RADIUS_TOLERANCE (0.02 sqrt 2 mm,
        // 0.002 sqrt 2 inch, its default), or by more if that is at most
        // 0.1 % (SPIRAL_RELATIVE_TOLERANCE) of the larger and at most 100
        // times the tolerance.
        const bool inch = s_.unit_mm > 1.0;
        const double r1 = r_start / s_.unit_mm, r2 = r_end / s_.unit_mm;
        const double zero_radius = inch ? 0.00005 : 0.00005 * 25.4;
        const double spiral_abs = (inch ? 0.002 : 0.02) * std::sqrt(2.0);
        if (r1 < zero_radius || r2 < zero_radius) fail(b, i0 ? i0 : i1, "arc of zero radius");
        const double abs_err = std::abs(r1 - r2), rel_err = abs_err / std::max(r1, r2);
        if (abs_err > spiral_abs * 100.0 || (rel_err > 0.001 && abs_err > spiral_abs))
          fail(b, i0 ? i0 : i1,
               fmt::format(
                   "radius to end of arc ({:.4f} mm) differs from radius to start "
                   "({:.4f} mm) by more than LinuxCNC allows; fix the centre or the end point",
                   r_end, r_start));
      }
      mo.center_mm = mo.start_mm;
      mo.center_mm[a0] = c2.x();
      mo.center_mm[a1] = c2.y();
      if (const Word* pw = word('P')) {
        if (pw->value < 1 || pw->value != std::floor(pw->value) || pw->value > kMaxArcTurns)
          fail(b, pw, fmt::format("P (turns) must be a positive integer up to {}", kMaxArcTurns));
        mo.extra_turns = static_cast<int>(pw->value) - 1;
      }
      (void)kN;
    } else if (is_cycle(mode)) {
      if (s_.plane != 0)
        fail(b, nullptr, "canned cycles in the G18 or G19 plane are not supported; use G17");
      const Word* l = word('L');
      if (l && (l->value < 1 || l->value != std::floor(l->value) || l->value > kMaxCycleRepeats))
        fail(b, l,
             fmt::format("L (repeats) must be a positive integer up to {}", kMaxCycleRepeats));
      const int repeats = l ? static_cast<int>(l->value) : 1;
      const bool starts = mode != motion_before;
      if (const Word* z = word('Z'))
        s_.cycle_z = z->value;
      else if (starts)
        fail(b, g[kMotion], "canned cycle needs a Z word (hole bottom)");
      if (const Word* r = word('R'))
        s_.cycle_r = r->value;
      else if (starts)
        fail(b, g[kMotion], "canned cycle needs an R word (retract plane)");
      if ((mode == 830 || mode == 730) && !word('Q') && starts)
        fail(b, g[kMotion], "peck drilling needs a Q word (peck depth)");
      // LinuxCNC (convert_cycle_g73/g83): "Negative or zero q value used".
      if (const Word* q = word('Q'); q && (mode == 830 || mode == 730) && q->value <= 0)
        fail(b, q, "the peck depth Q must be positive (LinuxCNC refuses a negative or zero Q)");
      if (const Word* q = word('Q'); q && (mode == 830 || mode == 730)) s_.cycle_q = q->value;
      if ((mode == 820 || mode == 860 || mode == 890) && !word('P') && starts)
        fail(b, g[kMotion], "dwell cycle needs a P word (seconds)");
      if (mode == 860 && !s_.spindle_turning)
        fail(b, g[kMotion] ? g[kMotion] : nullptr,
             "G86 with the spindle stopped; LinuxCNC refuses it (\"Spindle not turning in g86\"): "
             "start it "
             "with M3 or M4 first");
      // LinuxCNC (convert_cycle) refuses cycles under G93.
      if (s_.feed_mode == 930)
        fail(b, g[kMotion],
             "canned cycle under inverse time feed (G93); LinuxCNC refuses it: use G94");
      if (s_.feed <= 0.0) fail(b, nullptr, "canned cycle with no feed rate; add an F word");
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
      if (bottom_mm > r_mm)
        fail(b, nullptr, "canned cycle with the hole bottom (Z) above the R plane");
      double aa = at_x, bb = at_y;
      double aa_step = 0, bb_step = 0, radius_step = 0, angle_step_rad = 0;
      if (s_.absolute) {
        if (polar) {
          const double radius = polar_radius ? polar_radius->value : std::hypot(bb, aa);
          const double theta = polar_angle ? polar_angle->value * kDegToRad : std::atan2(bb, aa);
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
        if (polar_angle) angle_step_rad = polar_angle->value * kDegToRad;
      }
      if (polar && !xy_known)
        fail(b, polar_radius ? polar_radius : polar_angle,
             "polar coordinates from an unknown position: command X and Y first (or give "
             "--initial-position)");
      mo.r_mm = r_mm;
      mo.clear_mm = s_.g98 ? std::max(initial, r_mm) : r_mm;
      Eigen::Vector3d at = s_.position_mm;
      for (int k = 0; k < repeats; ++k) {
        aa += aa_step;
        bb += bb_step;
        if ((radius_step != 0 || angle_step_rad != 0) && aa == 0 && bb == 0)
          fail(b, polar_radius ? polar_radius : polar_angle,
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
        Motion& hole = k == 0 ? mo : effect.more_holes.emplace_back(mo);
        hole.start_mm = at;
        hole.end_mm = Eigen::Vector3d(aa * unit + wo.x(), bb * unit + wo.y(), bottom_mm);
        at = Eigen::Vector3d(hole.end_mm.x(), hole.end_mm.y(), mo.clear_mm);
      }
      target = at;
    } else {
      fail(b, nullptr, "axis words without a motion mode; add G0 or G1");
    }
    effect.has_motion = true;
    s_.position_mm = target;
    // An incremental word moves from where the axis is: it makes an unknown
    // axis no better known.
    for (int a = 0; a < 3; ++a)
      if ((given[static_cast<size_t>(a)] && s_.absolute) || mo.kind == MotionKind::kCycle)
        s_.axis_known[static_cast<size_t>(a)] = true;
    s_.position_known = s_.axis_known[0] && s_.axis_known[1] && s_.axis_known[2];
  }
  if (m[kMStop]) {
    effect.stop_code = true;
    const int c = m[kMStop]->code10;
    if (c == 20 || c == 300) {
      s_.ended = true;
      s_.spindle_turning = false;
    }
  }
}

void read_var_file(const std::string& path, ProgramSetup& setup) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open the parameter (.var) file; check the path");
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    std::istringstream ls(line);
    int param;
    double value;
    if (!(ls >> param)) continue;
    if (!(ls >> value) || !std::isfinite(value))
      throw InputError(path, n, "expected \"<parameter> <value>\"");
    // G54: 5221..5223, each following system 20 further, up to G59.3 (5381).
    if (param >= 5221 && param <= 5383) {
      const int k = (param - 5221) / 20, a = (param - 5221) % 20;
      if (a < 3 && k < 9) setup.work_offset_mm[static_cast<size_t>(k)][a] = value;
    }
  }
}

void read_tool_table(const std::string& path, ProgramSetup& setup) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open the tool table (.tbl); check the path");
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const size_t semi = line.find(';');
    if (semi != std::string::npos) line.resize(semi);
    std::istringstream ls(line);
    std::string tok;
    int tool = -1;
    std::optional<double> z;
    while (ls >> tok) {
      const char L = static_cast<char>(std::toupper(static_cast<unsigned char>(tok[0])));
      double v = 0;
      try {
        size_t used = 0;
        v = std::stod(tok.substr(1), &used);
        if (used != tok.size() - 1) throw std::invalid_argument("x");
      } catch (const std::exception&) {
        throw InputError(
            path, n,
            fmt::format("bad entry \"{}\"; expected letter and number (T1 P1 Z12.5)", tok));
      }
      if (!std::isfinite(v))  // std::stod reads nan and inf
        throw InputError(
            path, n,
            fmt::format("bad entry \"{}\": not a finite number; give the tool length offset in mm",
                        tok));
      if (L == 'T' && (v < 0 || v != std::floor(v) || v > kMaxToolNumber))
        throw InputError(path, n,
                         fmt::format("bad entry \"{}\": a tool number is an integer from 0 to {}",
                                     tok, kMaxToolNumber));
      if (L == 'T') tool = static_cast<int>(v);
      if (L == 'Z') z = v;
    }
    if (tool < 0) continue;
    setup.tool_length_mm[tool] = z.value_or(0.0);
  }
}

}  // namespace volmap::nc
