// Rotation matrices of small angles, exact: R(a, b, c) = Rz(c) Ry(b) Rx(a) of
// a joint's angular errors eps = (ex, ey, ez) = (a, b, c) (docs/model.md; the
// exact model, not I + [eps]x), written element by element with series for
// sin and cos, so that it inlines into the model's hot loops (error_model.cc,
// error_model_linear.cc). Internal to the model.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace volmap::small_rotation_detail {

// sin and cos of a small angle: Taylor series to beyond double precision for
// |x| < 1e-2 (next term x^9/9! < 3e-24), std::sin/cos otherwise.
inline void small_sincos(double x, double& s, double& c) {
  // Taylor series, Horner form with reciprocal constants, cut where the next
  // term is below half an ulp: |x| < 1e-3 (every realistic geometric error):
  // next terms x^7/7! < 2e-25 |x|-relative, x^6/6! < 1.4e-21;
  // |x| < 1e-2: next terms x^9/9! < 3e-24, x^10/10! < 3e-27.
  const double ax = std::abs(x), x2 = x * x;
  if (ax < 1e-3) {
    s = x * (1 - x2 * (1.0 / 6) * (1 - x2 * (1.0 / 20)));
    c = 1 - x2 * 0.5 * (1 - x2 * (1.0 / 12));
  } else if (ax < 1e-2) {
    s = x * (1 - x2 * (1.0 / 6) * (1 - x2 * (1.0 / 20) * (1 - x2 * (1.0 / 42))));
    c = 1 - x2 * 0.5 * (1 - x2 * (1.0 / 12) * (1 - x2 * (1.0 / 30) * (1 - x2 * (1.0 / 56))));
  } else {
    ::sincos(x, &s, &c);
  }
}

// sin and cos of the three small angles (ex, ey, ez) = (a, b, c).
[[gnu::always_inline]] inline void small_sincos3(double ex, double ey, double ez, double& sa,
                                                 double& ca, double& sb, double& cb, double& sc,
                                                 double& cc) {
  if (std::abs(ex) < 1e-3 && std::abs(ey) < 1e-3 && std::abs(ez) < 1e-3) {
    // The common case, every angle in small_sincos's first range: the same
    // series, two angles per packed operation (bit-identical results).
    using v2d = double __attribute__((vector_size(16)));
    const v2d x = {ex, ey}, x2 = x * x;
    const v2d s = x * (1 - x2 * (1.0 / 6) * (1 - x2 * (1.0 / 20)));
    const v2d c = 1 - x2 * 0.5 * (1 - x2 * (1.0 / 12));
    sa = s[0], sb = s[1], ca = c[0], cb = c[1];
    const double z = ez, z2 = z * z;
    sc = z * (1 - z2 * (1.0 / 6) * (1 - z2 * (1.0 / 20)));
    cc = 1 - z2 * 0.5 * (1 - z2 * (1.0 / 12));
  } else {
    small_sincos(ex, sa, ca);
    small_sincos(ey, sb, cb);
    small_sincos(ez, sc, cc);
  }
}

// Rz(c) Ry(b) Rx(a) of the angles (ex, ey, ez), written element by element
// so that it inlines into the hot loop; M is Eigen::Matrix3d or any type
// with R(i, j).
template <class M>
[[gnu::always_inline]] inline void small_rotation_elements(double ex, double ey, double ez, M& R) {
  double sa, ca, sb, cb, sc, cc;
  small_sincos3(ex, ey, ez, sa, ca, sb, cb, sc, cc);
  const double scsb = sc * sb, ccsb = cc * sb;
  R(0, 0) = cc * cb;
  R(0, 1) = ccsb * sa - sc * ca;
  R(0, 2) = ccsb * ca + sc * sa;
  R(1, 0) = sc * cb;
  R(1, 1) = scsb * sa + cc * ca;
  R(1, 2) = scsb * ca - cc * sa;
  R(2, 0) = -sb;
  R(2, 1) = cb * sa;
  R(2, 2) = cb * ca;
}
[[gnu::always_inline]] inline void small_rotation_into(const Eigen::Vector3d& eps_rad,
                                                       Eigen::Matrix3d& R) {
  small_rotation_elements(eps_rad.x(), eps_rad.y(), eps_rad.z(), R);
}

}  // namespace volmap::small_rotation_detail
