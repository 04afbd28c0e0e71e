#include "core/explain/parameter_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include "core/common/svg_plot.h"
#include "core/common/units.h"

namespace volmap::explanation {

double round_significant(double v, int digits) {
  if (!std::isfinite(v) || v == 0) return v == 0 ? 0.0 : v;
  return std::stod(fmt::format("{:.{}g}", v, digits));
}

nlohmann::json json_number(double v) {
  if (!std::isfinite(v)) return nullptr;
  return round_significant(v);
}

nlohmann::json json_number(const std::optional<double>& v) {
  return v ? json_number(*v) : nlohmann::json(nullptr);
}

double delta_se(const Eigen::VectorXd& g, const Eigen::MatrixXd& cov) {
  return std::sqrt(std::max(0.0, g.dot(cov * g)));
}

void amplitude_phase(const Eigen::VectorXd& beta, const Eigen::MatrixXd& cov, int i_sin, int i_cos,
                     double& amp, double& amp_se, double& phase_deg) {
  const double a = beta[i_sin], b = beta[i_cos];
  amp = std::hypot(a, b);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(beta.size());
  if (amp > 0) {
    g[i_sin] = a / amp;
    g[i_cos] = b / amp;
  }
  amp_se = delta_se(g, cov);
  phase_deg = std::atan2(b, a) * units::kDegPerRad;
}

namespace {

// The unit a parameter's name ends with, and the name without it.
struct NameUnit {
  std::string name, unit;
};
NameUnit split_unit(const std::string& key) {
  static const std::pair<const char*, const char*> kSuffixes[] = {
      {"_um_per_h", "µm/h"}, {"_um", "µm"}, {"_urad", "µrad"}, {"_mm", "mm"},
      {"_deg", "°"},         {"_s", "s"},   {"_c", "°C"}};
  if (key == "um_per_k") return {"coefficient", "µm/K"};
  for (const auto& [suffix, unit] : kSuffixes) {
    const std::string sfx(suffix);
    if (key.size() > sfx.size() && key.compare(key.size() - sfx.size(), sfx.size(), sfx) == 0)
      return {key.substr(0, key.size() - sfx.size()), unit};
  }
  return {key, ""};
}

std::optional<double> std_error_of(const std::vector<std::pair<std::string, double>>& se,
                                   const std::string& key) {
  for (const auto& [k, v] : se)
    if (k == key) return v;
  return std::nullopt;
}

std::string number_text(const nlohmann::json& v, std::optional<double> se) {
  if (v.is_number_integer()) return v.dump();
  if (v.is_number()) return svg::value_with_error(v.get<double>(), se.value_or(0.0));
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

}  // namespace

std::string parameters_text(const std::vector<std::pair<std::string, nlohmann::json>>& parameters,
                            const std::vector<std::pair<std::string, double>>& std_errors) {
  std::string s;
  for (const auto& [key, v] : parameters) {
    if (!s.empty()) s += ", ";
    const NameUnit nu = split_unit(key);
    std::string value;
    if (v.is_array()) {
      value = "[";
      for (std::size_t i = 0; i < v.size(); ++i)
        value += (i ? ", " : "") +
                 number_text(v[i], std_error_of(std_errors, key + "/" + std::to_string(i)));
      value += "]";
    } else {
      value = number_text(v, std_error_of(std_errors, key));
    }
    const bool has_unit = !nu.unit.empty() && (v.is_number() || v.is_array());
    s += nu.name + " " + value;
    if (has_unit) s += (nu.unit == "°" ? "" : " ") + nu.unit;
  }
  return s;
}

std::string unit_text(const std::string& unit) {
  static const std::pair<const char*, const char*> kUnits[] = {{"um", "µm"},
                                                               {"urad", "µrad"},
                                                               {"um_per_h", "µm/h"},
                                                               {"um_per_k", "µm/K"},
                                                               {"um_per_m_min", "µm per m/min"},
                                                               {"um_per_mm2", "µm/mm²"},
                                                               {"um_per_deg2", "µm/deg²"},
                                                               {"um_per_m", "µm/m"},
                                                               {"urad_per_m", "µrad/m"}};
  for (const auto& [key, text] : kUnits)
    if (unit == key) return text;
  return unit;
}

std::string regressor_label(const std::string& r) {
  auto upper = [](char c) {
    return static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  };
  if (r == "t_s") return "time since start, s";
  if (r == "run") return "run number";
  if (r.size() == 4 && r.compare(1, 3, "_mm") == 0)
    return std::string(1, upper(r[0])) + " position, mm";
  if (r.size() == 5 && r.compare(1, 4, "_deg") == 0)
    return std::string(1, upper(r[0])) + " position, deg";
  const std::string feed = "feed_mm_min * dir_";
  if (r.size() == feed.size() + 1 && r.compare(0, feed.size(), feed) == 0)
    return "feed × approach direction of " + std::string(1, upper(r.back())) + ", mm/min";
  if (r.size() > 7 && r.compare(0, 5, "temp_") == 0 && r.compare(r.size() - 2, 2, "_c") == 0)
    return "temperature " + r.substr(5, r.size() - 7) + ", °C";
  return r;
}

}  // namespace volmap::explanation
