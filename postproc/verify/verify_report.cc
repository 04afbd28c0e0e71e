#include "postproc/verify/verify_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/common/html.h"
#include "core/common/svg_plot.h"

namespace volmap::post {
namespace {

constexpr double kWidth = 760, kHeight = 300;
// The plotting area: the legend's row above it, the last tick label's
// half width to its right.
const svg::Frame kFrame{64, 34, kWidth - 64 - 32, kHeight - 34 - 46};
const char* const kColour[2] = {"#d95f02", "#1b65b0"};  // before, after

// Decades spanned by a log axis over the positive values [lo, hi].
struct LogAxis {
  double lo_exp, hi_exp;
  explicit LogAxis(double lo, double hi) {
    lo_exp = std::floor(std::log10(std::max(lo, 1e-6)));
    hi_exp = std::ceil(std::log10(std::max(hi, 1e-6)));
    if (hi_exp <= lo_exp) hi_exp = lo_exp + 1;
  }
  double y(double v) const {
    const double e = std::log10(std::max(v, std::pow(10.0, lo_exp)));
    return kFrame.top + kFrame.height * (hi_exp - e) / (hi_exp - lo_exp);
  }
};

// One plot: the largest deviation per bin along the path, both runs.
std::string profile_plot(const VerifyReportRun* runs[2], bool angles, const std::string& title,
                         const std::string& y_label) {
  double length = 0, lo = 1e300, hi = 0;
  for (int r = 0; r < 2; ++r) {
    const DeviationProfile& p = *runs[r]->profile;
    length = std::max(length, p.path_length_mm());
    for (const ProfileBin& b : p.bins()) {
      if (b.samples == 0) continue;
      const double v = angles ? b.max_urad : b.max_um;
      if (v > 0) lo = std::min(lo, v), hi = std::max(hi, v);
    }
  }
  if (hi <= 0) return fmt::format("<p>{}: no samples.</p>\n", html_escape(title));
  if (length <= 0) length = 1;
  const LogAxis ax(std::max(lo, hi * 1e-4), hi);
  const svg::Scale x_of{0.0, length, kFrame.left, kFrame.right()};
  std::string svg = fmt::format("<figure><figcaption>{}</figcaption>\n", html_escape(title)) +
                    svg::open_plot(kWidth, kHeight, title, true) + svg::frame_rect(kFrame);
  // A grid line and a label per decade; round path lengths.
  for (double e = ax.lo_exp; e <= ax.hi_exp + 1e-9; e += 1) {
    const double y = ax.y(std::pow(10.0, e));
    svg += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>"
        "<text class=\"y-tick\" x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"10\" "
        "text-anchor=\"end\">{:g}</text>\n",
        kFrame.left, y, kFrame.right(), y, kFrame.left - 6, y + 3.5, std::pow(10.0, e));
  }
  svg += svg::x_axis(kFrame, x_of, svg::nice_ticks(0.0, length), "path length, mm");
  svg += svg::vertical_label("y-label", 14, kFrame.top + kFrame.height / 2, y_label);
  for (int r = 0; r < 2; ++r) {
    const DeviationProfile& p = *runs[r]->profile;
    std::string points;
    for (std::size_t k = 0; k < p.bins().size(); ++k) {
      const ProfileBin& b = p.bins()[k];
      if (b.samples == 0) continue;
      const double v = angles ? b.max_urad : b.max_um;
      points += fmt::format("{:.1f},{:.1f} ",
                            x_of((static_cast<double>(k) + 0.5) * p.bin_width_mm()), ax.y(v));
    }
    svg += fmt::format(
        "<polyline class=\"data\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" "
        "points=\"{}\"/>\n",
        kColour[r], points);
  }
  svg += svg::legend_row(kFrame.left, kFrame.top - 10,
                         {{kColour[0], runs[0]->label}, {kColour[1], runs[1]->label}});
  svg += "</svg></figure>\n";
  return svg;
}

std::string worst_table(const VerifyReportRun& run) {
  std::string t = fmt::format(
      "<table><caption>{}: the lines with the largest tip deviation ({})</caption>\n"
      "<tr><th>line</th><th>max, &#181;m</th></tr>\n",
      html_escape(run.label), html_escape(run.program));
  for (const WorstLine& w : run.profile->worst_lines())
    t += fmt::format("<tr><td>{}</td><td>{:.3f}</td></tr>\n", w.line, w.max_um);
  return t + "</table>\n";
}

}  // namespace

std::string verify_report_html(const VerifyReportInfo& info, const VerifyReportRun& before,
                               const VerifyReportRun& after) {
  const VerifyReportRun* runs[2] = {&before, &after};
  std::string h =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
      "<title>volmap verify</title>\n<style>\n"
      "body{font-family:sans-serif;margin:24px;max-width:820px;color:#222}\n"
      "table{border-collapse:collapse;margin:12px 0}td,th{border:1px solid #bbb;padding:3px "
      "8px;text-align:right}\n"
      "caption{text-align:left;font-weight:bold;padding:4px "
      "0;white-space:nowrap}figure{margin:16px "
      "0}figcaption{font-weight:bold}\n"
      "</style></head><body>\n";
  h += fmt::format(
      "<h1>volmap verify</h1>\n<p>Machine <b>{}</b>, errors <code>{}</code>. Deviation of the "
      "actual "
      "tool {} from the nominal path of the program, sampled along every feed move (rapids are not "
      "measured); <i>before</i> is the nominal program run uncompensated, <i>after</i> the "
      "compensated one.</p>\n",
      html_escape(info.machine), html_escape(info.errors), info.five_axis ? "pose" : "tip");
  h += "<table id=\"summary\"><caption>Summary</caption>\n<tr><th></th><th>program</th><th>max, "
       "&#181;m</th>"
       "<th>rms, &#181;m</th>";
  if (info.five_axis) h += "<th>axis max, &#181;rad</th><th>axis rms, &#181;rad</th>";
  h += "<th>samples</th><th>worst line</th></tr>\n";
  for (const VerifyReportRun* r : runs) {
    h += fmt::format("<tr><th>{}</th><td>{}</td><td>{:.3f}</td><td>{:.3f}</td>",
                     html_escape(r->label), html_escape(r->program), r->max_um, r->rms_um);
    if (info.five_axis)
      h += fmt::format("<td>{:.2f}</td><td>{:.2f}</td>", r->max_urad, r->rms_urad);
    h += fmt::format("<td>{}</td><td>{}</td></tr>\n", r->samples, r->worst_line);
  }
  h += "</table>\n";
  h += profile_plot(runs, false, "Tool-tip deviation along the path (largest per stretch)",
                    "largest deviation, \u00b5m");
  if (info.five_axis)
    h += profile_plot(runs, true, "Tool-axis deviation along the path (largest per stretch)",
                      "largest deviation, \u00b5rad");
  h += worst_table(before);
  h += worst_table(after);
  h += "</body></html>\n";
  return h;
}

}  // namespace volmap::post
