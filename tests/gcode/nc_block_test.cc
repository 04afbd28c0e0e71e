// The NC lexer: byte spans and scaled codes kept, numbers read as their
// correctly rounded value, what it does not read refused; its fast paths
// (spans and decimals of every form, numbers against std::from_chars, plain
// axis words against the general lexer).
#include "gcode/nc_block.h"

#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <random>
#include <string>

#include "core/common/input_error.h"
#include "gcode/nc_writer.h"

namespace volmap {
namespace {

TEST(NcBlock, KeepsSpansAndScalesCodes) {
  const nc::Block b = nc::lex_block("N10 g1 x 1 0.5 Y-2 (comment) G38.2 ; rest", 3, "f.ngc");
  ASSERT_EQ(b.words.size(), 5u);
  EXPECT_EQ(b.words[1].code10, 10);
  EXPECT_DOUBLE_EQ(b.words[2].value, 10.5);  // spaces inside a number
  EXPECT_EQ(b.text.substr(b.words[2].begin, b.words[2].end - b.words[2].begin), "x 1 0.5");
  EXPECT_EQ(b.words[4].code10, 382);
  EXPECT_EQ(b.comment, "comment");
}

// Every number the lexer reads equals the correctly rounded value of its
// digits (std::from_chars), with its decimals and span, whatever follows it
// (the fast path for CAM's plain numbers and the general one agree).
TEST(NcBlock, NumbersReadAsTheirCorrectlyRoundedValue) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> len(0, 8), digit(0, 9), pick(0, 6);
  const char* tails[] = {"", " ", " Y1", "Y1", "(c)", " ;x", "\t"};
  for (int trial = 0; trial < 20000; ++trial) {
    std::string num = pick(rng) == 0 ? "-" : pick(rng) == 0 ? "+" : "";
    const int int_digits = len(rng), frac_digits = len(rng) % 7;
    for (int k = 0; k < int_digits; ++k) num += static_cast<char>('0' + digit(rng));
    const bool point = frac_digits > 0 || pick(rng) == 0;
    if (point) num += '.';
    for (int k = 0; k < frac_digits; ++k) num += static_cast<char>('0' + digit(rng));
    if (int_digits + frac_digits == 0) num += '7';
    const std::string text = "X" + num + tails[trial % 7];
    const nc::Block b = nc::lex_block(text, 1, "n.ngc");
    ASSERT_GE(b.words.size(), 1u) << text;
    const nc::Word& w = b.words[0];
    double want = 0;
    const char* first = num.data() + (num[0] == '+' ? 1 : 0);
    std::from_chars(first, num.data() + num.size(), want);
    EXPECT_EQ(w.value, want) << text;
    EXPECT_EQ(std::signbit(w.value), num[0] == '-') << text;
    EXPECT_EQ(w.end, 1 + num.size()) << text;
    const size_t dot = num.find('.');
    EXPECT_EQ(w.decimals, dot == std::string::npos ? 0 : static_cast<int>(num.size() - dot - 1))
        << text;
  }
  // Spaces inside a number join its parts (RS274NGC); a second point ends it.
  EXPECT_EQ(nc::lex_block("X 1 2.5 Y3", 1, "n.ngc").words[0].value, 12.5);
  EXPECT_EQ(nc::lex_block("X1 .5", 1, "n.ngc").words[0].value, 1.5);
  EXPECT_THROW(nc::lex_block("X1.2.3", 1, "n.ngc"), InputError);
}

TEST(NcBlock, RefusesWhatItDoesNotRead) {
  const std::pair<const char*, const char*> cases[] = {
      {"o100 sub", "O-word"},
      {"G1 X#1", "# parameters"},
      {"G1 X[1+2]", "expressions"},
      {"G1 X", "has no number"},
      {"G1 Y - ", "has no number"},
      {"G1 (open", "not closed"},
      {"G0 X1 $2", "unexpected character"},
  };
  for (const auto& [text, words] : cases) {
    try {
      nc::lex_block(text, 7, "p.ngc");
      ADD_FAILURE() << text;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("p.ngc:7:", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  }
}

// The lexer's fast path records what the general one does: spans, decimals
// and values of words whatever follows them.
TEST(NcBlockFast, SpansAndDecimalsOfEveryForm) {
  struct Case {
    const char* text;
    double value;
    int decimals;
    unsigned begin, end;
  };
  const Case cases[] = {{"X96.0000 Y1", 96, 4, 0, 8},
                        {"X-7.9882", -7.9882, 4, 0, 8},
                        {"x.5", 0.5, 1, 0, 3},
                        {"X5.(c)", 5, 0, 0, 3},
                        {"X +5 Y1", 5, 0, 0, 4},
                        {"X1 2.5", 12.5, 1, 0, 6},
                        {"X1 .5", 1.5, 1, 0, 5},
                        {"X1.2 Y3", 1.2, 1, 0, 4},
                        {"X12345678.5", 12345678.5, 1, 0, 11},
                        {"X1\t", 1, 0, 0, 2},
                        {"X-0", -0.0, 0, 0, 3},
                        {"X007", 7, 0, 0, 4}};
  for (const Case& c : cases) {
    const nc::Block b = nc::lex_block(c.text, 1, "t.ngc");
    ASSERT_GE(b.words.size(), 1u) << c.text;
    EXPECT_EQ(b.words[0].value, c.value) << c.text;
    EXPECT_EQ(std::signbit(b.words[0].value), std::signbit(c.value)) << c.text;
    EXPECT_EQ(b.words[0].decimals, c.decimals) << c.text;
    EXPECT_EQ(b.words[0].begin, c.begin) << c.text;
    EXPECT_EQ(b.words[0].end, c.end) << c.text;
    EXPECT_EQ(b.text, c.text);
  }
}

// The lexer's one-pass decimal parser gives std::from_chars's value, bit for
// bit: signs, leading zeros, no integer part, spaces inside, 1 to 25 digits.
TEST(NcBlockFast, NumbersEqualFromChars) {
  std::mt19937_64 rng(5);
  for (int k = 0; k < 200000; ++k) {
    std::string digits;
    const int n_int = static_cast<int>(rng() % 12), n_frac = static_cast<int>(rng() % 14);
    for (int i = 0; i < n_int; ++i) digits += static_cast<char>('0' + rng() % 10);
    std::string number = digits;
    if (n_frac > 0 || n_int == 0) {
      number += '.';
      for (int i = 0; i < std::max(n_frac, 1); ++i) number += static_cast<char>('0' + rng() % 10);
    }
    const int sign = static_cast<int>(rng() % 3);
    const std::string clean = (sign == 1 ? "-" : "") + number;
    std::string written = (sign == 1 ? "-" : sign == 2 ? "+" : "") + number;
    if (k % 7 == 0 && written.size() > 2) written.insert(1 + rng() % (written.size() - 1), " ");
    double want = 0;
    const auto res = std::from_chars(clean.data(), clean.data() + clean.size(), want);
    ASSERT_EQ(res.ec, std::errc()) << clean;
    const nc::Block b = nc::lex_block("X" + written + " Y1", 1, "t.ngc");
    ASSERT_EQ(b.words.size(), 2u) << written;
    ASSERT_EQ(std::memcmp(&b.words[0].value, &want, sizeof want), 0)
        << written << " " << b.words[0].value;
  }
}

// A random line of one to four words: mostly axis words in CAM's forms,
// sometimes after a G1 (or what looks like one), sometimes with what makes
// a line not plain (other letters, spaces and tabs where they change the
// line, comments, numbers with spaces inside or too many digits, a letter
// twice).
std::string random_axis_line(std::mt19937_64& rng) {
  auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); };
  static const char* const kPrefixes[] = {"G1 ",  "G01 ",  "g1 ", "G1",  "g01",  "G1  ",
                                          "G10 ", "G1.0 ", "G2 ", "G0 ", "G001 "};
  std::string line = pick(3) == 0 ? kPrefixes[pick(11)] : "";
  const int words = 1 + pick(4);
  for (int k = 0; k < words; ++k) {
    if (k > 0) {
      const int sep = pick(12);
      line += sep < 6 ? " " : sep < 10 ? "" : sep == 10 ? "  " : "\t";
    }
    const char* letters = pick(10) < 8 ? "XYZ" : "XYZFGN";
    char L = letters[pick(static_cast<int>(std::strlen(letters)))];
    if (pick(4) == 0) L = static_cast<char>(L - 'A' + 'a');
    line += L;
    const int sign = pick(5);
    if (sign == 0) line += '-';
    if (sign == 1) line += '+';
    const int n_int = pick(5), n_frac = pick(9) < 7 ? pick(6) : 10 + pick(8);
    for (int i = 0; i < n_int; ++i) line += static_cast<char>('0' + pick(10));
    if (n_frac > 0 || pick(3) == 0) line += '.';
    for (int i = 0; i < n_frac; ++i) line += static_cast<char>('0' + pick(10));
    if (pick(40) == 0) line += " 5";
  }
  const int tail = pick(30);
  if (tail == 0) line += " ";
  if (tail == 1) line += "(c)";
  if (tail == 2) line += ";c";
  if (tail == 3) line = " " + line;
  return line;
}

// Where lex_plain_axis_words takes a line, lex_block_into reads the same
// words: letters X Y Z, the same values to the bit, the case and spacing
// the writer keeps.
TEST(NcBlockFast, PlainAxisWordsAreTheLexersWords) {
  std::mt19937_64 rng(11);
  int plain = 0, other = 0, with_g1 = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    const std::string line = random_axis_line(rng);
    nc::PlainAxisWords p;
    if (!nc::lex_plain_axis_words(line, p)) {
      ++other;
      continue;
    }
    ++plain;
    nc::Block b;
    ASSERT_NO_THROW(nc::lex_block_into(line, 1, "t.ngc", b)) << line;
    const std::size_t g1 = p.g1 ? 1 : 0;  // a leading G1 word, then the axis words
    ASSERT_EQ(b.words.size(), static_cast<std::size_t>(p.count) + g1) << line;
    if (g1) {
      ASSERT_EQ(b.words[0].letter, 'G') << line;
      ASSERT_EQ(b.words[0].code10, 10) << line;
      ASSERT_EQ(b.words[1].begin, static_cast<std::uint32_t>(p.g1)) << line;
      ++with_g1;
    }
    unsigned seen = 0;
    for (std::size_t k = g1; k < b.words.size(); ++k) {
      const nc::Word& w = b.words[k];
      ASSERT_TRUE(w.letter >= 'X' && w.letter <= 'Z') << line;
      const int a = w.letter - 'X';
      ASSERT_FALSE(seen >> a & 1u) << line;
      seen |= 1u << a;
      ASSERT_EQ(std::memcmp(&w.value, &p.value[a], sizeof(double)), 0) << line << " " << w.value;
    }
    ASSERT_EQ(seen, p.given) << line;
    ASSERT_EQ(p.lower, nc::block_uses_lowercase(b)) << line;
    ASSERT_EQ(p.spaced, nc::block_uses_spaces(b)) << line;
    // The writer's edit that replaces every word leaves the insert alone.
    std::vector<int> all(b.words.size());
    for (size_t k = 0; k < all.size(); ++k) all[k] = static_cast<int>(k);
    std::string buf(line.size() + 8 + 1, '#');
    char* end = nc::apply_edit_to(b, all.data(), all.size(), "INSERT", p.spaced, buf.data());
    ASSERT_EQ(std::string(buf.data(), end), "INSERT") << line;
  }
  // Both kinds were met often.
  EXPECT_GT(plain, 20000);
  EXPECT_GT(other, 20000);
  EXPECT_GT(with_g1, 5000);
  EXPECT_FALSE(nc::lex_plain_axis_words("", *std::make_unique<nc::PlainAxisWords>()));
}

}  // namespace
}  // namespace volmap
