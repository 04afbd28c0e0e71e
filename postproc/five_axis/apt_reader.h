// Reading APT / CLDATA cutter-location files (ISO 4343 records in the
// dialects CAM systems write) into the five-axis post's nominal moves.
// docs/post-five-axis.md "APT / CLDATA" lists every record, its meaning, the
// source of that meaning and what volmap does with it. The rule: a record
// that can change where the tool goes is read exactly or refused with
// file:line; only records that move nothing become comments.
//
// Frames and units: the GOTO points are the tool tip in the program's frame
// (the workpiece frame w of the machine), read in the file's units and kept
// in mm; the tool axis points from the tip into the spindle.
#pragma once

#include <Eigen/Core>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "postproc/five_axis/five_axis_input.h"

namespace volmap::post {

/// The CAM system that wrote a CL file, where the same record means
/// different things (CIRCLE's direction, CYCLE's depth sign, CSYS).
enum class AptDialect { kUnknown, kNx, kSolidworks, kCreo, kNcl };
const char* apt_dialect_name(AptDialect d);

/// One APT statement: continuation lines joined, `$$` comment removed.
struct AptRecord {
  std::string key;                ///< upper case, blanks collapsed: "GOTO", "TOOL PATH", "PARTNO"
  std::vector<std::string> args;  ///< upper case, trimmed, comma separated (after the '/')
  std::string text;               ///< the statement as written (trimmed)
  bool slash = false;             ///< written KEY/...; false: KEY [text]
};
AptRecord parse_apt_record(const std::string& statement);

/// Whether `s` is a number as APT writes them ("1.", ".5", "-0.005061",
/// "+2", "1.5E-3"); its value in v.
bool apt_number(const std::string& s, double& v);

/// A record or word as a message shows it: at most 60 characters, bytes
/// outside printable ASCII as \xNN.
std::string apt_shown(const std::string& text);

class AptReader {
 public:
  /// `q`: the machine's rotary angles before the program (rad, AxisVector
  /// order); `chord_mm`: how far the chords of an arc about a tilted axis
  /// may stand off the arc.
  AptReader(std::string file, const AxisVector& q, const InitialPose& initial, double chord_mm);

  /// One statement starting at `line` (continuations joined, `$$` comment
  /// removed, not empty): the lines it gives, appended to `out`. Throws
  /// InputError with file:line.
  void statement(const std::string& text, int line, std::deque<FiveAxisLine>& out);
  /// A line of numbers only: more points of the GOTO before it (Creo's
  /// multi-point GOTO). False when no GOTO is open.
  bool more_points(const std::string& text, int line, std::deque<FiveAxisLine>& out);
  /// A `$$` comment (the text after `$$`): kept as a comment; read for the
  /// dialect cues and Creo's CUTCOM_GEOMETRY_TYPE.
  void comment(const std::string& text, int line, std::deque<FiveAxisLine>& out);
  /// The end of the file: a CIRCLE still waiting for its GOTO is an error;
  /// a file without FINI (NX writes none) gets the program end M2, once.
  void finish(int line, std::deque<FiveAxisLine>& out);
  AptDialect dialect() const { return dialect_; }
  /// The units of a file without UNITS/: those of its first FEDRAT's unit
  /// word (NX writes no UNITS record), found by the caller ahead of the
  /// reading; `line`: that FEDRAT's. Said in a comment line.
  void preset_units(double unit_mm, int line, std::deque<FiveAxisLine>& out);

 private:
  struct Cycle {
    std::string type;            ///< DRILL, DEEP, DEEP2, BRKCHP, REAM
    double depth_mm = 0;         ///< below the GOTO point, along the tool axis
    double rapto_mm = 0;         ///< R level above the point
    double retract_mm = 0;       ///< where the tool returns after each hole, above the point
    double first_peck_mm = 0;    ///< 0: no pecking
    double peck_mm = 0;          ///< the pecks after the first
    double dwell_s = 0;          ///< at the bottom
    double feed_mm_per_min = 0;  ///< of the feed moves
  };
  struct Circle {
    Eigen::Vector3d centre_mm, axis;  ///< axis: the direction of turning (right hand)
    double radius_mm = 0;             ///< 0: not given (SOLIDWORKS CAM)
    int line = 0;
  };

  [[noreturn]] void fail(const std::string& msg) const;
  void add_text(const std::string& g_code, std::deque<FiveAxisLine>& out) const;
  void add_comment(const AptRecord& r, std::deque<FiveAxisLine>& out) const;
  void note_dialect(const AptRecord& r);
  void motion_record(const AptRecord& r, std::deque<FiveAxisLine>& out);
  bool position_record(const AptRecord& r, std::deque<FiveAxisLine>& out);
  bool machine_record(const AptRecord& r, std::deque<FiveAxisLine>& out);
  bool frame_record(const AptRecord& r, std::deque<FiveAxisLine>& out);
  std::vector<double> numbers(const AptRecord& r, size_t from = 0) const;
  double feed_of(const AptRecord& r, size_t from, bool& per_rev) const;

  // apt_motion.cc
  /// The tip (program units) and, with six values, the tool axis of a GOTO.
  void goto_point(const std::vector<double>& v, std::deque<FiveAxisLine>& out);
  void add_move(const Eigen::Vector3d& end_mm, const Eigen::Vector3d& axis, bool rapid, double feed,
                std::deque<FiveAxisLine>& out);
  void circle_record(const AptRecord& r);
  void arc_to(const Eigen::Vector3d& end_mm, const Eigen::Vector3d& axis,
              std::deque<FiveAxisLine>& out);
  void cycle_record(const AptRecord& r, std::deque<FiveAxisLine>& out);
  void hole(const Eigen::Vector3d& top_mm, std::deque<FiveAxisLine>& out);
  double cycle_depth(double fedto) const;

  std::string file_;
  int line_ = 0;
  double chord_mm_;
  AptDialect dialect_ = AptDialect::kUnknown;
  bool creo_profile_points_ = false;  ///< Creo: CUTCOM_GEOMETRY_TYPE other than OUTPUT_ON_CENTER

  double unit_mm_ = 1.0;
  double feed_ = 0.0;  ///< mm/min
  Eigen::Vector3d tip_mm_ = Eigen::Vector3d::Zero();
  AxisVector q_;
  Eigen::Vector3d axis_ = Eigen::Vector3d::UnitZ();
  bool rapid_next_ = false;       ///< RAPID: the next motion record only
  bool goto_open_ = false;        ///< the last record was a GOTO (more points may follow)
  bool goto_rapid_ = false;       ///< that GOTO's RAPID
  bool moved_ = false;            ///< a motion record was read
  std::optional<Circle> circle_;  ///< CIRCLE read, its GOTO not yet
  bool circle_goto_ = false;      ///< the open GOTO is the circle's
  std::optional<Cycle> cycle_, last_cycle_;
  bool ended_ = false;  ///< FINI read, or the end of the file
  bool spindle_ccw_ = false;
  double spindle_rpm_ = 0.0;
  std::optional<Eigen::Vector3d> csys_axis_;  ///< SOLIDWORKS CAM CSYS's third column, to check
};

}  // namespace volmap::post
