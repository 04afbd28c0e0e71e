#include "maps/tables/map_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "core/common/html.h"
#include "core/common/svg_plot.h"
#include "maps/tables/layer_name.h"

namespace volmap::maps {

namespace {

constexpr int kMaxDrawn = 48;   // nodes per axis in a panel
constexpr double kPanel = 220;  // panel size, px (longer side)

double display(AxisName a, double v) { return is_rotary(a) ? v * 180.0 / M_PI : v; }
const char* unit(AxisName a) { return is_rotary(a) ? "deg" : "mm"; }

// Diverging blue - white - red for t in [-1, 1]; sequential white - red for magnitudes.
std::string colour(double t) {
  t = std::clamp(t, -1.0, 1.0);
  int r, g, b;
  if (t >= 0) {
    r = 255;
    g = static_cast<int>(std::lround(255 * (1 - t) + 40 * t));
    b = static_cast<int>(std::lround(255 * (1 - t) + 40 * t));
  } else {
    r = static_cast<int>(std::lround(255 * (1 + t) + 40 * -t));
    g = static_cast<int>(std::lround(255 * (1 + t) + 90 * -t));
    b = 255;
  }
  return fmt::format("#{:02x}{:02x}{:02x}", r, g, b);
}

std::vector<std::int64_t> drawn_nodes(const GridAxis& g) {
  const std::int64_t step = (g.count + kMaxDrawn - 1) / kMaxDrawn;
  std::vector<std::int64_t> k;
  for (std::int64_t i = 0; i < g.count; i += step) k.push_back(i);
  if (k.back() != g.count - 1) k.push_back(g.count - 1);
  return k;
}

struct Slice {
  int a = 0, b = 1;                // the axes of the plane (horizontal, vertical)
  std::vector<std::int64_t> base;  // node index on every axis (a, b overwritten)
};

struct Panel {
  std::string title;
  std::vector<int> channels;  // one: the channel; three: magnitude of those
  double scale = 1e3;         // to display units
  bool magnitude = false;
};

// Node index of the per-axis node indices idx.
std::int64_t node_of(const VolumetricTable& t, const std::vector<std::int64_t>& idx) {
  std::int64_t n = 0, s = 1;
  for (int d = 0; d < t.axis_count(); ++d) {
    n += idx[static_cast<size_t>(d)] * s;
    s *= t.grid[static_cast<size_t>(d)].count;
  }
  return n;
}

// A panel's value at a node's channels v, in display units.
double panel_value(const double* v, const Panel& p) {
  if (!p.magnitude || p.channels.size() == 1) return v[p.channels[0]] * p.scale;
  double s = 0.0;
  for (int c : p.channels) s += v[c] * v[c];
  return std::sqrt(s) * p.scale;
}

// The planes through the middle node: every pair of the first three axes.
std::vector<Slice> middle_slices(const VolumetricTable& t) {
  const int dims = t.axis_count();
  std::vector<std::int64_t> mid(static_cast<size_t>(dims));
  for (int d = 0; d < dims; ++d)
    mid[static_cast<size_t>(d)] = (t.grid[static_cast<size_t>(d)].count - 1) / 2;
  std::vector<Slice> slices;
  const int planar = std::min(dims, 3);
  for (int a = 0; a < planar; ++a)
    for (int b = a + 1; b < planar; ++b) slices.push_back({a, b, mid});
  return slices;
}

std::vector<Panel> panels_of(const VolumetricTable& t) {
  std::vector<Panel> panels;
  panels.push_back({"ex, µm", {0}, 1e3, false});
  panels.push_back({"ey, µm", {1}, 1e3, false});
  panels.push_back({"ez, µm", {2}, 1e3, false});
  panels.push_back({"|e|, µm", {0, 1, 2}, 1e3, true});
  if (const std::optional<int> ei = t.channel("ei"))
    panels.push_back({"|tool-axis error|, µrad", {*ei, *ei + 1, *ei + 2}, 1e6, true});
  if (const std::optional<int> ux = t.channel("ux")) {
    panels.push_back({"ux, µm", {*ux}, 1e3, false});
    panels.push_back({"uy, µm", {*ux + 1}, 1e3, false});
    panels.push_back({"uz, µm", {*ux + 2}, 1e3, false});
  }
  // Five-axis: the rotary axes' corrections (urad).
  for (const char* name : {"ua", "ub", "uc"})
    if (const std::optional<int> c = t.channel(name))
      panels.push_back({std::string(name) + ", µrad", {*c}, 1e6, false});
  if (const std::optional<int> u = t.channel("u"))
    panels.push_back({"u, standard uncertainty, µm", {*u}, 1e3, true});
  return panels;
}

// The page up to the first slice: title, style, the table's description.
std::string page_head(const VolumetricTable& t, const ReportInfo& info, int layer) {
  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n";
  h += fmt::format("<title>volmap map: {}</title>\n", html_escape(t.machine_name));
  h += "<style>\nbody{font-family:sans-serif;margin:1.5em;color:#222}\n"
       "table.info td{padding:0 1em 0 0}\n.panels{display:flex;flex-wrap:wrap;gap:12px}\n"
       "figure{margin:0}\nfigcaption{font-size:13px}\nsvg{background:#fafafa;border:1px solid "
       "#ccc}\n"
       "</style>\n</head>\n<body>\n";
  h += fmt::format("<h1>Error field of {}</h1>\n", html_escape(t.machine_name));
  h += "<table class=\"info\">\n";
  h += fmt::format("<tr><td>errors</td><td>{}</td></tr>\n", html_escape(t.errors_source));
  h += fmt::format("<tr><td>model</td><td>{}</td></tr>\n", html_escape(info.model));
  for (const GridAxis& g : t.grid)
    h += fmt::format("<tr><td>axis {}</td><td>{:g} .. {:g} {}, spacing {:g}, {} nodes</td></tr>\n",
                     axis_char(g.axis), display(g.axis, g.start), display(g.axis, g.end),
                     unit(g.axis), display(g.axis, g.spacing), g.count);
  h += fmt::format("<tr><td>layer shown</td><td>{} ({} of {})</td></tr>\n", layer_name(t, layer),
                   layer + 1, t.layer_count());
  if (info.max_interpolation_um >= 0)
    h += fmt::format("<tr><td>interpolation error</td><td>{:.4f} µm ({})</td></tr>\n",
                     info.max_interpolation_um, html_escape(info.interpolation));
  h += "</table>\n";
  h += "<p>Colour maps: red positive, blue negative, white zero, symmetric about zero (magnitudes: "
       "white at the slice's minimum to red at its maximum); e = tool-tip error, actual minus "
       "nominal, workpiece coordinates; "
       "u (ux uy uz) = commanded-position correction. Arrows: in-plane error, centred on their "
       "nodes, scaled so the longest is one cell (its length in the caption).</p>\n";
  return h;
}

// [lo, hi] of the cell drawn around drawn node i of axis g.
std::array<double, 2> cell_bounds(const std::vector<std::int64_t>& k, size_t i, const GridAxis& g) {
  const double lo = i == 0 ? g.node(k[i]) : 0.5 * (g.node(k[i - 1]) + g.node(k[i]));
  const double hi = i + 1 == k.size() ? g.node(k[i]) : 0.5 * (g.node(k[i]) + g.node(k[i + 1]));
  return std::array<double, 2>{lo, hi};
}

// One slice as drawn: its axes, the nodes drawn on each, and the plane
// scaled to kPanel px on its longer side (see side()), inside a frame with the axes'
// ticks and labels left and below and room for a colour bar on the right.
// `inset` px of frame around the nodes (the arrows' half cell).
struct SlicePlane {
  SlicePlane(const VolumetricTable& t, int layer, const Slice& s)
      : table(t),
        layer(layer),
        slice(s),
        ga(t.grid[static_cast<size_t>(s.a)]),
        gb(t.grid[static_cast<size_t>(s.b)]),
        ka(drawn_nodes(ga)),
        kb(drawn_nodes(gb)),
        W(side(ga.end - ga.start, std::max(ga.end - ga.start, gb.end - gb.start))),
        H(side(gb.end - gb.start, std::max(ga.end - ga.start, gb.end - gb.start))),
        pxa(W / std::max(ga.end - ga.start, 1e-12)),
        pxb(H / std::max(gb.end - gb.start, 1e-12)),
        idx(s.base) {}

  static constexpr double kLeft = 50, kTop = 10, kBottom = 42, kRight = 96;
  // A side of kPanel px for the longer axis, in proportion for the other,
  // but at least kMinSide px: room for the colour bar's label along it.
  static constexpr double kMinSide = 160;
  static double side(double span, double longest) {
    return std::max(kMinSide, longest > 0 ? kPanel * span / longest : kPanel);
  }
  double X(double qa) const { return kLeft + inset + (qa - ga.start) * pxa; }
  double Y(double qb) const { return kTop + inset + H - (qb - gb.start) * pxb; }  // vertical up
  svg::Frame frame() const { return {kLeft, kTop, W + 2 * inset, H + 2 * inset}; }
  // The channels of the node at node indices ia, ib of the plane's axes.
  const double* at(std::int64_t ia, std::int64_t ib) {
    idx[static_cast<size_t>(slice.a)] = ia;
    idx[static_cast<size_t>(slice.b)] = ib;
    return table.at(layer, node_of(table, idx));
  }
  // "X = 100 mm, ..." for the axes the plane holds fixed.
  std::string fixed_text() const {
    std::string text;
    for (int d = 0; d < table.axis_count(); ++d) {
      if (d == slice.a || d == slice.b) continue;
      const GridAxis& g = table.grid[static_cast<size_t>(d)];
      text +=
          fmt::format("{}{} = {:g} {}", text.empty() ? "" : ", ", axis_char(g.axis),
                      display(g.axis, g.node(slice.base[static_cast<size_t>(d)])), unit(g.axis));
    }
    return text;
  }
  // The plot's opening and both axes with round ticks in the axes' display
  // units; each panel draws the frame over what it plots.
  std::string svg_open(const std::string& title, bool colour_bar = true) const {
    const svg::Frame f = frame();
    const double a0 = display(ga.axis, ga.start), a1 = display(ga.axis, ga.end);
    const double b0 = display(gb.axis, gb.start), b1 = display(gb.axis, gb.end);
    const svg::Scale sx{a0, a1, X(ga.start), X(ga.end)}, sy{b0, b1, Y(gb.start), Y(gb.end)};
    return "<figure>\n" +
           svg::open_plot(f.right() + (colour_bar ? kRight : 16), f.bottom() + kBottom, title) +
           svg::x_axis(f, sx, svg::nice_ticks(a0, a1, 4),
                       fmt::format("{}, {}", axis_char(ga.axis), unit(ga.axis))) +
           svg::y_axis(f, sy, svg::nice_ticks(b0, b1, 4),
                       fmt::format("{}, {}", axis_char(gb.axis), unit(gb.axis)));
  }

  const VolumetricTable& table;
  const int layer;
  const Slice& slice;
  const GridAxis& ga;                      ///< horizontal axis
  const GridAxis& gb;                      ///< vertical axis
  const std::vector<std::int64_t> ka, kb;  ///< the nodes drawn on each
  const double W, H;                       ///< the nodes' extent, px
  const double pxa, pxb;                   ///< px per mm (or rad) of each axis
  double inset = 0.0;                      ///< frame beyond the nodes, px
  std::vector<std::int64_t> idx;           ///< node indices of the last at()
};

// The colour bar right of the frame: the colours of [lo, hi] from bottom
// to top, round ticks, and the panel's name and unit along it.
std::string colour_bar(const svg::Frame& f, double lo, double hi, bool magnitude,
                       const std::string& label) {
  constexpr int kSteps = 32;
  const double x = f.right() + 10, w = 12;
  std::string h = "<g class=\"colour-bar\">";
  for (int i = 0; i < kSteps; ++i) {
    const double t0 = static_cast<double>(i) / kSteps, t1 = static_cast<double>(i + 1) / kSteps;
    const double mid = 0.5 * (t0 + t1);  // 0 at lo, 1 at hi
    h += fmt::format(
        "<rect x=\"{:.1f}\" y=\"{:.2f}\" width=\"{:.1f}\" height=\"{:.2f}\" fill=\"{}\"/>", x,
        f.bottom() - t1 * f.height, w, f.height / kSteps + 0.05,
        colour(magnitude ? mid : 2 * mid - 1));
  }
  h += fmt::format(
      "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" "
      "stroke=\"#888\"/>\n",
      x, f.top, w, f.height);
  const svg::Ticks t = svg::nice_ticks(lo, hi, 4);
  const svg::Scale y{lo, hi, f.bottom(), f.top};
  for (double v : t.values)
    h += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{2:.1f}\" y2=\"{1:.1f}\" stroke=\"#333\"/>"
        "<text class=\"c-tick\" x=\"{3:.1f}\" y=\"{4:.1f}\" font-size=\"10\">{5}</text>\n",
        x + w, y(v), x + w + 3, x + w + 5, y(v) + 3.5, t.text(v));
  return h + svg::vertical_label("c-label", x + w + 62, f.top + f.height / 2, label) + "</g>\n";
}

// A colour map of one panel over the plane.
std::string colour_panel(SlicePlane& plane, const Panel& p) {
  const GridAxis &ga = plane.ga, &gb = plane.gb;
  const std::vector<std::int64_t>&ka = plane.ka, &kb = plane.kb;
  // Signed values: symmetric scale +-max|v|. Magnitudes: min .. max.
  double vabs = 0.0, vmin = std::numeric_limits<double>::infinity(), vmax = -vmin;
  for (std::int64_t ia : ka)
    for (std::int64_t ib : kb) {
      const double v = panel_value(plane.at(ia, ib), p);
      vabs = std::max(vabs, std::abs(v));
      vmin = std::min(vmin, v);
      vmax = std::max(vmax, v);
    }
  plane.inset = 0.0;
  std::string h = plane.svg_open(p.title);
  for (size_t i = 0; i < ka.size(); ++i) {
    const std::array<double, 2> ra = cell_bounds(ka, i, ga);
    for (size_t j = 0; j < kb.size(); ++j) {
      const std::array<double, 2> rb = cell_bounds(kb, j, gb);
      const double v = panel_value(plane.at(ka[i], kb[j]), p);
      const double tcol = p.magnitude ? (vmax > vmin ? (v - vmin) / (vmax - vmin) : 0.0)
                                      : (vabs > 0 ? v / vabs : 0.0);
      h += fmt::format(
          "<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" "
          "fill=\"{}\"><title>{} = {:g}, {} = {:g}: {:.4f}</title></rect>\n",
          plane.X(ra[0]), plane.Y(rb[1]), std::max(0.01, (ra[1] - ra[0]) * plane.pxa),
          std::max(0.01, (rb[1] - rb[0]) * plane.pxb), colour(tcol), axis_char(ga.axis),
          display(ga.axis, ga.node(ka[i])), axis_char(gb.axis), display(gb.axis, gb.node(kb[j])),
          v);
    }
  }
  h += svg::frame_rect(plane.frame(), "none");
  h += p.magnitude
           ? colour_bar(plane.frame(), vmin, vmax > vmin ? vmax : vmin + 1e-3, true, p.title)
           : colour_bar(plane.frame(), -std::max(vabs, 1e-3), std::max(vabs, 1e-3), false, p.title);
  h += "</svg>\n";
  h += fmt::format("<figcaption>{}: {:.4f} .. {:.4f}{}</figcaption>\n</figure>\n",
                   html_escape(p.title), vmin, vmax,
                   p.magnitude ? " (white .. red)" : fmt::format(" (scale ±{:.4f})", vabs));
  return h;
}

// The in-plane components of e as arrows centred on their nodes (a plane
// of two linear axes), the longest one cell long: every arrow inside the
// frame, which reaches half a cell beyond the outer nodes.
std::string vector_panel(SlicePlane& plane) {
  const GridAxis &ga = plane.ga, &gb = plane.gb;
  const std::vector<std::int64_t>&ka = plane.ka, &kb = plane.kb;
  const int ca = static_cast<int>(ga.axis), cb = static_cast<int>(gb.axis);
  double emax = 0.0;
  for (std::int64_t ia : ka)
    for (std::int64_t ib : kb) {
      const double* v = plane.at(ia, ib);
      emax = std::max(emax, std::hypot(v[ca], v[cb]));
    }
  const double cell = std::min(plane.W / std::max<double>(1, static_cast<double>(ka.size()) - 1),
                               plane.H / std::max<double>(1, static_cast<double>(kb.size()) - 1));
  const double k = emax > 0 ? cell / emax : 0.0;
  plane.inset = cell / 2;
  const std::string name =
      fmt::format("in-plane error (e{}, e{})", static_cast<char>(axis_char(ga.axis) - 'A' + 'a'),
                  static_cast<char>(axis_char(gb.axis) - 'A' + 'a'));
  std::string h = plane.svg_open(name, false);
  for (std::int64_t ia : ka)
    for (std::int64_t ib : kb) {
      const double* v = plane.at(ia, ib);
      const double xc = plane.X(ga.node(ia)), yc = plane.Y(gb.node(ib));
      const double dx = 0.5 * v[ca] * k, dy = -0.5 * v[cb] * k;
      h += fmt::format(
          "<line class=\"data arrow\" x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" "
          "stroke=\"#b22\" stroke-width=\"1.2\"/>"
          "<circle cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"1.2\" fill=\"#333\"/>\n",
          xc - dx, yc - dy, xc + dx, yc + dy, xc + dx, yc + dy);
    }
  h += svg::frame_rect(plane.frame(), "none");
  h += "</svg>\n";
  h += fmt::format(
      "<figcaption>{}: arrows centred on the nodes, head dotted; the longest, {:.4f} µm, is one "
      "cell</figcaption>\n</figure>\n",
      name, emax * 1e3);
  return h;
}

}  // namespace

std::string map_report_html(const VolumetricTable& t, const ReportInfo& info, int layer) {
  const std::vector<Panel> panels = panels_of(t);
  std::string h = page_head(t, info, layer);
  for (const Slice& s : middle_slices(t)) {
    SlicePlane plane(t, layer, s);
    const std::string fixed_text = plane.fixed_text();
    h += fmt::format("<h2>Plane {}{}{}</h2>\n<div class=\"panels\">\n", axis_char(plane.ga.axis),
                     axis_char(plane.gb.axis), fixed_text.empty() ? "" : " at " + fixed_text);
    for (const Panel& p : panels) h += colour_panel(plane, p);
    // Vectors: the in-plane components of e (linear axes only).
    if (!is_rotary(plane.ga.axis) && !is_rotary(plane.gb.axis)) h += vector_panel(plane);
    h += "</div>\n";
  }
  h += "</body>\n</html>\n";
  return h;
}

}  // namespace volmap::maps
