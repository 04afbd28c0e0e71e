// The fewest lines any three-axis post could write for a program on a
// machine (docs/post.md "How many lines"): the yardstick of the post's
// output size (bench/post_lines_benchmark.cc, tests/postproc/post_lines_test.cc).
//
// Counted from the program's nominal moves and the error model alone,
// independently of how the post cuts:
//  - every line of the program is written at least once;
//  - where an axis with lost motion turns round, at the start of a move or
//    inside an arc, and the jump of its error there exceeds the tolerance,
//    the tool cannot follow the nominal path through it in one block: the
//    play must be taken up by a move of its own (one more line), and an arc
//    cut there (one more);
//  - an axis that a straight move does not move, but whose correction
//    creeps along it by more than the tolerance against the way the axis
//    last moved, needs its play taken up by a move of its own;
//  - a canned cycle the controller repeats at several holes (L, G91, polar
//    words) needs a block per hole (each hole its own correction);
//  - a straight feed move needs as many pieces as the fewest chords between
//    exactly corrected points along it whose actual paths stay within the
//    tolerance (greedy: from each cut the longest piece that keeps it, found
//    by bisection and checked at 32 points; the minimum when a piece that
//    keeps the tolerance has parts that keep it too).
// Arcs are counted as one arc each (plus their forced cuts): the bound does
// not charge an arc for the field's bending, since an arc's centre and
// radius can follow it.
#pragma once

#include <cstdint>
#include <istream>
#include <string>

#include "core/model/error_model.h"
#include "gcode/program_setup.h"

namespace volmap::post {

struct LineBound {
  std::uint64_t lines_in = 0;     ///< the program's lines
  std::uint64_t turn_lines = 0;   ///< lines forced by axes turning round with play
  std::uint64_t chord_lines = 0;  ///< pieces of straight moves beyond their first
  std::uint64_t hole_lines = 0;   ///< holes of repeated cycles beyond their block's first
  std::uint64_t lower_bound() const { return lines_in + turn_lines + chord_lines + hole_lines; }
};

/// The bound for the program read from `in` (flattened as the post reads
/// it; its subroutine files on `subroutine_path`), at tolerance_mm.
LineBound fewest_lines(std::istream& in, const std::string& name, const Machine& machine,
                       const ErrorSet& errors, const nc::ProgramSetup& setup, double tolerance_mm,
                       const std::vector<std::string>& subroutine_path = {});

}  // namespace volmap::post
