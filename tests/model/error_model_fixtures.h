// Machines and error sets shared by the error model's tests: the bundled
// three- and five-axis samples, and seeded random error sets.
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "core/model/error_set.h"
#include "core/model/machine.h"
#include "core/model/machine_json.h"
#include "core/model/sensitivity.h"
#include "tests/support/test_paths.h"

namespace volmap::test {

inline Machine lei_hsu() {
  return load_machine_json(test::source_path("samples/machines/lei-hsu-xyzac.json"));
}
inline Machine hsu3() {
  return load_machine_json(test::source_path("samples/machines/hsu-3axis.json"));
}

// A random error set: every component error of every axis a smooth random
// curve (5 knots over the travel, or a closed 0..360 degree table for an
// unlimited rotary axis), and random location errors; amplitudes `scale`
// times realistic (20 um, 20 urad).
inline ErrorSet random_errors(const Machine& m, double scale, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  ErrorSet e;
  e.file = "<random>";
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisName a = m.axis_order[static_cast<size_t>(i)];
    const AxisLimits& L = m.limits[static_cast<size_t>(i)];
    AxisErrors ax;
    ax.axis = a;
    const int knots = 7;
    const double lo = L.unlimited ? 0.0 : L.min;
    const double hi = L.unlimited ? 2 * M_PI : L.max;
    for (int k = 0; k < knots; ++k) ax.plus.position.push_back(lo + (hi - lo) * k / (knots - 1));
    std::vector<std::vector<double>> y(kComponentCount);
    for (int c = 0; c < kComponentCount; ++c) {
      for (int k = 0; k < knots; ++k)
        y[static_cast<size_t>(c)].push_back(scale * n(rng) * (c < 3 ? 20e-3 : 20e-6));
      if (L.unlimited) y[static_cast<size_t>(c)].back() = y[static_cast<size_t>(c)].front();
      ax.present[static_cast<size_t>(c)] = true;
    }
    ax.plus.periodic = L.unlimited;
    ax.plus.value.resize(knots);
    ax.plus.slope.resize(knots);
    for (int c = 0; c < kComponentCount; ++c) {
      const std::vector<double> s = pchip_slopes(ax.plus.position, y[static_cast<size_t>(c)]);
      for (int k = 0; k < knots; ++k) {
        ax.plus.value[static_cast<size_t>(k)][static_cast<size_t>(c)] =
            y[static_cast<size_t>(c)][static_cast<size_t>(k)];
        ax.plus.slope[static_cast<size_t>(k)][static_cast<size_t>(c)] = s[static_cast<size_t>(k)];
      }
    }
    ax.plus.source = "<random>";
    e.axis[static_cast<size_t>(a)] = ax;
  }
  for (const std::string& name : model_error_names(m)) {
    const ErrorName en = *parse_error_name(name);
    if (!en.location) continue;
    e.location[name] = scale * n(rng) * (is_angular(en.component) ? 50e-6 : 30e-3);
  }
  return e;
}

}  // namespace volmap::test
