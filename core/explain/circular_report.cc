// The circular tests in explain's outputs (circular_report.h).
#include "core/explain/circular_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "core/common/html.h"
#include "core/common/svg_plot.h"
#include "core/explain/parameter_report.h"

namespace volmap::explanation {
namespace {

std::string optional_um(const std::optional<double>& v) {
  return v ? fmt::format("{:.3g} µm", *v) : std::string("n/a (one direction)");
}

/// One polar plot: each path's deviation (magnified) about the nominal
/// circle; `fit` draws the findings' fitted part dashed as well.
std::string polar_plot(const CircularTest& t, bool after, double um_per_ring) {
  // px: the nominal circle, and the spacing of the rings (two each side)
  constexpr double kSize = 360, kCentre = kSize / 2, kRing = 100, kSpacing = 32;
  std::ostringstream s;
  s << svg::open_plot(kSize, kSize + 24,
                      after ? "what the findings leave" : "recorded, with the findings' fit");
  // nominal circle and the rings +-1, +-2 um_per_ring
  const double px_per_um = kSpacing / um_per_ring;
  for (int k = -2; k <= 2; ++k)
    s << fmt::format(
        "<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" fill=\"none\" stroke=\"{}\" "
        "stroke-width=\"{}\"/>\n",
        kCentre, kCentre, kRing + k * kSpacing, k == 0 ? "#888" : "#ddd", k == 0 ? 1.2 : 0.8);
  const char* colours[] = {"#1f5fbf", "#c0392b"};
  auto trace = [&](const CircularTest::Path& p, const std::vector<double>& um, const char* colour,
                   const char* dash) {
    std::string pts;
    for (std::size_t i = 0; i < p.angle_deg.size(); ++i) {
      const double a = p.angle_deg[i] * std::numbers::pi / 180, r = kRing + um[i] * px_per_um;
      pts += fmt::format("{:.1f},{:.1f} ", kCentre + r * std::cos(a), kCentre - r * std::sin(a));
    }
    s << fmt::format(
        "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.2\"{}/>\n", pts,
        colour, dash[0] ? fmt::format(" stroke-dasharray=\"{}\"", dash) : "");
  };
  for (std::size_t k = 0; k < t.paths.size(); ++k) {
    const CircularTest::Path& p = t.paths[k];
    const char* colour = colours[p.direction == "ccw" ? 0 : 1];
    if (after) {
      std::vector<double> rest(p.deviation_um.size());
      for (std::size_t i = 0; i < rest.size(); ++i) rest[i] = p.deviation_um[i] - p.fitted_um[i];
      trace(p, rest, colour, "");
    } else {
      trace(p, p.deviation_um, colour, "");
      trace(p, p.fitted_um, "#222", "4 3");
    }
  }
  s << fmt::format(
      "<text x=\"6\" y=\"{:.0f}\" class=\"note\">{}: {:.3g} µm per ring; blue ccw, red "
      "cw{}</text>\n",
      kSize + 16, after ? "left by the findings" : "recorded", um_per_ring,
      after ? "" : "; dashed: fit");
  s << "</svg>";
  return s.str();
}

}  // namespace

nlohmann::ordered_json circular_json(const std::vector<CircularTest>& tests) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (const CircularTest& t : tests) {
    nlohmann::ordered_json paths = nlohmann::ordered_json::array();
    for (const CircularTest::Path& p : t.paths)
      paths.push_back({{"run", p.run},
                       {"direction", p.direction},
                       {"readings", p.angle_deg.size()},
                       {"g_um", json_number(p.g_um)},
                       {"g_after_um", json_number(p.g_after_um)}});
    out.push_back(
        {{"plane", t.plane},
         {"centre_mm",
          {json_number(t.centre_mm[0]), json_number(t.centre_mm[1]), json_number(t.centre_mm[2])}},
         {"radius_mm", json_number(t.radius_mm)},
         {"feed_mm_min", json_number(t.feed_mm_min)},
         {"paths", paths},
         {"h_um", json_number(t.h_um)},
         {"h_after_um", json_number(t.h_after_um)}});
  }
  return out;
}

std::string circular_text(const std::vector<CircularTest>& tests) {
  std::string s;
  for (const CircularTest& t : tests) {
    std::string g, g_after;
    for (const CircularTest::Path& p : t.paths) {
      g += fmt::format("{}{:.3g} µm {}", g.empty() ? "" : ", ", p.g_um, p.direction);
      g_after += fmt::format("{}{:.3g}", g_after.empty() ? "" : ", ", p.g_after_um);
    }
    s += fmt::format(
        "circular test {} r {:.4g} mm at {:.5g} mm/min (ISO 230-4): G {}, H {}; after the "
        "findings G {} µm, H {}\n",
        t.plane, t.radius_mm, t.feed_mm_min, g, optional_um(t.h_um), g_after,
        optional_um(t.h_after_um));
  }
  return s;
}

std::string circular_html(const std::vector<CircularTest>& tests) {
  if (tests.empty()) return "";
  std::ostringstream s;
  s << "<h2>Circular tests (ISO 230-4)</h2>\n<p class=\"note\">Radial deviation after the "
       "least-squares circle (centre offset and radius error removed). G: circular deviation "
       "(the radial band holding the path); H: circular hysteresis (the largest radial "
       "difference between the counter-clockwise and clockwise paths, about their common "
       "least-squares centre).</p>\n";
  for (const CircularTest& t : tests) {
    s << fmt::format(
        "<h3>{} plane, radius {:.4g} mm, centre ({:.4g}, {:.4g}, {:.4g}) mm, {:.5g} "
        "mm/min</h3>\n<table>\n<tr><th>run</th><th>direction</th><th>G recorded</th><th>G "
        "after the findings</th></tr>\n",
        t.plane, t.radius_mm, t.centre_mm[0], t.centre_mm[1], t.centre_mm[2], t.feed_mm_min);
    double largest = 0;
    for (const CircularTest::Path& p : t.paths) {
      s << fmt::format("<tr><td>{}</td><td>{}</td><td>{:.3g} µm</td><td>{:.3g} µm</td></tr>\n",
                       html_escape(p.run), p.direction, p.g_um, p.g_after_um);
      for (double v : p.deviation_um) largest = std::max(largest, std::abs(v));
    }
    s << fmt::format("<tr><td colspan=\"2\">H</td><td>{}</td><td>{}</td></tr>\n</table>\n",
                     optional_um(t.h_um), optional_um(t.h_after_um));
    // rings of a round size (1, 2, 5 x 10^k um): the largest deviation within two
    const double raw = std::max(largest, 1e-3) / 2,
                 decade = std::pow(10, std::floor(std::log10(raw)));
    double um_per_ring = 10 * decade;
    for (double m : {1.0, 2.0, 5.0})
      if (m * decade >= raw) {
        um_per_ring = m * decade;
        break;
      }
    s << "<div class=\"plots\">\n"
      << polar_plot(t, false, um_per_ring) << "\n"
      << polar_plot(t, true, um_per_ring) << "\n</div>\n";
  }
  return s.str();
}

}  // namespace volmap::explanation
