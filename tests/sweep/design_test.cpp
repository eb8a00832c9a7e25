// Tests of the experimental designs (sweep/design.hpp): the row layouts of every design kind, the
// distributions' quantiles, the Sobol' sequence against the Joe & Kuo reference, the scrambled nets'
// balance and integration accuracy, determinism, and the validation errors.
#include "sweep/design.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/random.hpp"

namespace {

using Matrix = std::vector<std::vector<double>>;
constexpr double kInf = std::numeric_limits<double>::infinity();

ff::Distribution uniform(double lo, double hi) {
  ff::Distribution d;
  d.kind = ff::DistributionKind::kUniform;
  d.lower = lo;
  d.upper = hi;
  return d;
}

ff::Distribution normal(double mean, double std) {
  ff::Distribution d;
  d.kind = ff::DistributionKind::kNormal;
  d.mean = mean;
  d.std = std;
  return d;
}

ff::Distribution truncated(double mean, double std, double lo, double hi) {
  ff::Distribution d;
  d.kind = ff::DistributionKind::kTruncatedNormal;
  d.mean = mean;
  d.std = std;
  d.lower = lo;
  d.upper = hi;
  return d;
}

ff::Distribution lognormal(double mu, double sigma) {
  ff::Distribution d;
  d.kind = ff::DistributionKind::kLognormal;
  d.mu = mu;
  d.sigma = sigma;
  return d;
}

ff::Distribution choice(std::vector<double> values, std::vector<double> weights = {}) {
  ff::Distribution d;
  d.kind = ff::DistributionKind::kChoice;
  d.values = std::move(values);
  d.weights = std::move(weights);
  return d;
}

ff::Variable var(const std::string& path, ff::Distribution dist) {
  ff::Variable v;
  v.path = path;
  v.dist = std::move(dist);
  return v;
}

ff::Variable levels_var(const std::string& path, std::vector<double> levels, double nominal = 0) {
  ff::Variable v;
  v.path = path;
  v.levels = std::move(levels);
  v.nominal = nominal;
  return v;
}

ff::DesignSpec spec(ff::DesignKind kind, int samples, std::uint64_t seed = 11) {
  ff::DesignSpec s;
  s.kind = kind;
  s.samples = samples;
  s.seed = seed;
  return s;
}

// Whether two matrices hold the same bits.
bool same_bits(const Matrix& a, const Matrix& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].size() != b[i].size()) return false;
    for (std::size_t j = 0; j < a[i].size(); ++j)
      if (std::bit_cast<std::uint64_t>(a[i][j]) != std::bit_cast<std::uint64_t>(b[i][j])) return false;
  }
  return true;
}

// `f` must throw std::invalid_argument whose message contains every one of `parts`.
void expect_invalid(const std::function<void()>& f, const std::vector<std::string>& parts) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    for (const std::string& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
    return;
  }
  ADD_FAILURE() << "no std::invalid_argument (expected one mentioning '" << parts.front() << "')";
}

// ---- grid and centered -----------------------------------------------------------------------------

TEST(Design, GridIsFullFactorialWithLastVariableFastest) {
  const std::vector<ff::Variable> vars = {levels_var("a", {1, 2}), levels_var("b", {10, 20, 30}),
                                          levels_var("c", {-1, 1})};
  const Matrix m = ff::make_design(spec(ff::DesignKind::kGrid, 0), vars);
  ASSERT_EQ(m.size(), 12u);
  EXPECT_EQ(ff::calc_design_size(spec(ff::DesignKind::kGrid, 0), vars), 12);
  const Matrix expected = {{1, 10, -1}, {1, 10, 1}, {1, 20, -1}, {1, 20, 1}, {1, 30, -1}, {1, 30, 1},
                           {2, 10, -1}, {2, 10, 1}, {2, 20, -1}, {2, 20, 1}, {2, 30, -1}, {2, 30, 1}};
  EXPECT_EQ(m, expected);
  // One variable: its levels in order.
  EXPECT_EQ(ff::make_design(spec(ff::DesignKind::kGrid, 0), {levels_var("x", {3, 1, 2})}),
            (Matrix{{3}, {1}, {2}}));
}

TEST(Design, CenteredVisitsEachLevelOnce) {
  const std::vector<ff::Variable> vars = {levels_var("a", {0, 1, 2}, 1),        // 1 is the nominal
                                          levels_var("b", {4, 6, 4, 5}, 5),     // repeat of 4, nominal 5
                                          levels_var("c", {}, 7)};              // no levels: only nominal
  const Matrix m = ff::make_design(spec(ff::DesignKind::kCentered, 0), vars);
  const Matrix expected = {{1, 5, 7}, {0, 5, 7}, {2, 5, 7}, {1, 4, 7}, {1, 6, 7}};
  EXPECT_EQ(m, expected);
  EXPECT_EQ(ff::calc_design_size(spec(ff::DesignKind::kCentered, 0), vars), 5);
}

// ---- Monte Carlo and Latin hypercube ---------------------------------------------------------------

// Row i draws from CounterRng(calc_variant_seed(seed, i)) in variable order, whatever the sample count.
TEST(Design, MonteCarloRowsDoNotDependOnSampleCount) {
  const std::vector<ff::Variable> vars = {var("m", normal(328.7, 5.0)), var("k", uniform(1, 2)),
                                          var("c", lognormal(0.1, 0.3)), var("n", choice({1, 2, 4}))};
  const Matrix small = ff::make_design(spec(ff::DesignKind::kMonteCarlo, 10, 5), vars);
  const Matrix large = ff::make_design(spec(ff::DesignKind::kMonteCarlo, 100, 5), vars);
  ASSERT_EQ(small.size(), 10u);
  ASSERT_EQ(large.size(), 100u);
  EXPECT_TRUE(same_bits(small, Matrix(large.begin(), large.begin() + 10)));
  for (int i : {0, 3, 57, 99}) {
    ff::CounterRng rng(ff::calc_variant_seed(5, static_cast<std::uint64_t>(i)));
    for (std::size_t j = 0; j < vars.size(); ++j)
      EXPECT_EQ(large[static_cast<std::size_t>(i)][j], ff::calc_quantile(vars[j].dist, rng.uniform()));
  }
  // Another seed, other values.
  const Matrix other = ff::make_design(spec(ff::DesignKind::kMonteCarlo, 10, 6), vars);
  EXPECT_NE(other[0][0], small[0][0]);
}

TEST(Design, LatinHypercubeHasOnePointPerStratum) {
  for (int n : {1, 2, 7, 50, 1000}) {
    const Matrix x = ff::make_latin_hypercube(n, 4, 77);
    ASSERT_EQ(x.size(), static_cast<std::size_t>(n));
    for (int j = 0; j < 4; ++j) {
      std::vector<int> strata;
      for (const auto& row : x) {
        ASSERT_GT(row[static_cast<std::size_t>(j)], 0.0);
        ASSERT_LT(row[static_cast<std::size_t>(j)], 1.0);
        strata.push_back(static_cast<int>(std::floor(row[static_cast<std::size_t>(j)] * n)));
      }
      std::sort(strata.begin(), strata.end());
      std::vector<int> all(static_cast<std::size_t>(n));
      std::iota(all.begin(), all.end(), 0);
      EXPECT_EQ(strata, all) << "n = " << n << ", column " << j;
    }
  }
  // Through a normal quantile: the CDF values of the design's points are again one per stratum.
  const int n = 200;
  const Matrix m = ff::make_design(spec(ff::DesignKind::kLatinHypercube, n, 3), {var("x", normal(10, 2))});
  std::set<int> strata;
  for (const auto& row : m) strata.insert(static_cast<int>(std::floor(ff::calc_normal_cdf((row[0] - 10) / 2) * n)));
  EXPECT_EQ(strata.size(), static_cast<std::size_t>(n));
  // The design is the mapped unit hypercube.
  const Matrix u = ff::make_latin_hypercube(n, 1, 3);
  for (int i = 0; i < n; ++i)
    EXPECT_EQ(m[static_cast<std::size_t>(i)][0], ff::calc_quantile(normal(10, 2), u[static_cast<std::size_t>(i)][0]));
}

// ---- Sobol' ----------------------------------------------------------------------------------------

// First 8 points of dimensions 1..3 of the unscrambled sequence, Gray-code order, as printed by Joe &
// Kuo's sobol.cc with new-joe-kuo-6.21201 (https://web.maths.unsw.edu.au/~fkuo/sobol/).
TEST(Design, SobolMatchesUnscrambledReference) {
  const Matrix expected = {{0, 0, 0},           {0.5, 0.5, 0.5},       {0.75, 0.25, 0.25},
                           {0.25, 0.75, 0.75},  {0.375, 0.375, 0.625}, {0.875, 0.875, 0.125},
                           {0.625, 0.125, 0.875}, {0.125, 0.625, 0.375}};
  EXPECT_EQ(ff::make_sobol_points_unscrambled(8, 3), expected);
  // Every one of the 100 embedded dimensions is a (0, m, 1)-net: the first 2^m points of a column hit
  // each of the 2^m cells k / 2^m exactly once (the property the initial m_k odd and < 2^k guarantee).
  const int m = 12, n = 1 << m;
  const Matrix x = ff::make_sobol_points_unscrambled(n, ff::kSobolMaxDimension);
  for (int j = 0; j < ff::kSobolMaxDimension; ++j) {
    std::vector<int> seen(static_cast<std::size_t>(n), 0);
    for (const auto& row : x) ++seen[static_cast<std::size_t>(row[static_cast<std::size_t>(j)] * n)];
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), n) << "dimension " << j + 1;
  }
  // Dimensions 1 and 2 form a (0, m, 2)-net: every 2^-k x 2^-(m-k) box holds one point.
  for (int k = 0; k <= m; ++k) {
    std::vector<int> box(static_cast<std::size_t>(n), 0);
    for (const auto& row : x) {
      const int bx = static_cast<int>(row[0] * (1 << k)), by = static_cast<int>(row[1] * (1 << (m - k)));
      ++box[static_cast<std::size_t>((bx << (m - k)) | by)];
    }
    EXPECT_EQ(std::count(box.begin(), box.end(), 1), n) << "k = " << k;
  }
}

// n = 2^m scrambled points: each column puts exactly one point in every interval [k 2^-m, (k+1) 2^-m);
// dimensions 1-2 stay a (0, m, 2)-net; the mean of a smooth 5-dimensional integrand is off by < 1e-4 in
// RMS at n = 4096 (plain Monte Carlo's standard error there is about 1.1e-2) and converges faster than
// n^-1.
TEST(Design, ScrambledSobolIsBalanced) {
  const int m = 12, n = 1 << m, d = 10;
  for (std::uint64_t seed : {0ull, 1ull, 12345ull}) {
    const Matrix x = ff::make_sobol_points(n, d, seed);
    ASSERT_EQ(x.size(), static_cast<std::size_t>(n));
    for (int j = 0; j < d; ++j) {
      std::vector<int> seen(static_cast<std::size_t>(n), 0);
      for (const auto& row : x) {
        const double v = row[static_cast<std::size_t>(j)];
        ASSERT_GT(v, 0.0);
        ASSERT_LT(v, 1.0);
        ++seen[static_cast<std::size_t>(v * n)];
      }
      EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), n) << "seed " << seed << ", dimension " << j + 1;
    }
    for (int k = 0; k <= m; ++k) {
      std::vector<int> box(static_cast<std::size_t>(n), 0);
      for (const auto& row : x) {
        const int bx = static_cast<int>(row[0] * (1 << k)), by = static_cast<int>(row[1] * (1 << (m - k)));
        ++box[static_cast<std::size_t>((bx << (m - k)) | by)];
      }
      EXPECT_EQ(std::count(box.begin(), box.end(), 1), n) << "seed " << seed << ", k = " << k;
    }
  }
  // Integral of prod_j (1 + (x_j - 1/2)) over [0,1]^5 is 1. Root-mean-square error over 16 scrambles:
  // below 1e-4 at n = 4096, and 16x more points cut it by more than 16 (plain MC: by 4).
  const auto rmse = [](int points) {
    double s2 = 0;
    for (std::uint64_t seed = 0; seed < 16; ++seed) {
      double mean = 0;
      for (const auto& row : ff::make_sobol_points(points, 5, seed)) {
        double f = 1;
        for (double v : row) f *= 1.0 + (v - 0.5);
        mean += f;
      }
      mean /= points;
      s2 += (mean - 1.0) * (mean - 1.0);
    }
    return std::sqrt(s2 / 16);
  };
  const double e4096 = rmse(4096), e256 = rmse(256);
  EXPECT_LT(e4096, 1e-4);
  EXPECT_GT(e256 / e4096, 16.0);
  // Scrambling changes the points, and different seeds give different points.
  const Matrix a = ff::make_sobol_points(8, 2, 1), b = ff::make_sobol_points(8, 2, 2);
  EXPECT_NE(a[0][0], b[0][0]);
  EXPECT_NE(a[0][0], 0.0);
  // The sobol design is the mapped point set.
  const Matrix s = ff::make_design(spec(ff::DesignKind::kSobol, 16, 4), {var("x", uniform(0, 1)), var("y", uniform(0, 1))});
  EXPECT_TRUE(same_bits(s, ff::make_sobol_points(16, 2, 4)));
}

// ---- distributions ---------------------------------------------------------------------------------

TEST(Design, UniformAndNormalQuantiles) {
  EXPECT_EQ(ff::calc_quantile(uniform(2, 6), 0.0), 2.0);
  EXPECT_EQ(ff::calc_quantile(uniform(2, 6), 1.0), 6.0);
  EXPECT_EQ(ff::calc_quantile(uniform(2, 6), 0.25), 3.0);
  EXPECT_NEAR(ff::calc_quantile(normal(10, 2), 0.975), 10 + 2 * 1.959963984540054, 1e-14);
  EXPECT_EQ(ff::calc_quantile(normal(10, 2), 0.5), 10.0);
  EXPECT_EQ(ff::calc_quantile(normal(10, 2), 0.0), -kInf);
  expect_invalid([] { ff::calc_quantile(uniform(0, 1), 1.5); }, {"u must be in [0, 1]"});
  expect_invalid([] { ff::calc_quantile(uniform(0, 1), std::nan("")); }, {"u must be in [0, 1]"});
}

TEST(Design, TruncatedNormalStaysInBounds) {
  struct Case {
    double mean, std, lo, hi;
  };
  const Case cases[] = {{0, 1, -1, 2}, {10, 2, 15, 30}, {0, 1, 8, 9}, {0, 1, -kInf, -3},
                        {5, 1, 5, kInf}, {0, 1, -38, -37}, {0, 1, 30, 31}, {1, 1e-3, 0.999, 1.0005}};
  for (const Case& c : cases) {
    const ff::Distribution d = truncated(c.mean, c.std, c.lo, c.hi);
    ASSERT_NO_THROW(ff::validate_distribution(d)) << c.lo << " " << c.hi;
    EXPECT_EQ(ff::calc_quantile(d, 0.0), c.lo);
    EXPECT_EQ(ff::calc_quantile(d, 1.0), c.hi);
    const Matrix m = ff::make_design(spec(ff::DesignKind::kMonteCarlo, 20000, 9), {var("x", d)});
    double sum = 0;
    for (const auto& row : m) {
      ASSERT_GE(row[0], c.lo);
      ASSERT_LE(row[0], c.hi);
      sum += row[0];
    }
    // Sample mean against mean + std (phi(a) - phi(b)) / Z for the finite, well-conditioned cases.
    if (std::isfinite(c.lo) && std::isfinite(c.hi) && c.lo > -20 && c.hi < 20) {
      const double a = (c.lo - c.mean) / c.std, b = (c.hi - c.mean) / c.std;
      const auto phi = [](double z) { return std::exp(-0.5 * z * z) / std::sqrt(2 * M_PI); };
      const double z = a >= 0 ? ff::calc_normal_cdf(-a) - ff::calc_normal_cdf(-b)
                              : ff::calc_normal_cdf(b) - ff::calc_normal_cdf(a);
      const double expected = c.mean + c.std * (phi(a) - phi(b)) / z;
      EXPECT_NEAR(sum / 20000, expected, 5 * (c.hi - c.lo) / 2 / std::sqrt(20000.0)) << c.lo << " " << c.hi;
    }
  }
  // Probability below 0 for N(0,1) on [-1, 2]: (Phi(0) - Phi(-1)) / (Phi(2) - Phi(-1)) = 0.40216...
  const ff::Distribution d = truncated(0, 1, -1, 2);
  const double p = (0.5 - ff::calc_normal_cdf(-1)) / (ff::calc_normal_cdf(2) - ff::calc_normal_cdf(-1));
  EXPECT_NEAR(ff::calc_quantile(d, p), 0.0, 1e-14);
  // Symmetric truncation: median at the mean.
  EXPECT_NEAR(ff::calc_quantile(truncated(3, 2, 1, 5), 0.5), 3.0, 1e-14);
}

TEST(Design, LognormalMedianIsExpMu) {
  const ff::Distribution d = lognormal(0.7, 0.4);
  EXPECT_EQ(ff::calc_quantile(d, 0.5), std::exp(0.7));
  EXPECT_EQ(ff::calc_quantile(d, 0.0), 0.0);
  EXPECT_NEAR(ff::calc_quantile(d, 0.975), std::exp(0.7 + 0.4 * 1.959963984540054), 1e-14);
  // Sample median of 10001 draws within 5 standard errors (1.2533 sigma e^mu / sqrt(n)).
  const int n = 10001;
  Matrix m = ff::make_design(spec(ff::DesignKind::kMonteCarlo, n, 21), {var("x", d)});
  std::vector<double> x;
  for (const auto& row : m) {
    ASSERT_GT(row[0], 0.0);
    x.push_back(row[0]);
  }
  std::nth_element(x.begin(), x.begin() + n / 2, x.end());
  EXPECT_NEAR(x[n / 2], std::exp(0.7), 5 * 1.2533 * 0.4 * std::exp(0.7) / std::sqrt(n));
}

TEST(Design, ChoiceFollowsWeights) {
  const ff::Distribution d = choice({1, 2, 3}, {1, 0, 3});
  // Exact on an even grid of u: a quarter 1, three quarters 3, never the zero-weight 2.
  int count[4] = {0, 0, 0, 0};
  for (int k = 0; k < 1000; ++k) ++count[static_cast<int>(ff::calc_quantile(d, (k + 0.5) / 1000))];
  EXPECT_EQ(count[1], 250);
  EXPECT_EQ(count[2], 0);
  EXPECT_EQ(count[3], 750);
  EXPECT_EQ(ff::calc_quantile(d, 0.0), 1.0);
  EXPECT_EQ(ff::calc_quantile(d, 1.0), 3.0);
  EXPECT_EQ(ff::calc_quantile(choice({5, 6}, {1, 0}), 1.0), 5.0);  // last value of positive weight
  // Monte Carlo: frequencies within 5 standard errors.
  const int n = 100000;
  const Matrix m = ff::make_design(spec(ff::DesignKind::kMonteCarlo, n, 8), {var("x", d)});
  int ones = 0;
  for (const auto& row : m) {
    ASSERT_TRUE(row[0] == 1.0 || row[0] == 3.0);
    ones += row[0] == 1.0;
  }
  EXPECT_NEAR(static_cast<double>(ones) / n, 0.25, 5 * std::sqrt(0.25 * 0.75 / n));
  // Empty weights: equal probabilities.
  const ff::Distribution eq = choice({10, 20, 30, 40});
  EXPECT_EQ(ff::calc_quantile(eq, 0.1), 10.0);
  EXPECT_EQ(ff::calc_quantile(eq, 0.3), 20.0);
  EXPECT_EQ(ff::calc_quantile(eq, 0.6), 30.0);
  EXPECT_EQ(ff::calc_quantile(eq, 0.9), 40.0);
}

// ---- Saltelli and Morris ---------------------------------------------------------------------------

TEST(Design, SaltelliLayoutMixesColumns) {
  const int N = 16, d = 3;
  const std::vector<ff::Variable> vars = {var("a", uniform(0, 1)), var("b", uniform(0, 1)),
                                          var("c", uniform(0, 1))};
  const Matrix m = ff::make_design(spec(ff::DesignKind::kSaltelli, N, 31), vars);
  ASSERT_EQ(m.size(), static_cast<std::size_t>(N * (d + 2)));
  EXPECT_EQ(ff::calc_design_size(spec(ff::DesignKind::kSaltelli, N, 31), vars), N * (d + 2));
  // A and B: the two halves of one 2d-dimensional scrambled Sobol' set.
  const Matrix ab = ff::make_sobol_points(N, 2 * d, 31);
  for (int k = 0; k < N; ++k)
    for (int j = 0; j < d; ++j) {
      EXPECT_EQ(m[k][j], ab[k][j]);
      EXPECT_EQ(m[N + k][j], ab[k][d + j]);
    }
  // Row N(2+i)+k equals row k of A except column i, which equals row k of B.
  for (int i = 0; i < d; ++i)
    for (int k = 0; k < N; ++k)
      for (int j = 0; j < d; ++j)
        EXPECT_EQ(m[N * (2 + i) + k][j], j == i ? m[N + k][j] : m[k][j]) << "i " << i << " k " << k << " j " << j;
  // Mapped by each variable's quantile, layout unchanged.
  const std::vector<ff::Variable> mixed = {var("a", normal(1, 2)), var("b", uniform(-1, 1)),
                                           var("c", lognormal(0, 1))};
  const Matrix q = ff::make_design(spec(ff::DesignKind::kSaltelli, N, 31), mixed);
  for (std::size_t r = 0; r < q.size(); ++r)
    for (int j = 0; j < d; ++j) EXPECT_EQ(q[r][j], ff::calc_quantile(mixed[j].dist, m[r][j]));
}

TEST(Design, MorrisStepsChangeOneVariableByDelta) {
  const int r = 20, d = 4;
  for (int p : {2, 4, 6}) {
    const double delta = ff::calc_morris_delta(p);
    EXPECT_DOUBLE_EQ(delta, p / (2.0 * (p - 1)));
    const Matrix x = ff::make_morris_points(r, d, p, 5);
    ASSERT_EQ(x.size(), static_cast<std::size_t>(r * (d + 1)));
    for (int t = 0; t < r; ++t) {
      std::vector<int> changed(d, 0);
      for (int k = 0; k <= d; ++k) {
        const auto& row = x[static_cast<std::size_t>(t * (d + 1) + k)];
        for (double u : row) {
          ASSERT_GE(u, 0.0);
          ASSERT_LE(u, 1.0);
          EXPECT_NEAR(u * (p - 1), std::round(u * (p - 1)), 1e-12) << "off the grid";
        }
        if (k == 0) continue;
        const auto& prev = x[static_cast<std::size_t>(t * (d + 1) + k - 1)];
        int moved = 0;
        for (int j = 0; j < d; ++j) {
          if (row[j] == prev[j]) continue;
          ++moved;
          ++changed[j];
          EXPECT_NEAR(std::fabs(row[j] - prev[j]), delta, 1e-12);
        }
        EXPECT_EQ(moved, 1) << "trajectory " << t << ", step " << k;
      }
      EXPECT_EQ(changed, std::vector<int>(d, 1)) << "every variable moves once per trajectory";
    }
    // Trajectories do not depend on r.
    const Matrix few = ff::make_morris_points(3, d, p, 5);
    EXPECT_TRUE(same_bits(few, Matrix(x.begin(), x.begin() + 3 * (d + 1))));
  }
  // Mapped: uniform on [2, 6] hits its bounds exactly and steps by 4 Delta; a normal variable is
  // clipped at 1e-12 so its ends stay finite.
  ff::DesignSpec s = spec(ff::DesignKind::kMorris, 0, 5);
  s.trajectories = 30;
  s.morris_levels = 4;
  const Matrix m = ff::make_design(s, {var("u", uniform(2, 6)), var("z", normal(0, 1))});
  ASSERT_EQ(m.size(), 90u);
  std::set<double> u_values, z_values;
  for (const auto& row : m) {
    u_values.insert(row[0]);
    z_values.insert(row[1]);
  }
  EXPECT_EQ(u_values.count(2.0), 1u);
  EXPECT_EQ(u_values.count(6.0), 1u);
  EXPECT_EQ(u_values.size(), 4u);
  for (double z : z_values) EXPECT_TRUE(std::isfinite(z));
  EXPECT_NEAR(*z_values.begin(), ff::calc_normal_quantile(1e-12), 1e-12);
  const Matrix unit = ff::make_morris_points(30, 2, 4, 5);
  for (std::size_t i = 1; i < m.size(); ++i) {
    if (i % 3 != 0 && m[i][0] != m[i - 1][0]) {
      EXPECT_NEAR(std::fabs(m[i][0] - m[i - 1][0]), 4 * ff::calc_morris_delta(4), 1e-12);
    }
  }
  for (std::size_t i = 0; i < m.size(); ++i) EXPECT_EQ(m[i][0], ff::calc_quantile(uniform(2, 6), unit[i][0]));
}

// ---- determinism -----------------------------------------------------------------------------------

TEST(Design, DesignsAreDeterministic) {
  const std::vector<ff::Variable> vars = {var("a", normal(1, 2)), var("b", truncated(0, 1, -1, 1)),
                                          var("c", choice({1, 2, 3}, {1, 1, 2}))};
  for (ff::DesignKind k : {ff::DesignKind::kMonteCarlo, ff::DesignKind::kLatinHypercube, ff::DesignKind::kSobol,
                           ff::DesignKind::kSaltelli, ff::DesignKind::kMorris}) {
    ff::DesignSpec s = spec(k, 64, 1234);
    s.trajectories = 10;
    const Matrix a = ff::make_design(s, vars), b = ff::make_design(s, vars);
    EXPECT_TRUE(same_bits(a, b)) << static_cast<int>(k);
    EXPECT_EQ(a.size(), static_cast<std::size_t>(ff::calc_design_size(s, vars)));
    s.seed = 1235;
    EXPECT_FALSE(same_bits(a, ff::make_design(s, vars))) << static_cast<int>(k);
  }
}

// Pinned bits: a change here changes the designs of every study, so it must be deliberate. Values
// produced by this implementation.
TEST(Design, DesignsArePinned) {
  const std::vector<ff::Variable> vars = {var("a", normal(1, 2)), var("b", uniform(0, 1))};
  const auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  ff::DesignSpec s = spec(ff::DesignKind::kMonteCarlo, 4, 2024);
  EXPECT_EQ(bits(ff::make_design(s, vars)[3][0]), 0x4004e0ef3c29044full);  // 2.609831304551825
  s.kind = ff::DesignKind::kLatinHypercube;
  EXPECT_EQ(bits(ff::make_design(s, vars)[3][1]), 0x3fe0470edd66ac02ull);  // 0.5086740802993293
  s.kind = ff::DesignKind::kSobol;
  EXPECT_EQ(bits(ff::make_design(s, vars)[3][1]), 0x3fef7de32225c64bull);  // 0.9841170947021934
  s.kind = ff::DesignKind::kMorris;
  s.trajectories = 2;
  EXPECT_EQ(bits(ff::make_design(s, vars)[4][0]), 0xc02a234fba57a32aull);  // 1 + 2 Phi^-1(1e-12)
}

// ---- validation ------------------------------------------------------------------------------------

TEST(Design, RejectsBadSpecs) {
  const std::vector<ff::Variable> one = {var("payload.mass", normal(328.7, 5))};
  expect_invalid([] { ff::make_design(spec(ff::DesignKind::kMonteCarlo, 10), {}); }, {"no variables"});
  expect_invalid([&] { ff::make_design(spec(ff::DesignKind::kMonteCarlo, 0), one); }, {"monte_carlo", "samples must be >= 1"});
  expect_invalid([&] { ff::make_design(spec(ff::DesignKind::kLatinHypercube, -3), one); }, {"lhs", "samples must be >= 1"});
  expect_invalid([&] { ff::make_design(spec(ff::DesignKind::kSobol, 0), one); }, {"sobol", "samples"});
  expect_invalid([&] { ff::make_design(spec(ff::DesignKind::kSaltelli, 0), one); }, {"saltelli", "samples"});
  expect_invalid([] { ff::make_design(spec(ff::DesignKind::kGrid, 0), {levels_var("payload.mass", {})}); },
                 {"payload.mass", "at least one level"});
  expect_invalid([] { ff::make_design(spec(ff::DesignKind::kGrid, 0), {levels_var("x", {1, std::nan("")})}); },
                 {"'x'", "not finite"});
  // Morris: p odd or < 2, no trajectories.
  ff::DesignSpec m = spec(ff::DesignKind::kMorris, 0);
  m.trajectories = 5;
  for (int p : {3, 0, 1, -2}) {
    m.morris_levels = p;
    expect_invalid([&] { ff::make_design(m, one); }, {"morris_levels p must be even and >= 2"});
  }
  m.morris_levels = 4;
  m.trajectories = 0;
  expect_invalid([&] { ff::make_design(m, one); }, {"trajectories must be >= 1"});
  // Too many Sobol' dimensions.
  std::vector<ff::Variable> many;
  for (int i = 0; i < 51; ++i) many.push_back(var(std::string("v").append(std::to_string(i)), uniform(0, 1)));
  expect_invalid([&] { ff::make_design(spec(ff::DesignKind::kSaltelli, 8), many); }, {"at most 50 variables"});
  EXPECT_NO_THROW(ff::make_design(spec(ff::DesignKind::kSobol, 8), many));
  expect_invalid([] { ff::make_sobol_points(8, 101, 0); }, {"101 Sobol' dimensions"});
  // More rows than an int eval_id can address.
  std::vector<ff::Variable> huge;
  for (int i = 0; i < 4; ++i)
    huge.push_back(levels_var(std::string("g").append(std::to_string(i)), std::vector<double>(300, 1.0)));
  expect_invalid([&] { ff::make_design(spec(ff::DesignKind::kGrid, 0), huge); }, {"exceed"});
}

TEST(Design, RejectsBadDistributions) {
  const auto bad = [](ff::Distribution d, std::vector<std::string> parts) {
    expect_invalid([&] { ff::validate_distribution(d); }, parts);
    // Through a design the message names the variable.
    parts.push_back("'payload.mass'");
    expect_invalid([&] { ff::make_design(spec(ff::DesignKind::kMonteCarlo, 4), {var("payload.mass", d)}); }, parts);
  };
  bad(uniform(2, 1), {"uniform", "lower < upper", "lower = 2", "upper = 1"});
  bad(uniform(1, 1), {"lower < upper"});
  bad(uniform(0, kInf), {"finite bounds"});
  bad(normal(0, 0), {"normal", "std > 0"});
  bad(normal(0, -1), {"std > 0"});
  bad(truncated(0, 0, -1, 1), {"truncated_normal", "std > 0"});
  bad(truncated(0, 1, 1, -1), {"truncated_normal", "lower < upper"});
  bad(truncated(0, 1, 40, 50), {"no probability mass"});
  bad(truncated(0, 1, -50, -40), {"no probability mass"});
  bad(lognormal(0, 0), {"lognormal", "sigma > 0"});
  bad(choice({}), {"choice", "at least one value"});
  bad(choice({1, 2}, {1, -1}), {"weights must be finite and >= 0"});
  bad(choice({1, 2}, {0, 0}), {"must not all be zero"});
  bad(choice({1, 2}, {1}), {"1 weights for 2 values"});
  EXPECT_NO_THROW(ff::validate_distribution(choice({1, 2}, {0, 2})));
  EXPECT_NO_THROW(ff::validate_distribution(truncated(0, 1, -kInf, kInf)));
  // Grid and centered designs do not look at the distribution.
  EXPECT_NO_THROW(ff::make_design(spec(ff::DesignKind::kGrid, 0), {levels_var("x", {1})}));
}

}  // namespace
