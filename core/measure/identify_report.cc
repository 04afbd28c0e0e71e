// The outputs of `volmap identify` (docs/identify.md): the errors CSV of the
// identified errors, and the report as JSON ("volmap-identify/1") and text.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <ostream>
#include <sstream>

#include "core/common/units.h"
#include "core/measure/identify.h"

namespace volmap {
namespace {

std::string fixed6(double v) {
  std::string s = fmt::format("{:.6f}", v);
  if (s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}
nlohmann::ordered_json number_or_null(double v) {
  if (!std::isfinite(v)) return nullptr;
  return v;
}

/// The blocks of a known errors file verbatim (comments dropped).
void append_known_blocks(std::string& text, const std::string& known_text) {
  std::istringstream in(known_text);
  std::string line;
  bool in_block = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos) {
      in_block = false;
      continue;
    }
    if (line[first] == '#') continue;
    if (!in_block) text += '\n';
    in_block = true;
    text += line;
    text += '\n';
  }
}

/// The fitted curves, one block per axis (positions mm or degrees, values
/// um or urad).
void append_curve_blocks(std::string& text, const std::vector<FittedCurve>& fitted) {
  std::map<AxisName, std::vector<const FittedCurve*>> by_axis;
  for (const FittedCurve& c : fitted) by_axis[c.axis].push_back(&c);
  for (const auto& [axis, curves] : by_axis) {
    const bool rotary = is_rotary(axis);
    text += '\n';
    text += axis_char(axis);
    for (const FittedCurve* c : curves) {
      text += ',';
      text += component_error_name(c->component, axis);
    }
    text += '\n';
    for (std::size_t k = 0; k < curves.front()->knots.size(); ++k) {
      text += fixed6(curves.front()->knots[k] * (rotary ? units::kDegPerRad : 1.0));
      for (const FittedCurve* c : curves) {
        text += ',';
        text += fixed6(c->values[k] *
                       (is_angular(c->component) ? units::kUradPerRad : units::kUmPerMm));
      }
      text += '\n';
    }
  }
}

/// The location errors grouped by axis (squareness of linear axes, then
/// each rotary axis), in the model's order (um or urad).
void append_location_blocks(std::string& text,
                            const std::vector<std::pair<std::string, double>>& estimates) {
  std::vector<std::pair<std::string, std::vector<std::pair<std::string, double>>>> groups;
  for (const auto& [name, value] : estimates) {
    const ErrorName n = *parse_error_name(name);
    const std::string key =
        is_rotary(n.axis) ? std::string(1, axis_char(n.axis)) : std::string("linear");
    auto it =
        std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == key; });
    if (it == groups.end()) {
      groups.push_back({key, {}});
      it = groups.end() - 1;
    }
    it->second.push_back(
        {name, value * (is_angular(n.component) ? units::kUradPerRad : units::kUmPerMm)});
  }
  for (const auto& [key, entries] : groups) {
    text += '\n';
    for (std::size_t k = 0; k < entries.size(); ++k) {
      if (k) text += ',';
      text += entries[k].first;
    }
    text += '\n';
    for (std::size_t k = 0; k < entries.size(); ++k) {
      if (k) text += ',';
      text += fixed6(entries[k].second);
    }
    text += '\n';
  }
}

}  // namespace

void write_identified_errors_csv(std::ostream& out, const IdentifyResult& res,
                                 const std::map<std::string, std::string>& metadata,
                                 const std::string& known_text) {
  std::string text = "# volmap component errors v1\n";
  for (const auto& [k, v] : metadata) text += "# " + k + ": " + v + "\n";
  std::string not_identified;
  for (const IdentifiedParameter& p : res.parameters)
    if (!p.identifiable) {
      if (!not_identified.empty()) not_identified += ", ";
      not_identified += p.name;
    }
  if (!not_identified.empty())
    text +=
        "# not identifiable from these recordings (fixed at 0, not written): " + not_identified +
        "\n";
  append_known_blocks(text, known_text);
  append_curve_blocks(text, res.curves);
  append_location_blocks(text, res.location_estimates);
  out << text;
}

nlohmann::ordered_json identify_report_json(const IdentifyResult& r) {
  nlohmann::ordered_json doc;
  doc["format"] = "volmap-identify/1";
  doc["rows"] = r.rows_used;
  doc["observations"] = r.equations;
  doc["parameter_count"] = r.parameters.size();
  doc["rank"] = r.rank;
  doc["condition_number"] = number_or_null(r.condition_number);
  doc["singular_values"] = r.singular_values;
  doc["iterations"] = r.iterations;
  doc["converged"] = r.converged;
  doc["rms_before_um"] = r.rms_before_um;
  doc["rms_after_um"] = r.rms_after_um;
  doc["sigma_um"] = number_or_null(r.sigma_um);
  doc["stated_noise_um"] = number_or_null(r.stated_noise_um);
  doc["warnings"] = r.warnings;
  nlohmann::ordered_json params = nlohmann::ordered_json::array();
  for (const IdentifiedParameter& p : r.parameters) {
    const char* kind = p.kind == ParameterKind::kLocation    ? "location"
                       : p.kind == ParameterKind::kComponent ? "component"
                                                             : "setup_offset";
    params.push_back({{"name", p.name},
                      {"kind", kind},
                      {"unit", p.unit},
                      {"status", p.identifiable ? "estimated" : "not_identifiable"},
                      {"estimate", p.identifiable ? number_or_null(p.estimate)
                                                  : nlohmann::ordered_json(nullptr)},
                      {"std_error", number_or_null(p.std_error)},
                      {"inflation", number_or_null(p.inflation)}});
  }
  doc["parameters"] = params;
  nlohmann::ordered_json un = nlohmann::ordered_json::array();
  for (const UnidentifiableCombination& u : r.unidentifiable) {
    nlohmann::ordered_json terms = nlohmann::ordered_json::object();
    for (const auto& [n, c] : u.terms) terms[n] = c;
    un.push_back({{"combination", terms},
                  {"text", u.text},
                  {"fixed", u.fixed},
                  {"explanation", u.explanation},
                  {"remedy", u.remedy}});
  }
  doc["unidentifiable"] = un;
  nlohmann::ordered_json strong = nlohmann::ordered_json::array();
  for (const auto& p : r.strong_correlations)
    strong.push_back({{"a", p.a}, {"b", p.b}, {"rho", p.rho}});
  doc["strong_correlations"] = strong;
  nlohmann::ordered_json matrix = nlohmann::ordered_json::array();
  for (Eigen::Index a = 0; a < r.correlation.rows(); ++a) {
    nlohmann::ordered_json row = nlohmann::ordered_json::array();
    for (Eigen::Index b = 0; b < r.correlation.cols(); ++b) row.push_back(r.correlation(a, b));
    matrix.push_back(row);
  }
  doc["correlation"] = {{"names", r.correlation_names}, {"matrix", matrix}};
  return doc;
}

std::string identify_report_text(const IdentifyResult& r) {
  std::string s;
  s += fmt::format(
      "Identification: {} observations in {} rows, {} parameters, rank {}, condition number "
      "{:.4g}\n",
      r.equations, r.rows_used, r.parameters.size(), r.rank, r.condition_number);
  s += fmt::format(
      "RMS residual {:.4g} µm before, {:.4g} µm after ({} Gauss-Newton iterations{}); sigma {:.4g} "
      "µm\n\n",
      r.rms_before_um, r.rms_after_um, r.iterations, r.converged ? "" : ", NOT converged",
      r.sigma_um);
  for (const std::string& w : r.warnings) s += "WARNING, " + w + "\n";
  if (!r.warnings.empty()) s += "\n";
  s += fmt::format("{:<16} {:>14} {:>12}  {}\n", "parameter", "estimate", "std error", "");
  for (const IdentifiedParameter& p : r.parameters) {
    if (p.identifiable)
      s += fmt::format("{:<16} {:>11.4f} {:<4} {:>10.4f}\n", p.name, p.estimate,
                       p.unit == "um"     ? "µm"
                       : p.unit == "urad" ? "µrad"
                                          : p.unit,
                       p.std_error);
    else
      s += fmt::format("{:<16} {:>16} {:>10}  not identifiable: fixed at 0\n", p.name, "-", "-");
  }
  if (!r.unidentifiable.empty()) {
    s += "\nCombinations these recordings cannot separate:\n";
    for (const UnidentifiableCombination& u : r.unidentifiable)
      s += fmt::format("  {}: {}; {} fixed at 0.\n    To separate: {}.\n", u.text, u.explanation,
                       u.fixed, u.remedy);
  }
  if (!r.strong_correlations.empty()) {
    s += "\nStrongly correlated estimates (|rho| >= 0.9):\n";
    for (const auto& p : r.strong_correlations)
      s += fmt::format("  {} ~ {}: {:+.4f}\n", p.a, p.b, p.rho);
  }
  return s;
}

namespace identification {

// Fit quality. A residual sigma above the noise the recording states, by
// more than sampling explains (sigma^2 / noise^2 is chi^2_dof / dof under a
// right model: its standard deviation is sqrt(2 / dof); four of those, and
// at least 20 %), means the parameters cannot reproduce what the machine
// does, and their estimates and standard errors follow the misfit. Without a
// stated noise, a fit that removes less than half the RMS says the same.
// A parameter whose standard error is more than 10 times the one it would
// have uncorrelated (variance inflation above 100) is barely identifiable.
std::vector<std::string> fit_warnings(const IdentifyResult& r, int dof) {
  std::vector<std::string> w;
  if (std::isfinite(r.stated_noise_um) && dof > 0 && std::isfinite(r.sigma_um)) {
    const double ratio = r.sigma_um / r.stated_noise_um;
    if (ratio > 1.2 && ratio * ratio > 1.0 + 4.0 * std::sqrt(2.0 / dof))
      w.push_back(fmt::format(
          "poor fit: the residual sigma {:.3g} µm is {:.1f} times the noise the recording states "
          "({:.3g} µm): the parameters cannot reproduce what the machine does (component errors "
          "left out of --params, an effect beyond geometry: volmap explain, or another machine "
          "file), so the estimates and their standard errors are not to be trusted",
          r.sigma_um, ratio, r.stated_noise_um));
  } else if (r.rms_before_um > 0 && r.rms_after_um > 0.5 * r.rms_before_um) {
    w.push_back(fmt::format(
        "poor fit: the fit removes only {:.0f} % of the RMS residual ({:.3g} -> {:.3g} µm): the "
        "parameters cannot reproduce most of what the recording shows",
        100.0 * (1.0 - r.rms_after_um / r.rms_before_um), r.rms_before_um, r.rms_after_um));
  }
  std::string barely;
  for (const IdentifiedParameter& p : r.parameters)
    if (p.identifiable && std::isfinite(p.inflation) && p.inflation > 10.0)
      barely += fmt::format("{}{} ({:.0f}x)", barely.empty() ? "" : ", ", p.name, p.inflation);
  if (!barely.empty())
    w.push_back(fmt::format(
        "barely identifiable: {}: each standard error is that many times what it would be were "
        "the parameter not correlated with the others{}; add observations that move them apart "
        "(docs/identify.md, the remedies)",
        barely,
        r.strong_correlations.empty()
            ? std::string()
            : fmt::format(" (strongest: {} with {}, rho {:.2f})", r.strong_correlations[0].a,
                          r.strong_correlations[0].b, r.strong_correlations[0].rho)));
  return w;
}

}  // namespace identification
}  // namespace volmap
