// The NC writer: deterministic numbers, the integer fast path of
// format_number against fmt, and apply_edit_to against apply_edit.
#include "gcode/nc_writer.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>

#include "gcode/nc_block.h"

namespace volmap {
namespace {

TEST(NcWriter, FormatsDeterministically) {
  EXPECT_EQ(nc::format_number(12.5, 4), "12.5");
  EXPECT_EQ(nc::format_number(3.0, 4), "3");
  EXPECT_EQ(nc::format_number(-0.00001, 4), "0");
  EXPECT_EQ(nc::format_number(-1.23456, 4), "-1.2346");
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

}  // namespace
}  // namespace volmap
