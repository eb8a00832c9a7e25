// Residual analysis (validate/residuals.cpp) on residuals whose answer is known.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "validate/residuals.hpp"

namespace ff {
namespace {

std::vector<double> white_noise(int n, unsigned seed, double sd = 1.0) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> d(0.0, sd);
  std::vector<double> x(n);
  for (auto& v : x) v = d(rng);
  return x;
}

// First-order low-pass e_k = a e_{k-1} + w_k: autocorrelation a^tau.
std::vector<double> filtered(const std::vector<double>& w, double a) {
  std::vector<double> e(w.size());
  double prev = 0.0;
  for (std::size_t k = 0; k < w.size(); ++k) e[k] = prev = a * prev + w[k];
  return e;
}

std::vector<double> times(int n, double dt) {
  std::vector<double> t(n);
  for (int k = 0; k < n; ++k) t[k] = k * dt;
  return t;
}

TEST(Autocorrelation, WhiteNoiseHasAboutOnePercentOfLagsOutsideTheBand) {
  const auto acf = calc_autocorrelation(white_noise(20000, 1), 200);
  EXPECT_DOUBLE_EQ(acf.value[0], 1.0);
  EXPECT_NEAR(acf.band, 2.58 / std::sqrt(20000.0), 1e-12);
  EXPECT_LE(acf.fraction_outside, 0.03);
  EXPECT_LT(acf.max_abs, 0.04);
}

TEST(Autocorrelation, FilteredNoiseHasManyLagsOutsideTheBand) {
  const auto acf = calc_autocorrelation(filtered(white_noise(20000, 1), 0.95), 200);
  // r(tau) = 0.95^tau exceeds the band 0.018 up to tau ~ 78: 39 % of lags 1..200.
  EXPECT_GT(acf.fraction_outside, 0.3);
  EXPECT_NEAR(acf.value[1], 0.95, 0.01);
  EXPECT_NEAR(acf.value[10], std::pow(0.95, 10), 0.05);
}

TEST(CrossCorrelation, ResidualThatEchoesTheInputPeaksAtItsDelay) {
  const auto u = white_noise(5000, 2);
  std::vector<double> e(u.size(), 0.0);
  for (std::size_t k = 5; k < e.size(); ++k) e[k] = u[k - 5];
  const auto ccf = calc_cross_correlation(e, u, 20);
  ASSERT_EQ(ccf.lag.size(), 41u);
  EXPECT_EQ(ccf.lag[20 + 5], 5);
  EXPECT_NEAR(ccf.value[20 + 5], 1.0, 0.01);
  EXPECT_LT(std::abs(ccf.value[20 - 5]), ccf.band);
  EXPECT_NEAR(ccf.fraction_outside, 1.0 / 41.0, 0.03);
}

TEST(CrossCorrelation, IndependentNoiseStaysInsideTheBand) {
  const auto ccf = calc_cross_correlation(white_noise(20000, 3), white_noise(20000, 4), 100);
  EXPECT_LE(ccf.fraction_outside, 0.03);
}

// A smooth move (a 0.5 rad S-curve over 4000 samples) with white noise of 0.01 rad on it.
std::vector<double> noisy_move(int n, double sd) {
  auto y = white_noise(n, 7, sd);
  for (int k = 0; k < n; ++k) y[k] += 0.5 * (1.0 - std::cos(M_PI * k / n)) / 2.0;
  return y;
}

TEST(StandardDeviation, OfOneToFourIsTheRootOfFiveQuarters) {
  EXPECT_DOUBLE_EQ(calc_standard_deviation({1, 2, 3, 4}), std::sqrt(1.25));
  EXPECT_EQ(calc_standard_deviation({}), 0.0);
}

TEST(NoiseFloor, WhiteNoiseOnASmoothMoveIsItsStandardDeviation) {
  EXPECT_NEAR(calc_noise_floor(noisy_move(4000, 0.01)), 0.01, 0.0005);
}

TEST(NoiseFloor, ARecordShorterThanOneWindowIsItsOwnWindow) {
  // 12 samples, 8 fourth differences, fewer than a window's 16: the estimate over all of them.
  const std::vector<double> y = {0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1};
  EXPECT_DOUBLE_EQ(calc_noise_floor(y), std::sqrt(std::min(4.0 / 6.0, 256.0 / 70.0)));
  EXPECT_EQ(calc_noise_floor({1, 2, 3}), 0.0);
}

TEST(NoiseFloor, ARingInAFifthOfTheRecordIsSignalNotNoise) {
  // A 240 Hz ring (at 1 kHz: sample to sample it looks like noise) of amplitude 0.1, 20 x the noise,
  // in 800 of 4000 samples: the differences of the whole record would put the floor at 0.017.
  auto y = noisy_move(4000, 0.01);
  for (int k = 1000; k < 1800; ++k) y[k] += 0.1 * std::sin(2.0 * M_PI * 0.24 * k);
  EXPECT_NEAR(calc_noise_floor(y), 0.01, 0.001);
}

TEST(NoiseFloor, ARattleInEveryWindowIsSignalNotNoise) {
  // A drive rattling at 250 Hz (a quarter of the 1 kHz rate, with its 500 Hz harmonic) through the whole
  // record, 30 x the noise: its differences look like noise (the difference estimates put the floor at
  // 0.2, 20 x the noise); its spectrum fills a few bins of each window (its leakage lifts the median by
  // under a quarter).
  auto y = noisy_move(4000, 0.01);
  for (int k = 0; k < 4000; ++k) y[k] += 0.3 * std::sin(2.0 * M_PI * 0.25 * k + 0.3) + 0.1 * ((k % 2) ? 1.0 : -1.0);
  EXPECT_NEAR(calc_noise_floor(y), 0.01, 0.0025);
}

TEST(Spectrum, SinusoidPeaksAtItsFrequencyWithinABin) {
  const int n = 5000;
  const auto t = times(n, 1e-3);
  const auto noise = white_noise(n, 5, 0.01);
  std::vector<double> e(n);
  for (int k = 0; k < n; ++k) e[k] = 0.3 * std::sin(2 * M_PI * 2.3 * t[k]) + 0.05 * t[k] + noise[k];
  const auto s = calc_amplitude_spectrum(t, e);
  EXPECT_NEAR(s.resolution, 1.0 / (8192 * (4.999 / 8191)), 1e-9);
  const auto peaks = find_spectrum_peaks(s, 3);
  ASSERT_FALSE(peaks.empty());
  EXPECT_NEAR(peaks[0].frequency, 2.3, s.resolution);
  EXPECT_NEAR(peaks[0].amplitude, 0.3, 0.3 * 0.16);  // Hann scalloping loss is at most 15 %
  EXPECT_LT(peaks[1].amplitude, 0.1 * peaks[0].amplitude);
}

TEST(Spectrum, SinusoidOnABinHasItsAmplitude) {
  const int n = 1024;
  const auto t = times(n, 1.0 / 1023.0);  // M = 1024 samples over 1 s: bins 1 / (M dt) = 1023/1024 Hz apart
  std::vector<double> e(n);
  for (int k = 0; k < n; ++k) e[k] = 0.7 * std::cos(2 * M_PI * 40.0 * (1023.0 / 1024.0) * t[k]);
  const auto peaks = find_spectrum_peaks(calc_amplitude_spectrum(t, e), 1);
  ASSERT_EQ(peaks.size(), 1u);
  EXPECT_NEAR(peaks[0].amplitude, 0.7, 1e-3);
}

TEST(Binning, CoulombResidualStepsByTwiceItsLevelAcrossZeroVelocity) {
  const int n = 20000;
  const double c = 0.8;
  const auto t = times(n, 1e-3);
  const auto noise = white_noise(n, 6, 0.1 * c);
  std::vector<double> w(n), e(n);
  for (int k = 0; k < n; ++k) {
    w[k] = 0.5 * std::sin(2 * M_PI * 0.25 * t[k]) + 0.1;  // rad/s, crosses zero in both directions
    e[k] = c * (w[k] > 0 ? 1.0 : -1.0) + noise[k];
  }
  const auto step = calc_zero_step(e, w);
  ASSERT_TRUE(step.ok);
  EXPECT_NEAR(step.step, 2 * c, 0.05 * 2 * c);
  EXPECT_NEAR(step.relative, 2 * c / std::sqrt(c * c + 0.01 * c * c), 0.1);
  const auto b = calc_binned_residual(e, w, 15, "hub_velocity");
  ASSERT_EQ(b.mean.size(), 15u);
  EXPECT_NEAR(b.mean.front(), -c, 0.05);
  EXPECT_NEAR(b.mean.back(), c, 0.05);
  EXPECT_GT(b.departure, 0.95);
  int total = 0;
  for (int k : b.count) total += k;
  EXPECT_NEAR(total, 0.98 * n, 0.005 * n);  // the 1-99 % range
}

TEST(Binning, ResidualIndependentOfTheStateDepartsLittle) {
  const int n = 20000;
  const auto e = white_noise(n, 7);
  const auto x = white_noise(n, 8);
  EXPECT_LT(calc_binned_residual(e, x).departure, 0.1);
  EXPECT_LT(std::abs(calc_zero_step(e, x).relative), 0.25);
}

TEST(Windows, BurstIsTheWorstWindow) {
  const int n = 10000;
  const auto t = times(n, 1e-3);
  auto e = white_noise(n, 9, 0.01);
  for (int k = 0; k < n; ++k)
    if (t[k] >= 3.0 && t[k] < 4.0) e[k] += std::sin(2 * M_PI * 5 * t[k]);
  const auto w = find_worst_windows(t, e, 1.0, 3);
  ASSERT_EQ(w.size(), 3u);
  EXPECT_NEAR(w[0].t0, 3.0, 1e-9);
  EXPECT_NEAR(w[0].t1, 4.0, 1e-9);
  EXPECT_NEAR(w[0].rms, std::sqrt(0.5), 0.01);
  EXPECT_LT(w[1].rms, 0.02);
}

TEST(FailureReport, NamesTheWindowThePeakAndTheFrictionStep) {
  const int n = 20000;
  const auto t = times(n, 1e-3);
  const auto noise = white_noise(n, 10, 0.05);
  std::vector<double> w(n), e(n), u(n);
  for (int k = 0; k < n; ++k) {
    w[k] = std::sin(2 * M_PI * 0.2 * t[k]);
    u[k] = std::cos(2 * M_PI * 0.2 * t[k]);
    e[k] = (w[k] > 0 ? 1.0 : -1.0) + noise[k];
  }
  const auto a = analyse_residual(t, e, u, {{"hub_velocity", w}, {"tip_deflection", noise}});
  ASSERT_TRUE(a.valid);
  EXPECT_TRUE(a.failure.friction_like);
  EXPECT_FALSE(a.failure.white);
  ASSERT_EQ(a.failure.states.size(), 2u);
  EXPECT_EQ(a.failure.states[0].first, "hub_velocity");
  ASSERT_FALSE(a.failure.peaks.empty());
  EXPECT_NEAR(a.failure.peaks[0].frequency, 0.2, 0.1);  // the square wave's fundamental
  const auto words = describe_failure(a.failure);
  bool friction = false;
  for (const auto& s : words) friction = friction || s.find("friction-like effect is missing") != std::string::npos;
  EXPECT_TRUE(friction);
}

TEST(FailureReport, NonFiniteResidualIsNotAnalysed) {
  const auto t = times(100, 0.01);
  std::vector<double> e(100, 0.0), u(100, 1.0);
  e[50] = NAN;
  EXPECT_FALSE(analyse_residual(t, e, u, {}).valid);
}

}  // namespace
}  // namespace ff
