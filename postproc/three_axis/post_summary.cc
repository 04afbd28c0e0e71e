#include "postproc/three_axis/post_summary.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstddef>
#include <string>

#include "core/common/html.h"

namespace volmap::post {
namespace {

constexpr std::size_t kCycleWarningsShown = 20;

std::string where(const PostSummaryInfo& info, const std::string& file, int line) {
  return fmt::format("{}:{}", file.empty() ? info.program : file, line);
}

std::string plural(std::uint64_t n, const char* one, const char* many) {
  return fmt::format("{} {}", n, n == 1 ? one : many);
}

}  // namespace

std::string post_summary_text(const PostSummaryInfo& info, const PostReport& r) {
  std::string s;
  if (r.lines_changed == 0 && r.lines_added == 0) {
    s = fmt::format(
        "post: {}: {}, none needed a change at the output's resolution: written as "
        "read\n",
        info.program, plural(r.lines_in, "line", "lines"));
  } else {
    s = fmt::format(
        "post: {}: {} in, {} out: {} changed, {} added; arcs: {} kept, {} cut into arcs, {} as "
        "lines; largest correction {:.2f} µm, largest predicted deviation between points "
        "{:.2f} µm (tolerance {:g} µm)\n",
        info.program, plural(r.lines_in, "line", "lines"), r.lines_out, r.lines_changed,
        r.lines_added, r.arcs_kept, r.arcs_split, r.arcs_linearized, r.max_correction_mm * 1e3,
        r.max_deviation_mm * 1e3, info.tolerance_um);
  }
  if (r.comp_moves > 0)
    s += fmt::format(
        "post: {}: cutter compensation (G41/G42) kept over {}, tool radius up to {:g} mm: the "
        "controller offsets the corrected contour, at most {:.3g} µm off (a quarter of the "
        "tolerance at most; docs/post.md, Cutter compensation)\n",
        info.program, plural(r.comp_moves, "move", "moves"), r.comp_radius_mm,
        r.comp_bound_mm * 1e3);
  for (std::size_t k = 0; k < r.cycle_warnings.size() && k < kCycleWarningsShown; ++k) {
    const PostReport::CycleWarning& w = r.cycle_warnings[k];
    s += fmt::format(
        fmt::runtime(
            w.rigid_tap
                ? "warning: {}: the rigid tap (G33.1) runs on a line the controller computes, "
                  "predicted {:.2f} µm off the nominal one (tolerance {:g} µm); a tap cannot be "
                  "split: its end is corrected, the line between is the controller's\n"
                : "warning: {}: the canned cycle's feed into the hole, which the controller "
                  "computes, "
                  "is predicted {:.2f} µm off the hole's axis (tolerance {:g} µm); --expand-cycles "
                  "writes it out as moves that keep the tolerance\n"),
        where(info, w.file, w.line), w.deviation_mm * 1e3, info.tolerance_um);
  }
  if (r.cycle_warning_count > kCycleWarningsShown)
    s += fmt::format("warning: {} more canned-cycle blocks like these (--report lists them)\n",
                     r.cycle_warning_count - kCycleWarningsShown);
  return s;
}

std::string post_report_html(const PostSummaryInfo& info, const PostReport& r) {
  std::string h =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>volmap post: " +
      html_escape(info.program) +
      "</title>\n<style>\n"
      "body{font-family:sans-serif;margin:2em;max-width:70em;color:#222}\n"
      "table{border-collapse:collapse;margin:1em 0}\n"
      "td,th{border:1px solid #ccc;padding:.25em .6em;text-align:left;vertical-align:top}\n"
      "td.n{text-align:right;font-variant-numeric:tabular-nums}\n"
      "pre{margin:0;font-size:.9em;white-space:pre-wrap}\n"
      ".in{background:#fdecea}.out{background:#e8f4ea}\n"
      "</style>\n</head>\n<body>\n";
  h += "<h1>volmap post</h1>\n<table>\n";
  auto row = [&](const std::string& k, const std::string& v, bool number = true) {
    h += "<tr><th>" + html_escape(k) + "</th><td" + (number ? " class=\"n\"" : "") + ">" +
         html_escape(v) + "</td></tr>\n";
  };
  row("program", info.program, false);
  row("output", info.output, false);
  row("machine", info.machine, false);
  row("errors", info.errors, false);
  row("tolerance", fmt::format("{:g} µm", info.tolerance_um));
  row("lines in / out", fmt::format("{} / {}", r.lines_in, r.lines_out));
  row("lines changed", fmt::format("{}", r.lines_changed));
  row("lines added", fmt::format("{}", r.lines_added));
  row("arcs kept as one arc", fmt::format("{}", r.arcs_kept));
  row("arcs cut into arcs", fmt::format("{}", r.arcs_split));
  row("arcs written as lines", fmt::format("{}", r.arcs_linearized));
  row("points corrected", fmt::format("{}", r.points_corrected));
  row("largest correction", fmt::format("{:.3f} µm", r.max_correction_mm * 1e3));
  row("largest predicted deviation between points",
      fmt::format("{:.3f} µm", r.max_deviation_mm * 1e3));
  if (r.read.flattened_from > 0)
    row("flattened",
        fmt::format(
            "from line {}: {} lines ran as {} blocks; {}", r.read.flattened_from,
            r.read.flat_source_lines, r.read.flat_blocks,
            r.flattened_written_as_read ? "none needed a change, written as read" : "written flat"),
        false);
  h += "</table>\n";
  if (r.cycle_warning_count > 0) {
    h += fmt::format(
        "<h2>Canned cycles whose feed leaves the tolerance ({})</h2>\n<p>The controller computes "
        "the feed into the hole; <code>--expand-cycles</code> writes it out as moves that keep "
        "the tolerance.</p>\n<table>\n<tr><th>line</th><th>predicted deviation</th></tr>\n",
        r.cycle_warning_count);
    for (const PostReport::CycleWarning& w : r.cycle_warnings)
      h += fmt::format("<tr><td>{}</td><td class=\"n\">{:.3f} µm</td></tr>\n",
                       html_escape(where(info, w.file, w.line)), w.deviation_mm * 1e3);
    h += "</table>\n";
  }
  h += fmt::format("<h2>Lines changed ({} shown)</h2>\n", r.changes.size());
  if (r.changes.empty()) {
    h += "<p>None: the output is the program as read.</p>\n";
  } else {
    h += "<table>\n<tr><th>line</th><th>as read</th><th>as written</th></tr>\n";
    for (const PostReport::Change& c : r.changes)
      h += "<tr><td>" + html_escape(where(info, c.file, c.line)) + "</td><td class=\"in\"><pre>" +
           html_escape(c.in) + "</pre></td><td class=\"out\"><pre>" + html_escape(c.out) +
           "</pre></td></tr>\n";
    h += "</table>\n";
  }
  h += "</body>\n</html>\n";
  return h;
}

}  // namespace volmap::post
