// Commanded-position correction of a three-axis (linear X, Y, Z) machine.
//
// Problem: find the commanded axis position x_cmd whose actual tool tip is
// the nominal tool tip of x_nominal:
//     p(x_cmd) + e(x_cmd) = p(x_nominal),
// p the nominal tool tip (affine in x for linear axes: p(x) = p0 + A x, A
// the axis directions in workpiece coordinates, +-identity for the samples),
// e = dP of ErrorModel::exact (actual minus nominal, workpiece coordinates).
// With A invertible:  x_cmd = x_nominal - A^-1 e(x_cmd),  solved by
// fixed-point iteration from x_0 = x_nominal. The map is a contraction with
// factor L = |A^-1 de/dx| (about 1e-4 for real machines); the iteration stops
// when a step is below 1e-9 mm, leaving an error of at most L/(1-L) times
// that step (about 1e-13 mm): usually two evaluations after e(x_nominal).
// du = x_cmd - x_nominal (mm).
//
// The error at positions beyond the travel (x_cmd may lie a few um outside
// near a travel end) is the error at the travel end: the iterate is clamped
// into travel before evaluation and the solve reports it.
//
// This is maps/'s own definition for three-axis tables (the iterate clamped
// into travel); the iteration is core/kinematics/fixed_point.h's, which the
// five-axis correction (core/kinematics/correction.h) and the three-axis
// post (postproc/three_axis/corrector.h) share.
#pragma once

#include <Eigen/Core>

#include "core/model/error_model.h"

namespace volmap::maps {

class ThreeAxisCorrection {
 public:
  /// Throws std::invalid_argument unless the machine has exactly the linear
  /// axes X, Y, Z with independent directions.
  explicit ThreeAxisCorrection(const ErrorModel& model);

  struct Result {
    Eigen::Vector3d du_mm = Eigen::Vector3d::Zero();
    int iterations = 0;      ///< evaluations of e, e(x_nominal) included
    bool clamped = false;    ///< an iterate was held at the travel end
    bool converged = false;  ///< last step below kStepTolerance_mm
  };
  /// Solves at x_nominal for the given approach directions. dP_nominal_mm is
  /// e(x_nominal) when the caller already has it (saves one evaluation).
  Result solve(const AxisVector& x_nominal, const ApproachDirections& dir,
               const Eigen::Vector3d& dP_nominal_mm) const;
  Result solve(const AxisVector& x_nominal, const ApproachDirections& dir = {}) const;

  static constexpr double kStepTolerance_mm = 1e-9;
  static constexpr int kMaxIterations = 30;

 private:
  const ErrorModel& model_;
  Eigen::Matrix3d A_inv_;  ///< d x / d p: axis displacement per tool-tip displacement
  Eigen::Vector3d min_mm_, max_mm_;
};

}  // namespace volmap::maps
