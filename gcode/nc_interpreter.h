// Modal interpretation of RS274NGC blocks into motions in machine
// coordinates (mm). Validation comes first, in numbered steps as grbl does:
// (1) every word known, (2) at most one G code per modal group and one M code
// per group (bitmask), (3) the values make sense for the active state, (4)
// only then the state changes and motions are produced. A block that fails
// any step raises InputError naming file:line and what to do, and leaves
// the state as it was: check() computes the state a block leads to without
// touching the interpreter's, execute() takes it on only when the block
// passed (tests/gcode/validate_before_mutate_test.cc).
//
// Supported: G0 G1 G2 G3 (centre I J K and R forms, full circles, helices,
// P turns), G17 G18 G19, G20 G21, G90 G91, G90.1 G91.1, G53, G54-G59.3,
// G43 H / G43.1 / G49, G10 L2/L20, G92 G92.1 G92.2 G92.3, G28 G30 (through the intermediate point
// to the positions of a parameter file) and G28.1 G30.1, G80-G89 (G73 G81 G82 G83 G85 G86 G89 in
// G17, G90 or G91, with G98/G99 and L repeats), LinuxCNC's polar coordinates (@ ^), G93 G94 G95,
// G4, G40, G61 G61.1 G64, G96 G97, F S T, M0-M9, M30, M48 M49 M60 and other M codes (passed
// through), N numbers, block delete (executed), comments. Everything else is refused with a reason:
// volmap never passes through a construct it did not understand.
//
// Machine coordinates here are those of the controlled point (the tool tip
// with tool length compensation, LinuxCNC's convention): program position
// times units plus the active work offset, or the G53 value.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "gcode/g_codes.h"
#include "gcode/linuxcnc_files.h"  // (read_var_file and read_tool_table were declared here)
#include "gcode/nc_block.h"
#include "gcode/program_setup.h"

namespace volmap::nc {

/// kTap: LinuxCNC's rigid tap G33.1, a straight move from start to end
/// synchronised with the spindle, then back to the start.
enum class MotionKind { kRapid, kLinear, kArc, kCycle, kTap };

struct Motion {
  MotionKind kind = MotionKind::kLinear;
  Eigen::Vector3d start_mm = Eigen::Vector3d::Zero();  ///< machine coordinates
  Eigen::Vector3d end_mm = Eigen::Vector3d::Zero();
  // Arcs: centre (in the plane; its coordinate along the plane normal is the
  // start's), plane 0 = XY (G17), 1 = ZX (G18), 2 = YZ (G19), direction,
  // extra full turns.
  Eigen::Vector3d center_mm = Eigen::Vector3d::Zero();
  int plane = 0;
  bool clockwise = false;
  int extra_turns = 0;
  // Canned cycles: hole at end_mm (x, y, bottom z); r plane and the level
  // the tool returns to (G98: initial level, G99: R).
  double r_mm = 0.0;
  double clear_mm = 0.0;
  double feed = 0.0;  ///< as programmed (units/min, inverse time, per rev)
};

/// A motion's part in cutter radius compensation (G41/G42): the controller
/// offsets the programmed path by the tool radius; the first move in the
/// plane after G41/G42 enters (the controller computes it from the move's
/// start), the first after G40 leaves.
enum class CompRole { kNone, kEntry, kCompensated, kExit };

struct State {
  double unit_mm = 1.0;       ///< 25.4 under G20
  bool absolute = true;       ///< G90
  bool arc_absolute = false;  ///< G90.1
  int plane = 0;              ///< 0 XY, 1 ZX, 2 YZ
  int motion = kG0Rapid;      ///< G code x 10 of the modal motion (G0 G1 G2 G3 G73 G80-G89)
  /// The last of G0 G1 G2 G3 (x 10): Fanuc keeps canned cycles in a group
  /// of their own (09), and G80 brings this motion back (LinuxCNC: G80 is a
  /// motion mode that moves nothing).
  int group01 = kG0Rapid;
  bool group01_given = false;  ///< a G0-G3 seen (Fanuc's power-on one is a parameter, 3402#0)
  /// G98 or G99 given: a Fanuc control's return level before either is
  /// its power-on setting, which an offline post cannot know.
  bool return_mode_given = false;
  /// Fanuc: the shift in g92_mm came from G92 (1) or G52 (2), or none (0).
  int fanuc_shift = 0;
  /// Fanuc: bit 3 n + a: axis a of system n set by G90 G10 L2 (G91 G10 L2
  /// adds to it then).
  unsigned fanuc_offsets_set = 0;
  int coord_system = 0;  ///< 0 = G54 .. 8 = G59.3
  /// The program's origin, machine mm: the active coordinate system's
  /// offset, plus the G92 offset while it applies.
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  /// G54 .. G59.3 (ProgramSetup's, changed by G10 L2/L20), machine mm.
  std::array<Eigen::Vector3d, 9> coord_offset_mm = [] {
    std::array<Eigen::Vector3d, 9> zero;
    zero.fill(Eigen::Vector3d::Zero());
    return zero;
  }();
  /// The G92 offset (LinuxCNC's #5211-#5213) and whether it applies
  /// (#5210: G92 and G92.3 apply it, G92.1 and G92.2 suspend it).
  Eigen::Vector3d g92_mm = Eigen::Vector3d::Zero();
  bool g92_applied = false;
  /// origin_mm from the active system and the G92 offset (after any of
  /// them changes).
  void update_origin() {
    origin_mm = coord_offset_mm[static_cast<size_t>(coord_system)] +
                (g92_applied ? g92_mm : Eigen::Vector3d::Zero());
  }
  bool tool_length_active = false;
  /// The active tool length offset (G43 H, G43.1), mm; 0 under G49 (and
  /// before any G43), so it is the offset in effect either way. As in
  /// LinuxCNC, a change of it moves the controlled point, not the axes:
  /// position_mm's Z changes by minus the change.
  double tool_length_mm = 0.0;
  int tool = 0;  ///< T in the spindle (after M6)
  /// M61 set the tool number since the last M6: for a G43 without H,
  /// LinuxCNC's rs274 then applies the offset of the tool the last M6
  /// loaded (none before any), a machine that of M61's tool: refused, give H.
  bool tool_from_m61 = false;
  int selected_tool = 0;     ///< last T word
  bool tool_loaded = false;  ///< an M6 or M61 named the tool in the spindle
  /// Cutter radius compensation: 0 off (G40), 1 left (G41), 2 right (G42),
  /// the sides swapped by a negative diameter as LinuxCNC swaps them; the
  /// radius (mm). The controller offsets the path; the post keeps the codes
  /// (cutter_comp.cc, docs/post.md "Cutter compensation").
  int comp_side = 0;
  double comp_radius_mm = 0.0;
  /// The next move in the XY plane enters the compensation (after G41/G42)
  /// or leaves it (after G40 with compensation on).
  bool comp_entry_pending = false, comp_exit_pending = false;
  /// LinuxCNC's arc_not_allowed: after G40 ends a compensation that moved,
  /// an arc is refused until a straight move (G0 G1, G33.1) comes.
  bool comp_arc_not_allowed = false;
  /// The last compensated straight side (XY, its unit direction; zero:
  /// none or an arc), its length and how much its start corner cut off it
  /// (LinuxCNC trims a side at an inside corner by r tan(turn / 2)), and
  /// how that cut changes with the turn (mm/rad).
  Eigen::Vector2d comp_side_dir = Eigen::Vector2d::Zero();
  double comp_side_len_mm = 0.0, comp_side_trim_mm = 0.0, comp_side_trim_rate = 0.0;
  /// Canned cycles return to the initial level (G98) or to R (G99).
  /// LinuxCNC's interpreter starts in G99 (its retract mode is zero,
  /// R_PLANE, until G98; rs274 shows it), not G98.
  bool g98 = false;
  double cycle_r = 0.0, cycle_z = 0.0;  ///< modal R and Z of canned cycles (program units)
  /// Modal peck depth Q of G73/G83 (program units, as written; LinuxCNC's
  /// cycle_q: a G73/G83 block without Q keeps the last one).
  double cycle_q = 0.0;
  /// LinuxCNC's initial level of a run of canned-cycle blocks: the Z (mm,
  /// machine) where the first of them started; G98 returns to it (or to R
  /// when R is higher) and G91's R counts from it. A motion that is not a
  /// cycle ends the run.
  bool cycle_il_known = false;
  double cycle_il_mm = 0.0;
  double feed = 0.0;
  int feed_mode = kG94UnitsPerMinute;                     ///< G93, G94, G95 (x10)
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();  ///< machine coordinates
  bool position_known = false;  ///< false until every axis has been commanded
  std::array<bool, 3> axis_known{};
  bool ended = false;  ///< after M2 / M30
  /// Spindle turning (M3 or M4 in effect; M5, M19 and the program's end
  /// stop it): LinuxCNC's G86 needs it ("Spindle not turning in g86").
  bool spindle_turning = false;
  /// The direction it turns (M3: true, M4: false): LinuxCNC's G84 needs
  /// clockwise, G74 counterclockwise.
  bool spindle_clockwise = true;
  /// Rotary axes A B C, rad (ProgramSetup::rotary_axes: only those the
  /// machine has move).
  std::array<double, 3> rotary_rad{};
  /// The tool axis of a tool-vector program (ProgramSetup::tool_axis_words),
  /// unit, in program coordinates.
  Eigen::Vector3d tool_axis = Eigen::Vector3d::UnitZ();
  /// The positions G28 and G30 return to (LinuxCNC's #5161-#5166 and
  /// #5181-#5186): axes X Y Z (machine mm) and A B C (rad), each known
  /// where a parameter file gave it or G28.1/G30.1 stored it.
  std::array<std::array<double, 6>, 2> home{};
  std::array<std::array<bool, 6>, 2> home_known{};

  friend bool operator==(const State&, const State&) = default;
};

/// A row of the tool table a block sets (G10 L1): the tool, and the length
/// offset and diameter given (mm).
struct ToolTableWrite {
  int tool = -1;  ///< -1: none
  std::optional<double> length_mm, diameter_mm;
};

/// What one block did, for the post-processor: its motion (at most one), and
/// for every axis word the machine coordinate it names.
struct BlockEffect {
  bool has_motion = false;
  Motion motion;
  bool g53 = false;
  bool stop_code = false;                ///< M0 M1 M2 M30 M60 in the block
  int motion_code = -1;                  ///< motion G code written in this block, x10, or -1
  CompRole comp_role = CompRole::kNone;  ///< the motion's, in cutter compensation
  ToolTableWrite tool_row;               ///< G10 L1 (execute() writes it into the table)
  /// An inside corner under compensation after a straight side: what is
  /// left of the side after both corners' cuts (mm; infinite: no such
  /// corner), the side's length, and how the cuts change with the turns
  /// (mm/rad): the post checks its correction cannot use up what is left.
  double comp_slack_mm = INFINITY, comp_slack_len_mm = 0.0, comp_slack_rate = 0.0;
  /// G92 or G10 L20 with axis words: offsets set from where the tool
  /// stands, which on the machine is where the post's command put it.
  bool offsets_from_position = false;
  /// G28.1/G30.1: the controller stores where it stands.
  bool stores_home = false;
  /// G28/G30: bit a for each axis X Y Z that went to its stored position
  /// (the controller stands exactly there after the block, whatever the
  /// correction; the block is written as it is).
  unsigned homed_axes = 0;
  /// A canned cycle repeated (L > 1): the holes after the first, in order
  /// (`motion` is the first). Each starts where the one before it left the
  /// tool: over its hole at the clearance level.
  std::vector<Motion> more_holes;
};

class Interpreter {
 public:
  Interpreter(ProgramSetup setup, std::string file);

  /// Interprets one block: check() then the state it computed. Throws
  /// InputError on anything refused, the state unchanged.
  void execute(const Block& b, BlockEffect& effect);
  /// Validates one block against the state (every step) and computes what
  /// it does: returns the state after it and sets `effect`. Changes nothing
  /// of the interpreter. Throws InputError on anything refused.
  State check(const Block& b, BlockEffect& effect) const;
  /// A block of axis words only (X Y Z, `value` in program units by axis,
  /// bit a of `given` for each word; the block nc::lex_plain_axis_words
  /// reads), after a G1 word when `g1`, when it needs none of execute()'s
  /// checks: G1 in effect, a feed rate set (or G93), every axis position
  /// known, the program not ended. Then it does what execute() does with
  /// that block, sets `motion` (a straight move; its other fields are left
  /// as they are) and returns true; otherwise it changes nothing and returns
  /// false (execute() the block then). The post-processor's shortcut past a
  /// Block.
  bool execute_linear_axes(const double (&value)[3], unsigned given, Motion& motion,
                           bool g1 = false);

  /// The program's dialect (the reader resolves `auto` before the first
  /// block). Fanuc: G28's reference position is the machine zero
  /// (parameter 1240's usual value) where the parameter file gives none.
  void set_dialect(Dialect d);
  bool fanuc() const { return setup_.dialect == Dialect::kFanuc; }

  const State& state() const { return s_; }
  const ProgramSetup& setup() const { return setup_; }
  /// Work offset of the active coordinate system, mm.
  const Eigen::Vector3d& work_offset() const { return s_.origin_mm; }

 private:
  ProgramSetup setup_;
  std::string file_;
  State s_;
};

}  // namespace volmap::nc
