// Tests of kernel/fastmath: calc_atan2 against std::atan2 over all quadrants, the axes, signed zeros
// and magnitudes from 1e-300 to 1e300.
#include "kernel/fastmath.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "tests/results/test_rng.hpp"

namespace {

using ff::test::TestRng;

// |a − b| in units in the last place of b (b != 0).
double ulps(double a, double b) {
  const double ulp = std::nextafter(std::abs(b), std::numeric_limits<double>::infinity()) - std::abs(b);
  return std::abs(a - b) / ulp;
}

TEST(Fastmath, Atan2IsWithinTwoUlpOfStdAtan2) {
  TestRng rng{2024};
  double worst = 0.0;
  for (int i = 0; i < 2'000'000; ++i) {
    // Signs at random; magnitudes over six decades, or (one point in four) over 1e-300 .. 1e300.
    const auto draw = [&] {
      const double decades = rng.uniform() < 0.25 ? 600.0 * rng.uniform() - 300.0 : 6.0 * rng.uniform() - 3.0;
      return (rng.uniform() < 0.5 ? -1.0 : 1.0) * (0.5 + rng.uniform()) * std::pow(10.0, decades);
    };
    const double y = draw(), x = draw();
    const double a = ff::calc_atan2(y, x), b = std::atan2(y, x);
    ASSERT_TRUE(ulps(a, b) <= 2.0 || std::abs(a - b) <= 1e-15) << "atan2(" << y << ", " << x << ")";
    worst = std::max(worst, ulps(a, b));
  }
  EXPECT_LE(worst, 2.0);
}

TEST(Fastmath, Atan2NearTheOctantEdgesIsWithinTwoUlp) {
  // |y| close to |x|, to 0.66 |x| (the reduction's switch) and to 0: each sign pair.
  TestRng rng{7};
  for (double ratio : {1.0, 0.66, 1.0 / 0.66, 1e-8, 1e8}) {
    for (int i = 0; i < 20000; ++i) {
      const double x = (0.5 + rng.uniform()) * (i % 2 ? -1.0 : 1.0);
      const double y = x * ratio * (1.0 + 1e-6 * (2.0 * rng.uniform() - 1.0)) * (i % 4 < 2 ? -1.0 : 1.0);
      const double a = ff::calc_atan2(y, x), b = std::atan2(y, x);
      EXPECT_TRUE(ulps(a, b) <= 2.0 || std::abs(a - b) <= 1e-15) << "atan2(" << y << ", " << x << ")";
    }
  }
}

TEST(Fastmath, Atan2OnTheAxesAndSignedZerosIsStdAtan2) {
  // Exactly equal: 0, ±pi/2, ±pi with the signs std::atan2 gives.
  for (double y : {0.0, -0.0, 1.0, -1.0, 1e-310, -3e200})
    for (double x : {0.0, -0.0, 2.0, -2.0, 1e-310, -5e250}) {
      if (y != 0.0 && x != 0.0) continue;
      const double a = ff::calc_atan2(y, x), b = std::atan2(y, x);
      EXPECT_EQ(a, b) << "atan2(" << y << ", " << x << ")";
      EXPECT_EQ(std::signbit(a), std::signbit(b)) << "atan2(" << y << ", " << x << ")";
    }
}

// A lane loop the compiler vectorises gives the scalar bits.
[[gnu::noinline]] double scalar_atan2(double y, double x) { return ff::calc_atan2(y, x); }

TEST(Fastmath, Atan2InALaneLoopGivesTheScalarBits) {
  TestRng rng{99};
  std::vector<double> y(1024), x(1024), out(1024);
  for (std::size_t i = 0; i < y.size(); ++i) {
    y[i] = 4.0 * rng.uniform() - 2.0;
    x[i] = 4.0 * rng.uniform() - 2.0;
  }
#pragma omp simd
  for (std::size_t i = 0; i < y.size(); ++i) out[i] = ff::calc_atan2(y[i], x[i]);
  for (std::size_t i = 0; i < y.size(); ++i) EXPECT_EQ(out[i], scalar_atan2(y[i], x[i]));
}

}  // namespace
