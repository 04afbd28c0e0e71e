// Which values a recorded column takes.
#pragma once

#include <vector>

namespace volmap::explanation {

/// Sorted distinct values (1e-9 apart).
std::vector<double> unique_sorted(std::vector<double> v);
/// True when the finite values are not all equal.
bool varies(const std::vector<double>& v);

}  // namespace volmap::explanation
