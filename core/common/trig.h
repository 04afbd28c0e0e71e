// sin and cos of an axis angle, computed the same way on every machine.
//
// glibc's sincos is correctly rounded in most cases but its result may
// change between library versions, and it costs ~120 instructions. volmap's
// outputs must be byte-identical on any machine, so rotary axis angles go
// through this: Cody–Waite reduction by pi/2 in three parts and the fdlibm
// (Sun, 1993) minimax kernels for |r| <= pi/4. Plain double arithmetic, no
// FMA contraction is relied on; error below 2 ulp for |x| < 1e5 rad
// (tests/common/trig_test.cc checks 1e6 angles against std::sin/cos).
#pragma once

#include <cmath>

namespace volmap {

inline void sincos_axis(double x, double& s, double& c) {
  constexpr double kTwoOverPi = 6.36619772367581382433e-01;
  // pi/2 in three parts (fdlibm's pio2_1, pio2_2, pio2_3): 33 + 33 + 53 bits.
  constexpr double kPio2_1 = 1.57079632673412561417e+00;
  constexpr double kPio2_2 = 6.07710050630396597660e-11;
  constexpr double kPio2_3 = 2.02226624871116645580e-21;
  constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                   S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                   S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                   C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                   C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  // Round to nearest by the 1.5 * 2^52 shift (exact for |x| < 2^50; no libm
  // call, no SSE4.1 needed). volatile-free: compilers keep this without
  // -ffast-math, which volmap never uses.
  constexpr double kShift = 6755399441055744.0;
  const double kf = (x * kTwoOverPi + kShift) - kShift;
  const double r = ((x - kf * kPio2_1) - kf * kPio2_2) - kf * kPio2_3;
  const double z = r * r;
  const double sr = r + r * z * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
  // cos r = 1 - z/2 + z^2 C(z) (fdlibm's __kernel_cos without its
  // split of 1 - z/2, which buys half an ulp near pi/4).
  const double tail = z * z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
  const double cr = 1.0 - (0.5 * z - tail);
  switch (static_cast<long>(kf) & 3) {
    case 0:
      s = sr;
      c = cr;
      break;
    case 1:
      s = cr;
      c = -sr;
      break;
    case 2:
      s = -sr;
      c = -cr;
      break;
    default:
      s = -cr;
      c = sr;
      break;
  }
}

}  // namespace volmap
