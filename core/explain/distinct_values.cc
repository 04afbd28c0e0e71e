#include "core/explain/distinct_values.h"

#include <algorithm>
#include <cmath>

namespace volmap::explanation {

std::vector<double> unique_sorted(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  v.erase(
      std::unique(v.begin(), v.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }),
      v.end());
  return v;
}

bool varies(const std::vector<double>& v) {
  double lo = INFINITY, hi = -INFINITY;
  for (double x : v)
    if (std::isfinite(x)) {
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  return hi > lo;
}

}  // namespace volmap::explanation
