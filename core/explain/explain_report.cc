// Writers of the explain result: JSON (explain.md), the stdout summary and
// the self-contained HTML report (inline SVG, no script, no network).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/common/html.h"
#include "core/common/svg_plot.h"
#include "core/explain/circular_report.h"
#include "core/explain/explain.h"
#include "core/explain/parameter_report.h"

namespace volmap {
namespace {

using explanation::json_number;
using explanation::round_significant;

nlohmann::json axis_json(const std::optional<AxisName>& a) {
  return a ? nlohmann::json(std::string(1, axis_char(*a))) : nlohmann::json(nullptr);
}

std::string params_text(const Finding& f) {
  return explanation::parameters_text(f.parameters, f.std_errors);
}

// A held-out RMS, or n/a (never followed by a unit) when there is none.
std::string opt_num(const std::optional<double>& v) {
  return v ? fmt::format("{:.3f}", *v) : std::string("n/a");
}
std::string opt_um(const std::optional<double>& v) {
  return v ? fmt::format("{:.3f} µm", *v) : std::string("n/a");
}

/// One scatter panel: points (x, y) coloured by group, y range [y_lo, y_hi]
/// shared by the pair of panels; `fit` (may be empty) the fitted term at
/// each point, drawn as a dark dash over the point's column.
std::string svg_panel(const std::string& title, const std::string& x_label,
                      const std::vector<double>& x, const std::vector<double>& y,
                      const std::vector<int>& group, const std::vector<double>& fit, double y_lo,
                      double y_hi) {
  constexpr double W = 440, H = 280;
  const svg::Frame f{58, 26, W - 58 - 18, H - 26 - 44};
  double x_lo = INFINITY, x_hi = -INFINITY;
  for (double v : x)
    if (std::isfinite(v)) {
      x_lo = std::min(x_lo, v);
      x_hi = std::max(x_hi, v);
    }
  if (!std::isfinite(x_lo)) x_lo = 0, x_hi = 1;
  if (x_hi <= x_lo) x_lo -= 0.5, x_hi += 0.5;
  const double pad = 0.03 * (x_hi - x_lo);
  const svg::Scale px{x_lo - pad, x_hi + pad, f.left, f.right()};
  const svg::Scale py{y_lo, y_hi, f.bottom(), f.top};
  std::ostringstream s;
  s << svg::open_plot(W, H, title) << svg::frame_rect(f);
  if (y_lo < 0 && y_hi > 0)
    s << fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#bbb\"/>\n", f.left,
        py(0), f.right(), py(0));
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    const int g = group.empty() ? 0 : group[i];
    const char* colour = g > 0 ? "#c0392b" : (g < 0 ? "#2471a3" : "#34495e");
    s << fmt::format(
        "<circle class=\"data\" cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2\" fill=\"{}\" "
        "fill-opacity=\"0.6\"/>",
        px(x[i]), py(y[i]), colour);
  }
  if (!fit.empty()) {
    std::string d;
    for (std::size_t i = 0; i < x.size() && i < fit.size(); ++i)
      if (std::isfinite(x[i]) && std::isfinite(fit[i]))
        d += fmt::format("M{:.1f},{:.1f}h6", px(x[i]) - 3, py(fit[i]));
    s << fmt::format(
        "\n<path class=\"data fit\" d=\"{}\" stroke=\"#111\" stroke-width=\"1.6\" "
        "fill=\"none\"/>",
        d);
  }
  s << fmt::format("\n<text x=\"{}\" y=\"16\" font-size=\"12\">{}</text>\n", f.left,
                   html_escape(title));
  s << svg::x_axis(f, px, svg::nice_ticks(x_lo - pad, x_hi + pad), x_label);
  s << svg::y_axis(f, py, svg::nice_ticks(y_lo, y_hi), "residual, µm");
  s << "</svg>";
  return s.str();
}

}  // namespace

/// Every candidate tested: status, statistic, detectable amplitude.
nlohmann::ordered_json candidates_json(const std::vector<CandidateResult>& candidates) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (const CandidateResult& c : candidates) {
    nlohmann::ordered_json o;
    o["effect"] = c.effect;
    o["axis"] = axis_json(c.axis);
    o["variant"] = c.variant;
    o["status"] = c.status;
    o["detectable_" + c.detectable_unit] = json_number(c.detectable);
    if (c.at) o["at"] = {{c.at->first, json_number(c.at->second)}};
    auto rounded = [](const std::optional<double>& v, int digits) {
      return v ? json_number(round_significant(*v, digits)) : nlohmann::json(nullptr);
    };
    o["chi2"] = rounded(c.chi2, 5);
    o["critical_chi2"] = rounded(c.critical_chi2, 5);
    o["p_value"] = rounded(c.p_value, 3);
    out.push_back(o);
  }
  return out;
}

/// The candidates' table of the report.
std::string candidates_html(const std::vector<CandidateResult>& candidates) {
  std::ostringstream s;
  s << "<h2>Detection limits</h2>\n<p class=\"note\">Every candidate tested: its likelihood-ratio "
       "statistic &chi;&sup2; against the critical value (family-wise 0.1 % false findings, "
       "the scan of its period, time constant or order and the number of candidates allowed "
       "for), and the smallest amplitude this recording would reveal with 95 % power "
       "(docs/explain.md, Detection).</p>\n<table id=\"candidates\">\n<tr><th>effect</th>"
       "<th>axis</th><th>variant</th><th>status</th><th>detectable</th><th>at</th>"
       "<th>&chi;&sup2;</th><th>critical</th><th>p</th></tr>\n";
  for (const CandidateResult& c : candidates) {
    const std::string detectable =
        c.detectable
            ? fmt::format("{:.3g} {}", *c.detectable, explanation::unit_text(c.detectable_unit))
            : std::string("not revealed by this design");
    const std::string at = c.at ? fmt::format("{} {:.4g}", c.at->first, c.at->second) : "";
    auto shown = [](const std::optional<double>& v, const char* f) {
      return v ? fmt::format(fmt::runtime(f), *v) : std::string("–");
    };
    s << fmt::format(
        "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
        "<td>{}</td><td>{}</td></tr>\n",
        c.effect, c.axis ? std::string(1, axis_char(*c.axis)) : "-", html_escape(c.variant),
        c.status, html_escape(detectable), html_escape(at), shown(c.chi2, "{:.1f}"),
        shown(c.critical_chi2, "{:.1f}"), shown(c.p_value, "{:.2g}"));
  }
  s << "</table>\n";
  return s.str();
}

nlohmann::ordered_json explain_json(const ExplainResult& r) {
  nlohmann::ordered_json j;
  j["format"] = "volmap-explain/1";
  j["recordings"] = r.recordings_file;
  j["observations"] = r.observations;
  j["runs"] = r.runs;
  j["baseline"] = {{"description", r.baseline_description},
                   {"rms_um", json_number(r.baseline_rms_um)},
                   {"heldout_rms_um", json_number(r.baseline_heldout_rms_um)}};
  nlohmann::ordered_json mm = nlohmann::ordered_json::array();
  for (const Mismatch& m : r.mismatch)
    mm.push_back({{"component", m.component},
                  {"regressor", m.regressor},
                  {"where", m.where},
                  {"strength", json_number(round_significant(m.strength, 3))}});
  j["mismatch"] = mm;
  nlohmann::ordered_json fs = nlohmann::ordered_json::array();
  for (const Finding& f : r.findings) {
    nlohmann::ordered_json o;
    o["effect"] = f.effect;
    o["axis"] = axis_json(f.axis);
    nlohmann::ordered_json p = nlohmann::ordered_json::object(),
                           se = nlohmann::ordered_json::object();
    for (const auto& [k, v] : f.parameters) p[k] = v;
    // "name/i" entries belong to an array parameter (setup_shift's
    // per_run_um): the same shape as the parameter.
    for (const auto& [k, v] : f.std_errors) {
      const std::size_t slash = k.find('/');
      if (slash == std::string::npos) {
        se[k] = json_number(v);
      } else {
        nlohmann::ordered_json& arr = se[k.substr(0, slash)];
        if (!arr.is_array()) arr = nlohmann::ordered_json::array();
        arr.push_back(nlohmann::ordered_json(json_number(v)));
      }
    }
    o["parameters"] = p;
    o["std_errors"] = se;
    o["rms_before_um"] = json_number(f.rms_before_um);
    o["rms_after_um"] = json_number(f.rms_after_um);
    o["heldout_rms_before_um"] = json_number(f.heldout_rms_before_um);
    o["heldout_rms_after_um"] = json_number(f.heldout_rms_after_um);
    o["evidence"] = {{"delta_bic", json_number(round_significant(f.delta_bic, 5))},
                     {"regressor", f.plot.regressor}};
    o["explanation"] = f.explanation;
    fs.push_back(o);
  }
  j["findings"] = fs;
  nlohmann::ordered_json cs = nlohmann::ordered_json::array();
  for (const Confounded& c : r.confounded)
    cs.push_back({{"effects", c.effects},
                  {"axis", axis_json(c.axis)},
                  {"explanation", c.explanation},
                  {"remedy", c.remedy}});
  j["confounded"] = cs;
  j["final"] = {{"rms_um", json_number(r.final_rms_um)},
                {"heldout_rms_um", json_number(r.final_heldout_rms_um)}};
  j["candidates"] = candidates_json(r.candidates);
  if (!r.circular_tests.empty()) j["circular_tests"] = explanation::circular_json(r.circular_tests);
  j["notes"] = r.notes;
  return j;
}

std::string explain_text(const ExplainResult& r) {
  std::ostringstream s;
  s << fmt::format("{}: {} observations in {} run(s)\n", r.recordings_file, r.observations, r.runs);
  s << fmt::format("baseline: {}\n  rms {:.3f} µm, held-out rms {}\n", r.baseline_description,
                   r.baseline_rms_um, opt_um(r.baseline_heldout_rms_um));
  if (!r.mismatch.empty()) {
    s << "strongest structure in the residuals:\n";
    for (std::size_t i = 0; i < std::min<std::size_t>(4, r.mismatch.size()); ++i)
      s << fmt::format("  {} vs {} (strength {:.2f}): {}\n", r.mismatch[i].component,
                       r.mismatch[i].regressor, r.mismatch[i].strength, r.mismatch[i].where);
  }
  if (r.findings.empty()) s << "findings: none beyond the baseline and noise\n";
  for (std::size_t i = 0; i < r.findings.size(); ++i) {
    const Finding& f = r.findings[i];
    s << fmt::format(
        "{}. {} {}: {}\n   rms {:.3f} -> {:.3f} µm, held-out {} -> {}, delta BIC {:.1f}\n   "
        "{}\n",
        i + 1, f.effect, f.axis ? std::string(1, axis_char(*f.axis)) : std::string("-"),
        params_text(f), f.rms_before_um, f.rms_after_um, opt_um(f.heldout_rms_before_um),
        opt_um(f.heldout_rms_after_um), f.delta_bic, f.explanation);
  }
  for (const Confounded& c : r.confounded) {
    std::string names;
    for (const std::string& e : c.effects) names += (names.empty() ? "" : " / ") + e;
    s << fmt::format("confounded: {} on {}: {}\n   remedy: {}\n", names,
                     c.axis ? std::string(1, axis_char(*c.axis)) : std::string("-"), c.explanation,
                     c.remedy);
  }
  s << fmt::format("final: rms {:.3f} µm, held-out rms {}\n", r.final_rms_um,
                   opt_um(r.final_heldout_rms_um));
  s << explanation::circular_text(r.circular_tests);
  return s.str();
}

std::string explain_html(const ExplainResult& r) {
  std::ostringstream s;
  s << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
       "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; style-src "
       "'unsafe-inline'; "
       "img-src data:\">\n<title>volmap explain: "
    << html_escape(r.recordings_file)
    << "</title>\n<style>\nbody{font-family:sans-serif;margin:24px;max-width:1000px}\n"
       "table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccc;padding:4px "
       "8px;text-align:left;"
       "font-size:13px}\nth{background:#f3f3f3}.plots{display:flex;gap:12px;flex-wrap:wrap}\n"
       ".note{color:#555;font-size:13px}\n</style>\n</head>\n<body>\n";
  s << "<h1>volmap explain</h1>\n";
  s << fmt::format("<p>Recording <code>{}</code>: {} observations in {} run(s).</p>\n",
                   html_escape(r.recordings_file), r.observations, r.runs);
  s << fmt::format(
      "<p>Baseline: {}.<br>RMS {:.3f} µm, held-out (leave one run out) {}. Final: RMS {:.3f} "
      "µm, held-out {}.</p>\n",
      html_escape(r.baseline_description), r.baseline_rms_um, opt_um(r.baseline_heldout_rms_um),
      r.final_rms_um, opt_um(r.final_heldout_rms_um));
  s << "<h2>Summary</h2>\n";
  if (r.findings.empty()) {
    s << "<p>No finding: nothing in the recording holds up beyond the baseline and noise.</p>\n";
  } else {
    s << "<table "
         "id=\"summary\">\n<tr><th>#</th><th>effect</th><th>axis</th><th>parameters</th><th>RMS "
         "before "
         "&rarr; after (µm)</th><th>held-out before &rarr; after "
         "(µm)</th><th>&Delta;BIC</th></tr>\n";
    for (std::size_t i = 0; i < r.findings.size(); ++i) {
      const Finding& f = r.findings[i];
      s << fmt::format(
          "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.3f} &rarr; {:.3f}</td><td>{} "
          "&rarr; "
          "{}</td><td>{:.1f}</td></tr>\n",
          i + 1, f.effect, f.axis ? std::string(1, axis_char(*f.axis)) : "-",
          html_escape(params_text(f)), f.rms_before_um, f.rms_after_um,
          opt_num(f.heldout_rms_before_um), opt_num(f.heldout_rms_after_um), f.delta_bic);
    }
    s << "</table>\n";
  }
  if (!r.confounded.empty()) {
    s << "<h2>Confounded: what this recording cannot "
         "decide</h2>\n<table>\n<tr><th>effects</th><th>axis</th>"
         "<th>why</th><th>test that would separate them</th></tr>\n";
    for (const Confounded& c : r.confounded) {
      std::string names;
      for (const std::string& e : c.effects) names += (names.empty() ? "" : " / ") + e;
      s << fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                       html_escape(names), c.axis ? std::string(1, axis_char(*c.axis)) : "-",
                       html_escape(c.explanation), html_escape(c.remedy));
    }
    s << "</table>\n";
  }
  s << "<h2>Where the baseline disagrees</h2>\n";
  if (r.mismatch.empty()) {
    s << "<p>No regressor explains more than 5 % of the baseline residual variance.</p>\n";
  } else {
    s << "<table>\n<tr><th>component</th><th>regressor</th><th>strength</th><th>where</th></tr>\n";
    for (const Mismatch& m : r.mismatch)
      s << fmt::format("<tr><td>{}</td><td>{}</td><td>{:.2f}</td><td>{}</td></tr>\n", m.component,
                       html_escape(m.regressor), m.strength, html_escape(m.where));
    s << "</table>\n";
  }
  for (std::size_t i = 0; i < r.findings.size(); ++i) {
    const Finding& f = r.findings[i];
    const std::string ax = f.axis ? std::string(1, axis_char(*f.axis)) : "-";
    s << fmt::format("<h2 id=\"finding-{}\">{}. {} {}</h2>\n<p>{}</p>\n<p class=\"note\">{}</p>\n",
                     i + 1, i + 1, f.effect, ax, html_escape(f.explanation),
                     html_escape(params_text(f)));
    double lo = INFINITY, hi = -INFINITY;
    for (const std::vector<double>* v : {&f.plot.before_um, &f.plot.after_um})
      for (double y : *v)
        if (std::isfinite(y)) {
          lo = std::min(lo, y);
          hi = std::max(hi, y);
        }
    if (!std::isfinite(lo)) lo = -1, hi = 1;
    const auto [y_lo, y_hi] = svg::nice_range(lo, hi);
    std::vector<double> fitted(f.plot.before_um.size());
    for (std::size_t k = 0; k < fitted.size() && k < f.plot.after_um.size(); ++k)
      fitted[k] = f.plot.before_um[k] - f.plot.after_um[k];
    const std::string x_label = explanation::regressor_label(f.plot.regressor);
    s << "<div class=\"plots\">\n"
      << svg_panel(fmt::format("before: residual without {} {}", f.effect, ax), x_label, f.plot.x,
                   f.plot.before_um, f.plot.group, fitted, y_lo, y_hi)
      << "\n"
      << svg_panel(fmt::format("after: residual with {} {}", f.effect, ax), x_label, f.plot.x,
                   f.plot.after_um, f.plot.group, {}, y_lo, y_hi)
      << "\n</div>\n";
    s << "<p class=\"note\">"
      << (f.plot.group.empty() ? "" : "Red: approached from +, blue: approached from &minus;. ")
      << "Black dashes: the finding's fitted term at each point.</p>\n";
  }
  s << explanation::circular_html(r.circular_tests);
  if (!r.candidates.empty()) s << candidates_html(r.candidates);
  if (!r.notes.empty()) {
    s << "<h2>Notes</h2>\n<ul>\n";
    for (const std::string& n : r.notes) s << "<li>" << html_escape(n) << "</li>\n";
    s << "</ul>\n";
  }
  s << "<p class=\"note\">Method: docs/explain.md. Before = final residual plus the finding's "
       "fitted term; after = "
       "final residual.</p>\n</body>\n</html>\n";
  return s.str();
}

}  // namespace volmap
