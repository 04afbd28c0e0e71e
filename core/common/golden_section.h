// Golden-section search for the minimum of a unimodal f on [lo, hi]: the
// one implementation (explain's fits of nonlinear shape parameters, verify's
// search for the nearest point of the nominal path).
#pragma once

#include <cmath>

namespace volmap {

struct GoldenSectionResult {
  double lo = 0, hi = 0;  ///< the final bracket
  double x1 = 0, f1 = 0;  ///< its two interior points (x1 < x2) and f there
  double x2 = 0, f2 = 0;
};

/// `iterations` steps from [lo, hi]; f is evaluated iterations + 2 times.
template <class F>
GoldenSectionResult golden_section(double lo, double hi, int iterations, F&& f) {
  const double g = (std::sqrt(5.0) - 1) / 2;
  GoldenSectionResult r;
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < iterations; ++it) {
    if (f1 < f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = f(x2);
    }
  }
  r.lo = lo;
  r.hi = hi;
  r.x1 = x1;
  r.f1 = f1;
  r.x2 = x2;
  r.f2 = f2;
  return r;
}

}  // namespace volmap
