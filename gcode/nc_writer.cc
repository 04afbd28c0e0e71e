#include "gcode/nc_writer.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>

#include <fmt/format.h>

namespace volmap::nc {

namespace {
// Fast path of format_number: value x 10^decimals rounded to an integer and
// printed with its decimal point, when that integer is certainly the
// correctly rounded one (the scaled value is not within 1e-6 of a tie and
// below 1e9). The product carries at most one rounding (relative 1.1e-16),
// far less than the margin, so the digits equal fmt's correctly rounded
// ones. Otherwise (ties, huge values, more than 9 decimals) fmt decides.
bool format_fixed_fast(double value, int decimals, std::string& s) {
  static constexpr double kPow10[] = {1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
  if (decimals < 0 || decimals > 9) return false;
  const double scaled = std::abs(value) * kPow10[decimals];
  if (!(scaled < 1e9)) return false;  // NaN, infinities and large values too
  // floor(scaled + 0.5) by truncation (scaled >= 0; std::floor is a call
  // without SSE4.1).
  auto k = static_cast<std::uint32_t>(scaled + 0.5);  // below 1e9
  if (std::abs(std::abs(scaled - static_cast<double>(k)) - 0.5) < 1e-6) return false;
  char buf[24];
  char* end = buf + sizeof buf;
  char* p = end;
  // Fraction digits, trailing zeros dropped: skip them first, then the rest.
  int d = 0;
  while (d < decimals && k % 10 == 0) {
    k /= 10;
    ++d;
  }
  const bool any = d < decimals;
  for (; d < decimals; ++d) {
    *--p = static_cast<char>('0' + k % 10);
    k /= 10;
  }
  if (any) *--p = '.';
  // Integer digits two at a time.
  static constexpr char kPairs[] =
      "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
      "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
      "8081828384858687888990919293949596979899";
  while (k >= 10) {
    const std::uint32_t q = k / 100, two = k - q * 100;
    if (k < 100) {
      *--p = kPairs[2 * two + 1];
      *--p = kPairs[2 * two];
      k = 0;
      break;
    }
    *--p = kPairs[2 * two + 1];
    *--p = kPairs[2 * two];
    k = q;
  }
  if (k != 0 || p == end || p[0] == '.') *--p = static_cast<char>('0' + k);
  const bool zero = !any && p[0] == '0' && p + 1 == end;
  if (value < 0 && !zero) *--p = '-';
  s.append(p, static_cast<std::size_t>(end - p));
  return true;
}
}  // namespace

void append_number(std::string& out, double value, int decimals) {
  if (format_fixed_fast(value, decimals, out)) return;
  std::string s = fmt::format("{:.{}f}", value, decimals);
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  out += s;
}

std::string format_number(double value, int decimals) {
  std::string s;
  append_number(s, value, decimals);
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
