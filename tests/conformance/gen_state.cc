#include "tests/conformance/gen_state.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>

namespace volmap::conformance::gen {

Gen::Gen(std::uint64_t seed) : rng_(seed * 0x9E3779B97F4A7C15ULL + 1) {}

double Gen::uniform(double lo_, double hi_) {
  return std::uniform_real_distribution<double>(lo_, hi_)(rng_);
}
int Gen::integer(int lo_, int hi_) { return std::uniform_int_distribution<int>(lo_, hi_)(rng_); }
bool Gen::chance(double p) { return uniform(0, 1) < p; }

void Gen::emit(const std::string& line) {
  if (style.line_numbers && !line.empty() && line[0] != '(' && line[0] != 'o' && line[0] != 'O' &&
      line[0] != '%' && line[0] != '#')
    lines.push_back(fmt::format("{}{} {}", style.lower ? 'n' : 'N', 10 * (lines.size() + 1), line));
  else
    lines.push_back(line);
}

void Gen::feature(const std::string& name) {
  if (std::find(features.begin(), features.end(), name) == features.end()) features.push_back(name);
}

double Gen::rounded(double value_units, int d) const {
  if (d < 0) d = decimals();
  const double f = std::pow(10.0, d);
  return std::round(value_units * f) / f;
}

std::string Gen::num(double value_units, int d) const {
  if (d < 0) d = decimals();
  const double r = rounded(value_units, d);
  std::string s = fmt::format("{:.{}f}", r == 0 ? 0.0 : r, d);
  if (style.strip_zeros && s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

std::string Gen::word(char letter, double value_units, int d) const {
  const char l = style.lower ? static_cast<char>(std::tolower(letter)) : letter;
  return std::string(1, l) + num(value_units, d);
}

std::string Gen::code(const std::string& c) const {
  if (!style.lower) return c;
  std::string s = c;
  for (char& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

std::string Gen::join(const std::vector<std::string>& words) const {
  std::string s;
  for (const std::string& w_ : words) {
    if (w_.empty()) continue;
    if (!s.empty() && !style.compact) s += ' ';
    s += w_;
  }
  return s;
}

std::string Gen::feed_word() {
  if (feed_set) return "";
  feed_set = true;
  return word('F', inch ? uniform(5, 60) : uniform(150, 1500), 1);
}

void Gen::move(int g, std::optional<double> x, std::optional<double> y, std::optional<double> z,
               const std::string& extra) {
  std::vector<std::string> words;
  if (style.restate_motion || motion != g || !known) words.push_back(code(fmt::format("G{}", g)));
  const std::optional<double> target[3] = {x, y, z};
  const double u = unit();
  for (int a = 0; a < 3; ++a) {
    if (!target[a]) continue;
    const double p_now = (w[a] - shift[a]) / u, p_to = (*target[a] - shift[a]) / u;
    const double v = incremental ? p_to - p_now : p_to;
    const double r = rounded(v);
    words.push_back(word("XYZ"[a], r));
    w[a] = (incremental ? p_now + r : r) * u + shift[a];
  }
  if (g == 1) words.push_back(feed_word());
  words.push_back(extra);
  emit(join(words));
  motion = g;
}

void Gen::arc(bool cw, const Vec& center, const Vec& end, int turns, bool r_form) {
  static constexpr int kA0[3] = {0, 2, 1}, kA1[3] = {1, 0, 2};
  static constexpr char kW[3] = {'I', 'J', 'K'};
  const int a0 = kA0[plane], a1 = kA1[plane];
  const double u = unit();
  std::vector<std::string> words = {code(cw ? "G2" : "G3")};
  Vec written = w;
  for (int a = 0; a < 3; ++a) {
    const double p_now = (w[a] - shift[a]) / u, p_to = (end[a] - shift[a]) / u;
    if (rounded(p_to) == rounded(p_now) && a != a0 && a != a1) continue;  // no helix move
    const double v = incremental ? p_to - p_now : p_to;
    const double r = rounded(v);
    words.push_back(word("XYZ"[a], r));
    written[a] = (incremental ? p_now + r : r) * u + shift[a];
  }
  if (r_form) {
    // R: rounded up, so that it reaches half the chord after the rounding.
    const double chord = std::hypot(written[a0] - w[a0], written[a1] - w[a1]);
    const double radius = std::max(std::hypot(w[a0] - center[a0], w[a1] - center[a1]), chord / 2);
    const double f = std::pow(10.0, decimals());
    const double r_units = std::ceil(radius / u * f + 1) / f;
    // The long way round (more than half a turn): R negative.
    const Vec s = w - center, e = written - center;
    const double cross = s[a0] * e[a1] - s[a1] * e[a0];
    const bool long_way = cw ? cross > 0 : cross < 0;
    words.push_back(word('R', long_way ? -r_units : r_units));
  } else {
    for (int a : {a0, a1}) {
      const double v = arc_absolute ? (center[a] - shift[a]) / u : (center[a] - w[a]) / u;
      words.push_back(word(kW[a], v));
    }
  }
  if (turns > 0) words.push_back(word('P', turns + 1, 0));
  words.push_back(feed_word());
  emit(join(words));
  w = written;
  motion = cw ? 2 : 3;
}

Vec Gen::random_point() {
  return Vec(uniform(lo.x(), hi.x()), uniform(lo.y(), hi.y()), uniform(lo.z(), hi.z()));
}

void Gen::retract() {
  if (!known || w.z() < safe_z - 0.01) move(0, std::nullopt, std::nullopt, safe_z);
}

void Gen::set_absolute() {
  if (!incremental) return;
  emit(code("G90"));
  incremental = false;
}

void Gen::set_plane(int p) {
  if (p == plane) return;
  emit(code(p == 0 ? "G17" : p == 1 ? "G18" : "G19"));
  plane = p;
}

void Gen::set_units(bool to_inch) {
  if (to_inch == inch) return;
  emit(code(to_inch ? "G20" : "G21"));
  inch = to_inch;
  feed_set = false;  // a feed in the old unit would be a surprise
}

}  // namespace volmap::conformance::gen
