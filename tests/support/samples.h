// The bundled sample machines and errors, and random axis positions over a
// machine's travel (seeded by the caller).
#pragma once

#include <cmath>
#include <random>
#include <sstream>
#include <string>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "tests/support/test_paths.h"

namespace volmap::test {

inline Machine sample_machine(const std::string& name) {
  return load_machine_json(source_path("samples/machines/" + name + ".json"));
}
inline ErrorSet sample_errors(const std::string& name) {
  return load_errors_csv(source_path("samples/errors/" + name + ".csv"));
}

/// An errors CSV given as text (named "inline.csv" in messages).
inline ErrorSet errors_from_text(const std::string& text) {
  std::istringstream in(text);
  return read_errors_csv(in, "inline.csv");
}

/// Uniform over each axis's travel; an unlimited rotary axis over two turns.
inline AxisVector random_pose(const Machine& m, std::mt19937& rng) {
  AxisVector u(m.axis_count());
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisLimits& L = m.limits[static_cast<size_t>(i)];
    std::uniform_real_distribution<double> d(L.unlimited ? -2 * M_PI : L.min,
                                             L.unlimited ? 2 * M_PI : L.max);
    u[i] = d(rng);
  }
  return u;
}

}  // namespace volmap::test
