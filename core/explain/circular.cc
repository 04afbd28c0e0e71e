// Circular tests in a recording (circular.h).
#include "core/explain/circular.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "core/explain/axis_labels.h"

namespace volmap::explanation {
namespace {

constexpr int kMinReadings = 12;
constexpr double kOnCircle = 1e-4;     ///< relative to the radius
constexpr double kLargestGapDeg = 30;  ///< a data-capture arc of (nearly) a full turn

/// Least-squares circle of radial deviations (ISO 230-4): d less its best
/// e0 + a cos(phi) + b sin(phi), the centre offset and radius error. Paths
/// evaluated together share one centre (hysteresis).
std::vector<Eigen::VectorXd> less_lsc(const std::vector<Eigen::VectorXd>& d,
                                      const std::vector<Eigen::VectorXd>& phi_rad) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t p = 0; p < d.size(); ++p)
    for (Eigen::Index i = 0; i < d[p].size(); ++i) {
      const Eigen::Vector3d row(1.0, std::cos(phi_rad[p][i]), std::sin(phi_rad[p][i]));
      A += row * row.transpose();
      rhs += row * d[p][i];
    }
  const Eigen::Vector3d fit = A.ldlt().solve(rhs);
  std::vector<Eigen::VectorXd> out = d;
  for (std::size_t p = 0; p < d.size(); ++p)
    for (Eigen::Index i = 0; i < d[p].size(); ++i)
      out[p][i] -= fit[0] + fit[1] * std::cos(phi_rad[p][i]) + fit[2] * std::sin(phi_rad[p][i]);
  return out;
}

double spread(const Eigen::VectorXd& v) { return v.size() ? v.maxCoeff() - v.minCoeff() : 0.0; }

/// Largest |a(phi) - b(phi)| over a's angles, b interpolated (periodic).
double largest_difference(const Eigen::VectorXd& phi_a, const Eigen::VectorXd& a,
                          const Eigen::VectorXd& phi_b, const Eigen::VectorXd& b) {
  std::vector<std::pair<double, double>> bs;
  for (Eigen::Index i = 0; i < b.size(); ++i)
    bs.push_back({std::remainder(phi_b[i], 2 * std::numbers::pi), b[i]});
  std::sort(bs.begin(), bs.end());
  double h = 0;
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    const double x = std::remainder(phi_a[i], 2 * std::numbers::pi);
    auto hi = std::lower_bound(bs.begin(), bs.end(), std::pair<double, double>{x, -INFINITY});
    const auto lo_it = hi == bs.begin() ? bs.end() - 1 : hi - 1;
    if (hi == bs.end()) hi = bs.begin();
    double x0 = lo_it->first, x1 = hi->first;
    if (x1 < x0) x1 += 2 * std::numbers::pi;
    double xx = x;
    if (xx < x0) xx += 2 * std::numbers::pi;
    const double w = x1 > x0 ? (xx - x0) / (x1 - x0) : 0.0;
    h = std::max(h, std::abs(a[i] - ((1 - w) * lo_it->second + w * hi->second)));
  }
  return h;
}

/// One run read as a circular path, if it is one.
struct RunCircle {
  int run = 0;
  std::string plane;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0, feed = 0;
  bool ccw = true;
  Eigen::VectorXd phi, before, after;
};

std::optional<RunCircle> run_circle(const Observations& obs, int r,
                                    const Eigen::VectorXd& before_um,
                                    const Eigen::VectorXd& after_um) {
  std::vector<int> eqs;
  for (int e : obs.equations_of_run[static_cast<std::size_t>(r)])
    if (obs.component[static_cast<std::size_t>(e)] == kProjection) eqs.push_back(e);
  if (static_cast<int>(eqs.size()) < kMinReadings) return std::nullopt;
  std::vector<Eigen::Vector3d> p(eqs.size());
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < eqs.size(); ++i) {
    // the tool tip against the workpiece (nominal), the frame of the beams:
    // an axis that moves the table moves the tip the other way
    const int row = obs.recording_row[static_cast<std::size_t>(eqs[i])];
    AxisVector u(obs.machine.axis_count());
    for (int a = 0; a < obs.machine.axis_count(); ++a)
      u[a] = obs.position(obs.machine.axis_order[static_cast<std::size_t>(a)], row);
    p[i] = nominal_forward(obs.machine, u).tip_mm;
    const Eigen::Vector3d b = obs.direction_wp.col(eqs[i]);
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - b * b.transpose();
    M += across;
    rhs += across * p[i];
  }
  RunCircle c;
  c.centre = M.ldlt().solve(rhs);
  // the plane: the two axes the path moves most along
  Eigen::Vector3d range = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& q : p) range = range.cwiseMax((q - c.centre).cwiseAbs());
  int normal = 2;
  range.minCoeff(&normal);  // the planes run XY, YZ, ZX
  const int a1 = (normal + 1) % 3, a2 = (normal + 2) % 3;
  c.plane = axis_letter(static_cast<AxisName>(a1)) + axis_letter(static_cast<AxisName>(a2));
  c.phi.resize(static_cast<Eigen::Index>(eqs.size()));
  c.before.resize(c.phi.size());
  c.after.resize(c.phi.size());
  double radius_sum = 0;
  for (std::size_t i = 0; i < eqs.size(); ++i) radius_sum += (p[i] - c.centre).norm();
  c.radius = radius_sum / static_cast<double>(eqs.size());
  double turning = 0;
  std::vector<double> sorted;
  for (std::size_t i = 0; i < eqs.size(); ++i) {
    const Eigen::Vector3d v = p[i] - c.centre;
    const Eigen::Vector3d b = obs.direction_wp.col(eqs[i]);
    if ((v - b * b.dot(v)).norm() > kOnCircle * c.radius || b.dot(v) < 0 ||
        std::abs(v.norm() - c.radius) > kOnCircle * c.radius)
      return std::nullopt;  // not radial readings on one circle
    const Eigen::Index ii = static_cast<Eigen::Index>(i);
    c.phi[ii] = std::atan2(v[a2], v[a1]);
    c.before[ii] = before_um[eqs[i]];
    c.after[ii] = after_um[eqs[i]];
    if (i > 0) turning += std::remainder(c.phi[ii] - c.phi[ii - 1], 2 * std::numbers::pi);
    sorted.push_back(c.phi[ii] * 180 / std::numbers::pi);
  }
  std::sort(sorted.begin(), sorted.end());
  double gap = sorted.front() + 360 - sorted.back();
  for (std::size_t i = 1; i < sorted.size(); ++i) gap = std::max(gap, sorted[i] - sorted[i - 1]);
  if (gap > kLargestGapDeg) return std::nullopt;
  c.ccw = turning > 0;
  c.run = r;
  c.feed = obs.feed_mm_per_min(obs.recording_row[static_cast<std::size_t>(eqs.front())]);
  return c;
}

CircularTest::Path path_of(const Observations& obs, const RunCircle& c) {
  CircularTest::Path path;
  const int e = obs.equations_of_run[static_cast<std::size_t>(c.run)].front();
  const Recordings& rec = obs.recordings;
  const int row = obs.recording_row[static_cast<std::size_t>(e)];
  path.run = rec.has_run() && rec.run[static_cast<std::size_t>(row)] >= 0
                 ? rec.run_names[static_cast<std::size_t>(rec.run[static_cast<std::size_t>(row)])]
                 : "1";
  path.direction = c.ccw ? "ccw" : "cw";
  const Eigen::VectorXd before = less_lsc({c.before}, {c.phi})[0];
  const Eigen::VectorXd after = less_lsc({c.after}, {c.phi})[0];
  for (Eigen::Index i = 0; i < c.phi.size(); ++i) {
    path.angle_deg.push_back(std::fmod(c.phi[i] * 180 / std::numbers::pi + 360, 360));
    path.deviation_um.push_back(before[i]);
    path.fitted_um.push_back(before[i] - after[i]);
  }
  path.g_um = spread(before);
  path.g_after_um = spread(after);
  return path;
}

bool same_circle(const CircularTest& t, const RunCircle& c) {
  return t.plane == c.plane && (t.centre_mm - c.centre).norm() < 1e-3 &&
         std::abs(t.radius_mm - c.radius) < 1e-3 && std::abs(t.feed_mm_min - c.feed) < 1e-6;
}

}  // namespace

std::vector<CircularTest> circular_tests(const Observations& obs, const Eigen::VectorXd& before_um,
                                         const Eigen::VectorXd& after_um) {
  std::vector<CircularTest> tests;
  std::vector<std::vector<RunCircle>> circles;  // per test, its runs
  for (int r = 0; r < obs.run_count; ++r) {
    std::optional<RunCircle> c = run_circle(obs, r, before_um, after_um);
    if (!c) continue;
    // pair with an earlier test on this circle that lacks this direction
    std::size_t t = 0;
    for (; t < tests.size(); ++t)
      if (same_circle(tests[t], *c) && circles[t].size() == 1 && circles[t][0].ccw != c->ccw) break;
    if (t == tests.size()) {
      CircularTest nt;
      nt.plane = c->plane;
      nt.centre_mm = c->centre;
      nt.radius_mm = c->radius;
      nt.feed_mm_min = c->feed;
      tests.push_back(nt);
      circles.emplace_back();
    }
    tests[t].paths.push_back(path_of(obs, *c));
    circles[t].push_back(std::move(*c));
  }
  for (std::size_t t = 0; t < tests.size(); ++t) {
    if (circles[t].size() != 2) continue;
    const RunCircle& a = circles[t][0];
    const RunCircle& b = circles[t][1];
    const std::vector<Eigen::VectorXd> before = less_lsc({a.before, b.before}, {a.phi, b.phi});
    const std::vector<Eigen::VectorXd> after = less_lsc({a.after, b.after}, {a.phi, b.phi});
    tests[t].h_um = largest_difference(a.phi, before[0], b.phi, before[1]);
    tests[t].h_after_um = largest_difference(a.phi, after[0], b.phi, after[1]);
  }
  return tests;
}

}  // namespace volmap::explanation
