// The path of a circular test (circular_test.h).
#include "core/measure/circular_test.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace volmap {

std::vector<CircularStop> circular_run(const Machine& m, const CircularTestPath& p,
                                       bool counter_clockwise) {
  if (!(p.radius_mm > 0)) throw std::invalid_argument("radius_mm: expected a number > 0");
  if (!(p.step_deg > 0 && p.step_deg <= 90))
    throw std::invalid_argument("step_deg: expected a number in (0, 90]");
  if (!(p.overshoot_deg >= 0 && p.overshoot_deg <= 360))
    throw std::invalid_argument("overshoot_deg: expected a number in 0..360");
  const std::optional<int> i1 = m.index_of(p.first), i2 = m.index_of(p.second);
  if (!i1 || !i2 || is_rotary(p.first) || is_rotary(p.second) || p.first == p.second)
    throw std::invalid_argument("plane: expected two different linear axes of the machine");
  const double sign = counter_clockwise ? 1.0 : -1.0;
  const int capture = static_cast<int>(std::llround(360.0 / p.step_deg));
  const int over = static_cast<int>(std::ceil(p.overshoot_deg / p.step_deg - 1e-9));
  // The ballbar measures the tool tip against the workpiece: the radial
  // direction is the tip's, in the workpiece frame (an axis that moves the
  // table moves the tip the other way).
  const Eigen::Vector3d centre_tip = nominal_forward(m, p.centre).tip_mm;
  std::vector<CircularStop> stops;
  for (int k = -over; k <= capture + over; ++k) {
    // the lead-in ends exactly at the start; the lead-out's last stop exactly at its end
    double along = k < 0 ? std::max(k * p.step_deg, -p.overshoot_deg) : k * p.step_deg;
    if (k >= capture) along = std::min(360.0 + p.overshoot_deg, k * p.step_deg);
    const double deg = p.start_deg + sign * along;
    const double rad = deg * std::numbers::pi / 180.0;
    CircularStop s;
    s.u = p.centre;
    s.u[*i1] += p.radius_mm * std::cos(rad);
    s.u[*i2] += p.radius_mm * std::sin(rad);
    s.radial = (nominal_forward(m, s.u).tip_mm - centre_tip).normalized();
    s.capture = k >= 0 && k < capture;
    s.angle_deg = std::fmod(std::fmod(deg, 360.0) + 360.0, 360.0);
    stops.push_back(s);
  }
  return stops;
}

}  // namespace volmap
