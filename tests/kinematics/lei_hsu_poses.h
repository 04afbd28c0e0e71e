// Helpers of the kinematics tests: sample machines, axis positions in mm and
// degrees, and Lei & Hsu's forward transformation of X'Y'ZA'C' typed from the
// paper (eqs. 10-15).
#pragma once

#include <cmath>
#include <initializer_list>
#include <string>

#include "core/kinematics/kinematics.h"
#include "tests/support/samples.h"

namespace volmap::test_kinematics {

inline constexpr double kDeg = M_PI / 180.0;

inline Machine load(const std::string& name) { return test::sample_machine(name); }

inline AxisVector pose(std::initializer_list<double> mm_deg, const Machine& m) {
  AxisVector u(m.axis_count());
  int i = 0;
  for (double x : mm_deg) {
    u[i] = is_rotary(m.axis_order[static_cast<size_t>(i)]) ? x * kDeg : x;
    ++i;
  }
  return u;
}

// Lei & Hsu eqs. (10)-(15), typed from the paper; sample offsets Z3 = 50,
// (Xw0, Yw0, Zw0) = (0, 0, 60).
inline constexpr double kZ3 = 50, kXw0 = 0, kYw0 = 0, kZw0 = 60;
inline ToolPose eq10_15(double xm, double ym, double zm, double a, double c) {
  ToolPose v;
  v.tip_mm.x() =
      zm * std::sin(c) * std::sin(a) - ym * std::sin(c) * std::cos(a) - xm * std::cos(c) - kXw0;
  v.tip_mm.y() =
      zm * std::cos(c) * std::sin(a) - ym * std::cos(c) * std::cos(a) + xm * std::sin(c) - kYw0;
  v.tip_mm.z() = zm * std::cos(a) + ym * std::sin(a) - kZ3 - kZw0;
  v.axis = {std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)};
  return v;
}

}  // namespace volmap::test_kinematics
