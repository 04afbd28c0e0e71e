// O-word control flow and parameters (gen_state.h): subroutines in the
// program and in files of their own (named and numbered, with numbered
// arguments and named locals, return values, nested calls), while, do,
// repeat, if/elseif/else, named and numbered parameters in expressions, and
// user M codes.
#include <fmt/format.h>

#include <cmath>

#include "tests/conformance/gen_state.h"

namespace volmap::conformance::gen {

namespace {

std::string user_m_line(Gen& g) {
  g.user_m = true;
  std::vector<std::string> words = {g.code(fmt::format("M{}", g.integer(100, 199)))};
  if (g.chance(0.6)) words.push_back(g.word('P', g.integer(0, 5), 0));
  if (g.chance(0.4)) words.push_back(g.word('Q', g.uniform(0, 10), 2));
  return g.join(words);
}

std::string text_of(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += l + "\n";
  return s;
}

// A sub's lines: its definition, with a user M code here and there (in its
// body, which runs, or before `sub` or after `endsub` in a file, which does
// not).
std::vector<std::string> sub_text(Gen& g, const std::string& label,
                                  const std::vector<std::string>& body, bool in_file) {
  std::vector<std::string> s;
  if (in_file && g.chance(0.1)) s.push_back(user_m_line(g));
  if (in_file && g.chance(0.2)) s.push_back("(subroutine " + label + ")");
  s.push_back("o" + label + " sub");
  if (g.chance(0.1)) s.push_back(user_m_line(g));
  s.insert(s.end(), body.begin(), body.end());
  s.push_back("o" + label + " endsub");
  if (in_file && g.chance(0.1)) s.push_back(user_m_line(g));
  if (in_file && g.chance(0.3)) s.push_back(g.code("M2"));
  return s;
}

// Where a sub is defined: a file of its own (named or numbered) or the program.
void define_sub(Gen& g, const std::string& label, const std::vector<std::string>& lines,
                bool in_file) {
  if (in_file) {
    std::string name = label.front() == '<' ? label.substr(1, label.size() - 2) : label;
    g.files.push_back({name + ".ngc", text_of(lines)});
  } else {
    for (const std::string& l : lines) g.lines.push_back(l);
  }
}

std::string call_line(Gen& g, const std::string& label, const std::vector<double>& args) {
  std::string s = "o" + label + " call";
  for (double a : args) s += " [" + g.num(a) + "]";
  return s;
}

}  // namespace

void sub_feature(Gen& g) {
  g.set_absolute();
  g.set_plane(0);
  g.retract();
  const double u = g.unit();
  const int kind = g.integer(0, 5);
  const bool in_file = kind != 1 && kind != 3;
  const int n = g.label++;
  const std::string label =
      kind == 2 ? std::to_string(n) : fmt::format("<{}{}>", kind == 4 ? "hole" : "slot", n);
  g.feature(in_file ? "sub file" : "sub");
  const std::string f = g.word('F', g.inch ? 20 : 400, 0);
  if (kind == 3) {  // a return value
    g.feature("return value");
    define_sub(g, label, sub_text(g, label, {"o" + label + " return [#1 * 2]"}, false), false);
    const Vec t = g.random_point();
    const double half = g.rounded((t.x() - g.shift.x()) / u / 2);
    g.lines.push_back(call_line(g, label, {half}));
    g.emit(g.join({g.code("G0"), g.code("X#<_value>")}));
    g.w.x() = 2 * half * u + g.shift.x();
    return;
  }
  std::vector<std::string> body;
  if (kind == 4) {  // a small full circle at (#1, #2), depth #3, radius #4
    g.feature("circle sub");
    body = {"G0 X[#1 + #4] Y#2", "G1 Z#3 " + f, "G2 X[#1 + #4] Y#2 I[-#4] J0", "G0 Z#5"};
  } else {  // a slot from (#1, #2) by (#5, #6) at depth #3, up to #4
    body = {
        "#<x> = #1", "#<y> = #2", "G0 X#<x> Y#<y>", "G1 Z#3 " + f, "G1 X[#<x> + #5] Y[#<y> + #6]",
        "G0 Z#4"};
  }
  if (kind == 5) {  // nested: an outer sub calls this one
    g.feature("nested call");
  }
  define_sub(g, label, sub_text(g, label, body, in_file), in_file);
  std::string outer;
  if (kind == 5) {
    outer = fmt::format("<outer{}>", g.label++);
    // The outer sub passes its arguments on.
    define_sub(g, outer,
               sub_text(g, outer, {"o" + label + " call [#1] [#2] [#3] [#4] [#5] [#6]"}, false),
               false);
  }
  for (int k = g.integer(1, 4); k > 0; --k) {
    const double r = kind == 4 ? g.uniform(0.15, 1.5) : 0;
    Vec p = g.random_point();
    p = p.cwiseMax(g.lo + Vec(r, r, 0)).cwiseMin(g.hi - Vec(r, r, 0));
    const Vec d(g.uniform(-15, 15), g.uniform(-15, 15), 0);
    const Vec e = g.clamp(p + d);
    const double depth = g.uniform(g.lo.z(), 0);
    const Vec q = (p - g.shift) / u, de = (e - p) / u;
    std::vector<double> args = {q.x(), q.y(), (depth - g.shift.z()) / u};
    if (kind == 4)
      args.insert(args.end(), {r / u, (g.safe_z - g.shift.z()) / u});
    else
      args.insert(args.end(), {(g.safe_z - g.shift.z()) / u, de.x(), de.y()});
    g.lines.push_back(call_line(g, kind == 5 ? outer : label, args));
    // Where the call leaves the tool (the written numbers).
    const auto val = [&](double v) { return g.rounded(v); };
    if (kind == 4) {
      g.w =
          Vec(val(q.x()) + val(r / u), val(q.y()), val((g.safe_z - g.shift.z()) / u)) * u + g.shift;
    } else {
      g.w = Vec(val(q.x()) + val(de.x()), val(q.y()) + val(de.y()),
                val((g.safe_z - g.shift.z()) / u)) *
                u +
            g.shift;
    }
    g.motion = 0;
  }
}

void loop_feature(Gen& g) {
  g.set_absolute();
  g.set_plane(0);
  const double u = g.unit();
  const int n = g.integer(2, 8), label = g.label++;
  const double step = g.uniform(1, 8);
  const double width = step * n;
  if (width > g.hi.x() - g.lo.x() - 2) return;
  const double x0 = g.uniform(g.lo.x(), g.hi.x() - width);
  const double y0 = g.uniform(g.lo.y(), g.hi.y() - 20), y1 = y0 + g.uniform(2, 20);
  approach(g, x0, y0, g.uniform(g.lo.z(), 0));
  const std::string var =
      g.chance(0.5) ? fmt::format("#<i{}>", label) : fmt::format("#{}", 100 + label % 50);
  const std::string o = fmt::format("o{}", label);
  const std::string xs = g.num((x0 - g.shift.x()) / u), ds = g.num(step / u);
  const std::string ya = g.num((y1 - g.shift.y()) / u), yb = g.num((y0 - g.shift.y()) / u);
  const int kind = g.integer(0, 2);
  if (kind == 2) {  // repeat, with G91 moves inside
    g.feature("repeat");
    g.lines.push_back(o + " repeat [" + std::to_string(n) + "]");
    g.emit(g.join({g.code("G91"), g.code("G1"), g.word('X', g.rounded(step / u)),
                   g.word('Y', g.rounded((y1 - y0) / u))}));
    g.emit(g.join({g.code("G1"), g.word('Y', -g.rounded((y1 - y0) / u))}));
    g.emit(g.code("G90"));
    g.lines.push_back(o + " endrepeat");
    g.w.x() += n * g.rounded(step / u) * u;
    g.motion = 1;
    return;
  }
  g.feature(kind == 0 ? "while" : "do-while");
  g.lines.push_back(var + " = 0");
  g.lines.push_back(kind == 0 ? o + " while [" + var + " LT " + std::to_string(n) + "]"
                              : o + " do");
  g.emit("G1 X[" + xs + " + " + var + " * " + ds + "] Y" + ya);
  if (g.chance(0.1)) g.lines.push_back(user_m_line(g));
  g.emit("G1 Y" + yb);
  g.lines.push_back(var + " = [" + var + " + 1]");
  g.lines.push_back(kind == 0 ? o + " endwhile"
                              : o + " while [" + var + " LT " + std::to_string(n) + "]");
  g.w.x() = (g.rounded((x0 - g.shift.x()) / u) + (n - 1) * g.rounded(step / u)) * u + g.shift.x();
  g.w.y() = g.rounded((y0 - g.shift.y()) / u) * u + g.shift.y();
  g.motion = 1;
}

void if_feature(Gen& g) {
  g.feature("if");
  g.set_absolute();
  if (!g.known) return;
  const double u = g.unit();
  const int value = g.integer(0, 4), label = g.label++;
  const std::string var = fmt::format("#<n{}>", label), o = fmt::format("o{}", label);
  g.lines.push_back(var + " = " + std::to_string(value));
  // Three branches, each one move somewhere in the region; one runs.
  const int taken = value > 2 ? 0 : value == 1 ? 1 : 2;
  const char* heads[3] = {" if [", " elseif [", " else"};
  const char* conds[3] = {" GT 2]", " EQ 1]", ""};
  Vec chosen = g.w;
  for (int b = 0; b < 3; ++b) {
    g.lines.push_back(o + heads[b] + (b < 2 ? var + conds[b] : ""));
    const Vec t = g.random_point();
    const Vec p = (t - g.shift) / u;
    g.emit(g.join({g.code("G1"), g.word('X', p.x()), g.word('Y', p.y()), g.feed_word()}));
    if (g.chance(0.15)) g.lines.push_back(user_m_line(g));
    if (b == taken)
      chosen = Vec(g.rounded(p.x()) * u + g.shift.x(), g.rounded(p.y()) * u + g.shift.y(), g.w.z());
  }
  g.lines.push_back(o + " endif");
  g.w = chosen;
  g.motion = 1;
}

void params_feature(Gen& g) {
  g.feature("parameters");
  g.set_absolute();
  g.set_plane(0);
  const double u = g.unit();
  const int label = g.label++;
  const std::string safe = fmt::format("#<_safe{}>", label),
                    depth = fmt::format("#{}", 31 + label % 60);
  const double s = g.rounded((g.safe_z - g.shift.z()) / u),
               d = g.rounded((g.uniform(g.lo.z(), 0) - g.shift.z()) / u);
  g.lines.push_back(safe + " = " + g.num(s));
  g.lines.push_back(depth + " = " + g.num(d));
  const double r = g.uniform(2, 30);
  const Vec c =
      g.clamp(g.random_point()).cwiseMax(g.lo + Vec(r, r, 0)).cwiseMin(g.hi - Vec(r, r, 0));
  const std::string cx = g.num((c.x() - g.shift.x()) / u), cy = g.num((c.y() - g.shift.y()) / u);
  const std::string rs = g.num(r / u);
  g.emit("G0 Z" + safe);
  g.w.z() = s * u + g.shift.z();
  double deg = g.integer(0, 359);
  const auto point = [&](const std::string& code, double a) {
    g.emit(code + " X[" + cx + " + " + rs + " * COS[" + g.num(a, 0) + "]] Y[" + cy + " + " + rs +
           " * SIN[" + g.num(a, 0) + "]]");
    const double ang = g.rounded(a, 0) * M_PI / 180;
    g.w.x() = (g.rounded(c.x() / u - g.shift.x() / u) + g.rounded(r / u) * std::cos(ang)) * u +
              g.shift.x();
    g.w.y() = (g.rounded(c.y() / u - g.shift.y() / u) + g.rounded(r / u) * std::sin(ang)) * u +
              g.shift.y();
  };
  point("G0", deg);
  g.emit("G1 Z" + depth + " " + g.feed_word());
  g.w.z() = d * u + g.shift.z();
  for (int k = g.integer(2, 8); k > 0; --k) point("G1", deg += g.integer(10, 60));
  g.emit("G0 Z" + safe);
  g.w.z() = s * u + g.shift.z();
  g.motion = 0;
}

void user_m_feature(Gen& g) {
  g.feature("user M");
  g.lines.push_back(user_m_line(g));
}

}  // namespace volmap::conformance::gen
