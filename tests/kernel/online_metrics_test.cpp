// Tests of kernel/online_metrics: the online move metrics give the stored-trace functions' doubles
// (kernel/metrics) bit for bit on random signals.
#include "kernel/online_metrics.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <vector>

#include "kernel/metrics.hpp"
#include "tests/results/test_rng.hpp"

namespace {

using ff::MoveWindow;
using ff::test::TestRng;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The same double, bit for bit (so NaN == NaN, and -0 != +0).
void expect_same_bits(double stored, double online, const char* what) {
  EXPECT_EQ(std::bit_cast<std::uint64_t>(stored), std::bit_cast<std::uint64_t>(online))
      << what << ": stored " << stored << ", online " << online;
}

// The stored function's value, or NaN when it finds no sample in its range (where it throws).
double stored_or_nan(const std::function<double()>& f) {
  try {
    return f();
  } catch (const std::invalid_argument&) {
    return kNaN;
  }
}

// Feeds (t, y) to the four online metrics of window w (overshoot and peak from t_from) and compares
// each with its stored form.
void expect_online_matches_stored(std::span<const double> t, std::span<const double> y, double t_from,
                                  const MoveWindow& w, double band) {
  ff::OnlineSettling settling(w, band);
  ff::OnlineOvershoot overshoot(t_from, w);
  ff::OnlinePeakAbs peak(t_from, w.t_window_end);
  ff::OnlineResidual residual(w.t_move_end, w.t_window_end);
  for (std::size_t k = 0; k < t.size(); ++k) {
    settling.add(t[k], y[k]);
    overshoot.add(t[k], y[k]);
    peak.add(t[k], y[k]);
    residual.add(t[k], y[k]);
  }
  expect_same_bits(stored_or_nan([&] { return ff::calc_settling_time(t, y, w, band); }), settling.result(), "settling");
  expect_same_bits(stored_or_nan([&] { return ff::calc_overshoot(t, y, t_from, w); }), overshoot.result(), "overshoot");
  expect_same_bits(stored_or_nan([&] { return ff::calc_peak_abs(t, y, t_from, w.t_window_end); }), peak.result(),
                   "peak_abs");
  expect_same_bits(stored_or_nan([&] { return ff::calc_residual_amplitude(t, y, w.t_move_end, w.t_window_end); }),
                   residual.result(), "residual");
}

// A strictly increasing time axis of n samples from 0: uniform steps, or random ones over six decades.
std::vector<double> make_times(TestRng& rng, int n, bool uniform) {
  std::vector<double> t(static_cast<std::size_t>(n));
  const double dt = std::pow(10.0, -4.0 + 3.0 * rng.uniform());
  for (int k = 1; k < n; ++k)
    t[k] = uniform ? k * dt : t[k - 1] + dt * std::pow(10.0, -3.0 + 6.0 * rng.uniform());
  return t;
}

// A window on the time axis: move end on a sample, between samples, before the first or past the last.
MoveWindow make_window(TestRng& rng, std::span<const double> t, double start, double target) {
  const double span = t.back() - t.front();
  const auto pick = [&] { return t[static_cast<std::size_t>(rng.uniform() * static_cast<double>(t.size()))]; };
  const double u = rng.uniform();
  double t1 = u < 0.3 ? pick() : u < 0.9 ? t.front() + span * rng.uniform() : t.front() + span * (2.2 * rng.uniform() - 0.6);
  double t2 = rng.uniform() < 0.3 ? pick() : t1 + span * 1.2 * rng.uniform();
  if (rng.uniform() < 0.05) t2 = t1;  // a window of one instant
  return {t1, t2, start, target};
}

// Random signals of the given shape: each case draws a time axis, a move and a response.
enum class Shape { kDecaying, kNeverSettling, kInsideBand, kSignedZeros };

void run_random_cases(Shape shape, std::uint64_t seed, int cases) {
  TestRng rng{seed};
  for (int c = 0; c < cases; ++c) {
    const int n = 1 + static_cast<int>(rng.uniform() * 600.0);
    const std::vector<double> t = make_times(rng, n, rng.uniform() < 0.5);
    // Moves up and down, over amplitudes from 1e-6 to 1e3.
    const double start = (rng.uniform() - 0.5) * std::pow(10.0, -3.0 + 6.0 * rng.uniform());
    const double amp = (rng.uniform() < 0.5 ? -1.0 : 1.0) * std::pow(10.0, -6.0 + 9.0 * rng.uniform());
    const double target = start + amp;
    const double band = rng.uniform() < 0.7 ? 0.02 : 0.001 + 0.2 * rng.uniform();
    const double span = t.back() - t.front() + 1e-9;
    const double decay = std::pow(10.0, -1.0 + 3.0 * rng.uniform()) / span;
    const double omega = std::pow(10.0, 3.0 * rng.uniform()) / span;
    const double noise = std::abs(amp) * band * 0.5 * rng.uniform();
    std::vector<double> y(t.size());
    for (std::size_t k = 0; k < t.size(); ++k) {
      const double e = 2.0 * rng.uniform() - 1.0;
      switch (shape) {
        case Shape::kDecaying:  // response to the target: a decaying oscillation plus noise
          y[k] = target - amp * std::exp(-decay * t[k]) * std::cos(omega * t[k]) + noise * e;
          break;
        case Shape::kNeverSettling:  // swings of growing amplitude about the target
          y[k] = target + amp * (0.5 + t[k] / span) * std::sin(omega * t[k]);
          break;
        case Shape::kInsideBand:  // always within half the band
          y[k] = target + 0.5 * band * std::abs(amp) * e;
          break;
        case Shape::kSignedZeros:  // +0, -0 and small values: ties of the extrema
          y[k] = e < -0.3 ? -0.0 : e < 0.3 ? 0.0 : 1e-300 * e;
          break;
      }
    }
    // Several windows on the same record, each with overshoot and peak from its move's start.
    for (int j = 0; j < 4; ++j) {
      const MoveWindow w = make_window(rng, t, start, target);
      const double t_from = w.t_move_end - (t.back() - t.front()) * rng.uniform();
      SCOPED_TRACE(testing::Message() << "case " << c << " window " << j << " n " << n);
      expect_online_matches_stored(t, y, t_from, w, band);
    }
  }
}

TEST(OnlineMetrics, DecayingOscillationsGiveTheStoredBits) { run_random_cases(Shape::kDecaying, 1, 2000); }

TEST(OnlineMetrics, NeverSettlingSignalsGiveTheStoredBits) { run_random_cases(Shape::kNeverSettling, 2, 1000); }

TEST(OnlineMetrics, SignalsNeverLeavingTheBandGiveTheStoredBits) { run_random_cases(Shape::kInsideBand, 3, 1000); }

TEST(OnlineMetrics, SignedZerosGiveTheStoredBits) { run_random_cases(Shape::kSignedZeros, 4, 500); }

// The edge cases by hand: not settled, never out of the band, a crossing before the window, clamping.
TEST(OnlineMetrics, SettlingEdgeCasesGiveTheStoredValues) {
  const std::vector<double> t = {0.0, 1.0, 2.0, 3.0, 4.0};
  const MoveWindow w{1.5, 4.0, 0.0, 1.0};
  const auto online = [&](const std::vector<double>& y) {
    ff::OnlineSettling s(w);
    for (std::size_t k = 0; k < t.size(); ++k) s.add(t[k], y[k]);
    return s.result();
  };
  EXPECT_TRUE(std::isnan(online({0.0, 0.5, 0.9, 1.0, 1.5})));  // out at the last sample: not settled
  EXPECT_EQ(online({1.0, 1.0, 1.0, 1.0, 1.0}), 0.0);           // never out of the band
  EXPECT_EQ(online({0.0, 0.97, 1.0, 1.0, 1.0}), 0.0);          // enters before t_move_end: clamped to 0
  const std::vector<double> late = {0.0, 0.5, 0.9, 1.0, 1.0};  // enters between t = 2 and 3
  expect_same_bits(ff::calc_settling_time(t, late, w), online(late), "settling");
  EXPECT_NEAR(online(late), 2.0 + 0.08 / 0.1 - 1.5, 1e-12);
}

TEST(OnlineMetrics, ZeroAmplitudeThrowsAsTheStoredForm) {
  const MoveWindow w{1.0, 2.0, 0.5, 0.5};
  EXPECT_THROW(ff::OnlineSettling{w}, std::invalid_argument);
  EXPECT_THROW((ff::OnlineOvershoot{0.0, w}), std::invalid_argument);
}

}  // namespace
