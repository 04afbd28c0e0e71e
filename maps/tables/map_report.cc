#include "maps/tables/map_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "core/common/html.h"

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

}  // namespace

std::string map_report_html(const VolumetricTable& t, const ReportInfo& info, int layer) {
  const int dims = t.axis_count();
  std::vector<std::int64_t> mid(static_cast<size_t>(dims));
  for (int d = 0; d < dims; ++d)
    mid[static_cast<size_t>(d)] = (t.grid[static_cast<size_t>(d)].count - 1) / 2;
  std::vector<Slice> slices;
  const int planar = std::min(dims, 3);
  for (int a = 0; a < planar; ++a)
    for (int b = a + 1; b < planar; ++b) slices.push_back({a, b, mid});

  std::vector<Panel> panels;
  panels.push_back({"ex (um)", {0}, 1e3, false});
  panels.push_back({"ey (um)", {1}, 1e3, false});
  panels.push_back({"ez (um)", {2}, 1e3, false});
  panels.push_back({"|e| (um)", {0, 1, 2}, 1e3, true});
  if (const std::optional<int> ei = t.channel("ei"))
    panels.push_back({"|tool-axis error| (urad)", {*ei, *ei + 1, *ei + 2}, 1e6, true});
  if (const std::optional<int> ux = t.channel("ux")) {
    panels.push_back({"ux (um)", {*ux}, 1e3, false});
    panels.push_back({"uy (um)", {*ux + 1}, 1e3, false});
    panels.push_back({"uz (um)", {*ux + 2}, 1e3, false});
  }
  // Five-axis: the rotary axes' corrections (urad).
  for (const char* name : {"ua", "ub", "uc"})
    if (const std::optional<int> c = t.channel(name))
      panels.push_back({std::string(name) + " (urad)", {*c}, 1e6, false});
  if (const std::optional<int> u = t.channel("u"))
    panels.push_back({"u, standard uncertainty (um)", {*u}, 1e3, true});

  auto node_of = [&](const std::vector<std::int64_t>& idx) {
    std::int64_t n = 0, s = 1;
    for (int d = 0; d < dims; ++d) {
      n += idx[static_cast<size_t>(d)] * s;
      s *= t.grid[static_cast<size_t>(d)].count;
    }
    return n;
  };
  auto value = [&](std::int64_t node, const Panel& p) {
    const double* v = t.at(layer, node);
    if (!p.magnitude || p.channels.size() == 1) return v[p.channels[0]] * p.scale;
    double s = 0.0;
    for (int c : p.channels) s += v[c] * v[c];
    return std::sqrt(s) * p.scale;
  };

  std::string layer_text = "both directions";
  if (!t.bidirectional_axes.empty()) {
    layer_text.clear();
    const ApproachDirections d = t.layer_directions(layer);
    for (int a : t.bidirectional_axes)
      layer_text += fmt::format("{}{}{}", layer_text.empty() ? "" : " ",
                                axis_char(t.grid[static_cast<size_t>(a)].axis),
                                d[static_cast<size_t>(a)] > 0 ? "+" : "-");
  }

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
  h += fmt::format("<tr><td>layer shown</td><td>{} ({} of {})</td></tr>\n", layer_text, layer + 1,
                   t.layer_count());
  if (info.max_interpolation_um >= 0)
    h += fmt::format("<tr><td>interpolation error</td><td>{:.4f} um ({})</td></tr>\n",
                     info.max_interpolation_um, html_escape(info.interpolation));
  h += "</table>\n";
  h +=
      "<p>Colour maps: red positive, blue negative, white zero, symmetric about zero (magnitudes: "
      "white at the slice's minimum to red at its maximum); e = tool-tip error, actual minus "
      "nominal, workpiece coordinates; "
      "u (ux uy uz) = commanded-position correction. Arrows: in-plane error, scaled so the longest "
      "is one cell (length in the caption).</p>\n";

  for (const Slice& s : slices) {
    const GridAxis& ga = t.grid[static_cast<size_t>(s.a)];
    const GridAxis& gb = t.grid[static_cast<size_t>(s.b)];
    const std::vector<std::int64_t> ka = drawn_nodes(ga), kb = drawn_nodes(gb);
    std::string fixed_text;
    for (int d = 0; d < dims; ++d) {
      if (d == s.a || d == s.b) continue;
      const GridAxis& g = t.grid[static_cast<size_t>(d)];
      fixed_text +=
          fmt::format("{}{} = {:g} {}", fixed_text.empty() ? "" : ", ", axis_char(g.axis),
                      display(g.axis, g.node(s.base[static_cast<size_t>(d)])), unit(g.axis));
    }
    h += fmt::format("<h2>Plane {}{}{}</h2>\n<div class=\"panels\">\n", axis_char(ga.axis),
                     axis_char(gb.axis), fixed_text.empty() ? "" : " at " + fixed_text);
    // Panel geometry: the plane scaled to kPanel on its longer side.
    const double wa = ga.end - ga.start, wb = gb.end - gb.start;
    const double px = kPanel / std::max(wa, wb);
    const double W = wa * px, H = wb * px;
    auto X = [&](double qa) { return 10 + (qa - ga.start) * px; };
    auto Y = [&](double qb) { return 10 + H - (qb - gb.start) * px; };  // vertical axis up
    std::vector<std::int64_t> idx = s.base;
    auto cell_bounds = [&](const std::vector<std::int64_t>& k, size_t i, const GridAxis& g) {
      const double lo = i == 0 ? g.node(k[i]) : 0.5 * (g.node(k[i - 1]) + g.node(k[i]));
      const double hi = i + 1 == k.size() ? g.node(k[i]) : 0.5 * (g.node(k[i]) + g.node(k[i + 1]));
      return std::array<double, 2>{lo, hi};
    };
    for (const Panel& p : panels) {
      // Signed values: symmetric scale +-max|v|. Magnitudes: min .. max.
      double vabs = 0.0, vmin = std::numeric_limits<double>::infinity(), vmax = -vmin;
      for (std::int64_t ia : ka)
        for (std::int64_t ib : kb) {
          idx[static_cast<size_t>(s.a)] = ia;
          idx[static_cast<size_t>(s.b)] = ib;
          const double v = value(node_of(idx), p);
          vabs = std::max(vabs, std::abs(v));
          vmin = std::min(vmin, v);
          vmax = std::max(vmax, v);
        }
      h += fmt::format(
          "<figure>\n<svg width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.0f} {:.0f}\" "
          "role=\"img\">\n",
          W + 20, H + 20, W + 20, H + 20);
      for (size_t i = 0; i < ka.size(); ++i) {
        const std::array<double, 2> ra = cell_bounds(ka, i, ga);
        for (size_t j = 0; j < kb.size(); ++j) {
          const std::array<double, 2> rb = cell_bounds(kb, j, gb);
          idx[static_cast<size_t>(s.a)] = ka[i];
          idx[static_cast<size_t>(s.b)] = kb[j];
          const double v = value(node_of(idx), p);
          const double tcol = p.magnitude ? (vmax > vmin ? (v - vmin) / (vmax - vmin) : 0.0)
                                          : (vabs > 0 ? v / vabs : 0.0);
          h += fmt::format(
              "<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" "
              "fill=\"{}\"><title>{} = {:g}, {} = {:g}: {:.4f}</title></rect>\n",
              X(ra[0]), Y(rb[1]), std::max(0.01, (ra[1] - ra[0]) * px),
              std::max(0.01, (rb[1] - rb[0]) * px), colour(tcol), axis_char(ga.axis),
              display(ga.axis, ga.node(ka[i])), axis_char(gb.axis),
              display(gb.axis, gb.node(kb[j])), v);
        }
      }
      h += "</svg>\n";
      h += fmt::format("<figcaption>{}: {:.4f} .. {:.4f}{}</figcaption>\n</figure>\n",
                       html_escape(p.title), vmin, vmax,
                       p.magnitude ? " (white .. red)" : fmt::format(" (scale +-{:.4f})", vabs));
    }
    // Vectors: the in-plane components of e (linear axes only).
    if (!is_rotary(ga.axis) && !is_rotary(gb.axis)) {
      const int ca = static_cast<int>(ga.axis), cb = static_cast<int>(gb.axis);
      double emax = 0.0;
      for (std::int64_t ia : ka)
        for (std::int64_t ib : kb) {
          idx[static_cast<size_t>(s.a)] = ia;
          idx[static_cast<size_t>(s.b)] = ib;
          const double* v = t.at(layer, node_of(idx));
          emax = std::max(emax, std::hypot(v[ca], v[cb]));
        }
      const double cell = std::min(W / std::max<double>(1, static_cast<double>(ka.size()) - 1),
                                   H / std::max<double>(1, static_cast<double>(kb.size()) - 1));
      const double k = emax > 0 ? cell / emax : 0.0;
      h += fmt::format(
          "<figure>\n<svg width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.0f} {:.0f}\" "
          "role=\"img\">\n",
          W + 20, H + 20, W + 20, H + 20);
      h += fmt::format(
          "<rect x=\"10\" y=\"10\" width=\"{:.2f}\" height=\"{:.2f}\" fill=\"none\" "
          "stroke=\"#999\"/>\n",
          W, H);
      for (std::int64_t ia : ka)
        for (std::int64_t ib : kb) {
          idx[static_cast<size_t>(s.a)] = ia;
          idx[static_cast<size_t>(s.b)] = ib;
          const double* v = t.at(layer, node_of(idx));
          const double x0 = X(ga.node(ia)), y0 = Y(gb.node(ib));
          const double x1 = x0 + v[ca] * k, y1 = y0 - v[cb] * k;
          h += fmt::format(
              "<line x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" stroke=\"#b22\" "
              "stroke-width=\"1.2\"/>"
              "<circle cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"1.2\" fill=\"#333\"/>\n",
              x0, y0, x1, y1, x0, y0);
        }
      h += "</svg>\n";
      h += fmt::format(
          "<figcaption>in-plane error (e{}, e{}): longest {:.4f} um = one "
          "cell</figcaption>\n</figure>\n",
          static_cast<char>(axis_char(ga.axis) - 'A' + 'a'),
          static_cast<char>(axis_char(gb.axis) - 'A' + 'a'), emax * 1e3);
    }
    h += "</div>\n";
  }
  h += "</body>\n</html>\n";
  return h;
}

}  // namespace volmap::maps
