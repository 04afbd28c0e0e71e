// LinuxCNC's interpreter as the conformance engine's judge: rs274 run on a
// program (its own HOME: rs274 keeps its tool table in $HOME/.tool.mmap),
// its canonical calls read back as moves in machine coordinates (mm) of the
// controlled point: the printed position (program units) plus the G5x and
// G92 offsets in effect, with the unit and the tool length offset of each
// move.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "gcode/nc_interpreter.h"

namespace volmap::conformance {

struct CanonMove {
  nc::Motion motion;            ///< kLinear (traverse or feed) or kArc; machine mm
  bool feed = false;            ///< a feed (cuts), not a traverse
  double unit_mm = 1.0;         ///< the program unit rs274 printed it in (4 decimals)
  double tool_offset_mm = 0.0;  ///< tool length offset (Z) in effect
};

/// A user M code rs274 ran on a judge copy (judge.h: its line is the
/// comment `(user M102 P1 Q2)`, which rs274 prints as it runs it), and where
/// the controlled point stood (machine mm).
struct UserM {
  std::string text;
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
};

struct Canon {
  bool ok = false;         ///< rs274 read the whole program without an error
  bool timed_out = false;  ///< rs274 did not finish (an endless loop)
  std::string error;       ///< rs274's message ("" when ok), and the line it names
  std::vector<CanonMove> moves;
  std::vector<UserM> user_m;
};

/// Where rs274 runs: its executable, a HOME of its own, the tool table and
/// parameter file it reads (inch values: rs274 without an INI file works in
/// inches), and a folder for its outputs.
struct Rs274Setup {
  std::string home;
  std::string tool_table;  ///< "" : none
  std::string var_file;    ///< "" : none; copied before every run (rs274 writes it back)
  std::string scratch;     ///< folder for the canonical output, the log and the var copy
  double timeout_s = 30.0;
};

/// Runs rs274 on `program` (in its own folder, where rs274 finds the
/// subroutine files) and reads its canonical calls.
Canon run_rs274(const Rs274Setup& setup, const std::string& program);

/// Reads canonical calls (rs274 -g output) into moves and user M codes.
void parse_canon(const std::string& text, Canon& into);

/// rs274's error message with its numbers replaced by '#' (a class key).
std::string normalized_message(const std::string& message);

}  // namespace volmap::conformance
