// Natural frequencies of a clamped–free Euler–Bernoulli beam with a tip mass M and tip rotary
// inertia J (see cantilever.hpp).
//
// Derivation (EI w'''' + rho A w_tt = 0, w = W(x) sin(omega t), lambda^4 = rho A omega^2 / EI):
//   W(x) = A cos lx + B sin lx + C cosh lx + D sinh lx.
//   x = 0, clamped:  W = 0 -> C = -A;  W' = 0 -> D = -B, so
//     W = A (cos - cosh) + B (sin - sinh).
//   x = L, tip body (b = lambda L, mu = M/(rho A L), j = J/(rho A L^3), c, s, ch, sh of b):
//     shear:  EI W''' = -M omega^2 W  (the tip mass's inertia force loads the end)
//       -> A [(s - sh) + mu b (c - ch)] + B [-(c + ch) + mu b (s - sh)] = 0
//     moment: EI W'' = J omega^2 W'   (the tip inertia's moment)
//       -> A [-(c + ch) + j b^3 (s + sh)] + B [-(s + sh) - j b^3 (c - ch)] = 0
//   The 2x2 determinant, divided by -2 (expanded with cosh^2 - sinh^2 = cos^2 + sin^2 = 1):
//     1 + c ch + mu b (c sh - s ch) - j b^3 (c sh + s ch) + mu j b^4 (1 - c ch) = 0,
//   which is 1 + cos b cosh b = 0 for M = J = 0 (cf. Laura, Pombo & Susemihl, J. Sound Vib.
//   37 (1974) 161; Blevins, "Formulas for natural frequency and mode shape", table 8-1).
//   Small-b expansion: 2 - b^4 (1/6 + 2 mu/3 + 2 j) + O(b^8) = 0, giving the spring–mass limits
//   omega^2 -> 3 EI / (M L^3) and omega^2 -> EI / (J L).
#include "kernel/cantilever.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace ff {

namespace {

// Rejects non-physical input with std::invalid_argument.
void validate(const CantileverSpec& s) {
  auto positive = [](double v, const char* name) {
    if (!(std::isfinite(v) && v > 0.0))
      throw std::invalid_argument(std::string("cantilever: ") + name + " must be positive and finite");
  };
  auto non_negative = [](double v, const char* name) {
    if (!(std::isfinite(v) && v >= 0.0))
      throw std::invalid_argument(std::string("cantilever: ") + name + " must be non-negative and finite");
  };
  positive(s.flexural_rigidity, "flexural_rigidity");
  positive(s.mass_per_length, "mass_per_length");
  positive(s.length, "length");
  non_negative(s.tip_mass, "tip_mass");
  non_negative(s.tip_inertia, "tip_inertia");
}

// Dimensionless tip mass ratio mu = M/(rho A L) and inertia ratio j = J/(rho A L^3).
struct Ratios {
  double mu;
  double j;
};

Ratios ratios_of(const CantileverSpec& s) {
  const double beam_mass = s.mass_per_length * s.length;  // kg
  return {s.tip_mass / beam_mass, s.tip_inertia / (beam_mass * s.length * s.length)};
}

// The frequency equation divided by cosh b * (1 + mu b + j b^3 + mu j b^4): bounded, continuous,
// free of poles and overflow, equal to 2 at b = 0. With
//   P = cos b sinh b - sin b cosh b,  Q = cos b sinh b + sin b cosh b,  R = 1 - cos b cosh b,
// the numerator is (2 - R) + mu b P - j b^3 Q + mu j b^4 R.
double scaled_equation(const Ratios& r, double b) {
  const double b3 = b * b * b;
  const double b4 = b3 * b;
  const double scale = 1.0 + r.mu * b + r.j * b3 + r.mu * r.j * b4;
  if (b < 1.0) {
    // Small b: P ~ -2b^3/3 and R ~ b^4/6 cancel catastrophically in closed form, so sum their
    // Taylor series (from cos x cosh x = sum (-4)^k x^4k/(4k)! and sinh((1+i)x)):
    //   R = -sum_{k>=1} (-4)^k b^4k/(4k)!,  P = sum_{k>=1} (-4)^k b^(4k-1)/(4k-1)!,
    //   Q = 2 sum_{k>=0} (-4)^k b^(4k+1)/(4k+1)!.
    double term = b;  // b^n / n!, starting at n = 1
    double p = 0.0, q = 0.0, rr = 0.0, sign4 = 1.0;  // sign4 = (-4)^k
    q += 2.0 * term;  // k = 0, n = 1
    for (int k = 1; k <= 9; ++k) {
      sign4 *= -4.0;
      term *= b / (4 * k - 2);  // n = 4k - 2
      term *= b / (4 * k - 1);  // n = 4k - 1
      p += sign4 * term;
      term *= b / (4 * k);      // n = 4k
      rr -= sign4 * term;
      term *= b / (4 * k + 1);  // n = 4k + 1
      q += 2.0 * sign4 * term;
    }
    const double numerator = (2.0 - rr) + r.mu * b * p - r.j * b3 * q + r.mu * r.j * b4 * rr;
    return numerator / (std::cosh(b) * scale);
  }
  // b >= 1: no cancellation; divide through by cosh b first so only 1/cosh b and tanh b appear.
  const double c = std::cos(b);
  const double s = std::sin(b);
  const double sech = 1.0 / std::cosh(b);  // 0 once cosh overflows, which is the right limit
  const double t = std::tanh(b);
  const double numerator = (sech + c) + r.mu * b * (c * t - s) - r.j * b3 * (c * t + s) +
                           r.mu * r.j * b4 * (sech - c);
  return numerator / scale;
}

// Bisects a sign change of f on [lo, hi] to 1e-13 relative width; returns the midpoint.
template <class F>
double bisect(const F& f, double lo, double hi, double f_lo) {
  for (int it = 0; it < 300; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi || hi - lo <= 1e-13 * mid) break;
    const double f_mid = f(mid);
    if (f_mid == 0.0) return mid;
    if ((f_mid > 0.0) == (f_lo > 0.0)) {
      lo = mid;
      f_lo = f_mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

}  // namespace

double calc_cantilever_frequency_equation(const CantileverSpec& s, double beta) {
  validate(s);
  if (!(std::isfinite(beta) && beta >= 0.0))
    throw std::invalid_argument("cantilever: beta must be non-negative and finite");
  return scaled_equation(ratios_of(s), beta);
}

std::vector<double> calc_cantilever_frequencies(const CantileverSpec& s, int count) {
  validate(s);
  if (count < 1) throw std::invalid_argument("cantilever: count must be >= 1");
  const Ratios r = ratios_of(s);
  auto f = [&r](double b) { return scaled_equation(r, b); };

  // omega = beta^2 * sqrt(EI / (rho A L^4)), rad/s.
  const double omega_per_beta2 =
      std::sqrt(s.flexural_rigidity / (s.mass_per_length * std::pow(s.length, 4)));

  // Grid: the small-beta estimate of the first root sets the finest step; steps grow by 1 % of
  // beta (roots are at least a factor ~1.9 apart at the low end) up to 0.02 (root spacing -> pi).
  const double beta1_estimate = std::pow(2.0 / (1.0 / 6.0 + 2.0 * r.mu / 3.0 + 2.0 * r.j), 0.25);
  const double step_min = 1e-3 * beta1_estimate;
  const double step_max = 0.02;
  // Tip bodies only lower the frequencies (Rayleigh), so beta_n < (n - 1/2) pi of the bare beam.
  const double beta_max = (count + 1) * std::numbers::pi + 2.0;

  std::vector<double> betas;
  // Accepts a root bracketed by a sign change on [lo, hi] if its residual is tiny (not a pole).
  auto add_root = [&](double lo, double hi, double f_lo, double f_hi) {
    const double root = bisect(f, lo, hi, f_lo);
    const double residual = std::abs(f(root));
    if (residual <= 1e-6 * std::max(std::abs(f_lo), std::abs(f_hi)) || residual <= 1e-14)
      betas.push_back(root);
  };
  // Scans [lo, hi] finely for sign changes; used where |f| dips without changing sign, which is
  // where two close roots could hide inside one coarse step.
  auto fine_scan = [&](double lo, double hi) {
    constexpr int pieces = 64;
    double a = lo;
    double fa = f(a);
    for (int i = 1; i <= pieces; ++i) {
      const double b = (i == pieces) ? hi : lo + (hi - lo) * i / pieces;
      const double fb = f(b);
      if ((fa > 0.0) != (fb > 0.0)) add_root(a, b, fa, fb);
      a = b;
      fa = fb;
    }
  };

  double b_prev2 = 0.0, f_prev2 = 0.0;  // point before last (valid once have_prev2)
  bool have_prev2 = false;
  double b_prev = 0.0, f_prev = f(0.0);  // f(0) = 2
  while (static_cast<int>(betas.size()) < count) {
    if (b_prev > beta_max) throw std::runtime_error("cantilever: root scan overran its bound");
    const double b = b_prev + std::clamp(0.01 * b_prev, step_min, step_max);
    const double fb = f(b);
    if ((f_prev > 0.0) != (fb > 0.0)) {
      add_root(b_prev, b, f_prev, fb);  // ordinary simple root
    } else if (have_prev2 && (f_prev2 > 0.0) == (f_prev > 0.0) &&
               std::abs(f_prev) < std::abs(f_prev2) && std::abs(f_prev) < std::abs(fb)) {
      fine_scan(b_prev2, b);  // a dip towards zero: look for a hidden pair of roots
    }
    b_prev2 = b_prev;
    f_prev2 = f_prev;
    have_prev2 = true;
    b_prev = b;
    f_prev = fb;
  }

  // Keep the lowest `count`, ascending, converted to rad/s.
  std::sort(betas.begin(), betas.end());
  betas.resize(static_cast<std::size_t>(count));
  std::vector<double> omegas;
  omegas.reserve(betas.size());
  for (double b : betas) omegas.push_back(b * b * omega_per_beta2);
  return omegas;
}

}  // namespace ff
