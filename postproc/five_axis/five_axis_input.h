// Reading five-axis tool paths: the three input forms of the five-axis
// post-processor (docs/post-five-axis.md), one line at a time, into nominal
// moves of the tool pose in workpiece coordinates.
//
//  - kTcp: RS274NGC with X Y Z the tool tip in workpiece coordinates and the
//    machine's rotary axis words (A C for X'Y'ZA'C') as angles in degrees:
//    LinuxCNC's TCP mode (M428 ... M429), Heidenhain M128, Siemens TRAORI
//    with rotary words. The nominal path: the tip moves along the programmed
//    line or arc, the rotary angles linearly with it.
//  - kToolVector: X Y Z tip plus the tool axis as I J K (or Siemens
//    A3= B3= C3=), unit or not (normalised), from the tip into the spindle.
//    The nominal path: the tip along the line, the axis along the great
//    circle (slerp).
//  - kApt: APT / CLDATA (apt_reader.h): GOTO and its kin, CIRCLE arcs,
//    CYCLE holes, the dialects of NX, SOLIDWORKS CAM and Creo; records that
//    move nothing become comments, records that may move the tool and are
//    not understood exactly are refused.
//  - kMachineAxes: RS274NGC of machine axis values (what the post writes):
//    verify reads compensated programs in this form.
//
// Frames and units: tips in the workpiece frame w of the machine (its origin
// is Machine::workpiece_origin_mm, which --part-origin sets), mm; angles rad;
// feeds mm/min (G94) or 1/min (G93). Program units are converted here.
//
// The G-code forms run on gcode's interpreter (nc::Interpreter, the three-axis
// post's), with the machine's rotary axis words and, in kToolVector, I J K
// of straight moves as the tool axis: its modal state, checks and messages
// are the three-axis post's. What the five-axis post does not take is
// refused first, with file:line:column: of the G codes it accepts G0 G1 G2
// G3 (I J K centre, XY/ZX/YZ planes), G17-G19, G20 G21, G90 G91, G90.1
// G91.1, G93 G94, G40 G49 G80, G54, G61 G61.1 G64 and G4, and no other (G43
// tool length: the machine file's tool is the one; other work offsets: one
// part origin); of the words N S T F P (with G4) X Y Z I J K and the
// machine's rotary axes. M428/M429/M430 (LinuxCNC's kinematics switches)
// are marked for stripping and not interpreted.
#pragma once

#include <Eigen/Core>
#include <array>
#include <deque>
#include <istream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/model/machine.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"

namespace volmap::post {

class AptReader;

enum class InputForm { kAuto, kTcp, kToolVector, kApt, kMachineAxes };

/// "auto", "tcp", "vector", "apt", "axes".
std::optional<InputForm> parse_input_form(const std::string& name);
const char* input_form_name(InputForm form);

/// The form of a program from its first lines: kApt when a statement is an
/// APT keyword with a slash (GOTO/, FEDRAT/, PARTNO ...); kToolVector when
/// a G0/G1 block has I, J or K, or A3=/B3=/C3= appear; else kTcp.
InputForm detect_input_form(const std::vector<std::string>& lines);

/// A G-code line's code: upper case, without comments ((...) and ';') and
/// the line's end, trimmed.
std::string gcode_code_of(const std::string& line);

/// One nominal move.
struct FiveAxisMove {
  bool rapid = false;
  /// Tip path in the workpiece frame, mm (kLinear or kArc; kMachineAxes:
  /// the linear axis values instead).
  nc::Motion tip;
  /// Orientation by angles (kTcp, kMachineAxes: rotary entries of q0, q1,
  /// rad, AxisVector order, linear entries 0) or by tool axes (a0, a1).
  bool by_angles = true;
  AxisVector q0, q1;
  Eigen::Vector3d a0 = Eigen::Vector3d::UnitZ(), a1 = Eigen::Vector3d::UnitZ();
  int feed_mode = nc::kG94UnitsPerMinute;  ///< G93 inverse time or G94 per minute (x10)
  double feed = 0.0;                       ///< mm/min (G94) or 1/min (G93)
};

/// One line of the input.
struct FiveAxisLine {
  int line = 0;
  nc::Block block;         ///< G-code forms: the lexed line
  bool synthetic = false;  ///< APT: no G-code line; `text` replaces it
  std::string text;        ///< APT: the G-code line for a non-move statement
  bool has_move = false;
  FiveAxisMove move;
  std::vector<int> strip;     ///< words to drop (M428 M429 M430)
  double unit_mm = 1.0;       ///< units after the line (25.4 under G20)
  int motion_code = -1;       ///< motion G code x10 written in the line (-1 none)
  bool ends_program = false;  ///< M2 / M30
  int tool = -1;              ///< a tool change to this tool (APT LOAD/TOOL, LOADTL; M6)
};

/// Where the tool stands before the program commands it: the tip in
/// program coordinates (mm), the rotary angles (rad, AxisVector order), the
/// tool axis (vector forms). Default: tip at the program origin, rotary axes
/// at home, axis +Z.
struct InitialPose {
  Eigen::Vector3d tip_mm = Eigen::Vector3d::Zero();
  AxisVector q;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
};

class FiveAxisReader {
 public:
  /// `form` kAuto: detected from the first 2000 lines (buffered).
  /// `arc_chord_mm`: APT arcs about a tilted axis become chords that stand
  /// at most this far off the arc.
  FiveAxisReader(std::istream& in, std::string file, const Machine& machine, InputForm form,
                 const InitialPose& initial, double arc_chord_mm = 0.25e-3);
  ~FiveAxisReader();
  /// The next line; false at the end. Throws InputError with file:line.
  bool next(FiveAxisLine& out);
  InputForm form() const { return form_; }
  /// Whether the last line read ended with a newline (kept on output); an
  /// APT statement's lines but its last always do.
  bool newline() const { return newline_ || !pending_.empty(); }
  /// The program opens with a Fanuc program number (nc::detect_dialect):
  /// axis words without a decimal point are refused (least input
  /// increments on the control), and the post writes every number with one.
  bool fanuc_head() const { return fanuc_head_; }
  const std::string& line_ending() const { return line_ending_; }
  /// The file began with a UTF-8 byte-order mark (taken off, written back
  /// by the post).
  bool byte_order_mark() const { return byte_order_mark_; }

 private:
  bool read_raw(std::string& text);
  // five_axis_input_gcode.cc: the G-code forms.
  struct GcodeWords;
  void gcode_line(const std::string& text, FiveAxisLine& out);
  /// What the five-axis post takes of a line, before the interpreter runs
  /// it: every word, sorted; the words to strip.
  void read_gcode_words(const nc::Block& b, FiveAxisLine& out, GcodeWords& words) const;
  void gcode_g_word(const nc::Word& w, int col, GcodeWords& words) const;
  /// The refusals of the five-axis post that depend on the block's motion.
  void check_gcode_motion(const nc::Block& b, const GcodeWords& words) const;
  /// The move of an interpreted line (out.move, out.has_move) from the
  /// state before it and what it did.
  void gcode_move(const GcodeWords& words, const nc::State& before, const nc::BlockEffect& effect,
                  FiveAxisLine& out) const;
  // The tape frame and TCP switches of the G-code forms
  // (five_axis_input_gcode.cc).
  /// Leader lines and whether the program switches TCP on, from the
  /// buffered first lines.
  void scan_tape();
  /// A line written as it is and not run: leader, '%', after the closing
  /// '%', a program number; Siemens TRAORI/TRAFOOF lines (a comment).
  bool frame_line(const std::string& text, FiveAxisLine& out);
  /// The next APT statement's lines into pending_; false at the end.
  bool apt_statement();
  [[noreturn]] void fail(int column, const std::string& msg) const;

  std::istream& in_;
  std::string file_;
  const Machine& machine_;
  std::deque<std::string> buffered_;  ///< lines read to detect the form
  InputForm form_;
  int line_ = 0;
  bool newline_ = true;
  std::string line_ending_ = "\n";
  bool byte_order_mark_ = false;
  int leader_lines_ = 0;
  bool tape_opened_ = false, tape_closed_ = false;
  /// The program switches TCP on (M428, G43.4, G43.5, G234, M128, TRAORI):
  /// its moves outside the switched-on part are not tool-tip moves.
  bool tcp_program_ = false, tcp_on_ = false;
  bool fanuc_head_ = false;
  bool tcp_by_g_code_ = false;  ///< switched on by G43.4/G43.5/G234: G49 ends it
  bool moved_ = false;

  // The G-code forms' modal state: the interpreter's (program coordinates,
  // no work offsets).
  nc::Interpreter interp_;
  // The APT form's.
  std::unique_ptr<AptReader> apt_;
  std::deque<FiveAxisLine> pending_;  ///< lines of the APT statement read last
};

}  // namespace volmap::post
