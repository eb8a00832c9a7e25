// sin, cos and atan2 by our own polynomials, so that loops over lanes vectorise and every machine, lane
// width and compiler gives the same bits: only +, -, *, /, comparisons, selects and round-to-nearest
// are used.
#pragma once

#include <cmath>

namespace ff {

// s = sin x, c = cos x for |x| < 1e5, within 3 ulp of the correctly rounded values.
// Rounding by the 1.5 * 2^52 trick (round-to-nearest mode), Cody–Waite reduction by pi/2 in three parts, then Taylor polynomials on [-pi/4, pi/4]
// (terms to x^15 and x^16: truncation below 2e-17).
#pragma omp declare simd
inline void calc_sincos(double x, double& s, double& c) {
  constexpr double kTwoOverPi = 0.63661977236758134308;
  constexpr double kP1 = 1.5707963267341256e+00;  // pi/2 split so k * kP1 and k * kP2 are exact
  constexpr double kP2 = 6.077100506303966e-11;
  constexpr double kP3 = 2.0222662487959506e-21;
  constexpr double kRound = 6755399441055744.0;  // 1.5 * 2^52: (y + kRound) - kRound rounds y to nearest
  const double k = (x * kTwoOverPi + kRound) - kRound;
  const double r = ((x - k * kP1) - k * kP2) - k * kP3;
  const double r2 = r * r;
  // sin r = r (1 - r^2/3! + r^4/5! - ...), cos r = 1 - r^2/2! + r^4/4! - ...
  const double sp =
      r * (1.0 + r2 * (-1.0 / 6 + r2 * (1.0 / 120 + r2 * (-1.0 / 5040 + r2 * (1.0 / 362880 + r2 * (-1.0 / 39916800 +
          r2 * (1.0 / 6227020800 + r2 * (-1.0 / 1307674368000.0))))))));
  const double cp =
      1.0 + r2 * (-0.5 + r2 * (1.0 / 24 + r2 * (-1.0 / 720 + r2 * (1.0 / 40320 + r2 * (-1.0 / 3628800 +
          r2 * (1.0 / 479001600 + r2 * (-1.0 / 87178291200.0 + r2 * (1.0 / 20922789888000.0))))))));
  // Quadrant n = k mod 4 rotates (sin, cos) by n quarter turns.
  const double n = k - 4.0 * (((k - 1.5) * 0.25 + kRound) - kRound);  // k mod 4, as 0, 1, 2 or 3
  const bool swap = (n == 1.0) | (n == 3.0);
  const double s0 = swap ? cp : sp, c0 = swap ? sp : cp;
  s = ((n == 2.0) | (n == 3.0)) ? -s0 : s0;
  c = ((n == 1.0) | (n == 2.0)) ? -c0 : c0;
}

// atan2(y, x) in (-pi, pi] for finite x, y with |x| + |y| <= DBL_MAX, within 2 ulp or 1e-15 absolute of
// std::atan2 (on 4e6 random points over all quadrants and magnitudes 1e-300 .. 1e300: 96.6 % the same
// double, 3.4 % 1 ulp apart, one point 2 ulp; tests/kernel/fastmath_test.cpp); the axes and signed
// zeros exactly as std::atan2.
// Reduction: a = min(|x|, |y|) / max(|x|, |y|) in [0, 1], and for a > 0.66 r = (a − 1)/(a + 1)
// (taken as (min − max)/(min + max); exact difference by Sterbenz) with atan a = pi/4 + atan r, so
// that |r| <= 0.66; atan r by Cephes' rational approximation (S. L. Moshier, Cephes Math Library,
// atan.c: P4/Q5 on [0, 0.66], peak relative error 1.8e-16), as Go's math.atan. The result is
// k·pi/4 ± atan r with k·pi/4 in two parts (hi + lo), added last.
#pragma omp declare simd
inline double calc_atan2(double y, double x) {
  constexpr double kP0 = -8.750608600031904122785e-01, kP1 = -1.615753718733365076637e+01,
                   kP2 = -7.500855792314704667340e+01, kP3 = -1.228866684490136173410e+02,
                   kP4 = -6.485021904942025371773e+01;
  constexpr double kQ0 = 2.485846490142306297962e+01, kQ1 = 1.650270098316988542046e+02,
                   kQ2 = 4.328810604912902668951e+02, kQ3 = 4.853903996359136964868e+02,
                   kQ4 = 1.945506571482613964425e+02;
  const double ax = std::abs(x), ay = std::abs(y);
  const bool swap = ay > ax;  // angle from the y axis: pi/2 − atan(ax/ay)
  const double num = swap ? ax : ay, den = swap ? ay : ax;
  const bool mid = num > 0.66 * den;
  const double r = den == 0.0 ? 0.0 : mid ? (num - den) / (num + den) : num / den;
  const double z = r * r;
  const double p = z * ((((kP0 * z + kP1) * z + kP2) * z + kP3) * z + kP4) /
                   (((((z + kQ0) * z + kQ1) * z + kQ2) * z + kQ3) * z + kQ4);
  const double at = r * p + r;  // atan r
  // atan(num/den) = m pi/4 + at; the first quadrant's angle k1 pi/4 + s at; x < 0 (or −0) mirrors it
  // to pi minus it. k pi/4 = hi + lo.
  const double m = mid ? 1.0 : 0.0;
  const double k1 = swap ? 2.0 - m : m, s1 = swap ? -1.0 : 1.0;
  const bool left = std::copysign(1.0, x) < 0.0;
  const double k = left ? 4.0 - k1 : k1, s = left ? -s1 : s1;
  const double hi = k == 0.0 ? 0.0 : k == 1.0 ? 0.7853981633974483 : k == 2.0 ? 1.5707963267948966
                  : k == 3.0 ? 2.356194490192345 : 3.141592653589793;
  const double lo = k == 0.0 ? 0.0 : k == 1.0 ? 3.061616997868383e-17 : k == 2.0 ? 6.123233995736766e-17
                  : k == 3.0 ? 9.184850993605148e-17 : 1.2246467991473532e-16;
  const double a = hi + (lo + s * at);
  // The sign of y, −0 included.
  return std::copysign(a, y);
}

}  // namespace ff
