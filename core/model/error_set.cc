// PCHIP slopes and the cubic Hermite evaluation of error tables
// (contract: core/error_set.h).
//
// Slopes: Fritsch & Carlson (1980) monotone PCHIP in the form MATLAB's pchip
// and SLATEC's PCHIM use (Brodlie's weighted harmonic mean, Fritsch & Butland
// 1984): at an interior knot k with secants d_b (interval before, width h_b)
// and d_a (interval after, width h_a)
//   m_k = 0                                    if d_b * d_a <= 0
//   1/m_k = w_b / d_b + w_a / d_a              otherwise, with
//   w_b = (h_b + 2 h_a) / (3 (h_b + h_a)),  w_a = (2 h_b + h_a) / (3 (h_b + h_a)).
// End slopes: the one-sided three-point formula, made shape-preserving
// (MATLAB's pchipend):
//   m_0 = ((2 h_0 + h_1) d_0 - h_0 d_1) / (h_0 + h_1);
//   m_0 = 0 if sign(m_0) != sign(d_0);
//   m_0 = 3 d_0 if sign(d_0) != sign(d_1) and |m_0| > |3 d_0|.
//
// Evaluation: on interval [x_i, x_{i+1}] of width h, s = (q - x_i) / h,
//   p(q) = h00(s) y_i + h10(s) h m_i + h01(s) y_{i+1} + h11(s) h m_{i+1},
//   h00 = (1 + 2s)(1 - s)^2, h10 = s (1 - s)^2, h01 = s^2 (3 - 2s),
//   h11 = s^2 (s - 1).
// At s = 0 and s = 1 the basis is exactly (1,0,0,0) and (0,0,1,0), so knots
// are hit exactly.
#include "core/model/error_set.h"

#include <algorithm>
#include <cassert>
#include <cctype>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include "core/common/internal_error.h"
#include "core/common/units.h"

namespace volmap {
namespace {

int sign_of(double v) { return (v > 0.0) - (v < 0.0); }

/// Brodlie's weighted harmonic mean of the secants around an interior knot;
/// zero at a local extremum (secants of opposite sign, or either zero).
double interior_slope(double h_b, double h_a, double d_b, double d_a) {
  if (sign_of(d_b) * sign_of(d_a) <= 0) return 0.0;
  const double three_h_sum = 3.0 * (h_b + h_a);
  const double w_b = (h_b + 2.0 * h_a) / three_h_sum;
  const double w_a = (2.0 * h_b + h_a) / three_h_sum;
  // 1/m = w_b/d_b + w_a/d_a, written without dividing by the secants.
  return d_b * d_a / (w_b * d_a + w_a * d_b);
}

/// MATLAB's pchipend: h0, d0 for the end interval, h1, d1 for its neighbour.
double end_slope(double h0, double h1, double d0, double d1) {
  double m = ((2.0 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
  if (sign_of(m) != sign_of(d0)) {
    m = 0.0;
  } else if (sign_of(d0) != sign_of(d1) && std::abs(m) > std::abs(3.0 * d0)) {
    m = 3.0 * d0;
  }
  return m;
}

std::string format_number(double v) {
  char buffer[64];
  const std::to_chars_result r =
      std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::general, 10);
  return std::string(buffer, r.ptr);
}

/// Position in the unit a user reads: degrees for rotary axes, mm otherwise.
std::string format_position(const AxisErrorTable& table, double q) {
  if (is_rotary(table.axis)) return format_number(q * units::kDegPerRad) + " deg";
  return format_number(q) + " mm";
}

}  // namespace

namespace detail {
void throw_outside(const AxisErrorTable& table, double q) {
  std::string message = table.source.empty() ? std::string("error table") : table.source;
  message += ": ";
  message += axis_char(table.axis);
  if (std::isnan(q)) {
    message +=
        " axis position is not a number; fix the program or model that "
        "produced it";
    throw OutsideTable(message);
  }
  message += " axis position " + format_position(table, q) + " is outside its error table (" +
             format_position(table, table.min_position()) + " .. " +
             format_position(table, table.max_position()) +
             "); keep the axis within the measured range, extend the table, or "
             "evaluate with the clamp policy";
  throw OutsideTable(message);
}
}  // namespace detail

std::vector<double> pchip_slopes(const std::vector<double>& x, const std::vector<double>& y) {
  assert(x.size() == y.size());
  const std::size_t n = x.size();
  std::vector<double> m(n, 0.0);
  if (n < 2) return m;  // one knot: constant
  if (n == 2) {         // two knots: linear
    const double d = (y[1] - y[0]) / (x[1] - x[0]);
    m[0] = m[1] = d;
    return m;
  }
  std::vector<double> h(n - 1), d(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    h[i] = x[i + 1] - x[i];
    d[i] = (y[i + 1] - y[i]) / h[i];
  }
  for (std::size_t k = 1; k + 1 < n; ++k) m[k] = interior_slope(h[k - 1], h[k], d[k - 1], d[k]);
  m[0] = end_slope(h[0], h[1], d[0], d[1]);
  m[n - 1] = end_slope(h[n - 2], h[n - 3], d[n - 2], d[n - 3]);
  return m;
}

std::vector<double> pchip_slopes_periodic(const std::vector<double>& x,
                                          const std::vector<double>& y) {
  assert(x.size() == y.size());
  const std::size_t n = x.size();
  std::vector<double> m(n, 0.0);
  if (n < 3) return m;
  std::vector<double> h(n - 1), d(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    h[i] = x[i + 1] - x[i];
    d[i] = (y[i + 1] - y[i]) / h[i];
  }
  for (std::size_t k = 1; k + 1 < n; ++k) m[k] = interior_slope(h[k - 1], h[k], d[k - 1], d[k]);
  // The first and last knot are one point of the circle: the interval before
  // it is the last one, the interval after it the first one.
  m[0] = m[n - 1] = interior_slope(h[n - 2], h[0], d[n - 2], d[0]);
  return m;
}

void prepare_lookup(AxisErrorTable& table) {
  table.uniform_inv_step = 0.0;
  const std::vector<double>& x = table.position;
  if (x.size() < 3) return;
  const double step = (x.back() - x.front()) / static_cast<double>(x.size() - 1);
  for (std::size_t i = 0; i < x.size(); ++i)
    if (std::abs(x[i] - (x.front() + step * static_cast<double>(i))) >
        1e-12 * std::abs(step) * static_cast<double>(x.size()))
      return;
  table.uniform_inv_step = 1.0 / step;
}

const char* location_convention_name(LocationConvention c) {
  return c == LocationConvention::kLink ? "link" : "iso230-1";
}

std::optional<LocationConvention> parse_location_convention(std::string_view text) {
  std::string t;
  for (char ch : text)
    if (ch != ' ' && ch != '-' && ch != '_')
      t += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (t == "iso2301" || t == "iso") return LocationConvention::kIso230;
  if (t == "link") return LocationConvention::kLink;
  return std::nullopt;
}

bool errors_all_zero(const ErrorSet& errors) {
  for (const auto& [name, value] : errors.location)
    if (value != 0.0) return false;
  auto zero_table = [](const AxisErrorTable& t) {
    for (const auto& row : t.value)
      for (double v : row)
        if (v != 0.0) return false;
    return true;
  };
  for (const auto& a : errors.axis)
    if (a && !(zero_table(a->plus) && zero_table(a->minus))) return false;
  return true;
}

void prepare_lookup(ErrorSet& errors) {
  for (auto& a : errors.axis) {
    if (!a) continue;
    if (!a->plus.empty()) prepare_lookup(a->plus);
    if (!a->minus.empty()) prepare_lookup(a->minus);
  }
}

}  // namespace volmap
