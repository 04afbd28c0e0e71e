#include "gcode/nc_writer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

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

// Decimal digits of v < 1e9 (at least 1).
inline int digit_count(std::uint32_t v) {
  static constexpr std::uint32_t kPow10u[] = {1,      10,      100,      1000,      10000,
                                              100000, 1000000, 10000000, 100000000, 1000000000};
  // floor(log10) from the bit length (1233 / 4096 ~ log10(2)), corrected by one comparison.
  const int bits = 32 - __builtin_clz(v | 1);
  const int guess = (bits * 1233) >> 12;
  return guess + (v >= kPow10u[guess] || v == 0 ? 1 : 0);
}
}  // namespace

// format_number_fast's other cases (see nc_writer.h): k = value x
// 10^decimals rounded, k >= 1e8 or more than 7 decimals; digits two at a
// time from the right.
char* detail::format_fixed_wide(double value, int decimals, std::uint32_t k, char* out) {
  static constexpr std::uint32_t kPow10u[] = {1,      10,      100,      1000,      10000,
                                              100000, 1000000, 10000000, 100000000, 1000000000};
  char* p = out;
  if (value < 0) *p++ = '-';
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

void append_number(std::string& out, double value, int decimals) {
  char buf[kNumberRoom];
  if (const char* end = format_number_fast(value, decimals, buf))
    out.append(buf, static_cast<std::size_t>(end - buf));
  else
    out += format_number(value, decimals);
}

std::string format_number(double value, int decimals) {
  char buf[kNumberRoom];
  if (const char* end = format_number_fast(value, decimals, buf))
    return std::string(buf, static_cast<std::size_t>(end - buf));
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
    if (std::isalpha(static_cast<unsigned char>(c)))
      return std::islower(static_cast<unsigned char>(c)) != 0;
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

namespace {
// memcpy for the short pieces of a line (a word, the gap between words):
// two overlapping word-sized moves instead of a library call.
inline char* copy_bytes(char* out, const char* from, size_t n) {
  if (n >= 8 && n <= 16) {
    std::uint64_t a, b;
    std::memcpy(&a, from, 8);
    std::memcpy(&b, from + n - 8, 8);
    std::memcpy(out, &a, 8);
    std::memcpy(out + n - 8, &b, 8);
  } else if (n >= 4 && n < 8) {
    std::uint32_t a, b;
    std::memcpy(&a, from, 4);
    std::memcpy(&b, from + n - 4, 4);
    std::memcpy(out, &a, 4);
    std::memcpy(out + n - 4, &b, 4);
  } else if (n < 4) {
    for (size_t k = 0; k < n; ++k) out[k] = from[k];
  } else {
    std::memcpy(out, from, n);
  }
  return out + n;
}
}  // namespace

char* apply_edit_to(const Block& b, const int* remove, std::size_t count, std::string_view insert,
                    bool spaces, char* out) {
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
    out = copy_bytes(out, t.data() + pos, cut - pos);
    if (!inserted) {
      if (out != line && spaces && out[-1] != ' ' && out[-1] != '\t') *out++ = ' ';
      out = copy_bytes(out, insert.data(), insert.size());
      inserted = true;
    }
    pos = w.end;
  }
  if (!inserted) {
    // Append after the last word, before any trailing comment or '\r'.
    const size_t at = b.words.empty() ? 0 : b.words.back().end;
    out = copy_bytes(out, t.data() + pos, at - pos);
    if (spaces && out != line && out[-1] != ' ') *out++ = ' ';
    out = copy_bytes(out, insert.data(), insert.size());
    pos = at;
  }
  return copy_bytes(out, t.data() + pos, t.size() - pos);
}

std::string apply_edit(const Block& b, const BlockEdit& edit) {
  std::string out;
  apply_edit(b, edit, out);
  return out;
}

void apply_edit(const Block& b, const BlockEdit& edit, std::string& out) {
  // The words the edit touches, in the line's order: removed (-1) or
  // renumbered (their index in edit.renumber); on the stack for the usual
  // handful (no allocation per line).
  constexpr std::size_t kOnStack = 16;
  std::pair<int, int> on_stack[kOnStack];
  std::vector<std::pair<int, int>> on_heap;
  const std::size_t most = edit.remove.size() + edit.renumber.size() + 1;
  if (most > kOnStack) on_heap.resize(most);
  std::pair<int, int>* const touched = most > kOnStack ? on_heap.data() : on_stack;
  std::size_t n = 0;
  for (int idx : edit.remove) touched[n++] = {idx, -1};
  for (std::size_t k = 0; k < edit.renumber.size(); ++k)
    touched[n++] = {edit.renumber[k].first, static_cast<int>(k)};
  constexpr int kInsertAfter = std::numeric_limits<int>::max();  // after the word's own edit
  if (edit.remove.empty() && edit.insert_after >= 0 && !edit.insert.empty())
    touched[n++] = {edit.insert_after, kInsertAfter};
  std::sort(touched, touched + n);
  const std::string& t = b.text;
  const bool spaces = block_uses_spaces(b);
  out.clear();
  size_t pos = 0;
  bool inserted = edit.insert.empty();
  for (std::size_t k = 0; k < n; ++k) {
    const auto [idx, renumbered] = touched[k];
    const Word& w = b.words[static_cast<size_t>(idx)];
    if (renumbered == kInsertAfter) {
      out.append(t, pos, w.end - pos);
      if (spaces) out += ' ';
      out += edit.insert;
      inserted = true;
      pos = w.end;
      continue;
    }
    if (renumbered >= 0) {
      out.append(t, pos, w.begin + 1 - pos);  // up to and with the letter
      out += edit.renumber[static_cast<size_t>(renumbered)].second;
      pos = w.end;
      continue;
    }
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
