// Canned cycles (gen_state.h): every cycle volmap reads, G98/G99, modal
// repeats at several holes, L repeats under G90 and G91, polar hole circles.
#include <fmt/format.h>

#include <cmath>

#include "tests/conformance/gen_state.h"

namespace volmap::conformance::gen {

namespace {

struct Cycle {
  const char* code;
  char extra;   // 'P' dwell, 'Q' peck, 0 none
  int spindle;  // 3 or 4: needs the spindle turning that way; 1 either
};
const std::vector<Cycle> kCycles = {{"G81", 0, 0},   {"G82", 'P', 0}, {"G83", 'Q', 0},
                                    {"G73", 'Q', 0}, {"G85", 0, 0},   {"G89", 'P', 0},
                                    {"G86", 'P', 1}, {"G84", 0, 3},   {"G74", 0, 4}};

void spindle_for(Gen& g, int need) {
  if (need == 0 || (need == 1 && g.spindle != 0) || need == g.spindle) return;
  const int dir = need == 1 ? 3 : need;
  g.emit(g.join({g.code(fmt::format("M{}", dir)), g.word('S', g.integer(3, 30) * 100, 0)}));
  g.spindle = dir;
}

}  // namespace

void drill_feature(Gen& g) {
  g.feature("cycles");
  g.set_plane(0);
  g.set_absolute();
  const Cycle& c = g.pick(kCycles);
  g.feature(c.code);
  const double u = g.unit();
  const Vec first = g.random_point();
  g.retract();
  g.move(0, first.x(), first.y(), std::nullopt);
  spindle_for(g, c.spindle);
  const double initial = g.w.z();
  const double r_w = g.uniform(0.5, 3), bottom = g.uniform(g.lo.z(), -0.5);
  if (g.chance(0.6)) {
    g.retract_r = g.chance(0.5);
    g.emit(g.code(g.retract_r ? "G99" : "G98"));
  }
  std::string extra;
  if (c.extra == 'P') extra = g.word('P', g.uniform(0.1, 1), 2);
  if (c.extra == 'Q') extra = g.word('Q', g.uniform(0.3, 3) / u);
  // 0-5 holes in G90, 6-7 L in G91, 8 polar, 9 L in G90; rs274 reads no L
  // on G74 ("L word with no ... canned cycle"): rarely.
  const int mode =
      c.code == std::string("G74") && g.chance(0.9) ? g.integer(0, 5) : g.integer(0, 9);
  std::vector<Vec> holes;
  std::string first_block;
  const auto p = [&](int a, double w_mm) { return (w_mm - g.shift[a]) / u; };
  if (mode <= 5 || mode == 9) {
    const std::string l = mode == 9 ? g.word('L', g.integer(2, 3), 0) : "";
    first_block =
        g.join({g.code(c.code), g.word('X', p(0, first.x())), g.word('Y', p(1, first.y())),
                g.word('Z', p(2, bottom)), g.word('R', p(2, r_w)), extra, l, g.feed_word()});
    holes.push_back(Vec(g.rounded(p(0, first.x())) * u + g.shift.x(),
                        g.rounded(p(1, first.y())) * u + g.shift.y(), 0));
    g.emit(first_block);
    for (int n = mode <= 5 ? g.integer(0, 5) : 0; n > 0; --n) {
      const Vec h = g.random_point();
      g.emit(g.join({g.word('X', p(0, h.x())), g.word('Y', p(1, h.y()))}));
      holes.push_back(Vec(g.rounded(p(0, h.x())) * u + g.shift.x(),
                          g.rounded(p(1, h.y())) * u + g.shift.y(), 0));
    }
  } else {
    // G91: R from the initial level, Z from R, X Y (or @ ^) once per repeat.
    const int n = g.integer(2, 6);
    const double r_inc = g.rounded((r_w - initial) / u), z_inc = g.rounded((bottom - r_w) / u);
    std::vector<std::string> words = {g.code("G91"), g.code(c.code)};
    const Vec origin = g.shift;
    if (mode <= 7) {
      const double len = g.uniform(2, 20), a = g.uniform(0, 2 * M_PI);
      const double dx = g.rounded(len * std::cos(a) / u), dy = g.rounded(len * std::sin(a) / u);
      words.push_back(g.word('X', dx));
      words.push_back(g.word('Y', dy));
      for (int k = 1; k <= n; ++k) holes.push_back(g.w + k * u * Vec(dx, dy, 0));
    } else {
      const double step = g.rounded(360.0 / n * (g.chance(0.5) ? 1 : -1), 3);
      words.push_back(g.word('@', 0));
      words.push_back(g.word('^', step, 3));
      const Vec q = g.w - origin;
      const double r = std::hypot(q.x(), q.y()), a0 = std::atan2(q.y(), q.x());
      for (int k = 1; k <= n; ++k) {
        const double a = a0 + k * step * M_PI / 180;
        holes.push_back(origin + r * Vec(std::cos(a), std::sin(a), 0));
      }
    }
    for (const Vec& h : holes)
      if (((h.array() < g.lo.array()) || (h.array() > g.hi.array())).head(2).any()) {
        // The pattern leaves the region: drill one hole in G90 instead.
        holes.clear();
        break;
      }
    if (holes.empty()) {
      g.emit(g.join({g.code(c.code), g.word('Z', p(2, bottom)), g.word('R', p(2, r_w)), extra,
                     g.feed_word()}));
      holes.push_back(g.w);
    } else {
      words.insert(words.end(), {g.word('Z', z_inc), g.word('R', r_inc), extra, g.word('L', n, 0),
                                 g.feed_word()});
      g.emit(g.join(words));
      g.incremental = true;
    }
  }
  g.emit(g.code("G80"));
  g.motion = 80;
  g.w.x() = holes.back().x(), g.w.y() = holes.back().y();
  // G98: back to the initial level (R lies below it here); G99: to R.
  g.w.z() = g.retract_r ? r_w : initial;
  g.set_absolute();
  if (c.spindle == 4) spindle_for(g, 3);
}

}  // namespace volmap::conformance::gen
