#include "gcode/nc_writer.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <fmt/format.h>

namespace volmap::nc {

std::string format_number(double value, int decimals) {
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

std::string apply_edit(const Block& b, const BlockEdit& edit) {
  std::vector<int> remove = edit.remove;
  std::sort(remove.begin(), remove.end());
  const std::string& t = b.text;
  const bool spaces = block_uses_spaces(b);
  std::string out;
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
  return out;
}

}  // namespace volmap::nc
