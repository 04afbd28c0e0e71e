// The one iteration that finds the commanded position of a point: the
// solution of  x_cmd + e(x_cmd) = x_nominal  (Hsu Fig. 5, "-du", solved
// exactly rather than to first order), in general
//   F_e(u + du) = F_f,n(u) = v                      (Lei & Hsu 2003, eq. 4)
// by the chord-Newton method  du <- du - J^-1 (F_e(u + du) - v)  with a
// fixed J (eq. 6 applied again and again). For a three-axis machine, J is
// the constant matrix A of the axis directions and the step is the fixed
// point  x <- x_nominal - A^-1 e(x), a contraction with factor
// L = |A^-1 de/dx| (about 1e-4 on a real machine).
//
// The callers own the form of the iterate (x, du, or du with its last step)
// and the stopping rule, since each keeps exactly the iterates and the
// stopping it has always had (outputs are compared byte for byte):
//   core/kinematics/correction  the step's linear and rotary norms within
//                               the tolerances (CorrectionOptions),
//   maps/tables/axis_correction the step's largest component within 1e-9 mm,
//   postproc/three_axis/corrector the step below 1e-12 mm, or certified
//                               within the accuracy by the Lipschitz bound.
// A header template so that the post-processor's per-point solve inlines.
#pragma once

#include <utility>

namespace volmap {

/// How many iterations a solve may take. `done` counts the iterations that
/// made the first iterate (1 when it is the one-step correction, 0 when it is
/// a guess); the loop stops unconverged once the count reaches `max`.
struct FixedPointLimits {
  int done = 0;
  int max = 1;
};

struct FixedPointOutcome {
  int iterations = 0;      ///< iterations made, FixedPointLimits::done included
  bool converged = false;  ///< the stopping rule held (false: the limit stopped it)
};

/// Iterates x <- next_iterate(x) from the first iterate x until
/// converged(previous, next) holds for a step or limits.max iterations are
/// made. x holds the last iterate on return.
///   next_iterate: Iterate(const Iterate& x), one evaluation of the error at x
///   converged:    bool(const Iterate& previous, const Iterate& next)
template <class Iterate, class NextIterate, class Converged>
FixedPointOutcome iterate_to_fixed_point(Iterate& x, FixedPointLimits limits,
                                         NextIterate&& next_iterate, Converged&& converged) {
  int iterations = limits.done;
  while (iterations < limits.max) {
    Iterate next = next_iterate(std::as_const(x));
    ++iterations;
    const bool done = converged(std::as_const(x), std::as_const(next));
    x = std::move(next);
    if (done) return {iterations, true};
  }
  return {iterations, false};
}

}  // namespace volmap
