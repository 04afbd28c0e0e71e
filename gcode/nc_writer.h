// Writing NC blocks: deterministic number formatting and the rewrite of a
// line that keeps every word it does not change, in order, byte for byte.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "gcode/nc_block.h"

namespace volmap::nc {

/// Fixed `decimals`, trailing zeros and a trailing point removed, never
/// "-0": 12.5 -> "12.5", 3.0 -> "3", -0.00001 (4 decimals) -> "0".
std::string format_number(double value, int decimals);
/// The same appended to `out` (no string of its own).
void append_number(std::string& out, double value, int decimals);
/// Room format_number_fast needs at its output pointer.
inline constexpr std::size_t kNumberRoom = 24;

namespace detail {
// The 8 decimal digits of v < 1e8 (zero-padded) as byte values 0..9, the
// most significant in the lowest byte (memory order on little-endian x86):
// splits by 10000, 100 and 10 done on all lanes of a 64-bit word at once by
// multiply-and-shift (exact for these ranges), no loop, no division.
inline std::uint64_t eight_digits(std::uint32_t v) {
  const std::uint64_t hl = (v / 10000) | (std::uint64_t{v % 10000} << 32);
  const std::uint64_t q = ((hl * 10486) >> 20) & 0x0000007F0000007Full;  // x / 100 for x < 10000
  const std::uint64_t hhll = q | ((hl - q * 100) << 16);
  const std::uint64_t q2 = ((hhll * 103) >> 10) & 0x000F000F000F000Full;  // x / 10 for x < 100
  return q2 | ((hhll - q2 * 10) << 8);
}
/// format_number_fast for k >= 1e8 or more than 7 decimals.
char* format_fixed_wide(double value, int decimals, std::uint32_t k, char* out);
}  // namespace detail

/// format_number's text written at `out` (kNumberRoom bytes of room) for
/// the values of its integer fast path (the usual ones: below 1e9 scaled,
/// at most 9 decimals, not near a rounding tie); returns the text's end, or
/// nullptr (nothing written) when the value needs format_number's general
/// path. No allocation, inline: the post's writer puts numbers straight
/// into its output buffer.
///
/// value x 10^decimals is rounded to an integer k and printed with its
/// decimal point when k is certainly the correctly rounded one (the scaled
/// value is not within 1e-6 of a tie and below 1e9). The product carries at
/// most one rounding (relative 1.1e-16), far less than the margin, so the
/// digits equal fmt's correctly rounded ones.
///
/// With `read`, *read is also set to the value the text reads back as (what
/// strtod gives for it), without reading it: +-k / 10^decimals, one
/// correctly rounded division of exact operands, i.e. the double nearest to
/// the decimal the text is.
inline char* format_number_fast(double value, int decimals, char* out, double* read = nullptr) {
  static constexpr double kPow10[] = {1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
  if (decimals < 0 || decimals > 9) return nullptr;
  const double scaled = std::abs(value) * kPow10[decimals];
  if (!(scaled < 1e9)) return nullptr;  // NaN, infinities and large values too
  // floor(scaled + 0.5) as a truncation (scaled >= 0; std::floor is a libm
  // call without SSE4.1); below 1e9 + 0.5, so it fits 32 bits.
  const auto k = static_cast<std::uint32_t>(scaled + 0.5);
  if (std::abs(std::abs(scaled - static_cast<double>(k)) - 0.5) < 1e-6) return nullptr;
  if (read) {
    const double r = static_cast<double>(k) / kPow10[decimals];
    *read = value < 0 && k != 0 ? -r : r;
  }
  if (k == 0) {  // never "-0"
    *out = '0';
    return out + 1;
  }
  if (k >= 100000000 || decimals > 7) return detail::format_fixed_wide(value, decimals, k, out);
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "eight_digits' byte order");
  // All digits of k at once, then the integer part (at least one digit),
  // the point and the fraction without its trailing zeros cut out of them
  // by shifts. Stores are 8 bytes wide, within kNumberRoom: 1 + 8 + 1 + 8.
  char* p = out;
  if (value < 0) *p++ = '-';
  const std::uint64_t raw = detail::eight_digits(k);
  const int significant = 8 - (__builtin_ctzll(raw) >> 3);  // k >= 1: some byte is nonzero
  const int shown = significant > decimals ? significant : decimals + 1;
  const std::uint64_t ascii = raw + 0x3030303030303030ull;
  const std::uint64_t lead = ascii >> (8 * (8 - shown));
  std::memcpy(p, &lead, 8);
  p += shown - decimals;
  if (decimals == 0) return p;
  const std::uint64_t frac = raw >> (8 * (8 - decimals));
  if (frac == 0) return p;
  *p = '.';
  const std::uint64_t frac_ascii = ascii >> (8 * (8 - decimals));
  std::memcpy(p + 1, &frac_ascii, 8);
  return p + 1 + (8 - (__builtin_clzll(frac) >> 3));  // up to its last nonzero digit
}

/// An edit of one block: words to delete (indices into Block::words) and
/// text to put at the place of the first deleted word (or, with none
/// deleted, after the last word, before a trailing comment).
struct BlockEdit {
  std::vector<int> remove;
  std::string insert;
  /// Words whose number is replaced in place (index, the new number's
  /// text): the letter and everything around the word stay as they were.
  std::vector<std::pair<int, std::string>> renumber;
  /// With nothing removed: the insert goes after this word (-1: after the
  /// last word, before a trailing comment).
  int insert_after = -1;
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
char* apply_edit_to(const Block& b, const int* remove, std::size_t count, std::string_view insert,
                    bool spaces, char* out);

/// Upper or lower case as the block writes its letters (first letter word).
bool block_uses_lowercase(const Block& b);
/// Whether the block separates words with spaces (else they are packed).
bool block_uses_spaces(const Block& b);

}  // namespace volmap::nc
