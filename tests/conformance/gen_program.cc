// Whole programs (generator.h): a header as CAM writes it, features drawn
// by weight, cutter compensation, odd constructs, the footer, and the tape
// frame (leader, `%` lines, trailer, byte-order mark, CRLF, the last line
// end).
#include <fmt/format.h>

#include <cmath>

#include "tests/conformance/gen_state.h"
#include "tests/conformance/setup_files.h"

namespace volmap::conformance {

namespace gen {

// An outside profile (a rectangle with rounded corners) under G41/G42,
// entered and left by moves longer than the tool's radius.
void cutter_comp_feature(Gen& g) {
  g.feature("cutter comp");
  g.set_absolute();
  g.set_plane(0);
  const double u = g.unit();
  // Mostly small cutters: the post keeps compensation where the error
  // field's slope times the radius is small.
  const int tool = g.chance(0.7) ? g.pick(std::vector<int>{3, 6}) : g.integer(1, 5);
  const double radius = kTools[tool - 1].d_mm / 2;
  const double wx = g.uniform(10, 80), wy = g.uniform(10, 60), e = 4 * radius + 3;
  if (wx + 2 * e > g.hi.x() - g.lo.x() || wy + 2 * e > g.hi.y() - g.lo.y()) return;
  const double x0 = g.uniform(g.lo.x() + e, g.hi.x() - e - wx);
  const double y0 = g.uniform(g.lo.y() + e, g.hi.y() - e - wy);
  const double rc = g.uniform(0, 1) < 0.5 ? 0.0 : g.uniform(0.5, std::min(wx, wy) / 3);
  const bool cw = g.chance(0.5);  // cw: the tool on the left (G41) is outside
  // The entry turns away from the tool's side into the first side (an
  // outside corner), from inside the profile's box.
  approach(g, x0 + wx / 2 + (cw ? e : -e), y0 + e / 2, g.uniform(g.lo.z(), 0));
  const int form = g.integer(0, 3);
  std::vector<std::string> on = {g.code(cw ? "G41" : "G42")};
  if (form == 0) on.push_back(g.code(fmt::format("D{}", tool)));
  if (form == 1) on = {g.code(cw ? "G41.1" : "G42.1"), g.word('D', kTools[tool - 1].d_mm / u)};
  if (form >= 2) {
    // The tool in the spindle (D0 or no D).
    if (g.tool != tool) {
      g.emit(g.join({g.code(fmt::format("T{}", tool)), g.code("M6")}));
      g.tool = tool;
      g.spindle = 0;
    }
    if (form == 2) on.push_back(g.code("D0"));
  }
  g.emit(g.join(on));
  g.comp = true;
  g.move(1, x0 + wx / 2, y0, std::nullopt);  // the entry
  const Vec c[4] = {Vec(x0 + rc, y0 + rc, g.w.z()), Vec(x0 + wx - rc, y0 + rc, g.w.z()),
                    Vec(x0 + wx - rc, y0 + wy - rc, g.w.z()), Vec(x0 + rc, y0 + wy - rc, g.w.z())};
  const Vec out[4] = {Vec(0, -1, 0), Vec(1, 0, 0), Vec(0, 1, 0), Vec(-1, 0, 0)};
  for (int k = 0; k < 4; ++k) {
    const int corner = cw ? (4 - k) % 4 : (k + 1) % 4;
    const int side_in = cw ? corner : (corner + 3) % 4, side_out = cw ? (corner + 3) % 4 : corner;
    const Vec a = c[corner] + rc * out[side_in], b = c[corner] + rc * out[side_out];
    g.move(1, a.x(), a.y(), std::nullopt);
    if (rc > 0) g.arc(cw, c[corner], b, 0, g.chance(0.3));
  }
  g.move(1, x0 + wx / 2, y0, std::nullopt);
  g.emit(g.code("G40"));
  g.comp = false;
  g.move(1, x0 + wx / 2 + (cw ? -e : e), y0 + e / 2, std::nullopt);  // the exit
  g.retract();
}

// Constructs a person or an old post writes: repeated points, G80 beside a
// motion, words in another order, spaces inside numbers, signs and points
// where CAM leaves them out, comments between words.
void odd_feature(Gen& g) {
  g.feature("odd");
  g.set_absolute();
  if (!g.known) return;
  const double u = g.unit();
  const Vec p = g.program(g.w) / u;
  const std::string x = g.num(p.x()), y = g.num(p.y());
  switch (g.integer(0, 7)) {
    case 0:  // the same point again
      g.emit(g.join({g.code("G1"), "X" + x, "Y" + y, g.feed_word()}));
      g.emit(g.join({g.code("G1"), "X" + x, "Y" + y}));
      g.motion = 1;
      break;
    case 1:  // G80 beside a rapid
      g.emit(g.join({g.code("G0"), "X" + x, g.code("G80")}));
      g.motion = 0;
      break;
    case 2:  // words in another order
      g.emit(g.join({"Y" + y, "X" + x, g.code("G1"), g.word('F', g.inch ? 30 : 700, 0)}));
      g.feed_set = true;
      g.motion = 1;
      break;
    case 3: {  // a space inside a number, a plus sign, a leading point
      const double dx = g.rounded(0.5 / u);
      g.emit(g.join({g.code("G1"), "X +" + g.num(p.x() + dx), g.feed_word()}));
      g.w.x() += dx * u;
      g.motion = 1;
      break;
    }
    case 4:  // comments between the words
      g.emit(g.code("G1") + " (move) X" + x + " ( same ) Y" + y + " " + g.feed_word());
      g.motion = 1;
      break;
    case 5:  // a tiny move
      g.emit(g.join(
          {g.code("G1"), g.word('X', p.x() + 1.0 / std::pow(10, g.decimals())), g.feed_word()}));
      g.w.x() += u / std::pow(10, g.decimals());
      g.motion = 1;
      break;
    case 6:  // a bare axis word in the modal motion
      if (g.motion == 1 || g.motion == 0) {
        g.emit(g.word('Z', p.z()));
      }
      break;
    default:  // a long run of very short moves (a dense CAM path)
      for (int k = g.integer(20, 200); k > 0; --k) {
        const Vec t = g.clamp(g.w + Vec(g.uniform(-0.2, 0.2), g.uniform(-0.2, 0.2), 0));
        g.move_to(1, t);
      }
      break;
  }
}

void header(Gen& g) {
  g.emit("(conformance program)");
  const bool inch = g.chance(0.3);
  const int k = g.integer(0, 2);
  if (k == 0) g.emit(g.join({g.code(inch ? "G20" : "G21"), g.code("G90"), g.code("G17")}));
  if (k == 1)
    g.emit(g.join({g.code("G00"), g.code("G17"), g.code(inch ? "G20" : "G21"), g.code("G40"),
                   g.code("G49"), g.code("G80"), g.code("G90")}));
  if (k == 2) {
    g.emit(g.code(inch ? "G20" : "G21"));
    g.emit(g.join({g.code("G17"), g.code("G90"), g.code("G94"), g.code("G54")}));
  }
  g.inch = inch;
  if (g.chance(0.6)) {
    g.tool = g.integer(1, 6);
    g.emit(g.join({g.code(fmt::format("T{}", g.tool)), g.code("M6")}));
    if (g.chance(0.8)) {
      g.emit(g.join({g.code("G43"), g.code(fmt::format("H{}", g.tool))}));
      g.tool_offset = kTools[g.tool - 1].z_mm;
    }
  }
  g.emit(g.join({g.code("M3"), g.word('S', g.integer(5, 40) * 500, 0)}));
  g.spindle = 3;
  // rs274 starts at machine zero: Z first, then over the part.
  g.w = -kWorkOffsetMm;
  g.w.z() -= g.tool_offset;
  g.move(0, std::nullopt, std::nullopt, g.safe_z);
  const Vec p = g.random_point();
  g.move(0, p.x(), p.y(), std::nullopt);
  g.known = true;
}

using Feature = void (*)(Gen&);
struct Weighted {
  Feature f;
  double weight;
};
const std::vector<Weighted> kFeatures = {
    {lines_feature, 6},
    {zigzag_feature, 3},
    {contour_feature, 4},
    {circle_feature, 3},
    {plane_arc_feature, 2},
    {polar_feature, 2},
    {polar_spiral_feature, 0.4},
    {drill_feature, 4},
    {incremental_feature, 2},
    {units_feature, 1.5},
    {arc_distance_feature, 1},
    {local_offset_feature, 1},
    {g92_feature, 1},
    {g10_feature, 1.2},
    {home_feature, 1},
    {tool_change_feature, 1.5},
    {cutter_comp_feature, 1.5},
    {misc_feature, 2},
    {g53_feature, 0.5},
    {sub_feature, 2.5},
    {loop_feature, 2},
    {if_feature, 1},
    {params_feature, 1.5},
    {user_m_feature, 0.5},
    {odd_feature, 2},
    {invalid_feature, 0.25},
};

Feature draw(Gen& g) {
  double total = 0;
  for (const Weighted& w : kFeatures) total += w.weight;
  double x = g.uniform(0, total);
  for (const Weighted& w : kFeatures)
    if ((x -= w.weight) < 0) return w.f;
  return lines_feature;
}

void footer(Gen& g) {
  g.set_absolute();
  g.retract();
  if (g.chance(0.5)) g.emit(g.code("M5"));
  if (g.chance(0.3)) g.emit(g.code("M9"));
}

// The file's bytes: the tape frame around the lines.
std::string frame(Gen& g, const std::vector<std::string>& body) {
  std::vector<std::string> out;
  const double odd = g.uniform(0, 1);
  const bool open = odd < 0.04 ? false : g.chance(0.55);
  const bool close = odd < 0.04 ? true : open ? g.chance(0.85) : false;
  if (odd < 0.04) g.feature("% at the end only");
  if (odd >= 0.04 && odd < 0.08) {
    g.feature("leader");
    out.push_back(g.pick(
        std::vector<std::string>{"<<<<<<< HEAD", "(leader)", "PART 17", "", "# exported by hand"}));
  }
  if (open || (odd >= 0.04 && odd < 0.08)) out.push_back("%");
  out.insert(out.end(), body.begin(), body.end());
  const bool end_code = !(odd >= 0.08 && odd < 0.1) && !(odd < 0.04 && g.chance(0.7));
  if (end_code) out.push_back(g.code(g.chance(0.6) ? "M2" : "M30"));
  if (close) out.push_back("%");
  if (close && g.chance(0.1)) {
    g.feature("trailer");
    out.push_back(g.pick(std::vector<std::string>{">>>>>>> other", "trailer text", "(end)"}));
  }
  const bool crlf = g.chance(0.1), last_newline = !g.chance(0.08);
  if (crlf) g.feature("CRLF");
  if (!last_newline) g.feature("no final newline");
  std::string s = g.chance(0.03) ? "\xEF\xBB\xBF" : "";
  if (!s.empty()) g.feature("BOM");
  for (size_t k = 0; k < out.size(); ++k) {
    s += out[k];
    if (k + 1 < out.size() || last_newline) s += crlf ? "\r\n" : "\n";
  }
  return s;
}

}  // namespace gen

Program generate_program(std::uint64_t seed) {
  gen::Gen g(seed);
  g.style.decimals_mm = g.integer(2, 4);
  g.style.decimals_inch = g.integer(4, 5);
  g.style.strip_zeros = g.chance(0.7);
  g.style.lower = g.chance(0.1);
  g.style.compact = g.chance(0.1);
  g.style.line_numbers = g.chance(0.15);
  g.style.restate_motion = g.chance(0.7);
  // The part: a region of the travel around the origin.
  const gen::Vec half(g.uniform(20, 110), g.uniform(20, 85), 0);
  g.lo = gen::Vec(-half.x(), -half.y(), g.uniform(-25, -3));
  g.hi = gen::Vec(half.x(), half.y(), g.uniform(3, 40));
  g.safe_z = g.hi.z() + g.uniform(2, 10);
  gen::header(g);
  for (int n = g.integer(2, 10); n > 0; --n) gen::draw(g)(g);
  gen::footer(g);
  Program p;
  p.main = gen::frame(g, g.lines);
  p.files = g.files;
  p.features = g.features;
  return p;
}

}  // namespace volmap::conformance
