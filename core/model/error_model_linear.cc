// The three-axis hot path: ErrorModel::tip_error_linear and its flat plan
// (contract: core/model/error_model.h).
#include <array>
#include <cstdint>

#include "core/model/error_model.h"
#include "core/model/small_rotation.h"

namespace volmap {

using small_rotation_detail::small_rotation_elements;
using small_rotation_detail::small_sincos3;

// evaluate() for linear joints only, on the tool tip alone: the same
// operations in the same order (PointDir's lane 0, joint_error's arithmetic),
// so the result is exact()'s to the bit (tests/model/tip_error_linear_test.cc
// checks it). The joints' constants come from the flat plan linear_; each joint's error
// rotation lives in registers, never in a Matrix3d array.
namespace {
// A 3x3 matrix as nine scalars (small_rotation_elements writes it).
struct M33 {
  double m[3][3];
  [[gnu::always_inline]] double& operator()(int i, int j) { return m[i][j]; }
  [[gnu::always_inline]] double operator()(int i, int j) const { return m[i][j]; }
};

using v2d = double __attribute__((vector_size(16)));
using v2i = long long __attribute__((vector_size(16)));
[[gnu::always_inline]] inline v2d load2(const double (&p)[2]) { return v2d{p[0], p[1]}; }

// small_rotation_elements' matrix, rows 0 and 1 of each column packed:
// c_j = {R(0, j), R(1, j)}, and row 2.
struct PackedRotation {
  v2d c0, c1, c2;
  double r20, r21, r22;
};
[[gnu::always_inline]] inline void small_rotation_packed(double ex, double ey, double ez,
                                                         PackedRotation& R) {
  double sa, ca, sb, cb, sc, cc;
  small_sincos3(ex, ey, ez, sa, ca, sb, cb, sc, cc);
  const v2d C = {cc, sc}, S = {sc, cc};
  const v2d T = C * sb;  // {ccsb, scsb}
  // x - y is x + (-y) in IEEE arithmetic, signed zeros included: the sign
  // bit flipped in one lane turns the lane's addition into the subtraction.
  const v2i neg0 = {static_cast<long long>(0x8000000000000000ULL), 0};
  const v2i neg1 = {0, static_cast<long long>(0x8000000000000000ULL)};
  R.c0 = C * cb;  // cc cb, sc cb
  R.c1 = T * sa + reinterpret_cast<v2d>(reinterpret_cast<v2i>(S * ca) ^
                                        neg0);  // ccsb sa - sc ca, scsb sa + cc ca
  R.c2 = T * ca + reinterpret_cast<v2d>(reinterpret_cast<v2i>(S * sa) ^
                                        neg1);  // ccsb ca + sc sa, scsb ca - cc sa
  R.r20 = -sb;
  R.r21 = cb * sa;
  R.r22 = cb * ca;
}

// joint_error() for tip_error_linear: E(q) = [R | delta], the independent
// pivot folded into delta (Eigen's R * r: rows 0 and 1 summed left to right
// as packets, row 2 as a scalar reduction, (a0 + (a1 + a2))). LinearJoint is
// ErrorModel::LinearJoint, a private type, deduced.
template <class LinearJoint>
[[gnu::always_inline]] inline void linear_joint_error(const LinearJoint& J,
                                                      const std::array<double, kComponentCount>& e,
                                                      double q, M33& R, double (&delta)[3]) {
  if (!J.components) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) R(i, j) = i == j ? 1.0 : 0.0;
      delta[i] = 0.0;
    }
    return;
  }
  small_rotation_elements(e[3], e[4], e[5], R);
  delta[0] = e[0], delta[1] = e[1], delta[2] = e[2];
  if (J.independent) {
    double r[3];
    if (J.workpiece)
      for (int i = 0; i < 3; ++i) r[i] = J.r_meas_mm[i] - q * J.direction[i];
    else
      for (int i = 0; i < 3; ++i) r[i] = J.r_meas_mm[i];
    const double p0 = (R(0, 0) * r[0] + R(0, 1) * r[1]) + R(0, 2) * r[2];
    const double p1 = (R(1, 0) * r[0] + R(1, 1) * r[1]) + R(1, 2) * r[2];
    const double p2 = R(2, 0) * r[0] + (R(2, 1) * r[1] + R(2, 2) * r[2]);
    delta[0] -= p0 - r[0];
    delta[1] -= p1 - r[1];
    delta[2] -= p2 - r[2];
  }
}

// ISO 230-1's P^-1 = R_loc^T (p - t_P) of a tool-chain joint, on the tip's
// packed rows 0, 1 and row 2 (PointDir's translate_back, rotate_transposed).
template <class LinearJoint>
[[gnu::always_inline]] inline void inverse_placement(const LinearJoint& J, v2d& a01, double& a2) {
  a01 -= v2d{J.t_P_mm[0], J.t_P_mm[1]};
  a2 -= J.t_P_mm[2];
  const double x = a01[0], y = a01[1];
  double r[3];
  for (int i = 0; i < 3; ++i) r[i] = (J.R_loc[0][i] * x + J.R_loc[1][i] * y) + J.R_loc[2][i] * a2;
  a01 = v2d{r[0], r[1]};
  a2 = r[2];
}
}  // namespace

Eigen::Vector3d ErrorModel::tip_error_linear(const double* u, const ApproachDirections& dir,
                                             std::uint64_t* clamped_out) const {
  const int n_work = linear_work_;
  const int n_all = linear_count_;
  // Phase 1: the table lookups, in evaluate()'s order (the same exception
  // first when several positions are outside).
  std::array<std::array<double, kComponentCount>, kMaxLinearJoints> v;
  std::uint64_t clamped = 0;
  for (int k = 0; k < n_all; ++k) {
    const LinearJoint& J = linear_[static_cast<size_t>(k)];
    if (J.components)
      evaluate_axis(*J.components, u[J.index], dir[static_cast<size_t>(J.index)], options_.outside,
                    v[static_cast<size_t>(k)], &clamped);
  }
  if (clamped_out)
    *clamped_out += clamped;
  else if (clamped)
    clamped_->fetch_add(clamped, std::memory_order_relaxed);

  // Tool chain, spindle to base, rows 0 and 1 of the tip in one register
  // (packed IEEE operations round as the scalar ones), row 2 beside it.
  v2d a01 = {linear_start_mm_[0], linear_start_mm_[1]}, n01 = a01;
  double a2 = linear_start_mm_[2], n2 = a2;
  for (int k = n_all - 1; k >= n_work; --k) {
    const LinearJoint& J = linear_[static_cast<size_t>(k)];
    const double q = u[J.index];
    if (J.conjugated) inverse_placement(J, a01, a2);  // ISO 230-1: P^-1 first
    PackedRotation R;
    v2d d01;
    double d2;
    if (J.components) {
      const std::array<double, kComponentCount>& e = v[static_cast<size_t>(k)];
      small_rotation_packed(e[3], e[4], e[5], R);
      d01 = v2d{e[0], e[1]};
      d2 = e[2];
      if (J.independent) {  // tool chain: r = r_meas
        const v2d r0 = load2(J.r_meas_pair[0]), r1 = load2(J.r_meas_pair[1]),
                  r2 = load2(J.r_meas_pair[2]);
        const v2d r01 = {J.r_meas_mm[0], J.r_meas_mm[1]};
        // Eigen's R * r: rows 0 and 1 as packets, left to right; row 2 as
        // a scalar reduction, a0 + (a1 + a2).
        const v2d p01 = (R.c0 * r0 + R.c1 * r1) + R.c2 * r2;
        const double p2 =
            R.r20 * J.r_meas_mm[0] + (R.r21 * J.r_meas_mm[1] + R.r22 * J.r_meas_mm[2]);
        d01 = d01 - (p01 - r01);
        d2 = d2 - (p2 - J.r_meas_mm[2]);
      }
    } else {
      R.c0 = v2d{1.0, 0.0}, R.c1 = v2d{0.0, 1.0}, R.c2 = v2d{0.0, 0.0};
      R.r20 = 0.0, R.r21 = 0.0, R.r22 = 1.0;
      d01 = v2d{0.0, 0.0};
      d2 = 0.0;
    }
    const v2d m01 = q * v2d{J.direction[0], J.direction[1]};
    const double m2 = q * J.direction[2];
    n01 += m01;
    n2 += m2;
    {
      const double x = a01[0], y = a01[1];
      const v2d r01 = (R.c0 * x + R.c1 * y) + R.c2 * a2;
      a2 = (R.r20 * x + R.r21 * y) + R.r22 * a2;
      a01 = r01;
    }
    a01 += d01;
    a2 += d2;
    a01 += m01;
    a2 += m2;
    n01 += v2d{J.offset_mm[0], J.offset_mm[1]};
    n2 += J.offset_mm[2];
    if (J.has_location_rotation) {
      const double x = a01[0], y = a01[1];
      const v2d r01 = (load2(J.R_loc_col01[0]) * x + load2(J.R_loc_col01[1]) * y) +
                      load2(J.R_loc_col01[2]) * a2;
      a2 = (J.R_loc[2][0] * x + J.R_loc[2][1] * y) + J.R_loc[2][2] * a2;
      a01 = r01;
    }
    a01 += v2d{J.t_loc_mm[0], J.t_loc_mm[1]};
    a2 += J.t_loc_mm[2];
  }
  double a[3] = {a01[0], a01[1], a2}, n[3] = {n01[0], n01[1], n2};
  // Workpiece chain, base to workpiece.
  for (int k = 0; k < n_work; ++k) {
    const LinearJoint& J = linear_[static_cast<size_t>(k)];
    const double q = u[J.index];
    M33 R;
    double delta[3];
    linear_joint_error(J, v[static_cast<size_t>(k)], q, R, delta);
    double motion[3];
    for (int i = 0; i < 3; ++i) motion[i] = q * J.direction[i];
    for (int i = 0; i < 3; ++i) n[i] -= J.offset_mm[i];
    for (int i = 0; i < 3; ++i) a[i] -= J.t_loc_mm[i];
    double r[3];
    if (J.has_location_rotation) {
      for (int i = 0; i < 3; ++i)
        r[i] = J.R_loc[0][i] * a[0] + J.R_loc[1][i] * a[1] + J.R_loc[2][i] * a[2];
      for (int i = 0; i < 3; ++i) a[i] = r[i];
    }
    for (int i = 0; i < 3; ++i) n[i] -= motion[i];
    for (int i = 0; i < 3; ++i) a[i] -= delta[i];
    for (int i = 0; i < 3; ++i) a[i] -= motion[i];
    for (int i = 0; i < 3; ++i) r[i] = R(0, i) * a[0] + R(1, i) * a[1] + R(2, i) * a[2];
    for (int i = 0; i < 3; ++i) a[i] = r[i];
    if (J.conjugated) {  // ISO 230-1: P = [R_loc | t_P] last
      for (int i = 0; i < 3; ++i)
        r[i] = (J.R_loc[i][0] * a[0] + J.R_loc[i][1] * a[1]) + J.R_loc[i][2] * a[2];
      for (int i = 0; i < 3; ++i) a[i] = r[i] + J.t_P_mm[i];
    }
  }
  return {(a[0] - linear_origin_mm_[0]) - (n[0] - linear_origin_mm_[0]),
          (a[1] - linear_origin_mm_[1]) - (n[1] - linear_origin_mm_[1]),
          (a[2] - linear_origin_mm_[2]) - (n[2] - linear_origin_mm_[2])};
}

}  // namespace volmap
