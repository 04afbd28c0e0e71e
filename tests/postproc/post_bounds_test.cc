// The post-processor's fast paths against the exact model: the error-field
// bounds (Corrector::lipschitz_bound, curvature_bound, chord_deviation_bound)
// measured on the exact HTM model, the warm-started fixed point, and the
// integer fast path of format_number against fmt, and the shortcut of
// plain lines (nc::lex_plain_axis_words, the post's plain_line) against the
// general lexer and post.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "gcode/nc_writer.h"
#include "postproc/three_axis/corrector.h"
#include "postproc/three_axis/post_program.h"
#include "tests/support/test_paths.h"

namespace volmap {
namespace {

using Eigen::Vector3d;

Machine hsu() { return load_machine_json(test::source_path("samples/machines/hsu-3axis.json")); }
ErrorSet hsu_errors() { return load_errors_csv(test::source_path("samples/errors/hsu-3axis.csv")); }

// Every approach-direction combination the post uses (0: the mean).
std::vector<ApproachDirections> all_directions() {
  std::vector<ApproachDirections> out;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z)
        out.push_back({static_cast<std::int8_t>(x), static_cast<std::int8_t>(y),
                       static_cast<std::int8_t>(z), 0, 0, 0});
  return out;
}

struct Box {
  Vector3d lo, hi;
};

// The part of the machine frame where the tables hold, found by probing
// (the bound box is private): the sample errors cover the travel.
Box box_of(const post::Corrector& c, const Machine& m) {
  Box b{Vector3d(1e9, 1e9, 1e9), Vector3d(-1e9, -1e9, -1e9)};
  std::mt19937 rng(7);
  for (int k = 0; k < 20000; ++k) {
    Vector3d p;
    for (int a = 0; a < 3; ++a)
      p[a] =
          std::uniform_real_distribution<double>(m.limits[a].min - 400, m.limits[a].max + 400)(rng);
    if (!c.in_bound_box(p)) continue;
    b.lo = b.lo.cwiseMin(p);
    b.hi = b.hi.cwiseMax(p);
  }
  return b;
}

void check_bounds(const ErrorSet& errors, double tool_mm) {
  const Machine m = hsu();
  const post::Corrector c(m, errors, tool_mm, OutsidePolicy::kError);
  const double K1 = c.lipschitz_bound(), K2 = c.curvature_bound();
  ASSERT_TRUE(std::isfinite(K1) && std::isfinite(K2));
  const Box box = box_of(c, m);
  ASSERT_TRUE((box.lo.array() < box.hi.array()).all());
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto dirs = all_directions();
  double max_slope = 0, max_second = 0, max_chord_ratio = 0;
  const double h = 0.5;  // mm: the second difference of a C1 piecewise cubic is an average of e''
  for (int k = 0; k < 4000; ++k) {
    Vector3d x, v(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    v.normalize();
    for (int a = 0; a < 3; ++a) x[a] = box.lo[a] + h + (box.hi[a] - box.lo[a] - 2 * h) * unit(rng);
    const ApproachDirections& d = dirs[static_cast<size_t>(k) % dirs.size()];
    const Vector3d e0 = c.error_at(x, d), ep = c.error_at(x + h * v, d),
                   em = c.error_at(x - h * v, d);
    max_slope = std::max(max_slope, (ep - e0).norm() / h);
    max_second = std::max(max_second, (ep - 2 * e0 + em).norm() / (h * h));
    // A long chord, sampled densely: its deviation from the chord of its
    // end values stays below the bound.
    Vector3d c1;
    for (int a = 0; a < 3; ++a) c1[a] = box.lo[a] + (box.hi[a] - box.lo[a]) * unit(rng);
    const double bound = c.chord_deviation_bound(x, c1);
    ASSERT_TRUE(std::isfinite(bound));
    const Vector3d ex = c.error_at(x, d), e1 = c.error_at(c1, d);
    double dev = 0;
    for (int i = 1; i < 64; ++i) {
      const double t = i / 64.0;
      dev = std::max(dev, (c.error_at(x + t * (c1 - x), d) - ((1 - t) * ex + t * e1)).norm());
    }
    max_chord_ratio = std::max(max_chord_ratio, dev / bound);
  }
  std::printf(
      "tool %g mm: Lipschitz bound %.3g (measured %.3g), curvature bound %.3g mm^-1 "
      "(measured %.3g), worst chord deviation / bound %.3f\n",
      tool_mm, K1, max_slope, K2, max_second, max_chord_ratio);
  EXPECT_LE(max_slope, K1);
  EXPECT_LE(max_second, K2);
  EXPECT_LE(max_chord_ratio, 1.0);
  // Useful, not vacuous: a 0.5 mm piece is far inside a 1 um tolerance.
  EXPECT_LT(K2 * 0.25 / 8, 1e-6);
  EXPECT_LT(K1, 1e-2);
  // The box is the tables' range (outside it the bound is not claimed).
  EXPECT_FALSE(c.in_bound_box(box.hi + Vector3d(1, 1, 1) * 50));
}

class Bounds : public ::testing::TestWithParam<double> {};  // tool length, mm

TEST_P(Bounds, HoldOnTheExactModel) { check_bounds(hsu_errors(), GetParam()); }

INSTANTIATE_TEST_SUITE_P(ToolLengths, Bounds, ::testing::Values(100.0, 0.0, 180.0));

// Axes without a table (their box side is their travel), and no location
// errors.
TEST(PostBounds, HoldWithPartialTables) {
  ErrorSet e = hsu_errors();
  e.axis[static_cast<size_t>(AxisName::Y)].reset();
  check_bounds(e, 100.0);
  e.location.clear();
  e.axis[static_cast<size_t>(AxisName::Z)].reset();
  check_bounds(e, 100.0);
}

TEST(PostBounds, WarmStartedFixedPointIsTheExactSolution) {
  const post::Corrector c(hsu(), hsu_errors(), 100.0, OutsidePolicy::kError);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(50, 250);
  const auto dirs = all_directions();
  for (int k = 0; k < 500; ++k) {
    const Vector3d p(u(rng), u(rng), u(rng) * 0.8);
    const ApproachDirections& d = dirs[static_cast<size_t>(k) % dirs.size()];
    const Vector3d cold = c.command_for(p, d);
    // A neighbour's correction (0.5 mm away, other directions too) as the start.
    const Vector3d q = p + Vector3d(0.5, -0.2, 0.1);
    const Vector3d warm =
        c.command_for(p, d, c.command_for(q, dirs[(static_cast<size_t>(k) + 5) % dirs.size()]) - q);
    EXPECT_LT((cold + c.error_at(cold, d) - p).norm(), 1e-11);
    EXPECT_LT((warm + c.error_at(warm, d) - p).norm(), 1e-11);
    EXPECT_LT((warm - cold).norm(), 1e-11);
    // The post's accuracy (1e-9 mm, certified by the Lipschitz bound).
    const Vector3d warm9 = c.command_for(p, d, c.command_for(q, d) - q, 1e-9);
    EXPECT_LT((warm9 - cold).norm(), 1e-9);
  }
}

TEST(NcWriterFast, FormatNumberEqualsFmt) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> mag(-7, 5);
  int checked = 0;
  for (int k = 0; k < 200000; ++k) {
    const int dec = static_cast<int>(rng() % 10);
    double v = std::pow(10.0, mag(rng)) * (rng() % 2 ? 1 : -1);
    if (k % 4 == 0) v = std::round(v * std::pow(10.0, dec)) / std::pow(10.0, dec);  // on the grid
    if (k % 4 == 1) v = (std::round(v * std::pow(10.0, dec)) + 0.5) / std::pow(10.0, dec);  // ties
    std::string want = fmt::format("{:.{}f}", v, dec);
    if (want.find('.') != std::string::npos) {
      while (want.back() == '0') want.pop_back();
      if (want.back() == '.') want.pop_back();
    }
    if (want == "-0") want = "0";
    ASSERT_EQ(nc::format_number(v, dec), want) << v << " " << dec;
    ++checked;
  }
  EXPECT_EQ(nc::format_number(-0.00004, 4), "0");
  EXPECT_EQ(nc::format_number(0.00005, 4), fmt::format("{:.4f}", 0.00005));
  EXPECT_EQ(nc::format_number(1e12, 4), "1000000000000");
  EXPECT_EQ(checked, 200000);
}

// format_number_fast against format_number's general path (fmt) where its
// cases meet: k = value x 10^dec near 10^j (digit counts), near 1e8 (the
// eight-digit form and the wide one), near 1e9 (the limit), every decimals.
TEST(NcWriterFast, FormatNumberAtTheEdgesOfItsCases) {
  auto general = [](double v, int dec) {
    std::string s = fmt::format("{:.{}f}", v, dec);
    if (s.find('.') != std::string::npos) {
      while (s.back() == '0') s.pop_back();
      if (s.back() == '.') s.pop_back();
    }
    return s == "-0" ? std::string("0") : s;
  };
  int written = 0;
  for (int dec = 0; dec <= 9; ++dec) {
    for (int j = 0; j <= 9; ++j) {
      for (long long dk = -3; dk <= 3; ++dk) {
        const long long k = static_cast<long long>(std::pow(10.0, j)) + dk;
        if (k < 0) continue;
        for (double frac : {0.0, 0.3, 0.7}) {
          for (double sign : {1.0, -1.0}) {
            const double v = sign * (static_cast<double>(k) + frac) / std::pow(10.0, dec);
            char buf[nc::kNumberRoom];
            if (const char* end = nc::format_number_fast(v, dec, buf)) {
              ASSERT_EQ(std::string(buf, static_cast<size_t>(end - buf)), general(v, dec))
                  << v << " " << dec;
              ++written;
            }
            ASSERT_EQ(nc::format_number(v, dec), general(v, dec)) << v << " " << dec;
          }
        }
      }
    }
  }
  EXPECT_GT(written, 2000);
}

// apply_edit_to (the post's in-place writer) writes what apply_edit does.
TEST(NcWriterFast, ApplyEditToEqualsApplyEdit) {
  std::mt19937_64 rng(9);
  const char* forms[] = {"N10 G1 X1.5 Y-2 Z3 F100",
                         "x1y2z3",
                         "G1  X1\tY2 (c) Z3 ; end",
                         "X1 Y2 Z3 ",
                         "G2 X1 Y2 I3 J4",
                         "/G0 X1",
                         "M3 S1000",
                         "Z-7.9882 Y0.2 X96"};
  for (int trial = 0; trial < 5000; ++trial) {
    const nc::Block b = nc::lex_block(forms[trial % 8], 1, "t.ngc");
    nc::BlockEdit e;
    for (size_t k = 0; k < b.words.size(); ++k)
      if (rng() % 2) e.remove.push_back(static_cast<int>(k));
    const char* inserts[] = {"", "X9 Y8 Z7", "g1 x1", "X1.2345"};
    e.insert = inserts[rng() % 4];
    std::string buf(b.text.size() + e.insert.size() + 1, '#');
    char* end = nc::apply_edit_to(b, e.remove.data(), e.remove.size(), e.insert,
                                  nc::block_uses_spaces(b), buf.data());
    ASSERT_LE(static_cast<size_t>(end - buf.data()), buf.size());
    ASSERT_EQ(std::string(buf.data(), end), nc::apply_edit(b, e))
        << forms[trial % 8] << " + " << e.insert;
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
// sometimes with what makes a line not plain (other letters, spaces and
// tabs where they change the line, comments, numbers with spaces inside or
// too many digits, a letter twice).
std::string random_axis_line(std::mt19937_64& rng) {
  auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); };
  std::string line;
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
  int plain = 0, other = 0;
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
    ASSERT_EQ(static_cast<int>(b.words.size()), p.count) << line;
    unsigned seen = 0;
    for (const nc::Word& w : b.words) {
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
  EXPECT_FALSE(nc::lex_plain_axis_words("", *std::make_unique<nc::PlainAxisWords>()));
}

// A random program of the forms a three-axis program mixes: plain lines in
// every case and spacing, lines that are not plain, G0 and G1 with F, G91
// and G20 stretches, tool length offsets, comments, block delete, CRLF,
// short zig-zag steps (lost-motion reversals, split pieces) and long ones.
std::string random_program(std::mt19937_64& rng) {
  auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); };
  auto uni = [&](double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(rng() % 1000001) / 1e6;
  };
  std::string p = "%\nG21 G90 G17 G94\nG0 X10 Y10 Z20\nG1 F800\n";
  double x = 10, y = 10, z = 20;  // nominal, mm, G90 program coordinates
  bool inch = false, incremental = false, rapid = false;
  for (int k = 0; k < 1500; ++k) {
    const int what = pick(100);
    const char* eol = pick(50) == 0 ? "\r\n" : "\n";
    if (what < 3) {
      incremental = !incremental;
      p += incremental ? "G91" : "G90";
    } else if (what < 5) {
      inch = !inch;
      p += inch ? "G20" : "G21";
    } else if (what < 7) {
      p += pick(2) ? "G43 H1" : (pick(2) ? "G43 H2" : "G49");
    } else if (what < 9) {
      p += "(a comment)";
    } else if (what < 11) {
      p += fmt::format("G0 Z{:.3f}", (incremental ? 0.0 : z) / (inch ? 25.4 : 1.0));
      rapid = true;
    } else if (what < 13) {
      p += fmt::format("F{}", 200 + pick(2000));
    } else {
      // A move: short steps zig-zag (reversals), some long ones.
      const double step = pick(4) == 0 ? uni(5, 40) : uni(0.001, 0.8);
      double nx = std::clamp(x + (pick(2) ? step : -step), 0.0, 200.0);
      double ny = std::clamp(y + (pick(3) == 0 ? uni(-2, 2) : 0.0), 0.0, 200.0);
      double nz = std::clamp(z + (pick(2) ? uni(-1, 1) : 0.0), -20.0, 50.0);
      const int axes = 1 + pick(7);  // which of X Y Z the line names
      if (!(axes & 1)) nx = x;
      if (!(axes & 2)) ny = y;
      if (!(axes & 4)) nz = z;
      const double unit = inch ? 25.4 : 1.0;
      const int dec = inch ? 5 : 4;
      const bool lower = pick(10) == 0;
      const std::string sep = pick(8) == 0 ? "" : " ";
      std::string words;
      const double v[3] = {nx, ny, nz}, was[3] = {x, y, z};
      for (int a = 0; a < 3; ++a) {
        if (!(axes >> a & 1)) continue;
        if (!words.empty()) words += sep;
        words += lower ? "xyz"[a] : "XYZ"[a];
        words += fmt::format("{:.{}f}", (incremental ? v[a] - was[a] : v[a]) / unit, dec);
      }
      const int form = pick(20);
      if (form == 0) words = "G1 " + words, rapid = false;
      if (form == 1) words = "N" + std::to_string(k) + " " + words;
      if (form == 2) words += " (c)";
      if (form == 3) words = "/" + words;
      if (form == 4) words = "G0 " + words, rapid = true;  // plain lines in G0 follow
      if (form > 4 && rapid && pick(3) == 0) words = "G1 " + words, rapid = false;
      p += words;
      x = nx, y = ny, z = nz;  // (a block-delete line runs too: volmap executes it)
    }
    p += eol;
  }
  p += "G90 G21\nG0 Z50\nM2\n%\n";
  return p;
}

std::pair<std::string, post::PostReport> post_with(const std::string& program, const Machine& m,
                                                   const ErrorSet& e, double tol_um,
                                                   bool shortcuts) {
  nc::ProgramSetup setup;
  setup.work_offset_mm[0] =
      m.name == "hsu-3axis" ? Vector3d(150, 100, 200) : Vector3d(300, 200, 100);
  setup.tool_length_mm[1] = 12.5;
  setup.tool_length_mm[2] = -7.25;
  post::PostOptions o;
  o.tolerance_mm = tol_um * 1e-3;
  o.shortcuts = shortcuts;
  std::istringstream in(program);
  std::ostringstream out;
  const post::PostReport r = post::post_program(in, "random.ngc", out, m, e, setup, o);
  return {out.str(), r};
}

// The errors times `factor` (values, slopes and location errors).
ErrorSet scaled(ErrorSet e, double factor) {
  for (auto& axis : e.axis) {
    if (!axis) continue;
    for (AxisErrorTable* t : {&axis->plus, &axis->minus})
      for (auto* rows : {&t->value, &t->slope})
        for (auto& row : *rows)
          for (double& v : row) v *= factor;
  }
  for (auto& [name, v] : e.location) v *= factor;
  return e;
}

// The shortcut of plain lines writes what the general path writes, byte for
// byte, and counts the same, on programs that go in and out of it: on two
// machines, and with errors a hundred times smaller (corrections of about
// the output's resolution: lines kept as written and lines changed mixed).
TEST(PostShortcut, PlainLinesGiveTheGeneralPathsOutput) {
  std::mt19937_64 rng(23);
  const Machine machines[] = {
      hsu(), load_machine_json(test::source_path("samples/machines/gantry-3axis.json")), hsu()};
  const ErrorSet errors[] = {hsu_errors(),
                             load_errors_csv(test::source_path("samples/errors/gantry-3axis.csv")),
                             scaled(hsu_errors(), 0.01)};
  for (int trial = 0; trial < 9; ++trial) {
    const std::string program = random_program(rng);
    int plain = 0;
    std::istringstream lines(program);
    for (std::string l; std::getline(lines, l);) {
      nc::PlainAxisWords w;
      plain += nc::lex_plain_axis_words(l, w) ? 1 : 0;
    }
    EXPECT_GT(plain, 800);
    const int k = trial % 3;
    const double tol_um = trial < 6 ? 1.0 : 0.2;
    const auto general = post_with(program, machines[k], errors[k], tol_um, false);
    const auto shortcut = post_with(program, machines[k], errors[k], tol_um, true);
    ASSERT_EQ(shortcut.first, general.first) << "trial " << trial;
    EXPECT_EQ(shortcut.second.lines, general.second.lines);
    EXPECT_EQ(shortcut.second.lines_changed, general.second.lines_changed);
    EXPECT_EQ(shortcut.second.lines_added, general.second.lines_added);
    EXPECT_EQ(shortcut.second.points_corrected, general.second.points_corrected);
    EXPECT_EQ(shortcut.second.max_correction_mm, general.second.max_correction_mm);
    // The programs are corrected, pieces added (the small errors: some
    // lines kept, some changed).
    EXPECT_GT(general.second.lines_changed, k == 2 ? 100u : 500u) << trial;
    EXPECT_LT(general.second.lines_changed, general.second.lines - (k == 2 ? 300u : 0u)) << trial;
    if (k < 2) {
      EXPECT_GT(general.second.lines_added, 10u) << trial;
    }
  }
  // The sample and LinuxCNC's programs.
  std::vector<std::string> paths = {test::source_path("samples/programs/pocket.ngc")};
  for (const char* name : {"tort.ngc", "arcspiral.ngc", "3dtest.ngc", "cds.ngc"})
    if (std::ifstream(std::string("/usr/share/linuxcnc/ncfiles/") + name))
      paths.push_back(std::string("/usr/share/linuxcnc/ncfiles/") + name);
  for (const std::string& path : paths) {
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    const auto general = post_with(ss.str(), machines[0], errors[0], 1.0, false);
    const auto shortcut = post_with(ss.str(), machines[0], errors[0], 1.0, true);
    EXPECT_EQ(shortcut.first, general.first) << path;
    EXPECT_EQ(shortcut.second.points_corrected, general.second.points_corrected) << path;
  }
}

}  // namespace
}  // namespace volmap
