#include "core/common/svg_plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/common/html.h"

namespace volmap::svg {
namespace {

// The step of 1, 2 or 5 x 10^k nearest to span / target.
double nice_step(double span, int target) {
  const double raw = span / std::max(1, target);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  const double m = raw / p;
  return (m < 1.5 ? 1.0 : m < 3.5 ? 2.0 : m < 7.5 ? 5.0 : 10.0) * p;
}

// Decimals that write every multiple of step exactly: 0 for steps >= 1.
int decimals_of(double step) {
  const int d = static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  return std::clamp(d, 0, 12);
}

// v with `decimals` digits after the point, never "-0" or "-0.00".
std::string fixed(double v, int decimals) {
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

}  // namespace

std::string Ticks::text(double v) const { return fixed(v, decimals); }

Ticks nice_ticks(double lo, double hi, int target) {
  Ticks t;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) {
    t.values = {std::isfinite(lo) ? lo : 0.0};
    t.decimals = 3;
    return t;
  }
  t.step = nice_step(hi - lo, target);
  t.decimals = decimals_of(t.step);
  const double slack = 1e-9 * t.step;
  for (double k = std::ceil((lo - slack) / t.step); k * t.step <= hi + slack; k += 1)
    t.values.push_back(k * t.step == 0.0 ? 0.0 : k * t.step);
  return t;
}

std::pair<double, double> nice_range(double lo, double hi, int target) {
  if (!(hi > lo)) {
    const double d = std::max(1.0, std::abs(lo)) * 0.5;
    return {lo - d, hi + d};
  }
  const double step = nice_step(hi - lo, target);
  return {std::floor(lo / step + 1e-9) * step, std::ceil(hi / step - 1e-9) * step};
}

std::string value_with_error(double value, double std_error) {
  if (!std::isfinite(value)) return "n/a";
  if (!(std_error > 0) || !std::isfinite(std_error)) return fmt::format("{:.4g}", value);
  // Two significant digits of the error set the last digit of both, but an
  // integer part is never rounded ("988 ± 150", not "990 ± 150").
  const int place = static_cast<int>(std::floor(std::log10(std_error))) - 1;
  const double e = std::round(std_error / std::pow(10.0, place)) * std::pow(10.0, place);
  const int decimals = std::max(0, -place);
  return fmt::format("{} ± {:.{}f}", fixed(value, decimals), e, decimals);
}

std::string open_plot(double width, double height, const std::string& title, bool log_y) {
  std::string s = fmt::format(
      "<svg class=\"plot{2}\" width=\"{0:.0f}\" height=\"{1:.0f}\" viewBox=\"0 0 {0:.0f} {1:.0f}\" "
      "role=\"img\" font-family=\"sans-serif\">",
      width, height, log_y ? " log-y" : "");
  if (!title.empty()) s += fmt::format("<title>{}</title>", html_escape(title));
  return s + "\n";
}

std::string frame_rect(const Frame& f, const char* fill) {
  return fmt::format(
      "<rect class=\"frame\" x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" "
      "fill=\"{}\" stroke=\"#888\"/>\n",
      f.left, f.top, f.width, f.height, fill);
}

std::string x_axis(const Frame& f, const Scale& x, const Ticks& t, const std::string& label) {
  std::string s;
  for (double v : t.values) {
    const double px = x(v);
    s += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{0:.1f}\" y2=\"{2:.1f}\" stroke=\"#888\"/>"
        "<text class=\"x-tick\" x=\"{0:.1f}\" y=\"{3:.1f}\" font-size=\"10\" "
        "text-anchor=\"middle\">{4}</text>\n",
        px, f.bottom(), f.bottom() + 4, f.bottom() + 14, t.text(v));
  }
  s += fmt::format(
      "<text class=\"x-label\" x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" "
      "text-anchor=\"middle\">{}</text>\n",
      f.left + f.width / 2, f.bottom() + 28, html_escape(label));
  return s;
}

std::string y_axis(const Frame& f, const Scale& y, const Ticks& t, const std::string& label,
                   double label_x) {
  std::string s;
  for (double v : t.values) {
    const double py = y(v);
    s += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{1:.1f}\" x2=\"{2:.1f}\" y2=\"{1:.1f}\" stroke=\"#888\"/>"
        "<text class=\"y-tick\" x=\"{3:.1f}\" y=\"{4:.1f}\" font-size=\"10\" "
        "text-anchor=\"end\">{5}</text>\n",
        f.left - 4, py, f.left, f.left - 6, py + 3.5, t.text(v));
  }
  return s + vertical_label("y-label", label_x, f.top + f.height / 2, label);
}

std::string vertical_label(const char* cls, double x, double y, const std::string& label) {
  return fmt::format(
      "<text class=\"{0}\" x=\"{1:.1f}\" y=\"{2:.1f}\" font-size=\"11\" "
      "transform=\"rotate(-90 {1:.1f} {2:.1f})\" text-anchor=\"middle\">{3}</text>\n",
      cls, x, y, html_escape(label));
}

std::string legend_row(double x, double y,
                       const std::vector<std::pair<std::string, std::string>>& entries) {
  std::string s = "<g class=\"legend\">";
  for (const auto& [colour, name] : entries) {
    s += fmt::format(
        "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"14\" height=\"3\" fill=\"{}\"/>"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\">{}</text>",
        x, y - 4, colour, x + 18, y, html_escape(name));
    x += 18 + 7.0 * static_cast<double>(name.size()) + 16;
  }
  return s + "</g>\n";
}

}  // namespace volmap::svg
