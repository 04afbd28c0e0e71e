// Writing NC blocks: deterministic number formatting and the rewrite of a
// line that keeps every word it does not change, in order, byte for byte.
#pragma once

#include <string>
#include <vector>

#include "gcode/nc_block.h"

namespace volmap::nc {

/// Fixed `decimals`, trailing zeros and a trailing point removed, never
/// "-0": 12.5 -> "12.5", 3.0 -> "3", -0.00001 (4 decimals) -> "0".
std::string format_number(double value, int decimals);
/// The same appended to `out` (no string of its own: the writer's hot path).
void append_number(std::string& out, double value, int decimals);

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

/// Upper or lower case as the block writes its letters (first letter word).
bool block_uses_lowercase(const Block& b);
/// Whether the block separates words with spaces (else they are packed).
bool block_uses_spaces(const Block& b);

}  // namespace volmap::nc
