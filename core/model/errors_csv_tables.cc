#include "core/model/errors_csv_tables.h"

#include <algorithm>
#include <cassert>
#include <charconv>
#include <cmath>
#include <utility>

#include "core/common/input_error.h"
#include "core/common/units.h"

namespace volmap::errors_csv_tables {
namespace {

constexpr double kFullTurnDeg = 360.0;
constexpr double kFullTurnTolerance = 1e-9;  // degrees
constexpr double kClosureTolerance = 1e-9;   // um or urad, file units

/// Value and slope of a component's own interpolant at q inside its range.
std::pair<double, double> value_and_slope(const ComponentTable& t, double q) {
  const std::vector<double>& x = t.position;
  const std::size_t n = x.size();
  const auto at = std::lower_bound(x.begin(), x.end(), q);
  if (at != x.end() && *at == q) {
    const auto k = static_cast<std::size_t>(at - x.begin());
    return {t.value[k], t.slope[k]};
  }
  // x[i] < q < x[i+1]: the caller keeps q inside [x.front(), x.back()].
  const std::size_t i = static_cast<std::size_t>(at - x.begin()) - 1;
  assert(i + 1 < n);
  (void)n;
  const double h = x[i + 1] - x[i];
  const double s = (q - x[i]) / h;
  const double y0 = t.value[i], y1 = t.value[i + 1];
  const double m0 = t.slope[i], m1 = t.slope[i + 1];
  const double value = (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s) * y0 +
                       s * (1.0 - s) * (1.0 - s) * h * m0 + s * s * (3.0 - 2.0 * s) * y1 +
                       s * s * (s - 1.0) * h * m1;
  const double slope = (6.0 * s * s - 6.0 * s) * (y0 - y1) / h +
                       (3.0 * s * s - 4.0 * s + 1.0) * m0 + (3.0 * s * s - 2.0 * s) * m1;
  return {value, slope};
}

std::string format(double v) {
  char buffer[64];
  const std::to_chars_result r = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, r.ptr);
}

}  // namespace

ComponentTable make_component_table(const ComponentRows& rows, AxisName axis, Component c,
                                    int header_line, const std::string& file) {
  const bool rotary = is_rotary(axis);
  // file unit per internal
  const double value_scale = is_angular(c) ? units::kUradPerRad : units::kUmPerMm;
  const std::size_t n = rows.position_file.size();
  ComponentTable t;
  t.line = header_line;
  t.position.reserve(n);
  t.value.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    t.position.push_back(rotary ? rows.position_file[i] * units::kRadPerDeg
                                : rows.position_file[i]);
    t.value.push_back(rows.value_file[i][static_cast<int>(c)] / value_scale);
  }
  const double span_deg = rows.position_file.back() - rows.position_file.front();
  t.periodic = rotary && n >= 2 && std::abs(span_deg - kFullTurnDeg) <= kFullTurnTolerance;
  if (t.periodic) {
    const double first = rows.value_file.front()[static_cast<int>(c)];
    const double last = rows.value_file.back()[static_cast<int>(c)];
    if (std::abs(last - first) > kClosureTolerance) {
      const std::string name = component_error_name(c, axis);
      throw InputError(file, rows.line.back(),
                       std::string(1, axis_char(axis)) +
                           " table spans 360 degrees, so it is one full turn, and a "
                           "periodic table must close: " +
                           name + " is " + format(last) + " here but " + format(first) +
                           " at line " + std::to_string(rows.line.front()) +
                           "; make the values at both ends equal");
    }
    t.slope = pchip_slopes_periodic(t.position, t.value);
  } else {
    t.slope = pchip_slopes(t.position, t.value);
  }
  return t;
}

AxisErrorTable merge_component_tables(const AxisDraft& draft, AxisName axis, bool minus,
                                      const std::string& file) {
  std::array<const ComponentTable*, kComponentCount> tables{};
  std::vector<double> knots;
  const ComponentTable* periodic = nullptr;  // the first full-turn table
  for (int c = 0; c < kComponentCount; ++c) {
    if (!draft.component[c]) continue;
    const ComponentData& data = *draft.component[c];
    const ComponentTable& t = minus && data.minus ? *data.minus : data.plus;
    tables[c] = &t;
    knots.insert(knots.end(), t.position.begin(), t.position.end());
    if (t.periodic && periodic == nullptr) periodic = &t;
  }
  if (periodic != nullptr) {
    // A merged table wraps as a whole: every component must be the same
    // full turn, or the wrap would jump.
    for (int c = 0; c < kComponentCount; ++c) {
      const ComponentTable* t = tables[c];
      if (t == nullptr) continue;
      if (!t->periodic || t->position.front() != periodic->position.front() ||
          t->position.back() != periodic->position.back()) {
        const std::string a(1, axis_char(axis));
        throw InputError(file, t->line,
                         component_error_name(static_cast<Component>(c), axis) +
                             " does not cover the same full turn as the " + a + " table at line " +
                             std::to_string(periodic->line) +
                             "; give every component error of the " + a +
                             " axis over the same 360 degrees (same first and last "
                             "position), or none over a full turn");
      }
    }
  }
  std::sort(knots.begin(), knots.end());
  knots.erase(std::unique(knots.begin(), knots.end()), knots.end());

  AxisErrorTable merged;
  merged.axis = axis;
  merged.periodic = periodic != nullptr;
  merged.source = file + ":" + std::to_string(draft.first_line);
  merged.position = knots;
  merged.value.assign(knots.size(), {});
  merged.slope.assign(knots.size(), {});
  for (int c = 0; c < kComponentCount; ++c) {
    const ComponentTable* t = tables[c];
    if (t == nullptr) continue;  // missing component: zero
    for (std::size_t i = 0; i < knots.size(); ++i) {
      const double q = knots[i];
      if (q < t->position.front()) {
        merged.value[i][c] = t->value.front();  // held at its end value
      } else if (q > t->position.back()) {
        merged.value[i][c] = t->value.back();
      } else {
        const auto [value, slope] = value_and_slope(*t, q);
        merged.value[i][c] = value;
        merged.slope[i][c] = slope;
      }
    }
  }
  return merged;
}

}  // namespace volmap::errors_csv_tables
