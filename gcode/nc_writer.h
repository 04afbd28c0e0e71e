// Writing NC blocks: deterministic number formatting and the rewrite of a
// line that keeps every word it does not change, in order, byte for byte.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "gcode/nc_block.h"

namespace volmap::nc {

/// Fixed `decimals`, trailing zeros and a trailing point removed, never
/// "-0": 12.5 -> "12.5", 3.0 -> "3", -0.00001 (4 decimals) -> "0".
std::string format_number(double value, int decimals);
/// Room format_number_fast needs at its output pointer.
inline constexpr std::size_t kNumberRoom = 24;
/// format_number's text written at `out` (kNumberRoom bytes of room) for
/// the values of its integer fast path (the usual ones: below 1e9 scaled,
/// at most 9 decimals, not near a rounding tie); returns the text's end, or
/// nullptr (nothing written) when the value needs format_number's general
/// path. No allocation: the post's writer puts numbers straight into its
/// output buffer.
char* format_number_fast(double value, int decimals, char* out);

/// An edit of one block: words to delete (indices into Block::words) and
/// text to put at the place of the first deleted word (or, with none
/// deleted, after the last word, before a trailing comment).
struct BlockEdit {
  std::vector<int> remove;
  std::string insert;
};

/// Applies an edit to the block's text. Separators: a deleted word takes one
/// space before it with it; inserted text gets a space before it when the
/// line separates its words with spaces.
std::string apply_edit(const Block& b, const BlockEdit& edit);
/// The same into `out` (replaced; its storage reused).
void apply_edit(const Block& b, const BlockEdit& edit, std::string& out);
/// The same written at `out`, which has room for b.text.size() +
/// insert.size() + 1 bytes; `remove` (count indices) strictly ascending,
/// `spaces` as block_uses_spaces(b). Returns the end of the text written.
char* apply_edit_to(const Block& b, const int* remove, std::size_t count, std::string_view insert, bool spaces,
                    char* out);

/// Upper or lower case as the block writes its letters (first letter word).
bool block_uses_lowercase(const Block& b);
/// Whether the block separates words with spaces (else they are packed).
bool block_uses_spaces(const Block& b);
/// Both of the above in one pass over the words.
struct BlockStyle {
  bool lowercase = false, spaces = true;
};
BlockStyle block_style(const Block& b);

}  // namespace volmap::nc
