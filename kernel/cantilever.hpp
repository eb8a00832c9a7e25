// Analytic oracle: natural frequencies of a continuous Euler–Bernoulli clamped–free beam
// carrying a tip body (point mass M and rotary inertia J at x = L). The segmented model
// must converge to these values as its segment count grows.
#pragma once

#include <vector>

namespace ff {

// A uniform cantilever with a rigid tip body whose centre of mass sits at the free end.
struct CantileverSpec {
  double flexural_rigidity;  // EI, N·m^2
  double mass_per_length;    // rho*A, kg/m
  double length;             // L, m
  double tip_mass;           // M, kg, a point mass at x = L
  double tip_inertia;        // J, kg·m^2, rotary inertia of the tip body about its centre of mass at x = L
};

// The lowest `count` natural frequencies (rad/s) of the clamped–free beam, ascending.
// Throws std::invalid_argument unless EI, rho*A, L > 0, M, J >= 0 (all finite) and count >= 1.
std::vector<double> calc_cantilever_frequencies(const CantileverSpec& s, int count);

// Its frequency equation as a function of beta = lambda*L (omega = beta^2 sqrt(EI / (rho A L^4)));
// roots are the modes. With mu = M/(rho A L), j = J/(rho A L^3) it returns the bounded, pole-free
//   F(beta) = [1 + cos b cosh b + mu b (cos b sinh b - sin b cosh b)
//              - j b^3 (cos b sinh b + sin b cosh b) + mu j b^4 (1 - cos b cosh b)]
//             / [cosh b (1 + mu b + j b^3 + mu j b^4)],
// i.e. 1/cosh b + cos b for the bare beam. Same validation as above; beta must be >= 0.
double calc_cantilever_frequency_equation(const CantileverSpec& s, double beta);

}  // namespace ff
