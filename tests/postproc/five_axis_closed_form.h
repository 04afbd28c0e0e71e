// The X'Y'ZA'C' sample machine derived independently of volmap's
// Kinematics (Lei & Hsu eqs. (10)-(15), the selection policy re-implemented),
// and the tools of the five-axis post's tests: the output parsed back into
// poses, random poses and tool-vector programs.
#pragma once

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/error_model.h"
#include "gcode/nc_block.h"
#include "postproc/five_axis/five_axis_post.h"
#include "postproc/five_axis/five_axis_transform.h"
#include "tests/support/samples.h"

namespace volmap {

using Eigen::Vector3d;
inline constexpr double kDeg = M_PI / 180.0;

// Lei & Hsu eqs. (10)-(15) with the sample's offsets: Z3 = 50 (C table face
// above the A line), (Xw0, Yw0, Zw0) = the workpiece origin in the C frame.
struct Offsets {
  double Z3 = 50, Xw0 = 0, Yw0 = 0, Zw0 = 60;
};
inline ToolPose eq10_15(const Offsets& o, double xm, double ym, double zm, double a, double c) {
  ToolPose v;
  v.tip_mm.x() =
      zm * std::sin(c) * std::sin(a) - ym * std::sin(c) * std::cos(a) - xm * std::cos(c) - o.Xw0;
  v.tip_mm.y() =
      zm * std::cos(c) * std::sin(a) - ym * std::cos(c) * std::cos(a) + xm * std::sin(c) - o.Yw0;
  v.tip_mm.z() = zm * std::cos(a) + ym * std::sin(a) - o.Z3 - o.Zw0;
  v.axis = {std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)};
  return v;
}
// Linear axes from eqs. (10)-(12) for given angles: their matrix is
// orthogonal, so (x_m, y_m, z_m) = M^T (x + Xw0, y + Yw0, z + Z3 + Zw0).
inline Vector3d linear_closed_form(const Offsets& o, const Vector3d& tip, double a, double c) {
  const double X = tip.x() + o.Xw0, Y = tip.y() + o.Yw0, Z = tip.z() + o.Z3 + o.Zw0;
  const double sa = std::sin(a), ca = std::cos(a), sc = std::sin(c), cc = std::cos(c);
  return {-cc * X + sc * Y, -sc * ca * X - cc * ca * Y + sa * Z,
          sc * sa * X + cc * sa * Y + ca * Z};
}
// The backward transformation with the policy: A = +-acos(k) within
// -100..30 deg; C = atan2(i, j) (sin A > 0) or atan2(-i, -j) (sin A < 0),
// unwrapped next to the previous C; the least (dA^2 + dC^2); at k = 1 the
// previous C is kept.
struct Axes {
  double x, y, z, a, c;
};
inline Axes closed_form_backward(const Offsets& o, const ToolPose& v, const Axes& prev) {
  const double k = std::clamp(v.axis.z(), -1.0, 1.0);
  Axes best{};
  double best_d = 1e300;
  bool best_inside = false;
  if (std::hypot(v.axis.x(), v.axis.y()) <= 1e-10) {
    const Vector3d l = linear_closed_form(o, v.tip_mm, 0.0, prev.c);
    return {l.x(), l.y(), l.z(), 0.0, prev.c};
  }
  for (double sign : {1.0, -1.0}) {
    const double a = sign * std::acos(k);
    if (a < -100 * kDeg - 1e-12 || a > 30 * kDeg + 1e-12) continue;
    double c = sign > 0 ? std::atan2(v.axis.x(), v.axis.y()) : std::atan2(-v.axis.x(), -v.axis.y());
    c += 2 * M_PI * std::round((prev.c - c) / (2 * M_PI));
    const double d = (a - prev.a) * (a - prev.a) + (c - prev.c) * (c - prev.c);
    const Vector3d l = linear_closed_form(o, v.tip_mm, a, c);
    // Solutions within the linear travel first (X +-300, Y +-250, Z -50..450).
    const bool inside =
        std::abs(l.x()) <= 300 && std::abs(l.y()) <= 250 && l.z() >= -50 && l.z() <= 450;
    if ((inside && !best_inside) || (inside == best_inside && d < best_d)) {
      best_d = d;
      best_inside = inside;
      best = {l.x(), l.y(), l.z(), a, c};
    }
  }
  EXPECT_LT(best_d, 1e299) << "unreachable test pose";
  return best;
}

struct OutLine {
  bool numbered = false;
  int n = 0;
  bool move = false;
  Axes u{};
  double f = 0;
  bool g93 = false;
};
inline std::vector<OutLine> parse_output(const std::string& text) {
  std::vector<OutLine> out;
  std::istringstream in(text);
  std::string l;
  int line = 0;
  while (std::getline(in, l)) {
    const nc::Block b = nc::lex_block(l, ++line, "out");
    OutLine o;
    for (const nc::Word& w : b.words) {
      switch (w.letter) {
        case 'N':
          o.numbered = true;
          o.n = static_cast<int>(w.value);
          break;
        case 'X':
          o.u.x = w.value;
          o.move = true;
          break;
        case 'Y':
          o.u.y = w.value;
          break;
        case 'Z':
          o.u.z = w.value;
          break;
        case 'A':
          o.u.a = w.value * kDeg;
          break;
        case 'C':
          o.u.c = w.value * kDeg;
          break;
        case 'F':
          o.f = w.value;
          break;
        case 'G':
          if (w.code10 == 930) o.g93 = true;
          break;
        default:
          break;
      }
    }
    out.push_back(o);
  }
  return out;
}

inline post::FiveAxisPostReport run_post(const std::string& program, const Machine& m,
                                         const ErrorSet& e, const post::FiveAxisPostOptions& o,
                                         std::string& output) {
  std::istringstream in(program);
  std::ostringstream out;
  const post::FiveAxisPostReport r = post::post_five_axis(in, "test.ngc", out, m, e, o);
  output = out.str();
  return r;
}

// Random reachable poses: from random axis positions through eqs. (10)-(15).
inline std::vector<ToolPose> random_poses(const Offsets& o, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-150, 150), y(-150, 150), z(0, 300), a(-95, 25),
      c(-180, 180);
  std::vector<ToolPose> v;
  for (int i = 0; i < n; ++i)
    v.push_back(eq10_15(o, x(rng), y(rng), z(rng), a(rng) * kDeg, c(rng) * kDeg));
  return v;
}

inline std::string vector_program(const std::vector<ToolPose>& poses, bool rapid = false) {
  std::string p = "G21 G90 G94\n";
  for (size_t i = 0; i < poses.size(); ++i) {
    const ToolPose& v = poses[i];
    p += fmt::format("N{} {} X{:.6f} Y{:.6f} Z{:.6f} I{:.9f} J{:.9f} K{:.9f}{}\n", (i + 1) * 10,
                     rapid || i == 0 ? "G0" : "G1", v.tip_mm.x(), v.tip_mm.y(), v.tip_mm.z(),
                     v.axis.x(), v.axis.y(), v.axis.z(), rapid || i == 0 ? "" : " F1000");
  }
  p += "M30\n";
  return p;
}

// The written end position of every numbered input line: the last line of
// its group (the line itself and the pieces added after it).
inline std::vector<OutLine> group_ends(const std::vector<OutLine>& out) {
  std::vector<OutLine> ends;
  for (const OutLine& o : out) {
    if (o.numbered && o.move)
      ends.push_back(o);
    else if (o.move && !ends.empty())
      ends.back() = OutLine{true, ends.back().n, true, o.u, o.f, o.g93};
  }
  return ends;
}

}  // namespace volmap
