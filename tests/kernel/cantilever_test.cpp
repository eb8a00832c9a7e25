// Tests of the analytic cantilever oracle (kernel/cantilever.hpp) against classical roots and
// the spring–mass limits of a heavy tip body.
#include "kernel/cantilever.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <vector>

namespace {

// Unit beam (EI = rho A = L = 1): omega = beta^2, so tip ratios are mu = M and j = J.
ff::CantileverSpec unit_beam(double mu, double j) { return {1.0, 1.0, 1.0, mu, j}; }

// beta_n = sqrt(omega_n) for the unit beam.
std::vector<double> unit_betas(double mu, double j, int count) {
  std::vector<double> betas = ff::calc_cantilever_frequencies(unit_beam(mu, j), count);
  for (double& b : betas) b = std::sqrt(b);
  return betas;
}

// Clamped–free roots of 1 + cos b cosh b = 0 (Blevins, table 8-1).
TEST(Cantilever, BareCantileverMatchesClassicalRoots) {
  const std::vector<double> b = unit_betas(0.0, 0.0, 5);
  EXPECT_NEAR(b[0], 1.87510407, 1e-8);
  EXPECT_NEAR(b[1], 4.69409113, 1e-8);
  EXPECT_NEAR(b[2], 7.85475744, 1e-8);
  EXPECT_NEAR(b[3], 10.99554073, 1e-8);
  EXPECT_NEAR(b[4], 14.13716839, 1e-8);
  // Dimensional check: omega_1 = 1.8751^2 sqrt(EI / (rho A L^4)), rad/s.
  const ff::CantileverSpec s{200.0, 3.0, 2.0, 0.0, 0.0};
  const double w1 = ff::calc_cantilever_frequencies(s, 1)[0];
  EXPECT_NEAR(w1, 1.87510407 * 1.87510407 * std::sqrt(200.0 / (3.0 * 16.0)), 1e-7);
}

// M/(rho A L) = 1: beta_1 = 1.24792 (Blevins, table 8-1; Laura et al. 1974); beta_2 = 4.03114.
TEST(Cantilever, TipMassRatioOneMatchesTabulatedRoot) {
  const std::vector<double> b = unit_betas(1.0, 0.0, 2);
  EXPECT_NEAR(b[0], 1.24792, 1e-5);
  EXPECT_NEAR(b[1], 4.03114, 1e-5);
}

// Heavy tip mass: omega_1^2 -> 3 EI / (L^3 (M + 0.2357 rho A L)) (Rayleigh's effective mass).
TEST(Cantilever, HeavyTipMassTendsToSpringMassLimit) {
  for (double mu : {10.0, 100.0, 1.0e4}) {
    const double w1 = ff::calc_cantilever_frequencies(unit_beam(mu, 0.0), 1)[0];
    const double rayleigh = 3.0 / (mu + 0.2357);
    EXPECT_NEAR(w1 * w1 / rayleigh, 1.0, 1e-3) << "mu = " << mu;
  }
  // Dimensional: 2 kg/m beam, L = 1.5 m, EI = 50 N m^2, M = 300 kg.
  const ff::CantileverSpec s{50.0, 2.0, 1.5, 300.0, 0.0};
  const double w1 = ff::calc_cantilever_frequencies(s, 1)[0];
  EXPECT_NEAR(w1 * w1 / (3.0 * 50.0 / (std::pow(1.5, 3) * (300.0 + 0.2357 * 3.0))), 1.0, 1e-3);
}

// Huge tip inertia, no tip mass: the beam is a rotational spring EI/L (end moment m rotates the
// tip by m L / EI), so omega_1^2 -> EI / (L J).
TEST(Cantilever, HugeTipInertiaTendsToRotationalSpringLimit) {
  for (double j : {100.0, 1.0e4, 1.0e8}) {
    const double w1 = ff::calc_cantilever_frequencies(unit_beam(0.0, j), 1)[0];
    EXPECT_NEAR(w1 * w1 * j, 1.0, 1e-2) << "j = " << j;
  }
  const ff::CantileverSpec s{80.0, 1.5, 2.0, 0.0, 5.0e4};
  const double w1 = ff::calc_cantilever_frequencies(s, 1)[0];
  EXPECT_NEAR(w1 * w1 / (80.0 / (2.0 * 5.0e4)), 1.0, 1e-2);
}

// Roots ascend, satisfy the equation, none is missed (dense independent scan) and a tip body
// only lowers each frequency (Rayleigh), across mild and extreme tip bodies.
TEST(Cantilever, FrequenciesAscendAndResidualVanishes) {
  const std::vector<std::pair<double, double>> tips = {
      {0.0, 0.0}, {1.0, 0.0}, {0.0, 0.5}, {1.75, 0.0365}, {0.3, 3.0}, {50.0, 0.01},
      {1.0e6, 1.0e6}, {1.0e20, 1.0e30}};
  const int count = 30;
  const std::vector<double> bare = unit_betas(0.0, 0.0, count);
  for (const auto& [mu, j] : tips) {
    SCOPED_TRACE(testing::Message() << "mu = " << mu << ", j = " << j);
    const ff::CantileverSpec s = unit_beam(mu, j);
    const std::vector<double> b = unit_betas(mu, j, count);
    ASSERT_EQ(b.size(), static_cast<std::size_t>(count));
    for (int n = 0; n < count; ++n) {
      if (n > 0) {
        EXPECT_GT(b[n], b[n - 1] * (1.0 + 1e-9));
      }
      EXPECT_LE(b[n], bare[n] * (1.0 + 1e-12));
      EXPECT_LT(std::abs(ff::calc_cantilever_frequency_equation(s, b[n])), 1e-9);
      // Residual is zero within the 1e-13 root tolerance: neighbours either side differ in sign.
      const double lo = ff::calc_cantilever_frequency_equation(s, b[n] * (1.0 - 1e-11));
      const double hi = ff::calc_cantilever_frequency_equation(s, b[n] * (1.0 + 1e-11));
      EXPECT_LT(lo * hi, 0.0) << "mode " << n + 1;
    }
    // Independent dense scan (step 1e-3) from 0 to just past the last root (next one is ~pi
    // further) for the moderate cases, where no root lies below 1e-3.
    if (mu <= 100.0 && j <= 100.0) {
      int sign_changes = 0;
      double f_prev = ff::calc_cantilever_frequency_equation(s, 0.0);
      const int steps = static_cast<int>((b.back() + 0.01) / 1e-3);
      for (int i = 1; i <= steps; ++i) {
        const double f = ff::calc_cantilever_frequency_equation(s, i * 1e-3);
        if ((f > 0.0) != (f_prev > 0.0)) ++sign_changes;
        f_prev = f;
      }
      EXPECT_EQ(sign_changes, count);
    }
  }
}

// Invalid specs and counts are rejected.
TEST(Cantilever, RejectsInvalidInput) {
  EXPECT_THROW(ff::calc_cantilever_frequencies({0.0, 1.0, 1.0, 0.0, 0.0}, 1), std::invalid_argument);
  EXPECT_THROW(ff::calc_cantilever_frequencies({1.0, -1.0, 1.0, 0.0, 0.0}, 1), std::invalid_argument);
  EXPECT_THROW(ff::calc_cantilever_frequencies({1.0, 1.0, 0.0, 0.0, 0.0}, 1), std::invalid_argument);
  EXPECT_THROW(ff::calc_cantilever_frequencies({1.0, 1.0, 1.0, -1.0, 0.0}, 1), std::invalid_argument);
  EXPECT_THROW(ff::calc_cantilever_frequencies({1.0, 1.0, 1.0, 0.0, -1.0}, 1), std::invalid_argument);
  EXPECT_THROW(ff::calc_cantilever_frequencies({1.0, 1.0, NAN, 0.0, 0.0}, 1), std::invalid_argument);
  EXPECT_THROW(ff::calc_cantilever_frequencies(unit_beam(0.0, 0.0), 0), std::invalid_argument);
  EXPECT_THROW(ff::calc_cantilever_frequency_equation(unit_beam(0.0, 0.0), -1.0), std::invalid_argument);
}

// The project's rig (reference-rig.md): steel beam 4.1656 m x 0.3048 m x 0.01905 m with its tip
// body. For the record: first two frequencies in Hz for kappa = 1 and kappa = 0.905 (EI scaled).
TEST(Cantilever, ReferenceRigFirstTwoFrequencies) {
  const double E = 207e9;                                     // Pa
  const double I = 0.3048 * std::pow(0.01905, 3) / 12.0;      // m^4, bending about the thin axis
  const double rho_a = 7750.0 * 0.3048 * 0.01905;             // kg/m
  const double to_hz = 1.0 / (2.0 * std::numbers::pi);
  std::vector<double> hz[2];
  const double kappas[2] = {1.0, 0.905};
  for (int k = 0; k < 2; ++k) {
    const ff::CantileverSpec s{kappas[k] * E * I, rho_a, 4.1656, 328.7, 118.6};
    for (double w : ff::calc_cantilever_frequencies(s, 2)) hz[k].push_back(w * to_hz);
    std::printf("rig kappa = %.3f: f1 = %.6f Hz, f2 = %.6f Hz\n", kappas[k], hz[k][0], hz[k][1]);
  }
  EXPECT_NEAR(hz[0][0] / 0.31, 1.0, 0.10);
  EXPECT_NEAR(hz[0][1] / 2.4, 1.0, 0.10);
  // EI enters only through sqrt(EI / (rho A L^4)) (mu and j do not depend on it): f ~ sqrt(kappa).
  EXPECT_NEAR(hz[1][0] / hz[0][0], std::sqrt(0.905), 1e-12);
  EXPECT_NEAR(hz[1][1] / hz[0][1], std::sqrt(0.905), 1e-12);
}

}  // namespace
