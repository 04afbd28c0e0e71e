// The reports' plots as Chromium lays them out (issue 23, "reports one
// reads at a glance"): a copy of the page with a measuring script loads in
// headless Chromium, and the boxes of every text, frame, legend and data
// mark of each <svg class="plot"> (core/common/svg_plot.h's classes) come
// back as JSON. expect_plots_read_at_a_glance checks what every plot must
// satisfy; the report tests check their own labels on what it returns.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/browser.h"

namespace volmap::test {

inline const char* const kLayoutProbeScript = R"JS(
<script>
(function () {
  const box = (r) => [r.left, r.top, r.right, r.bottom];
  const plots = [];
  document.querySelectorAll('svg.plot').forEach((svg) => {
    const m = svg.getScreenCTM();
    const at = (x, y) => { const p = new DOMPoint(x, y).matrixTransform(m); return [p.x, p.y]; };
    const o = { cls: svg.getAttribute('class'), box: box(svg.getBoundingClientRect()),
                frame: null, legend: null, texts: [], marks: [] };
    const frame = svg.querySelector('.frame');
    if (frame) o.frame = box(frame.getBoundingClientRect());
    const legend = svg.querySelector('.legend');
    if (legend) o.legend = box(legend.getBoundingClientRect());
    svg.querySelectorAll('text').forEach((t) => o.texts.push(
        { cls: t.getAttribute('class') || '', text: t.textContent,
          box: box(t.getBoundingClientRect()) }));
    svg.querySelectorAll('.data').forEach((e) => {
      const kind = (e.getAttribute('class') || '').includes('fit') ? 'fit' : e.tagName;
      if (e.tagName === 'polyline') {
        for (const p of e.points) o.marks.push([kind, ...at(p.x, p.y)]);
      } else if (e.tagName === 'circle') {
        o.marks.push([kind, ...at(e.cx.baseVal.value, e.cy.baseVal.value)]);
      } else if (e.tagName === 'line') {
        o.marks.push([kind, ...at(e.x1.baseVal.value, e.y1.baseVal.value)]);
        o.marks.push([kind, ...at(e.x2.baseVal.value, e.y2.baseVal.value)]);
      } else {
        const r = e.getBoundingClientRect();
        o.marks.push([kind, r.left, r.top], [kind, r.right, r.bottom]);
      }
    });
    plots.push(o);
  });
  const pre = document.createElement('pre');
  pre.id = 'layout-probe';
  pre.textContent = JSON.stringify(plots);
  document.body.appendChild(pre);
})();
</script>
)JS";

/// The plots of the page at html_path as laid out by Chromium (an array,
/// one object per plot: cls, box, frame, legend, texts [{cls, text, box}],
/// marks [[kind, x, y]]; boxes [left, top, right, bottom] px). The page
/// itself is not touched: the probe loads a copy, without the page's
/// Content-Security-Policy (which forbids scripts).
inline nlohmann::json probe_plot_layout(const std::string& html_path) {
  std::string page = read_text_file(html_path);
  const std::size_t csp = page.find("<meta http-equiv=\"Content-Security-Policy\"");
  if (csp != std::string::npos) page.erase(csp, page.find('>', csp) + 1 - csp);
  const std::size_t end = page.rfind("</body>");
  EXPECT_NE(end, std::string::npos);
  if (end == std::string::npos) return nlohmann::json::array();
  page.insert(end, kLayoutProbeScript);
  const std::string probe = html_path + ".probe.html";
  std::ofstream(probe, std::ios::binary) << page;
  std::string dom, console;
  load_in_chromium(probe, dom, console);
  const std::string open = "<pre id=\"layout-probe\">";
  const std::size_t a = dom.find(open);
  EXPECT_NE(a, std::string::npos) << "the probe did not run: " << console;
  if (a == std::string::npos) return nlohmann::json::array();
  const std::size_t b = dom.find("</pre>", a);
  std::string text = dom.substr(a + open.size(), b - a - open.size());
  // --dump-dom escapes &, < and > in text.
  for (const auto& [ref, ch] :
       {std::pair<std::string, std::string>{"&lt;", "<"}, {"&gt;", ">"}, {"&amp;", "&"}})
    for (std::size_t p = text.find(ref); p != std::string::npos; p = text.find(ref, p + 1))
      text.replace(p, ref.size(), ch);
  return nlohmann::json::parse(text);
}

namespace layout_detail {
inline bool inside(const nlohmann::json& inner, const nlohmann::json& outer, double tol) {
  return inner[0].get<double>() >= outer[0].get<double>() - tol &&
         inner[1].get<double>() >= outer[1].get<double>() - tol &&
         inner[2].get<double>() <= outer[2].get<double>() + tol &&
         inner[3].get<double>() <= outer[3].get<double>() + tol;
}
inline double overlap_area(const nlohmann::json& p, const nlohmann::json& q) {
  const double w = std::min(p[2].get<double>(), q[2].get<double>()) -
                   std::max(p[0].get<double>(), q[0].get<double>());
  const double h = std::min(p[3].get<double>(), q[3].get<double>()) -
                   std::max(p[1].get<double>(), q[1].get<double>());
  return w > 0 && h > 0 ? w * h : 0.0;
}
// The numbers of an axis's tick labels; false when a label is no plain number.
inline bool tick_values(const nlohmann::json& plot, const std::string& cls,
                        std::vector<double>& v) {
  v.clear();
  for (const auto& t : plot["texts"])
    if (t["cls"] == cls) {
      const std::string s = t["text"];
      char* end = nullptr;
      v.push_back(std::strtod(s.c_str(), &end));
      if (s.empty() || *end != '\0') return false;
    }
  std::sort(v.begin(), v.end());
  return true;
}
// Evenly spaced by 1, 2 or 5 times a power of ten (a linear axis), or by
// factors of ten (a logarithmic one).
inline bool round_ticks(const std::vector<double>& v, bool log) {
  if (v.size() < 2) return false;
  const double step = log ? v[1] / v[0] : v[1] - v[0];
  if (!(step > 0)) return false;
  for (std::size_t i = 1; i < v.size(); ++i) {
    const double d = log ? v[i] / v[i - 1] : v[i] - v[i - 1];
    if (std::abs(d - step) > 1e-6 * step) return false;
  }
  if (log) return std::abs(step - 10.0) < 1e-9;
  const double m = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
  return std::abs(m - 1) < 1e-6 || std::abs(m - 2) < 1e-6 || std::abs(m - 5) < 1e-6;
}
}  // namespace layout_detail

/// What every plot of the reports satisfies, as laid out: an x and a y axis
/// label (and a colour bar's label where there is a bar), each axis with at
/// least three round ticks (decades on a log axis), no text clipped by the
/// plot's edge or overlapping another, the legend outside the plotting
/// area, every data mark inside it.
inline void expect_plots_read_at_a_glance(const nlohmann::json& plots) {
  using namespace layout_detail;
  ASSERT_FALSE(plots.empty()) << "no <svg class=\"plot\"> in the page";
  for (const auto& p : plots) {
    const std::string title =
        p["texts"].empty() ? p["cls"].get<std::string>() : p["texts"][0]["text"].get<std::string>();
    SCOPED_TRACE(title);
    int labels[3] = {0, 0, 0};
    bool bar = false;
    for (const auto& t : p["texts"]) {
      const std::string cls = t["cls"], text = t["text"];
      if (cls == "x-label") labels[0] += !text.empty();
      if (cls == "y-label") labels[1] += !text.empty();
      if (cls == "c-label") labels[2] += !text.empty();
      bar = bar || cls == "c-tick";
      EXPECT_TRUE(inside(t["box"], p["box"], 1.0)) << "clipped: \"" << text << "\"";
    }
    EXPECT_EQ(labels[0], 1) << "x axis label";
    EXPECT_EQ(labels[1], 1) << "y axis label";
    if (bar) {
      EXPECT_EQ(labels[2], 1) << "colour bar label";
    }
    const bool log_y = p["cls"].get<std::string>().find("log-y") != std::string::npos;
    for (const char* axis : {"x-tick", "y-tick", "c-tick"}) {
      std::vector<double> v;
      EXPECT_TRUE(tick_values(p, axis, v)) << axis << ": a label is not a number";
      if (std::string(axis) == "c-tick" && !bar) continue;
      const bool log = log_y && std::string(axis) == "y-tick";
      EXPECT_GE(v.size(), log ? 2u : 3u) << axis;
      EXPECT_TRUE(round_ticks(v, log)) << axis << " ticks are not round";
    }
    for (std::size_t i = 0; i < p["texts"].size(); ++i)
      for (std::size_t j = i + 1; j < p["texts"].size(); ++j)
        EXPECT_LT(overlap_area(p["texts"][i]["box"], p["texts"][j]["box"]), 1.0)
            << "\"" << p["texts"][i]["text"] << "\" overlaps \"" << p["texts"][j]["text"] << "\"";
    ASSERT_FALSE(p["frame"].is_null()) << "no plotting area";
    if (!p["legend"].is_null()) {
      EXPECT_EQ(overlap_area(p["legend"], p["frame"]), 0.0) << "the legend is in the plot";
    }
    int outside = 0;
    for (const auto& m : p["marks"]) {
      const nlohmann::json pt = {m[1], m[2], m[1], m[2]};
      outside += !inside(pt, p["frame"], 1.0);
    }
    EXPECT_EQ(outside, 0) << "data marks outside the plotting area";
  }
}

/// The texts of class cls in the plots (in page order).
inline std::vector<std::string> plot_texts(const nlohmann::json& plots, const std::string& cls) {
  std::vector<std::string> out;
  for (const auto& p : plots)
    for (const auto& t : p["texts"])
      if (t["cls"] == cls) out.push_back(t["text"]);
  return out;
}

}  // namespace volmap::test
