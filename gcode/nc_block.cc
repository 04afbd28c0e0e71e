#include "gcode/nc_block.h"

#include <cctype>
#include <charconv>
#include <cmath>

#include "core/input_error.h"

namespace volmap::nc {
namespace {

[[noreturn]] void fail(const std::string& file, int line, size_t col, const std::string& msg) {
  throw InputError(file, line, static_cast<int>(col) + 1, msg);
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }

}  // namespace

Block lex_block(std::string_view text, int line, const std::string& file) {
  Block b;
  b.text = std::string(text);
  b.line = line;
  size_t i = 0;
  const size_t n = text.size();
  auto skip_space = [&] {
    while (i < n && is_space(text[i])) ++i;
  };
  skip_space();
  if (i < n && text[i] == '%') {
    b.percent = true;
    ++i;
    skip_space();
    if (i < n && text[i] != ';' && text[i] != '(')
      fail(file, line, i, "text after '%' on the program delimiter line; put it on a line of its own");
    return b;
  }
  if (i < n && text[i] == '/') {
    b.block_delete = true;
    ++i;
  }
  while (i < n) {
    skip_space();
    if (i >= n) break;
    const char c = text[i];
    if (c == ';') break;  // comment to end of line
    if (c == '(') {
      const size_t close = text.find(')', i + 1);
      if (close == std::string_view::npos)
        fail(file, line, i, "comment '(' is not closed; add ')'");
      if (text.substr(i + 1, close - i - 1).find('(') != std::string_view::npos)
        fail(file, line, i, "nested comment; RS274NGC comments do not nest");
      if (b.comment.empty()) b.comment = std::string(text.substr(i + 1, close - i - 1));
      i = close + 1;
      continue;
    }
    if (c == '#')
      fail(file, line, i,
           "# parameters are not supported: the post-processor needs literal numbers; "
           "expand parameters in CAM (or with LinuxCNC's interpreter) first");
    if (c == '@' || c == '^')
      fail(file, line, i,
           "polar coordinates (@ radius, ^ angle; a LinuxCNC extension) are not supported; "
           "output X and Y from CAM");
    if (c == '[')
      fail(file, line, i,
           "[ ] expressions are not supported; output literal numbers from CAM");
    const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (letter == 'O')
      fail(file, line, i,
           "O-word control flow (subroutines, loops, conditionals) is not supported; "
           "expand it in CAM to a flat program");
    if (letter < 'A' || letter > 'Z')
      fail(file, line, i, std::string("unexpected character '") + c + "'; not a G-code word");
    Word w;
    w.letter = letter;
    w.begin = static_cast<std::uint32_t>(i);
    ++i;
    {
      size_t k = i;
      while (k < n && is_space(text[k])) ++k;
      if (k < n && text[k] == '#')
        fail(file, line, k,
             "# parameters are not supported: the post-processor needs literal numbers; "
             "expand parameters in CAM (or with LinuxCNC's interpreter) first");
      if (k < n && text[k] == '[')
        fail(file, line, k, "[ ] expressions are not supported; output literal numbers from CAM");
    }
    // The number: sign, digits, point; spaces allowed between its characters.
    std::string number;
    size_t last = i;
    bool seen_point = false;
    int decimals = 0;
    while (i < n) {
      const char d = text[i];
      if (is_space(d)) {
        ++i;
        continue;
      }
      const bool sign = (d == '+' || d == '-') && number.empty();
      if (std::isdigit(static_cast<unsigned char>(d)) || sign || (d == '.' && !seen_point)) {
        if (d == '.') seen_point = true;
        else if (seen_point && std::isdigit(static_cast<unsigned char>(d))) ++decimals;
        number += d;
        ++i;
        last = i;
        continue;
      }
      break;
    }
    i = last;
    if (number.empty() || number == "+" || number == "-" || number == "." ||
        number == "+." || number == "-.")
      fail(file, line, w.begin, std::string("word '") + letter + "' has no number");
    const char* first = number.data() + (number[0] == '+' ? 1 : 0);
    double v = 0;
    const auto res = std::from_chars(first, number.data() + number.size(), v);
    if (res.ec != std::errc() || res.ptr != number.data() + number.size() || !std::isfinite(v))
      fail(file, line, w.begin, std::string("bad number in word '") + letter + "'");
    w.value = v;
    w.decimals = decimals;
    w.end = static_cast<std::uint32_t>(last);
    if (letter == 'G' || letter == 'M') {
      const double scaled = v * 10.0;
      const double r = std::round(scaled);
      // Codes beyond G/M 99999 do not exist; a longer number stays -1 (an
      // unknown code, refused by the interpreter) instead of overflowing int.
      if (std::abs(scaled - r) < 1e-6 && decimals <= 1 && v >= 0 && r < 1e6) w.code10 = static_cast<int>(r);
    }
    b.words.push_back(w);
  }
  return b;
}

}  // namespace volmap::nc
