#include "gcode/nc_block.h"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include "core/common/input_error.h"

namespace volmap::nc {
namespace {

[[noreturn]] void fail(const std::string& file, int line, size_t col, const std::string& msg) {
  throw InputError(file, line, static_cast<int>(col) + 1, msg);
}

// The letters that begin a word, upper case: A-Z, and LinuxCNC's polar
// coordinates @ (radius) and ^ (angle, degrees), which the interpreter reads
// as X and Y. The one place that says which letters are G-code words.
constexpr bool is_word_letter(char upper) {
  return (upper >= 'A' && upper <= 'Z') || upper == '@' || upper == '^';
}

// Character classes, looked up once per character instead of a chain of
// comparisons: the lexer's inner loops are the post's hottest code.
enum CharClass : std::uint8_t { kOther = 0, kSpace, kDigit };
struct CharTable {
  std::array<std::uint8_t, 256> cls{};
  std::array<char, 256>
      upper{};  ///< the word letter a character begins (ASCII toupper), or 0 (and for O)
};
constexpr CharTable make_char_table() {
  CharTable t;
  for (int c = 0; c < 256; ++c) {
    const char ch = static_cast<char>(c);
    if (ch == ' ' || ch == '\t' || ch == '\r') t.cls[static_cast<size_t>(c)] = kSpace;
    if (ch >= '0' && ch <= '9') t.cls[static_cast<size_t>(c)] = kDigit;
    const char up = ch >= 'a' && ch <= 'z' ? static_cast<char>(ch - 'a' + 'A') : ch;
    // O is a letter of RS274NGC but begins control flow, refused with its
    // own message: 0 here sends it to the lexer's rare branch.
    if (c < 128 && is_word_letter(up) && up != 'O') t.upper[static_cast<size_t>(c)] = up;
  }
  return t;
}
constexpr CharTable kChars = make_char_table();

bool is_space(char c) { return kChars.cls[static_cast<unsigned char>(c)] == kSpace; }

constexpr const char* kNoParameters =
    "# parameters are not supported: the post-processor needs literal numbers; "
    "expand parameters in CAM (or with LinuxCNC's interpreter) first";
constexpr const char* kNoExpressions =
    "[ ] expressions are not supported; output literal numbers from CAM";

constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                             1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

struct GeneralNumber {
  size_t end = 0;           ///< where the word ends (after its last number character)
  std::string_view number;  ///< its characters (into `spaced` when spaces were inside)
  std::uint64_t mantissa = 0;
  int significant = 0, decimals = 0;
  bool negative = false;
};

// The number of a word in every form RS274NGC allows: sign, digits, point,
// with spaces allowed between its characters (collected into `spaced` only
// when there are such spaces). `i` is just after the letter.
GeneralNumber read_number_general(std::string_view text, int line, const std::string& file,
                                  size_t i, std::string& spaced) {
  const size_t n = text.size();
  {
    size_t k = i;
    while (k < n && is_space(text[k])) ++k;
    if (k < n && text[k] == '#') fail(file, line, k, kNoParameters);
    if (k < n && text[k] == '[') fail(file, line, k, kNoExpressions);
  }
  GeneralNumber g;
  size_t first_char = i;
  bool contiguous = true;
  size_t last = i;
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
        g.negative = d == '-';
      } else {
        if (seen_point) ++g.decimals;
        if (g.mantissa != 0 || d != '0') ++g.significant;
        g.mantissa = g.mantissa * 10 +
                     static_cast<std::uint64_t>(d - '0');  // wraps harmlessly past 19 digits
      }
      if (last == first_char) {
        first_char = i;                      // spaces before the number: it starts here
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
  g.end = last;
  g.number = contiguous ? text.substr(first_char, last - first_char) : std::string_view(spaced);
  return g;
}

// The number of a word in the form CAM writes: [sign] digits [. digits]
// right after the letter, not continued after spaces by a digit or a point.
struct FastNumber {
  std::uint64_t mantissa = 0;  ///< wraps harmlessly past 19 digits: then `digits` says so
  int decimals = 0;
  bool negative = false;
  size_t digits = 0;
  size_t end = 0;     ///< after its last character
  size_t next = 0;    ///< where the line goes on: past the spaces after the number
  bool fast = false;  ///< false: the general path must read it
};

// `t` is zero-terminated (the zero is not a digit, a sign, a point or a
// space), `i` just after the letter.
FastNumber read_number_fast(const char* t, size_t i) {
  FastNumber f;
  size_t k = i;
  if (t[k] == '-' || t[k] == '+') f.negative = t[k++] == '-';
  const size_t int_begin = k;
  auto read_digits = [&] {
    unsigned d;
    while ((d = static_cast<unsigned char>(t[k]) - '0') <= 9) {
      f.mantissa = f.mantissa * 10 + d;
      ++k;
    }
  };
  read_digits();
  f.digits = k - int_begin;
  if (t[k] == '.') {
    const size_t frac_begin = ++k;
    read_digits();
    f.decimals = static_cast<int>(k - frac_begin);
    f.digits += k - frac_begin;
  }
  f.fast = f.digits > 0;
  f.end = f.next = k;
  if (f.fast && kChars.cls[static_cast<unsigned char>(t[k])] == kSpace) {
    ++f.next;
    while (kChars.cls[static_cast<unsigned char>(t[f.next])] == kSpace) ++f.next;
    // Spaces inside a number join its parts (RS274NGC): the general path.
    if (kChars.cls[static_cast<unsigned char>(t[f.next])] == kDigit || t[f.next] == '.')
      f.fast = false;
  }
  return f;
}

// A character at `i` that does not begin a word: the ( ) comment it opens
// (kept in b.comment when it is the first) and the index after it, or npos
// for ';' (a comment to the end of the line); anything else is refused.
size_t skip_comment(std::string_view text, int line, const std::string& file, size_t i, Block& b) {
  const char c = text[i];
  if (c == ';') return std::string_view::npos;
  if (c == '(') {
    const size_t close = text.find(')', i + 1);
    if (close == std::string_view::npos) fail(file, line, i, "comment '(' is not closed; add ')'");
    if (text.substr(i + 1, close - i - 1).find('(') != std::string_view::npos)
      fail(file, line, i, "nested comment; RS274NGC comments do not nest");
    if (b.comment.empty()) b.comment = std::string(text.substr(i + 1, close - i - 1));
    return close + 1;
  }
  if (c == '#') fail(file, line, i, kNoParameters);
  if (c == '[') fail(file, line, i, kNoExpressions);
  if (c == 'O' || c == 'o')
    fail(file, line, i,
         "O-word control flow (subroutines, loops, conditionals) is not supported; "
         "expand it in CAM to a flat program");
  // Shown as it is when printable ASCII, else as \xNN: a message is one
  // line of text.
  const auto u = static_cast<unsigned char>(c);
  char shown[8];
  std::snprintf(shown, sizeof shown, u >= 0x20 && u < 0x7f ? "%c" : "\\x%02X", u);
  fail(file, line, i, std::string("unexpected character '") + shown + "'; not a G-code word");
}

// The value of a number of `mantissa` over 10^decimals (`exact`: at most 15
// significant digits), or std::from_chars' reading of its characters.
double number_value(std::uint64_t mantissa, int decimals, bool negative, bool exact,
                    std::string_view number, int line, const std::string& file, const Word& w) {
  if (exact && decimals <= 22) {
    // Exact: an integer below 2^53 over an exact power of ten, one
    // correctly rounded division (Clinger), as std::from_chars gives.
    // (Below 2^63: the signed conversion, one instruction.)
    const double r = static_cast<double>(static_cast<std::int64_t>(mantissa)) / kPow10[decimals];
    return negative ? -r : r;
  }
  // More digits: std::from_chars decides.
  double v = 0;
  const char* first = number.data() + (number[0] == '+' ? 1 : 0);
  const auto res = std::from_chars(first, number.data() + number.size(), v);
  if (res.ec != std::errc() || res.ptr != number.data() + number.size() || !std::isfinite(v))
    fail(file, line, w.begin, std::string("bad number in word '") + w.letter + "'");
  return v;
}

// Word::code10 of a G or M word of value `v`.
int scaled_code(double v, int decimals) {
  const double scaled = v * 10.0;
  const double r = std::round(scaled);
  // Codes beyond G/M 99999 do not exist; a longer number stays -1 (an
  // unknown code, refused by the interpreter) instead of overflowing int.
  if (std::abs(scaled - r) < 1e-6 && decimals <= 1 && v >= 0 && r < 1e6) return static_cast<int>(r);
  return -1;
}

// Lexes the word whose letter is at `i` into a new word of `b`; returns
// where the line goes on.
size_t lex_word(std::string_view text, int line, const std::string& file, size_t i, char letter,
                Block& b, std::string& spaced) {
  const char* const t = b.text.c_str();
  Word& w = b.words.emplace_back();  // (on InputError the block is as far as it got)
  w.letter = letter;
  w.begin = static_cast<std::uint32_t>(i);
  ++i;
  // Fast path, the form CAM writes. Anything else (spaces inside the
  // number, no digits, # or [ after the letter, ...) takes the general
  // path, which reads every form.
  const FastNumber f = read_number_fast(t, i);
  std::uint64_t mantissa = f.mantissa;
  int decimals = f.decimals;
  bool negative = f.negative;
  // mantissa < 10^15: at most 15 significant digits, exact in a double
  // (at most 15 digits say so at once).
  bool exact = f.digits <= 15 || (f.digits <= 19 && mantissa < 1000000000000000ull);
  std::string_view number;  // needed only when std::from_chars reads it
  size_t end;               // of the word
  if (f.fast) {
    number = std::string_view(t + i, f.end - i);
    end = f.end;
    i = f.next;  // (the spaces are not looked at again)
  } else {
    const GeneralNumber g = read_number_general(text, line, file, i, spaced);
    end = i = g.end;
    number = g.number;
    mantissa = g.mantissa;
    decimals = g.decimals;
    negative = g.negative;
    exact = g.significant <= 15;
    if (number.empty() || number == "+" || number == "-" || number == "." || number == "+." ||
        number == "-.")
      fail(file, line, w.begin, std::string("word '") + letter + "' has no number");
  }
  w.value = number_value(mantissa, decimals, negative, exact, number, line, file, w);
  w.decimals = decimals;
  w.end = static_cast<std::uint32_t>(end);
  if (letter == 'G' || letter == 'M') w.code10 = scaled_code(w.value, decimals);
  return i;
}

}  // namespace

Block lex_block(std::string_view text, int line, const std::string& file) {
  Block b;
  lex_block_into(text, line, file, b);
  return b;
}

void lex_block_into(std::string_view text, int line, const std::string& file, Block& b) {
  // The lexer reads its copy of the line: std::string ends it with a zero
  // byte, which is not a digit, a sign, a point or a space, so the loops
  // inside a word need no end checks.
  b.text.assign(text);
  b.line = line;
  b.block_delete = false;
  b.percent = false;
  b.words.clear();
  b.comment.clear();
  b.file = nullptr;
  b.evaluated = false;
  size_t i = 0;
  const size_t n = text.size();
  const char* const t = b.text.c_str();
  auto skip_space = [&] {
    while (kChars.cls[static_cast<unsigned char>(t[i])] == kSpace) ++i;
  };
  skip_space();
  if (i < n && t[i] == '%') {
    b.percent = true;
    ++i;
    skip_space();
    if (i < n && t[i] != ';' && t[i] != '(')
      fail(file, line, i,
           "text after '%' on the program delimiter line; put it on a line of its own");
    return;
  }
  if (i < n && t[i] == '/') {
    b.block_delete = true;
    ++i;
  }
  std::string spaced;  // a number written with spaces inside, joined (rare)
  // One pass over the line: each character is looked at once on the path
  // CAM's plain words take (letter, [sign] digits [. digits]).
  for (;;) {
    skip_space();
    if (i >= n) break;
    const char letter =
        kChars.upper[static_cast<unsigned char>(t[i])];  // 0: not a word letter, or O
    if (letter == 0) {
      i = skip_comment(text, line, file, i, b);
      if (i == std::string_view::npos) break;
      continue;
    }
    i = lex_word(text, line, file, i, letter, b, spaced);
  }
}

bool lex_plain_axis_words(std::string_view text, PlainAxisWords& out) {
  // Locals only until the end: a store through `out` could, for all the
  // compiler knows, change the characters (char aliases everything).
  const char* p = text.data();
  const char* const end = p + text.size();
  if (p == end) return false;
  const bool lower = *p >= 'a';
  double value[3] = {};
  unsigned given = 0;
  int count = 0;
  bool spaced = false;
  // A leading G1 (G01), then one space or none: the motion word of CAM
  // posts that write it on every line.
  int g1 = 0;
  if ((*p | 0x20) == 'g') {
    const char* q = p + 1;
    if (q != end && *q == '0') ++q;
    if (q == end || *q != '1') return false;
    ++q;
    if (q != end && *q == ' ') {
      spaced = true;
      ++q;
    }
    if (q == end) return false;  // G1 alone (or with a trailing space)
    g1 = static_cast<int>(q - p);
    p = q;
  }
  for (;;) {
    // The letter: X Y Z in either case (0x20 is the case bit of ASCII letters).
    const char c = *p;
    const unsigned a = static_cast<unsigned>((c | 0x20) - 'x');
    if (a > 2 || (c & ~0x20) < 'X' || (c & ~0x20) > 'Z') return false;
    if (given & (1u << a)) return false;  // twice: the interpreter's error
    ++p;
    bool negative = false;
    if (p != end && (*p == '-' || *p == '+')) negative = *p++ == '-';
    // Digits and the point, as lex_block_into's fast path reads them.
    std::uint64_t mantissa = 0;
    const char* const first = p;
    unsigned d;
    while (p != end && (d = static_cast<unsigned char>(*p) - '0') <= 9) {
      mantissa = mantissa * 10 + d;
      ++p;
    }
    long digits = p - first;
    int decimals = 0;
    if (p != end && *p == '.') {
      const char* const frac = ++p;
      while (p != end && (d = static_cast<unsigned char>(*p) - '0') <= 9) {
        mantissa = mantissa * 10 + d;
        ++p;
      }
      decimals = static_cast<int>(p - frac);
      digits += decimals;
    }
    if (digits == 0 || digits > 15) return false;  // no number, or from_chars' case
    const double r = static_cast<double>(static_cast<std::int64_t>(mantissa)) / kPow10[decimals];
    value[a] = negative ? -r : r;
    given |= 1u << a;
    ++count;
    if (p == end) break;
    if (*p == ' ') {
      spaced = true;
      if (++p == end) return false;  // a trailing space: the writer keeps it
    }
  }
  for (int a = 0; a < 3; ++a) out.value[a] = value[a];
  out.given = given;
  out.count = count;
  out.g1 = static_cast<std::uint8_t>(g1);
  out.lower = lower;
  out.spaced = spaced || count + (g1 > 0) <= 1;
  return true;
}

}  // namespace volmap::nc
