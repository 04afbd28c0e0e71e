// volmap post, three-axis: rewrites an NC program written for the ideal
// machine so that the real machine (its error model) cuts the nominal
// geometry.
//
// Policy (docs/post.md):
//  - every commanded point moves to the solution of x_cmd + e(x_cmd) = x_nom
//    (Corrector), in the frame and units of the program (G20/G21, G90/G91,
//    G53, G54-G59.3, tool length from G43);
//  - feed moves (G1) are split until the actual path stays within the
//    tolerance of the nominal line: on straight pieces by a bound of the
//    deviation along the whole piece (Corrector::chord_deviation_bound),
//    where that bound is too large by samples at 1/4, 1/2, 3/4 of the piece;
//    arcs (G2/G3, helices, full circles) are linearised the same way, with
//    the chord error inside the same tolerance; under G93 every piece gets
//    its inverse-time F so the programmed time is kept;
//  - rapid moves (G0) are corrected at their end point only (not cutting);
//    a rapid before X, Y and Z are all known passes unchanged;
//  - canned cycles: the hole position and depth (X, Y, Z at the bottom) and
//    the R plane are corrected; every cycle block then states Z and R;
//  - lines that need no change are written byte for byte; a changed line
//    keeps its other words in their order; added lines follow it.
// Streaming, constant memory: one block at a time.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/model/error_model.h"
#include "gcode/nc_interpreter.h"
#include "gcode/program_reader.h"
#include "postproc/three_axis/self_check.h"

namespace volmap::maps {
struct VolumetricTable;
}

namespace volmap::post {

struct PostOptions {
  double tolerance_mm = 1e-3;
  int decimals = -1;  ///< -1: 4 for mm blocks, 5 for inch blocks
  OutsidePolicy outside = OutsidePolicy::kError;
  /// Canned cycles G81 G82 G85 G89 written out as their moves (G0, G1
  /// segmented like any feed move, G4), so that the feed into the hole (and
  /// out of it for G85 G89) keeps the tolerance too, not only the hole's
  /// bottom. Other cycles (pecking, spindle stops) are refused with it.
  bool expand_cycles = false;
  /// Arcs and helices (G2 G3) stay arcs (the default): the end point
  /// corrected, the centre moved by the mean correction of its ends, cut
  /// only where lost motion or the field needs it, each arc the controller
  /// then runs checked against the nominal one (docs/post.md "Arcs kept as
  /// arcs"); an arc that cannot be kept so is linearised within the
  /// tolerance. false (--linearize-arcs): every arc linearised.
  bool keep_arcs = true;
  /// Plain lines of axis words take the post's shortcut past the lexer's
  /// Block, the interpreter's checks and the line editor (docs/post.md
  /// "Speed"); the output is the same byte for byte. false: every line the
  /// general way (the tests compare both).
  bool shortcuts = true;
  /// The first this many lines that come out other than they went in are
  /// kept in PostReport::changes (for --report); 0: none.
  std::size_t max_recorded_changes = 0;
  /// Where `O<name> call` finds NAME.ngc (LinuxCNC's SUBROUTINE_PATH).
  std::vector<std::string> subroutine_path;
  /// Every written line read back and its points run on the simulated
  /// machine before they are committed (self_check.h); a point beyond the
  /// tolerance is a refusal (InputError) at the line it was written for.
  bool self_check = true;
  /// The flattener's endless-loop guard (flatten::kMaxExecutedLines; the
  /// fuzz targets take fewer).
  long max_executed_lines = nc::flatten::kMaxExecutedLines;
};

struct PostReport {
  std::uint64_t lines = 0;
  std::uint64_t lines_changed = 0;
  std::uint64_t lines_added = 0;
  std::uint64_t points_corrected = 0;
  /// Blocks that move the machine (feed, rapid, cycle, G28/G30): a program
  /// without any is refused (nothing to post; it may not be what was meant).
  std::uint64_t moves = 0;
  double max_correction_mm = 0.0;
  std::uint64_t arcs_kept = 0;        ///< arcs written as one arc
  std::uint64_t arcs_split = 0;       ///< arcs written as several arcs
  std::uint64_t arcs_linearized = 0;  ///< arcs written as straight pieces
  /// The largest deviation of the actual path from the nominal one between
  /// the points of a feed move, as the post predicts it (its bound, or its
  /// largest sample where the bound was not enough; mm).
  double max_deviation_mm = 0.0;
  /// Lines of the program file, and of the output (leader and trailer
  /// included in both).
  std::uint64_t lines_in = 0, lines_out = 0;
  /// Canned-cycle blocks kept as cycles whose feed into the hole, which the
  /// controller computes, leaves the tolerance: line, predicted deviation
  /// (mm), file (empty: the program). The first kMaxCycleWarnings only;
  /// cycle_warning_count counts all.
  struct CycleWarning {
    int line;
    double deviation_mm;
    std::string file;
    bool rigid_tap = false;  ///< a G33.1 tap (it cannot be split or written out)
  };
  static constexpr std::size_t kMaxCycleWarnings = 1000;
  std::vector<CycleWarning> cycle_warnings;
  std::uint64_t cycle_warning_count = 0;
  /// Lines that came out other than they went in (the first
  /// PostOptions::max_recorded_changes): file (empty: the program), line,
  /// the line as read, what was written for it (its lines, '\n' between).
  struct Change {
    std::string file;
    int line;
    std::string in, out;
  };
  std::vector<Change> changes;
  /// The program was flattened, but no line of the flattened part needed a
  /// change: that part was written back as it was read, not flat.
  bool flattened_written_as_read = false;
  /// Cutter compensation kept (G41/G42): moves under it, the largest tool
  /// radius, and the largest bound of how far the controller's offset of
  /// the corrected contour can leave the tool off (mm; docs/post.md).
  std::uint64_t comp_moves = 0;
  double comp_radius_mm = 0.0, comp_bound_mm = 0.0;
  /// How the program was read: its tape frame, whether it was flattened.
  nc::ReadReport read;
  /// The self-check ran (PostOptions::self_check, a machine with errors):
  /// the points it measured and the farthest from the nominal path.
  bool self_checked = false;
  SelfCheckStats self_check;
};

PostReport post_program(std::istream& in, const std::string& in_name, std::ostream& out,
                        const Machine& machine, const ErrorSet& errors,
                        const nc::ProgramSetup& setup, const PostOptions& options);
/// The same from a three-axis compensation table (volmap map) instead of
/// the errors: the table's interpolated tool-tip error stands for the model
/// (Corrector's table form). Programs that change the tool length (G43 with
/// another tool) are refused at that line: the table holds the errors of the
/// machine file's tool only.
PostReport post_program(std::istream& in, const std::string& in_name, std::ostream& out,
                        const Machine& machine, const maps::VolumetricTable& table,
                        const nc::ProgramSetup& setup, const PostOptions& options);

}  // namespace volmap::post
