// Tests of kernel/metrics: move metrics on analytic signals, stepinfo against MATLAB's documented examples.
#include "kernel/metrics.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace {

using ff::MoveWindow;

// Uniform grid t_k = t0 + k·dt, k = 0..n.
std::vector<double> grid(double t0, double t1, double dt) {
  const auto n = static_cast<int>(std::lround((t1 - t0) / dt));
  std::vector<double> t(static_cast<std::size_t>(n) + 1);
  for (int k = 0; k <= n; ++k) t[static_cast<std::size_t>(k)] = t0 + k * dt;
  return t;
}

template <class F>
std::vector<double> sample(const std::vector<double>& t, F f) {
  std::vector<double> y(t.size());
  for (std::size_t k = 0; k < t.size(); ++k) y[k] = f(t[k]);
  return y;
}

// num(s)/den(s) (coefficients highest power first, den monic, deg num < deg den, den(0) != 0) in
// controllable canonical form; exact step response y(t) = C A^-1 (e^{At} − I) B, impulse C e^{At} B.
struct TransferFunction {
  Eigen::MatrixXd A;
  Eigen::VectorXd B;
  Eigen::RowVectorXd C, CAinv;

  TransferFunction(const std::vector<double>& num, const std::vector<double>& den) {
    const auto n = static_cast<Eigen::Index>(den.size()) - 1;
    A = Eigen::MatrixXd::Zero(n, n);
    for (Eigen::Index i = 0; i + 1 < n; ++i) A(i, i + 1) = 1.0;
    for (Eigen::Index j = 0; j < n; ++j) A(n - 1, j) = -den[static_cast<std::size_t>(n - j)];  // −a_j
    B = Eigen::VectorXd::Zero(n);
    B(n - 1) = 1.0;
    C = Eigen::RowVectorXd::Zero(n);
    for (std::size_t i = 0; i < num.size(); ++i) C(static_cast<Eigen::Index>(num.size() - 1 - i)) = num[i];  // b_j
    CAinv = A.transpose().partialPivLu().solve(C.transpose()).transpose();
  }
  double step(double t) const {
    const Eigen::VectorXd eAtB = (A * t).exp() * B;
    return static_cast<double>(CAinv * eAtB) - static_cast<double>(CAinv * B);
  }
  double impulse(double t) const { return static_cast<double>(C * ((A * t).exp() * B)); }
  std::vector<double> step(const std::vector<double>& t) const {
    return sample(t, [this](double tk) { return step(tk); });
  }
};

// Root of f in [a, b] (f(a), f(b) of opposite signs) by bisection to machine precision.
template <class F>
double bisect(F f, double a, double b) {
  const bool fa_pos = f(a) > 0.0;
  for (int i = 0; i < 80; ++i) {
    const double m = 0.5 * (a + b);
    ((f(m) > 0.0) == fa_pos ? a : b) = m;
  }
  return 0.5 * (a + b);
}

// Exact value of an underdamped second-order unit step: zeta, natural frequency wn.
double second_order_step(double zeta, double wn, double t) {
  const double sigma = zeta * wn, wd = wn * std::sqrt(1.0 - zeta * zeta);
  return 1.0 - std::exp(-sigma * t) * (std::cos(wd * t) + sigma / wd * std::sin(wd * t));
}

// ---------------------------------------------------------------- move metrics

TEST(MoveMetrics, FirstOrderSettlesAtTauLn50) {
  // y = A(1 − e^{−(t−1)/τ}) after a move ending at t = 1: |y − A| = 2 % of A at τ·ln 50 after it.
  // Linear interpolation of the concave error gives a crossing late by at most dt²/(8τ)·e^{dt/τ}.
  const double A = 0.8, tau = 0.5, dt = 1e-3, t_end = 1.0;
  const auto t = grid(0.0, 10.0, dt);
  const auto y = sample(t, [&](double tk) { return tk < t_end ? 0.0 : A * (1.0 - std::exp(-(tk - t_end) / tau)); });
  const double ts = ff::calc_settling_time(t, y, MoveWindow{t_end, 10.0, 0.0, A});
  const double exact = tau * std::log(50.0);
  const double bound = dt * dt / (8.0 * tau) * std::exp(dt / tau);
  EXPECT_GE(ts - exact, -1e-12);
  EXPECT_LE(ts - exact, bound);
}

TEST(MoveMetrics, DecayingSinusoidSettlesInsideItsEnvelopeBound) {
  // y = 1 − e^{−t/τ}cos ωt: the error stays inside its envelope e^{−t/τ}, so the last exit from the
  // ±2 % band lies in [τ ln 50 − π/ω, τ ln 50]; its exact time is found by bisection on the formula.
  const double tau = 0.4, w = 2.0 * std::numbers::pi * 3.0, dt = 1e-3;
  const auto err = [&](double tk) { return std::exp(-tk / tau) * std::cos(w * tk); };
  const auto t = grid(0.0, 5.0, dt);
  const auto y = sample(t, [&](double tk) { return 1.0 - err(tk); });
  const double ts = ff::calc_settling_time(t, y, MoveWindow{0.0, 5.0, 0.0, 1.0});

  const double t_env = tau * std::log(50.0);
  EXPECT_GE(ts, t_env - std::numbers::pi / w);
  EXPECT_LE(ts, t_env);

  // Reference: walk back from t_env to the last time |err| > 0.02, then bisect the crossing.
  const double h = 1e-5;
  double a = t_env;
  while (std::abs(err(a)) <= 0.02) a -= h;
  double b = a + h;
  for (int i = 0; i < 60; ++i) {
    const double m = 0.5 * (a + b);
    (std::abs(err(m)) > 0.02 ? a : b) = m;
  }
  // Chord error dt²/8·max|e''| (|e''| <= env·(ω + 1/τ)²) over the error's slope |e'| at the crossing.
  const double slope = std::exp(-a / tau) * std::abs(std::cos(w * a) / tau + w * std::sin(w * a));
  const double bound = dt * dt / 8.0 * std::exp(-(a - dt) / tau) * std::pow(w + 1.0 / tau, 2) / slope;
  EXPECT_NEAR(ts, a, bound);
}

TEST(MoveMetrics, StillOutsideBandAtEndIsNotSettled) {
  // τ ln 50 ≈ 7.8 s but the record (and then the window) ends earlier.
  const double tau = 2.0;
  const auto t = grid(0.0, 20.0, 1e-2);
  const auto y = sample(t, [&](double tk) { return 1.0 - std::exp(-tk / tau); });
  EXPECT_TRUE(std::isnan(ff::calc_settling_time(std::span(t).first(501), std::span(y).first(501),
                                                MoveWindow{0.0, 5.0, 0.0, 1.0})));
  EXPECT_TRUE(std::isnan(ff::calc_settling_time(t, y, MoveWindow{0.0, 5.0, 0.0, 1.0})));  // window cut at 5 s
  EXPECT_NEAR(ff::calc_settling_time(t, y, MoveWindow{0.0, 20.0, 0.0, 1.0}), tau * std::log(50.0), 1e-4);
}

TEST(MoveMetrics, AlreadyInsideBandAtMoveEndSettlesAtZero) {
  // A ramp that reaches the target exactly at the move end and stays there.
  const auto t = grid(0.0, 2.0, 1e-2);
  const auto y = sample(t, [](double tk) { return std::min(tk, 1.0); });
  EXPECT_EQ(ff::calc_settling_time(t, y, MoveWindow{1.0, 2.0, 0.0, 1.0}), 0.0);
}

TEST(MoveMetrics, CrossingBetweenLastMoveSampleAndWindowIsInterpolated) {
  // Error 0.08 at t = 0.1 and 0 from t = 0.2 on (linear in between): the 2 % band of a unit move is
  // entered at t = 0.175, i.e. 0.025 s after a move end at 0.15 that falls between two samples.
  const std::vector<double> t{0.0, 0.1, 0.2, 0.3, 0.4};
  const std::vector<double> y{0.5, 0.92, 1.0, 1.0, 1.0};
  EXPECT_NEAR(ff::calc_settling_time(t, y, MoveWindow{0.15, 0.4, 0.0, 1.0}), 0.025, 1e-15);
  // Crossing before the move end clamps to 0.
  EXPECT_EQ(ff::calc_settling_time(t, y, MoveWindow{0.19, 0.4, 0.0, 1.0}), 0.0);
}

TEST(MoveMetrics, OvershootOfSecondOrderStepIsExpOfMinusZetaPiOverSqrt) {
  // Peak of an underdamped second-order step: 100·exp(−ζπ/√(1−ζ²)) percent over the target.
  // Sampling the peak with dt = 1e-4 loses at most |y''|·dt²/8 ≈ 2e-8 of the unit amplitude.
  const double zeta = 0.3, wn = 2.0 * std::numbers::pi, A = 2.0;
  const auto t = grid(0.0, 6.0, 1e-4);
  const auto y = sample(t, [&](double tk) { return A * second_order_step(zeta, wn, tk); });
  const double expected = 100.0 * std::exp(-zeta * std::numbers::pi / std::sqrt(1.0 - zeta * zeta));
  EXPECT_NEAR(ff::calc_overshoot(t, y, 0.0, MoveWindow{0.0, 6.0, 0.0, A}), expected, 1e-5);
  // A response that never passes its target has no overshoot.
  const auto y1 = sample(t, [](double tk) { return 1.0 - std::exp(-tk); });
  EXPECT_EQ(ff::calc_overshoot(t, y1, 0.0, MoveWindow{0.0, 6.0, 0.0, 1.0}), 0.0);
}

TEST(MoveMetrics, NegativeMoveMeasuresOvershootBelowTarget) {
  // Move 0.5 → 0: the mirrored second-order response dips below 0 by the same percentage and
  // settles at the same time as the move 0 → 0.5.
  const double zeta = 0.3, wn = 2.0 * std::numbers::pi;
  const auto t = grid(0.0, 6.0, 1e-4);
  const auto down = sample(t, [&](double tk) { return 0.5 - 0.5 * second_order_step(zeta, wn, tk); });
  const auto up = sample(t, [&](double tk) { return 0.5 * second_order_step(zeta, wn, tk); });
  const MoveWindow wd{0.0, 6.0, 0.5, 0.0}, wu{0.0, 6.0, 0.0, 0.5};
  const double expected = 100.0 * std::exp(-zeta * std::numbers::pi / std::sqrt(1.0 - zeta * zeta));
  EXPECT_NEAR(ff::calc_overshoot(t, down, 0.0, wd), expected, 1e-5);
  EXPECT_NEAR(ff::calc_settling_time(t, down, wd), ff::calc_settling_time(t, up, wu), 1e-12);

  // Bulging above the start (against the move) and approaching 0 from above is no overshoot.
  // (0.5 + t)e^{−t} peaks at e^{−1/2} ≈ 0.61 at t = 0.5.
  const auto bulge = sample(t, [](double tk) { return (0.5 + tk) * std::exp(-tk); });
  EXPECT_EQ(ff::calc_overshoot(t, bulge, 0.0, wd), 0.0);
  EXPECT_NEAR(ff::calc_peak_abs(t, bulge, 0.0, 6.0), std::exp(-0.5), 1e-12);
}

TEST(MoveMetrics, ResidualAmplitudeOfSineIsItsAmplitude) {
  // 0.2 + 0.3 sin(2π·5t): peaks fall on the 1 ms grid, so half the peak-to-peak is 0.3 and |y| peaks at 0.5.
  const auto t = grid(0.0, 2.0, 1e-3);
  const auto y = sample(t, [](double tk) { return 0.2 + 0.3 * std::sin(2.0 * std::numbers::pi * 5.0 * tk); });
  EXPECT_NEAR(ff::calc_residual_amplitude(t, y, 0.5, 1.5), 0.3, 1e-12);
  EXPECT_NEAR(ff::calc_peak_abs(t, y, 0.5, 1.5), 0.5, 1e-12);
}

TEST(MoveMetrics, RejectsZeroAmplitudeAndMalformedSignals) {
  const std::vector<double> t{0.0, 1.0, 2.0}, y{0.0, 1.0, 1.0}, bad_t{0.0, 1.0, 1.0}, short_y{0.0, 1.0};
  const std::vector<double> none;
  const MoveWindow w{0.0, 2.0, 0.0, 1.0}, flat{0.0, 2.0, 1.0, 1.0};
  EXPECT_THROW(ff::calc_settling_time(t, y, flat), std::invalid_argument);
  EXPECT_THROW(ff::calc_overshoot(t, y, 0.0, flat), std::invalid_argument);
  EXPECT_THROW(ff::calc_settling_time(t, short_y, w), std::invalid_argument);
  EXPECT_THROW(ff::calc_settling_time(none, none, w), std::invalid_argument);
  EXPECT_THROW(ff::calc_settling_time(bad_t, y, w), std::invalid_argument);
  EXPECT_THROW(ff::calc_peak_abs(t, y, 2.5, 3.0), std::invalid_argument);  // no sample in range
  EXPECT_THROW(ff::calc_residual_amplitude(t, short_y, 0.0, 2.0), std::invalid_argument);
  EXPECT_THROW(ff::calc_stepinfo(t, y, 1.0, 1.0), std::invalid_argument);
}

// ---------------------------------------------------------------- stepinfo

// MATLAB evaluates stepinfo(sys) on the samples of its own step() grid, so its printed values
// carry that grid's sampling (PeakTime, Peak, Overshoot) and interpolation (RiseTime, SettlingTime)
// errors. Each example's grid is pinned by its PeakTime (the peak sample): t_peak / k for the
// integer k below; the other values are then independent checks and must match to the 4 printed
// decimals (±5e-5). StepinfoOnFineGridGivesContinuousValues covers the dense-grid values.
const TransferFunction kDocH({8, 18, 32}, {1, 6, 14, 24});  // H(s) of the stepinfo documentation

TEST(Stepinfo, StepinfoMatchesMatlabDocumentedExample) {
  // MATLAB: H = tf([8 18 32],[1 6 14 24]); stepinfo(H) → RiseTime 0.2087, TransientTime 3.4972,
  // SettlingTime 3.4972, SettlingMin 1.1956, SettlingMax 1.6871, Overshoot 26.5302, Undershoot 0,
  // Peak 1.6871, PeakTime 0.5987; with 'SettlingTimeThreshold' 0.005: SettlingTime 4.8896.
  // MATLAB's grid: dt = 0.59867/26 ≈ 23 ms (k = 27 fits as well).
  const auto t = grid(0.0, 12.0, 0.59867 / 26.0);
  const auto y = kDocH.step(t);
  const ff::StepInfo s = ff::calc_stepinfo(t, y, 32.0 / 24.0);
  EXPECT_NEAR(s.rise_time, 0.2087, 5e-5);
  EXPECT_NEAR(s.transient_time, 3.4972, 5e-5);
  EXPECT_NEAR(s.settling_time, 3.4972, 5e-5);
  EXPECT_NEAR(s.settling_min, 1.1956, 5e-5);
  EXPECT_NEAR(s.settling_max, 1.6871, 5e-5);
  EXPECT_NEAR(s.overshoot, 26.5302, 5e-5);
  EXPECT_EQ(s.undershoot, 0.0);
  EXPECT_NEAR(s.peak, 1.6871, 5e-5);
  EXPECT_NEAR(s.peak_time, 0.5987, 5e-5);
  EXPECT_NEAR(ff::calc_stepinfo(t, y, 32.0 / 24.0, 0.0, 0.005).settling_time, 4.8896, 5e-5);
}

TEST(Stepinfo, StepinfoMatchesMatlabFourthOrderExample) {
  // MATLAB: stepinfo(tf([1 5 5],[1 1.65 5 6.5 2])) → RiseTime 3.8456, TransientTime 27.9762,
  // SettlingTime 27.9762, SettlingMin 2.0689, SettlingMax 2.6873, Overshoot 7.4915, Undershoot 0,
  // Peak 2.6873, PeakTime 8.0530. MATLAB's grid: dt = 8.05299/92 ≈ 87.5 ms (the only k that fits).
  const TransferFunction h({1, 5, 5}, {1, 1.65, 5, 6.5, 2});
  const auto t = grid(0.0, 80.0, 8.05299 / 92.0);
  const ff::StepInfo s = ff::calc_stepinfo(t, h.step(t), 2.5);
  EXPECT_NEAR(s.rise_time, 3.8456, 5e-5);
  EXPECT_NEAR(s.transient_time, 27.9762, 5e-5);
  EXPECT_NEAR(s.settling_time, 27.9762, 5e-5);
  EXPECT_NEAR(s.settling_min, 2.0689, 5e-5);
  EXPECT_NEAR(s.settling_max, 2.6873, 5e-5);
  EXPECT_NEAR(s.overshoot, 7.4915, 5e-5);
  EXPECT_EQ(s.undershoot, 0.0);
  EXPECT_NEAR(s.peak, 2.6873, 5e-5);
  EXPECT_NEAR(s.peak_time, 8.0530, 5e-5);
}

TEST(Stepinfo, StepinfoOnFineGridGivesContinuousValues) {
  // dt = 0.1 ms: rise and settling times agree with MATLAB's to its grid error (< 2e-4); the peak
  // is that of the continuous response (impulse response zero, found by bisection), 9 ms later and
  // 0.013 %-points higher than the peak sample of MATLAB's 23 ms grid.
  const double dt = 1e-4;
  const auto t = grid(0.0, 10.0, dt);
  const auto y = kDocH.step(t);
  const ff::StepInfo s = ff::calc_stepinfo(t, y, 32.0 / 24.0);
  EXPECT_NEAR(s.rise_time, 0.2087, 5e-5);
  EXPECT_NEAR(s.settling_time, 3.4972, 1e-4);
  EXPECT_EQ(s.transient_time, s.settling_time);  // y(0) = y_init: peak error = |y_final − y_init|
  EXPECT_NEAR(ff::calc_stepinfo(t, y, 32.0 / 24.0, 0.0, 0.005).settling_time, 4.8896, 2e-4);
  EXPECT_NEAR(s.settling_min, 1.1956, 5e-5);

  const double tp = bisect([](double tk) { return kDocH.impulse(tk); }, 0.4, 0.8);
  const double os = 100.0 * (kDocH.step(tp) / (32.0 / 24.0) - 1.0);
  EXPECT_NEAR(s.peak_time, tp, dt / 2);
  EXPECT_NEAR(s.peak, kDocH.step(tp), 1e-8);
  EXPECT_NEAR(s.overshoot, os, 1e-6);
  EXPECT_NEAR(tp - 0.5987, 0.0092, 1e-4);  // MATLAB's peak sample misses the true peak
}

TEST(Stepinfo, FirstOrderRiseIsTauLn9AndSettlingTauLn50) {
  const double tau = 0.5, dt = 1e-4;
  const auto t = grid(0.0, 5.0, dt);
  const auto y = sample(t, [&](double tk) { return 1.0 - std::exp(-tk / tau); });
  const ff::StepInfo s = ff::calc_stepinfo(t, y, 1.0);
  EXPECT_NEAR(s.rise_time, tau * std::log(9.0), dt * dt / tau);
  EXPECT_NEAR(s.settling_time, tau * std::log(50.0), dt * dt / tau);
  EXPECT_EQ(s.overshoot, 0.0);
  EXPECT_EQ(s.undershoot, 0.0);
  EXPECT_EQ(s.peak, y.back());
  EXPECT_EQ(s.peak_time, t.back());
  EXPECT_NEAR(s.settling_min, 0.9, 1e-4);
  EXPECT_EQ(s.settling_max, y.back());
}

TEST(Stepinfo, OffsetAndNegativeStepGiveSameCharacteristics) {
  // y' = 3 − y with y_init = 3, y_final' = 3 − y_final: same times and percentages, Peak = max|y' − y_init|.
  const auto t = grid(0.0, 10.0, 1e-3);
  const auto y = kDocH.step(t);
  std::vector<double> m(y.size());
  for (std::size_t k = 0; k < y.size(); ++k) m[k] = 3.0 - y[k];
  const ff::StepInfo a = ff::calc_stepinfo(t, y, 32.0 / 24.0);
  const ff::StepInfo b = ff::calc_stepinfo(t, m, 3.0 - 32.0 / 24.0, 3.0);
  EXPECT_NEAR(b.rise_time, a.rise_time, 1e-9);
  EXPECT_NEAR(b.settling_time, a.settling_time, 1e-9);
  EXPECT_NEAR(b.transient_time, a.transient_time, 1e-9);
  EXPECT_NEAR(b.overshoot, a.overshoot, 1e-9);
  EXPECT_NEAR(b.peak, a.peak, 1e-12);
  EXPECT_EQ(b.peak_time, a.peak_time);
  EXPECT_NEAR(b.settling_min, 3.0 - a.settling_max, 1e-12);
  EXPECT_NEAR(b.settling_max, 3.0 - a.settling_min, 1e-12);
}

TEST(Stepinfo, UnsettledOrUnrisenRecordGivesNaN) {
  const auto t = grid(0.0, 1.0, 1e-3);
  const auto y = sample(t, [](double tk) { return 1.0 - std::exp(-tk); });  // reaches only 63 % of 1
  const ff::StepInfo s = ff::calc_stepinfo(t, y, 1.0);
  EXPECT_TRUE(std::isnan(s.settling_time));
  EXPECT_TRUE(std::isnan(s.rise_time));
  EXPECT_TRUE(std::isnan(s.settling_min));
  EXPECT_TRUE(std::isnan(s.settling_max));
}

}  // namespace
