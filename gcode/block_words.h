// Steps 1 and 2 of the interpreter's validation (nc_interpreter.h): every
// word of a block known, at most one G code per modal group and one M code
// per group (bitmasks, as grbl), no letter twice (except G, M and N); the
// words sorted into slots by letter and group for the steps after.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "gcode/modal_groups.h"
#include "gcode/nc_block.h"

namespace volmap::nc {

struct BlockWords {
  // The slots are filled as the words come; only those a word filled are
  // valid (the masks say which) until null_unfilled(): clearing all 48
  // slots first would cost the common block more than everything else the
  // interpreter does for it.
  std::array<const Word*, kGroupCount> g;
  std::array<const Word*, kMGroupCount> m;
  std::array<const Word*, 26> letter;
  const Word* polar_radius = nullptr;  ///< @: LinuxCNC polar coordinates in the XY plane
  const Word* polar_angle = nullptr;   ///< ^: degrees, counter-clockwise from +X
  unsigned g_mask = 0, m_mask = 0;
  std::uint32_t letter_mask = 0;  ///< bit L - 'A' for each letter of letter[] set

  /// The word of letter L, read through the mask (valid before null_unfilled()).
  const Word* given_word(char L) const {
    const size_t k = static_cast<size_t>(L - 'A');
    return (letter_mask & (1u << k)) ? letter[k] : nullptr;
  }
  bool polar() const { return polar_radius || polar_angle; }
  /// Nulls the slots no word filled: the general steps read every slot.
  void null_unfilled();
};

/// Sorts the words of `b` into `out` (steps 1 and 2). Throws InputError
/// naming `file`, the block's line and the word's column.
/// `rotary_axes`: the rotary axis letters that are words (ProgramSetup).
void collect_block_words(const Block& b, const std::string& file, const std::string& rotary_axes,
                         BlockWords& out);

/// Throws the InputError of a refused block: file:line:column of word `w`
/// (column 0 without one) and `msg`.
[[noreturn]] void refuse_block(const std::string& file, const Block& b, const Word* w,
                               const std::string& msg);

}  // namespace volmap::nc
