#include "gcode/nc_block.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>

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
  lex_block_into(text, line, file, b);
  return b;
}

void lex_block_into(std::string_view text, int line, const std::string& file, Block& b) {
  b.text.assign(text);
  b.line = line;
  b.block_delete = false;
  b.percent = false;
  b.words.clear();
  b.comment.clear();
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
    return;
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
    if (c == '[')
      fail(file, line, i,
           "[ ] expressions are not supported; output literal numbers from CAM");
    const char letter = c >= 'a' && c <= 'z' ? static_cast<char>(c - 'a' + 'A') : c;  // ASCII toupper
    if (letter == 'O')
      fail(file, line, i,
           "O-word control flow (subroutines, loops, conditionals) is not supported; "
           "expand it in CAM to a flat program");
    // Word letters: A-Z, and LinuxCNC's polar coordinates @ (radius) and ^
    // (angle, degrees), which the interpreter reads as X and Y.
    if ((letter < 'A' || letter > 'Z') && letter != '@' && letter != '^')
      fail(file, line, i, std::string("unexpected character '") + c + "'; not a G-code word");
    Word w;
    w.letter = letter;
    w.begin = static_cast<std::uint32_t>(i);
    ++i;
    // The number: sign, digits, point; spaces allowed between its characters
    // (collected into `number` only when there are such spaces).
    std::string_view number;
    std::string spaced;
    size_t last = i;
    int decimals = 0;
    // The value as the digits go by: mantissa, significant digits, sign.
    std::uint64_t mantissa = 0;
    int significant = 0;
    bool negative = false;
    // Fast path, the form CAM writes: [sign] digits [. digits] right after
    // the letter, not continued after spaces by a digit or a point. One pass,
    // the same digits, counts and value as the general loop below.
    bool fast = false;
    {
      size_t k = i;
      if (k < n && (text[k] == '-' || text[k] == '+')) negative = text[k++] == '-';
      const size_t int_begin = k;
      unsigned d;
      while (k < n && (d = static_cast<unsigned char>(text[k]) - '0') <= 9) {
        mantissa = mantissa * 10 + d;
        ++k;
      }
      size_t digits = k - int_begin;
      if (k < n && text[k] == '.') {
        const size_t frac_begin = ++k;
        while (k < n && (d = static_cast<unsigned char>(text[k]) - '0') <= 9) {
          mantissa = mantissa * 10 + d;
          ++k;
        }
        decimals = static_cast<int>(k - frac_begin);
        digits += k - frac_begin;
      }
      // `significant` only decides whether the mantissa is exact (below
      // 2^53) for the one-division value below; with at most 19 digits the
      // mantissa has not wrapped, and it tells that directly.
      significant = digits <= 19 && mantissa < (std::uint64_t{1} << 53) ? 0 : 99;
      size_t after = k;
      while (after < n && is_space(text[after])) ++after;
      const bool continues =
          after > k && after < n && ((text[after] >= '0' && text[after] <= '9') || text[after] == '.');
      if (digits > 0 && !continues) {
        fast = true;
        number = text.substr(i, k - i);
        last = k;
        i = k;
      } else {
        decimals = 0;
        mantissa = 0;
        significant = 0;
        negative = false;
      }
    }
    if (!fast) {
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
      size_t first_char = i;
      bool contiguous = true;
      bool seen_point = false;
      while (i < n) {
        const char d = text[i];
        if (is_space(d)) {
          ++i;
          continue;
        }
        const bool sign = (d == '+' || d == '-') && last == first_char;
        if ((d >= '0' && d <= '9') || sign || (d == '.' && !seen_point)) {
          if (d == '.') {
            seen_point = true;
          } else if (d == '-' || d == '+') {
            negative = d == '-';
          } else {
            if (seen_point) ++decimals;
            if (mantissa != 0 || d != '0') ++significant;
            mantissa = mantissa * 10 + static_cast<std::uint64_t>(d - '0');  // wraps harmlessly past 19 digits
          }
          if (last == first_char) {
            first_char = i;  // spaces before the number: it starts here
          } else if (contiguous && i != last) {  // spaces inside the number: collect it
            contiguous = false;
            spaced.assign(text.substr(first_char, last - first_char));
            std::erase_if(spaced, is_space);
          }
          if (!contiguous) spaced += d;
          ++i;
          last = i;
          continue;
        }
        break;
      }
      i = last;
      number = contiguous ? text.substr(first_char, last - first_char) : std::string_view(spaced);
    }
    if (number.empty() || number == "+" || number == "-" || number == "." ||
        number == "+." || number == "-.")
      fail(file, line, w.begin, std::string("word '") + letter + "' has no number");
    double v = 0;
    static constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                        1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                        1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    if (significant <= 15 && decimals <= 22) {
      // Exact: an integer below 2^53 over an exact power of ten, one
      // correctly rounded division (Clinger), as std::from_chars gives.
      const double r = static_cast<double>(mantissa) / kPow10[decimals];
      v = negative ? -r : r;
    } else {  // more digits: std::from_chars decides
      const char* first = number.data() + (number[0] == '+' ? 1 : 0);
      const auto res = std::from_chars(first, number.data() + number.size(), v);
      if (res.ec != std::errc() || res.ptr != number.data() + number.size() || !std::isfinite(v))
        fail(file, line, w.begin, std::string("bad number in word '") + letter + "'");
    }
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
}

}  // namespace volmap::nc
