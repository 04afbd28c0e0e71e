// Features of straight moves and arcs (gen_state.h): random walks, facing
// passes, profiles with rounded corners, full circles and helices, arcs in
// G18 and G19, polar moves, and an incremental stretch.
#include <fmt/format.h>

#include <cmath>

#include "tests/conformance/gen_state.h"

namespace volmap::conformance::gen {

void approach(Gen& g, double x, double y, double depth) {
  g.set_absolute();
  g.retract();
  g.move(0, x, y, std::nullopt);
  if (g.chance(0.5)) g.move(0, std::nullopt, std::nullopt, std::min(g.safe_z, depth + 2));
  g.move(1, std::nullopt, std::nullopt, depth);
}

double step_length(Gen& g) {
  const double k = g.uniform(0, 1);
  return k < 0.25 ? g.uniform(0.05, 3) : k < 0.8 ? g.uniform(3, 30) : g.uniform(30, 180);
}

void lines_feature(Gen& g) {
  g.feature("lines");
  const Vec p = g.random_point();
  if (!g.known) approach(g, p.x(), p.y(), p.z());
  for (int n = g.integer(3, 15); n > 0; --n) {
    const double len = step_length(g), a = g.uniform(0, 2 * M_PI);
    Vec t = g.w + Vec(len * std::cos(a), len * std::sin(a), 0);
    if (g.chance(0.3)) t.z() += g.uniform(-5, 5);
    t = g.clamp(t);
    const bool x = g.chance(0.9), y = g.chance(0.9), z = g.chance(0.4);
    g.move(1, x ? std::optional(t.x()) : std::nullopt, y ? std::optional(t.y()) : std::nullopt,
           z ? std::optional(t.z()) : std::nullopt);
  }
}

void zigzag_feature(Gen& g) {
  g.feature("zigzag");
  const double width = g.uniform(10, 160), step = g.uniform(0.5, 6);
  const int rows = g.integer(2, 14);
  const double x0 = g.uniform(g.lo.x(), g.hi.x() - width);
  const double y0 = g.uniform(g.lo.y(), std::max(g.lo.y(), g.hi.y() - rows * step));
  const double depth = g.uniform(g.lo.z(), 0);
  approach(g, x0, y0, depth);
  const bool along_y = g.chance(0.2);
  for (int r = 0; r < rows; ++r) {
    const double far = r % 2 == 0 ? x0 + width : x0;
    if (along_y)
      g.move(1, std::nullopt, g.clamp(Vec(0, y0 + (far - x0) / 2, 0)).y(), std::nullopt);
    else
      g.move(1, far, std::nullopt, std::nullopt);
    if (r + 1 < rows)
      g.move(1, std::nullopt, std::min(g.hi.y(), y0 + (r + 1) * step), std::nullopt);
  }
}

// A rectangle with rounded corners (arcs of radius rc), clockwise or not.
void contour_feature(Gen& g) {
  g.feature("contour");
  g.set_plane(0);
  const double wx = g.uniform(8, 120), wy = g.uniform(8, 100);
  const double rc = g.uniform(0.2, std::min(wx, wy) / 2 - 0.1);
  const double x0 = g.uniform(g.lo.x(), g.hi.x() - wx), y0 = g.uniform(g.lo.y(), g.hi.y() - wy);
  const double depth = g.uniform(g.lo.z(), 0);
  const bool cw = g.chance(0.5), r_form = g.chance(0.3);
  // Corners' centres counter-clockwise from the lower left.
  const Vec c[4] = {Vec(x0 + rc, y0 + rc, depth), Vec(x0 + wx - rc, y0 + rc, depth),
                    Vec(x0 + wx - rc, y0 + wy - rc, depth), Vec(x0 + rc, y0 + wy - rc, depth)};
  const Vec out[4] = {Vec(0, -1, 0), Vec(1, 0, 0), Vec(0, 1, 0), Vec(-1, 0, 0)};  // side normals
  // Start on the bottom side's middle.
  approach(g, x0 + wx / 2, y0, depth);
  for (int k = 0; k < 4; ++k) {
    // ccw: bottom side to corner 1, arc to the right side, ...; cw: mirrored.
    const int corner = cw ? (4 - k) % 4 : (k + 1) % 4;
    const int side_in = cw ? corner : (corner + 3) % 4;   // the side that reaches the corner
    const int side_out = cw ? (corner + 3) % 4 : corner;  // the side that leaves it
    const Vec a = c[corner] + rc * out[side_in], b = c[corner] + rc * out[side_out];
    g.move(1, a.x(), a.y(), std::nullopt);
    g.arc(cw, c[corner], b, 0, r_form);
  }
  g.move(1, x0 + wx / 2, y0, std::nullopt);
}

// Full circles (end = start), with turns P, helices, small and large radii.
void circle_feature(Gen& g) {
  g.feature("circle");
  g.set_plane(0);
  const double r = g.chance(0.3) ? g.uniform(0.2, 2) : g.uniform(2, 45);
  const Vec c(g.uniform(g.lo.x() + r, g.hi.x() - r), g.uniform(g.lo.y() + r, g.hi.y() - r), 0);
  const double depth = g.uniform(g.lo.z() + 6, 0), a = g.uniform(0, 2 * M_PI);
  const Vec s = c + r * Vec(std::cos(a), std::sin(a), 0);
  approach(g, s.x(), s.y(), depth);
  const bool cw = g.chance(0.5);
  for (int n = g.integer(1, 3); n > 0; --n) {
    const int turns = g.chance(0.3) ? g.integer(1, 3) : 0;
    const bool helix = g.chance(0.4);
    Vec end = g.w;
    if (helix) end.z() = std::max(g.lo.z(), g.w.z() - g.uniform(0.2, 2));
    Vec centre = c;
    centre.z() = g.w.z();
    g.arc(cw, centre, end, turns, false);
  }
}

// Arcs in G18 (X Z) or G19 (Y Z): a ball-end profile across a slot.
void plane_arc_feature(Gen& g) {
  g.feature("plane-arcs");
  const int p = g.chance(0.5) ? 1 : 2;
  const double r = g.uniform(1, 20);
  const int a = p == 1 ? 0 : 1;  // the in-plane horizontal axis
  Vec c(g.uniform(g.lo.x() + r, g.hi.x() - r), g.uniform(g.lo.y() + r, g.hi.y() - r), 0);
  c.z() = g.uniform(g.lo.z() + r, g.hi.z() - r);
  Vec s = c;
  s[a] -= r;
  approach(g, s.x(), s.y(), s.z());
  g.set_plane(p);
  for (int n = g.integer(1, 4); n > 0; --n) {
    const double from = std::atan2(g.w.z() - c.z(), g.w[a] - c[a]);
    const double sweep = g.uniform(0.2, 3.0) * (g.chance(0.5) ? 1 : -1);
    Vec e = g.w;
    e[a] = c[a] + r * std::cos(from + sweep);
    e.z() = c.z() + r * std::sin(from + sweep);
    if (g.chance(0.3)) e[1 - a] = g.clamp(e + g.uniform(-3, 3) * Vec::Ones())[1 - a];  // helix
    // sweep > 0 is counter-clockwise in (X, Z) for G18 but the plane's own
    // axes are (Z, X) there: G2 and G3 swap.
    const bool ccw_xz = sweep > 0;
    g.arc(p == 1 ? ccw_xz : !ccw_xz, c, e, 0, g.chance(0.2));
    c[1 - a] = g.w[1 - a];
  }
  g.set_plane(0);
}

// Polar moves about the program origin: G90 @ ^ points of a polygon, G91 @0
// ^step around it.
void polar_feature(Gen& g) {
  g.feature("polar");
  g.set_plane(0);
  const double u = g.unit();
  const Vec origin = g.shift;  // the program origin in w
  const double rmax = std::min(
      {g.hi.x() - origin.x(), origin.x() - g.lo.x(), g.hi.y() - origin.y(), origin.y() - g.lo.y()});
  if (rmax < 5) return;
  const double r = g.uniform(3, rmax - 1), depth = g.uniform(g.lo.z(), 0);
  double angle = g.uniform(-180, 180);
  const auto at = [&](double radius, double deg) -> Vec {
    return origin + radius * Vec(std::cos(deg * M_PI / 180), std::sin(deg * M_PI / 180), 0);
  };
  const Vec s = at(r, angle);
  approach(g, s.x(), s.y(), depth);
  const double step = g.uniform(3, 40) * (g.chance(0.5) ? 1 : -1);
  const int n = g.integer(3, 12);
  const bool incremental = g.chance(0.5);
  if (incremental) {
    g.emit(g.code("G91"));
    g.incremental = true;
  }
  for (int k = 0; k < n; ++k) {
    const std::string code = g.code(g.chance(0.1) ? "G0" : "G1");
    const double dr = g.chance(0.3) ? g.uniform(-0.1, 0.1) * r : 0.0;
    // The radius and angle of where the controller stands (program frame).
    const Vec p = (g.w - origin) / u;
    const double cur_r = std::hypot(p.x(), p.y()), cur_a = std::atan2(p.y(), p.x()) * 180 / M_PI;
    double new_r = 0, new_a = 0;
    if (incremental) {
      const double wr = g.rounded(dr / u), wa = g.rounded(step, 3);
      g.emit(g.join({code, g.word('@', wr), g.word('^', wa, 3), g.feed_word()}));
      new_r = cur_r + wr, new_a = cur_a + wa;
    } else {
      angle += step;
      const double wr = g.rounded((r + dr) / u), wa = g.rounded(angle, 3);
      g.emit(g.join({code, g.word('@', wr), g.word('^', wa, 3), g.feed_word()}));
      new_r = wr, new_a = wa;
    }
    const Vec e = at(new_r * u, new_a);
    g.w.x() = e.x(), g.w.y() = e.y();
    g.motion = code == g.code("G0") ? 0 : 1;
  }
  g.set_absolute();
}

// The shape of issue 35's class 2: one G91 polar increment repeated a few
// hundred times (a slow spiral in), inch or mm.
void polar_spiral_feature(Gen& g) {
  g.feature("polar-spiral");
  g.set_plane(0);
  const bool to_inch = g.chance(0.7);
  g.set_absolute();
  g.set_units(to_inch);
  const double u = g.unit();
  const Vec origin = g.shift;
  const double rmax = std::min({g.hi.x() - origin.x(), origin.x() - g.lo.x(), g.hi.y() - origin.y(),
                                origin.y() - g.lo.y()}) -
                      2;
  const int n = g.integer(60, 400);
  const double dr = (to_inch ? -0.0025 : -0.05) * g.uniform(0.5, 1.5);
  const double r0 = std::min(rmax / u, -dr * n + g.uniform(0.3, 1.0) * 25.4 / u);
  if (r0 + dr * n < 2 / u) return;
  const double a0 = g.uniform(0, 360);
  const Vec s = origin + r0 * u * Vec(std::cos(a0 * M_PI / 180), std::sin(a0 * M_PI / 180), 0);
  approach(g, s.x(), s.y(), g.uniform(g.lo.z(), 0));
  const double wr = g.rounded(dr, 4), wa = g.rounded(g.uniform(1, 8), 1);
  g.emit(g.code("G91"));
  g.incremental = true;
  const std::string line = g.join({g.code("G1"), g.word('@', wr, 4), g.word('^', wa, 1)});
  g.emit(g.join({line, g.feed_word()}));
  for (int k = 1; k < n; ++k) g.emit(line);
  // Where it ends: radius and angle step n times from the start's.
  const Vec p = (g.w - origin) / u;
  const double r_end = std::hypot(p.x(), p.y()) + n * wr;
  const double a_end = std::atan2(p.y(), p.x()) * 180 / M_PI + n * wa;
  const Vec e =
      origin + r_end * u * Vec(std::cos(a_end * M_PI / 180), std::sin(a_end * M_PI / 180), 0);
  g.w.x() = e.x(), g.w.y() = e.y();
  g.motion = 1;
  g.set_absolute();
}

// A stretch of G91 moves and arcs (IJK relative to the start), then G90.
void incremental_feature(Gen& g) {
  g.feature("incremental");
  g.set_plane(0);
  if (!g.known) return;
  if (!g.incremental) g.emit(g.code("G91"));
  g.incremental = true;
  for (int n = g.integer(2, 10); n > 0; --n) {
    if (g.chance(0.3)) {
      const double r = g.uniform(0.5, 15), a = g.uniform(0, 2 * M_PI);
      const Vec c = g.w - r * Vec(std::cos(a), std::sin(a), 0);
      if (((c.array() - r) < g.lo.array()).head(2).any() ||
          ((c.array() + r) > g.hi.array()).head(2).any())
        continue;
      const double b = a + g.uniform(-2.5, 2.5);
      g.arc(g.chance(0.5), c, c + r * Vec(std::cos(b), std::sin(b), 0), 0, g.chance(0.2));
    } else {
      const double len = step_length(g), a = g.uniform(0, 2 * M_PI);
      const Vec t = g.clamp(g.w + Vec(len * std::cos(a), len * std::sin(a), g.uniform(-2, 2)));
      g.move_to(1, t);
    }
  }
  g.set_absolute();
}

}  // namespace volmap::conformance::gen
