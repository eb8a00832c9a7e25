// sin and cos by our own polynomial, so that loops over lanes vectorise and every machine, lane
// width and compiler gives the same bits: only +, -, *, and round-to-nearest are used.
#pragma once

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

}  // namespace ff
