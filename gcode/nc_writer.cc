#include "gcode/nc_writer.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <fmt/format.h>

namespace volmap::nc {

namespace {
constexpr char kDigitPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

// The `count` decimal digits of v (zero-padded), ending at `end`, two at a
// time (half the divisions of one at a time).
inline void write_digits(std::uint32_t v, int count, char* end) {
  for (; count >= 2; count -= 2) {
    const std::uint32_t q = v / 100, two = v - q * 100;
    end -= 2;
    std::memcpy(end, kDigitPairs + 2 * two, 2);
    v = q;
  }
  if (count) *--end = static_cast<char>('0' + v % 10);
}

// The 8 decimal digits of v < 1e8 (zero-padded) as byte values 0..9, the
// most significant in the lowest byte (memory order on little-endian x86):
// two splits by 10000, 100 and 10 done on all lanes of a 64-bit word at
// once by multiply-and-shift (exact for these ranges), no loop.
inline std::uint64_t eight_digits(std::uint32_t v) {
  const std::uint64_t hl = (v / 10000) | (std::uint64_t{v % 10000} << 32);
  const std::uint64_t q = ((hl * 10486) >> 20) & 0x0000007F0000007Full;  // x / 100 for x < 10000
  const std::uint64_t hhll = q | ((hl - q * 100) << 16);
  const std::uint64_t q2 = ((hhll * 103) >> 10) & 0x000F000F000F000Full;  // x / 10 for x < 100
  return q2 | ((hhll - q2 * 10) << 8);
}

// Decimal digits of v < 1e9 (at least 1).
inline int digit_count(std::uint32_t v) {
  static constexpr std::uint32_t kPow10u[] = {1, 10, 100, 1000, 10000, 100000, 1000000, 10000000,
                                              100000000, 1000000000};
  // floor(log10) from the bit length (1233 / 4096 ~ log10(2)), corrected by one comparison.
  const int bits = 32 - __builtin_clz(v | 1);
  const int guess = (bits * 1233) >> 12;
  return guess + (v >= kPow10u[guess] || v == 0 ? 1 : 0);
}
}  // namespace

// Fast path of format_number: value x 10^decimals rounded to an integer and
// printed with its decimal point, when that integer is certainly the
// correctly rounded one (the scaled value is not within 1e-6 of a tie and
// below 1e9). The product carries at most one rounding (relative 1.1e-16),
// far less than the margin, so the digits equal fmt's correctly rounded
// ones. Otherwise (ties, huge values, more than 9 decimals) fmt decides.
char* format_number_fast(double value, int decimals, char* out) {
  static constexpr double kPow10[] = {1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
  static constexpr std::uint32_t kPow10u[] = {1, 10, 100, 1000, 10000, 100000, 1000000, 10000000,
                                              100000000, 1000000000};
  if (decimals < 0 || decimals > 9) return nullptr;
  const double scaled = std::abs(value) * kPow10[decimals];
  if (!(scaled < 1e9)) return nullptr;  // NaN, infinities and large values too
  // floor(scaled + 0.5) as a truncation (scaled >= 0; std::floor is a libm
  // call without SSE4.1); below 1e9 + 0.5, so it fits 32 bits.
  const auto k = static_cast<std::uint32_t>(scaled + 0.5);
  if (std::abs(std::abs(scaled - static_cast<double>(k)) - 0.5) < 1e-6) return nullptr;
  if (k == 0) {  // never "-0"
    *out = '0';
    return out + 1;
  }
  char* p = out;
  if (value < 0) *p++ = '-';
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "eight_digits' byte order");
  if (k < 100000000 && decimals <= 7) {
    // The usual case: all digits of k at once, then the integer part (at
    // least one digit), the point and the fraction without its trailing
    // zeros cut out of them by shifts. Stores are 8 bytes wide, within
    // kNumberRoom: 1 + 8 + 1 + 8 at most.
    const std::uint64_t raw = eight_digits(k);
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
  const std::uint32_t int_part = k / kPow10u[decimals], frac = k - int_part * kPow10u[decimals];
  const int int_digits = digit_count(int_part);
  p += int_digits;
  write_digits(int_part, int_digits, p);
  if (frac == 0) return p;
  // All the fraction's digits, then its trailing zeros dropped (a nonzero
  // digit stops that before the point).
  *p++ = '.';
  p += decimals;
  write_digits(frac, decimals, p);
  while (p[-1] == '0') --p;
  return p;
}

std::string format_number(double value, int decimals) {
  char buf[kNumberRoom];
  if (const char* end = format_number_fast(value, decimals, buf)) return std::string(buf, static_cast<std::size_t>(end - buf));
  std::string s = fmt::format("{:.{}f}", value, decimals);
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

bool block_uses_lowercase(const Block& b) {
  for (const Word& w : b.words) {
    const char c = b.text[w.begin];
    if (std::isalpha(static_cast<unsigned char>(c))) return std::islower(static_cast<unsigned char>(c)) != 0;
  }
  return false;
}

bool block_uses_spaces(const Block& b) {
  for (size_t k = 1; k < b.words.size(); ++k) {
    const Word& prev = b.words[k - 1];
    const Word& w = b.words[k];
    if (w.begin > prev.end) return true;
  }
  return b.words.size() <= 1;  // a single word: spaces by default
}

BlockStyle block_style(const Block& b) {
  // The same answers as block_uses_lowercase and block_uses_spaces (word
  // letters are ASCII: isalpha/islower are these comparisons in any locale
  // for them).
  BlockStyle st;
  bool case_known = false, spaced = false;
  const size_t n = b.words.size();
  for (size_t k = 0; k < n; ++k) {
    const Word& w = b.words[k];
    if (!case_known) {
      const char c = b.text[w.begin];
      if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z')) {
        case_known = true;
        st.lowercase = c >= 'a';
      }
    }
    if (k > 0 && w.begin > b.words[k - 1].end) spaced = true;
  }
  st.spaces = spaced || n <= 1;
  return st;
}

char* apply_edit_to(const Block& b, const int* remove, std::size_t count, std::string_view insert, bool spaces,
                    char* out) {
  // apply_edit's steps on a raw buffer (no capacity checks: the caller made
  // room for everything the line can become).
  const std::string_view t = b.text;
  char* const line = out;
  size_t pos = 0;
  bool inserted = insert.empty();
  for (std::size_t r = 0; r < count; ++r) {
    const Word& w = b.words[static_cast<size_t>(remove[r])];
    size_t cut = w.begin;
    if (cut > pos && t[cut - 1] == ' ') --cut;  // the separating space goes with the word
    std::memcpy(out, t.data() + pos, cut - pos);
    out += cut - pos;
    if (!inserted) {
      if (out != line && spaces && out[-1] != ' ' && out[-1] != '\t') *out++ = ' ';
      std::memcpy(out, insert.data(), insert.size());
      out += insert.size();
      inserted = true;
    }
    pos = w.end;
  }
  if (!inserted) {
    // Append after the last word, before any trailing comment or '\r'.
    const size_t at = b.words.empty() ? 0 : b.words.back().end;
    std::memcpy(out, t.data() + pos, at - pos);
    out += at - pos;
    if (spaces && out != line && out[-1] != ' ') *out++ = ' ';
    std::memcpy(out, insert.data(), insert.size());
    out += insert.size();
    pos = at;
  }
  std::memcpy(out, t.data() + pos, t.size() - pos);
  return out + (t.size() - pos);
}

std::string apply_edit(const Block& b, const BlockEdit& edit) {
  std::string out;
  apply_edit(b, edit, out);
  return out;
}

void apply_edit(const Block& b, const BlockEdit& edit, std::string& out) {
  std::vector<int> sorted;
  const std::vector<int>* removep = &edit.remove;
  if (!std::is_sorted(edit.remove.begin(), edit.remove.end())) {
    sorted = edit.remove;
    std::sort(sorted.begin(), sorted.end());
    removep = &sorted;
  }
  const std::vector<int>& remove = *removep;
  const std::string& t = b.text;
  const bool spaces = block_uses_spaces(b);
  out.clear();
  size_t pos = 0;
  bool inserted = edit.insert.empty();
  for (int idx : remove) {
    const Word& w = b.words[static_cast<size_t>(idx)];
    size_t cut = w.begin;
    if (cut > pos && t[cut - 1] == ' ') --cut;  // the separating space goes with the word
    out.append(t, pos, cut - pos);
    if (!inserted) {
      if (!out.empty() && spaces && out.back() != ' ' && out.back() != '\t') out += ' ';
      out += edit.insert;
      inserted = true;
    }
    pos = w.end;
  }
  if (!inserted) {
    // Append after the last word, before any trailing comment or '\r'.
    size_t at = b.words.empty() ? 0 : b.words.back().end;
    out.append(t, pos, at - pos);
    if (spaces && !out.empty() && out.back() != ' ') out += ' ';
    out += edit.insert;
    pos = at;
  }
  out.append(t, pos, std::string::npos);
}

}  // namespace volmap::nc
