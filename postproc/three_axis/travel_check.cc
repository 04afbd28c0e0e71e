#include "postproc/three_axis/travel_check.h"

#include <fmt/format.h>

#include <cmath>

#include "core/common/input_error.h"

namespace volmap::post {
namespace {

// Calls f on each point of the motion that can be extreme on an axis: its
// end; a cycle's R plane and clearance level above the hole; an arc's
// points where its sweep crosses a multiple of 90 degrees in its plane (the
// helix axis is linear in the angle, so its extremes are the ends).
template <typename F>
void for_each_extreme(const nc::Motion& m, F&& f) {
  f(m.end_mm);
  if (m.kind == nc::MotionKind::kCycle) {
    for (double z : {m.r_mm, m.clear_mm}) f(Eigen::Vector3d(m.end_mm.x(), m.end_mm.y(), z));
    return;
  }
  if (m.kind != nc::MotionKind::kArc) return;
  // The plane's (i, k) axes: G17 XY, G18 ZX, G19 YZ.
  const int i = m.plane == 0 ? 0 : m.plane == 1 ? 2 : 1;
  const int k = m.plane == 0 ? 1 : m.plane == 1 ? 0 : 2;
  const double r = std::hypot(m.start_mm[i] - m.center_mm[i], m.start_mm[k] - m.center_mm[k]);
  const double a0 = std::atan2(m.start_mm[k] - m.center_mm[k], m.start_mm[i] - m.center_mm[i]);
  const double a1 = std::atan2(m.end_mm[k] - m.center_mm[k], m.end_mm[i] - m.center_mm[i]);
  double sweep = a1 - a0;  // counter-clockwise in the plane's (i, k) order
  if (m.clockwise) {
    while (sweep >= 0) sweep -= 2 * M_PI;
    sweep -= 2 * M_PI * m.extra_turns;
  } else {
    while (sweep <= 0) sweep += 2 * M_PI;
    sweep += 2 * M_PI * m.extra_turns;
  }
  const double dir = sweep >= 0 ? 1.0 : -1.0;
  for (int q = 0; q < 4; ++q) {
    // Is there a sweep angle t in (0, |sweep|) where the radius points
    // along +-i or +-k? (Further turns reach the same point again.)
    double t = std::fmod(dir * (q * M_PI / 2 - a0), 2 * M_PI);
    if (t < 0) t += 2 * M_PI;
    if (t >= std::abs(sweep)) continue;
    Eigen::Vector3d p = m.end_mm;
    p[i] = m.center_mm[i] + r * std::cos(q * M_PI / 2);
    p[k] = m.center_mm[k] + r * std::sin(q * M_PI / 2);
    f(p);
  }
}

[[noreturn, gnu::cold]] void throw_outside(const Machine& machine, int a, double u_mm,
                                           const Eigen::Vector3d& origin, const std::string& file,
                                           int line) {
  const AxisLimits& L = machine.limits[static_cast<size_t>(a)];
  throw InputError(
      file, line,
      fmt::format(
          "this block moves {} to {:.4f} mm, outside its travel {:g}..{:g} mm (machine {}); {}",
          "XYZ"[a], u_mm, L.min, L.max, machine.name,
          origin.isZero(0.0)
              ? "the program's origin is the machine's zero (no --work-offset was given, or "
                "the program's G10 or G92 put it there): give the part's work offset with "
                "--work-offset X,Y,Z"
              : fmt::format("the program lies outside the travel at its origin {:g},{:g},{:g} "
                            "mm (--work-offset, G10, G92): check the work offset",
                            origin.x(), origin.y(), origin.z())));
}

}  // namespace

void check_travel(const Machine& machine, const nc::Motion& m, const Corrector& c,
                  const Eigen::Vector3d& origin_mm, const std::string& file, int line,
                  double xy_margin_mm) {
  const auto check = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d u = c.axis_position(p);
    const int a = first_axis_outside_travel(machine, u.data(), 3);
    if (a >= 0) throw_outside(machine, a, u[a], origin_mm, file, line);
  };
  for_each_extreme(m, [&](const Eigen::Vector3d& p) {
    check(p);
    if (xy_margin_mm > 0)
      for (int k = 0; k < 4; ++k)
        check(p + Eigen::Vector3d(k == 0   ? xy_margin_mm
                                  : k == 1 ? -xy_margin_mm
                                           : 0.0,
                                  k == 2   ? xy_margin_mm
                                  : k == 3 ? -xy_margin_mm
                                           : 0.0,
                                  0.0));
  });
}

}  // namespace volmap::post
