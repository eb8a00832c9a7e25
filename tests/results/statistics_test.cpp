// results/statistics.cpp: percentiles, summaries, bootstrap intervals, Wilson intervals, group-by and its bins.
#include "results/statistics.hpp"

#include <gtest/gtest.h>

#include "tests/results/test_rng.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace ff {
namespace {

const double kNaN = std::nan("");

using TestRng = ff::test::TestRng;

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(Statistics, PercentileMatchesNumpyType7) {
  // Values from numpy.percentile (method="linear", the default).
  EXPECT_DOUBLE_EQ(calc_percentile({1, 2, 3, 4}, 25), 1.75);
  EXPECT_DOUBLE_EQ(calc_percentile({1, 2, 3, 4}, 50), 2.5);
  EXPECT_DOUBLE_EQ(calc_percentile({4, 3, 2, 1}, 75), 3.25);
  EXPECT_DOUBLE_EQ(calc_percentile({1, 2, 3, 4, 5, 6, 7, 8, 9, 10}, 95), 9.55);
  EXPECT_DOUBLE_EQ(calc_percentile({1, 2, 3, 4, 5, 6, 7, 8, 9, 10}, 5), 1.45);
  EXPECT_DOUBLE_EQ(calc_percentile({3, 1, 4, 1, 5, 9, 2, 6}, 90), 6.9);
  EXPECT_DOUBLE_EQ(calc_percentile({3, 1, 4, 1, 5, 9, 2, 6}, 33), 2.31);
  EXPECT_DOUBLE_EQ(calc_percentile({3, 1, 4, 1, 5, 9, 2, 6}, 0), 1.0);
  EXPECT_DOUBLE_EQ(calc_percentile({3, 1, 4, 1, 5, 9, 2, 6}, 100), 9.0);
  EXPECT_DOUBLE_EQ(calc_percentile({7}, 37), 7.0);
  // NaNs are ignored; nothing left gives NaN; p outside [0, 100] is an error.
  EXPECT_DOUBLE_EQ(calc_percentile({kNaN, 1, 2, kNaN, 3, 4}, 25), 1.75);
  EXPECT_TRUE(std::isnan(calc_percentile({kNaN, kNaN}, 50)));
  EXPECT_TRUE(std::isnan(calc_percentile({}, 50)));
  EXPECT_THROW(calc_percentile({1, 2}, 100.5), std::invalid_argument);
  EXPECT_THROW(calc_percentile({1, 2}, kNaN), std::invalid_argument);
  // Infinite values interpolate without producing NaN.
  const double inf = INFINITY;
  EXPECT_EQ(calc_percentile({1, inf, inf}, 75), inf);
}

TEST(Statistics, SummaryIgnoresNan) {
  const Summary s = calc_summary({kNaN, 2, 4, kNaN, 4, 4, 5, 5, 7, 9, kNaN});
  EXPECT_EQ(s.count, 8);
  EXPECT_EQ(s.missing, 3);
  EXPECT_DOUBLE_EQ(s.mean, 5.0);
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(32.0 / 7.0));  // sample standard deviation (numpy ddof=1)
  EXPECT_DOUBLE_EQ(s.min, 2.0);
  EXPECT_DOUBLE_EQ(s.max, 9.0);
  EXPECT_DOUBLE_EQ(s.p5, 2.7);   // numpy.percentile([2,4,4,4,5,5,7,9], 5)
  EXPECT_DOUBLE_EQ(s.p50, 4.5);
  EXPECT_DOUBLE_EQ(s.p95, 8.3);
  // All missing: counts only, statistics NaN; one value: no standard deviation.
  const Summary none = calc_summary({kNaN, kNaN});
  EXPECT_EQ(none.count, 0);
  EXPECT_EQ(none.missing, 2);
  EXPECT_TRUE(std::isnan(none.mean) && std::isnan(none.p50) && std::isnan(none.min));
  const Summary one = calc_summary({3.0});
  EXPECT_DOUBLE_EQ(one.mean, 3.0);
  EXPECT_TRUE(std::isnan(one.std));
  EXPECT_DOUBLE_EQ(one.p95, 3.0);
}

TEST(Statistics, BootstrapIsDeterministicAndCoversTrueMean) {
  // 1000 draws of Exp(1) (true mean 1): the 95 % interval holds 1.
  TestRng rng{12345};
  std::vector<double> x(1000);
  for (double& v : x) v = rng.exponential();
  const Interval ci = calc_bootstrap_mean(x, 2000, 0.95, 7);
  EXPECT_LT(ci.lower, 1.0);
  EXPECT_GT(ci.upper, 1.0);
  EXPECT_LT(ci.lower, ci.estimate);
  EXPECT_GT(ci.upper, ci.estimate);
  // Roughly +-1.96 sigma / sqrt(n) = +-0.062 around the sample mean (measured [0.935, 1.059] around 0.999).
  EXPECT_NEAR(ci.upper - ci.lower, 2 * 1.96 / std::sqrt(1000.0), 0.015);

  // Same seed: the same bits; another seed: another interval.
  const Interval again = calc_bootstrap_mean(x, 2000, 0.95, 7);
  EXPECT_TRUE(same_bits(ci.estimate, again.estimate) && same_bits(ci.lower, again.lower) &&
              same_bits(ci.upper, again.upper));
  const Interval other = calc_bootstrap_mean(x, 2000, 0.95, 8);
  EXPECT_FALSE(same_bits(ci.lower, other.lower) && same_bits(ci.upper, other.upper));
  // NaNs are dropped before resampling: the interval is that of the NaN-free sample.
  std::vector<double> with_nan = x;
  with_nan.insert(with_nan.begin() + 10, kNaN);
  with_nan.push_back(kNaN);
  const Interval nan_ci = calc_bootstrap_mean(with_nan, 2000, 0.95, 7);
  EXPECT_TRUE(same_bits(ci.lower, nan_ci.lower) && same_bits(ci.upper, nan_ci.upper));

  // Coverage over 40 independent samples of 1000: measured 39 / 40 hold the true mean.
  int covered = 0;
  for (std::uint64_t s = 0; s < 40; ++s) {
    TestRng r{1000 + s};
    for (double& v : x) v = r.exponential();
    const Interval c = calc_bootstrap_mean(x, 1000, 0.95, s);
    covered += c.lower < 1.0 && 1.0 < c.upper;
  }
  EXPECT_GE(covered, 35);

  // Width shrinks as 1 / sqrt(n): 16 times the draws, a quarter of the width (measured ratio 4.15).
  TestRng r2{99};
  std::vector<double> small(250), big(4000);
  for (double& v : small) v = r2.uniform();
  for (double& v : big) v = r2.uniform();
  const Interval cs = calc_bootstrap_mean(small, 2000, 0.95, 1);
  const Interval cb = calc_bootstrap_mean(big, 2000, 0.95, 1);
  const double ratio = (cs.upper - cs.lower) / (cb.upper - cb.lower);
  EXPECT_NEAR(ratio, 4.0, 0.5);

  EXPECT_THROW(calc_bootstrap_mean(x, 0, 0.95, 1), std::invalid_argument);
  EXPECT_THROW(calc_bootstrap_mean(x, 10, 1.0, 1), std::invalid_argument);
  const Interval empty = calc_bootstrap_mean({kNaN}, 10, 0.95, 1);
  EXPECT_TRUE(std::isnan(empty.estimate) && std::isnan(empty.lower) && std::isnan(empty.upper));
}

TEST(Statistics, BootstrapPercentileCoversTrueQuantile) {
  // 1000 uniforms: the 95 % interval of the median holds 0.5, that of the 90th percentile holds 0.9.
  TestRng rng{2024};
  std::vector<double> x(1000);
  for (double& v : x) v = rng.uniform();
  const Interval med = calc_bootstrap_percentile(x, 50, 1000, 0.95, 3);
  EXPECT_DOUBLE_EQ(med.estimate, calc_percentile(x, 50));
  EXPECT_LT(med.lower, 0.5);
  EXPECT_GT(med.upper, 0.5);
  const Interval p90 = calc_bootstrap_percentile(x, 90, 1000, 0.95, 3);
  EXPECT_LT(p90.lower, 0.9);
  EXPECT_GT(p90.upper, 0.9);
  // Width about 2 x 1.96 sqrt(p (1-p) / n) for a uniform: 0.062 for the median.
  EXPECT_NEAR(med.upper - med.lower, 2 * 1.96 * std::sqrt(0.25 / 1000), 0.015);
  const Interval again = calc_bootstrap_percentile(x, 90, 1000, 0.95, 3);
  EXPECT_TRUE(same_bits(p90.lower, again.lower) && same_bits(p90.upper, again.upper));
  EXPECT_THROW(calc_bootstrap_percentile(x, -1, 10, 0.95, 1), std::invalid_argument);
}

TEST(Statistics, MissProbabilityCountsNanAsMiss) {
  // 10 values, limit 2: misses are 2.5, 3, NaN, NaN (a value equal to the limit meets it).
  const std::vector<double> v = {1.0, 2.0, 2.5, kNaN, 0.5, 3.0, kNaN, 1.9, 1.0, 0.0};
  const Interval m = calc_miss_probability(v, 2.0, 0.95);
  EXPECT_DOUBLE_EQ(m.estimate, 0.4);
  // Wilson 4 of 10 at 95 % (as statsmodels proportion_confint(4, 10, method="wilson")).
  EXPECT_NEAR(m.lower, 0.1681803297, 1e-9);
  EXPECT_NEAR(m.upper, 0.6873262303, 1e-9);
  // Only NaNs: everything misses.
  const Interval all = calc_miss_probability({kNaN, kNaN, kNaN}, 1e9, 0.95);
  EXPECT_DOUBLE_EQ(all.estimate, 1.0);
  EXPECT_DOUBLE_EQ(all.upper, 1.0);
  EXPECT_TRUE(std::isnan(calc_miss_probability({}, 1.0, 0.95).estimate));
}

TEST(Statistics, WilsonIntervalKnownValues) {
  const double z = 1.959963984540054;  // Phi^-1(0.975)
  std::vector<double> ten(10, 0.0);
  // 0 of 10 at 95 %: [0, z^2 / (n + z^2)] = [0, 0.2775].
  const Interval none = calc_miss_probability(ten, 1.0, 0.95);
  EXPECT_EQ(none.estimate, 0.0);
  EXPECT_EQ(none.lower, 0.0);
  EXPECT_NEAR(none.upper, z * z / (10 + z * z), 1e-14);
  EXPECT_NEAR(none.upper, 0.2775, 5e-5);
  // 5 of 10 at 95 %: [0.2366, 0.7634].
  for (int i = 0; i < 5; ++i) ten[i] = 2.0;
  const Interval half = calc_miss_probability(ten, 1.0, 0.95);
  EXPECT_DOUBLE_EQ(half.estimate, 0.5);
  EXPECT_NEAR(half.lower, 0.2366, 5e-5);
  EXPECT_NEAR(half.upper, 0.7634, 5e-5);
  EXPECT_NEAR(half.lower + half.upper, 1.0, 1e-15);
  // 10 of 10 at 95 %: the mirror of 0 of 10.
  for (double& v : ten) v = 2.0;
  const Interval every = calc_miss_probability(ten, 1.0, 0.95);
  EXPECT_EQ(every.upper, 1.0);
  EXPECT_NEAR(every.lower, 10 / (10 + z * z), 1e-14);
  // 1 of 20 at 90 % (z = 1.6448536): [0.011235, 0.196007].
  std::vector<double> twenty(20, 0.0);
  twenty[7] = 5.0;
  const Interval ninety = calc_miss_probability(twenty, 1.0, 0.90);
  EXPECT_NEAR(ninety.lower, 0.0112348169, 1e-9);
  EXPECT_NEAR(ninety.upper, 0.1960072368, 1e-9);
  EXPECT_THROW(calc_miss_probability(ten, 1.0, 0.0), std::invalid_argument);
}

TEST(Statistics, TwoSidedZKnownValues) {
  // Python's statistics.NormalDist().inv_cdf((1 + c) / 2) (Wichura AS241).
  EXPECT_NEAR(calc_two_sided_z(0.95), 1.9599639845400536, 1e-15);
  EXPECT_NEAR(calc_two_sided_z(0.90), 1.6448536269514715, 1e-14);
  EXPECT_NEAR(calc_two_sided_z(0.98), 2.3263478740408408, 1e-14);
  EXPECT_NEAR(calc_two_sided_z(0.5), 0.6744897501960817, 1e-15);
  EXPECT_NEAR(calc_two_sided_z(0.999), 3.2905267314919255, 1e-13);
  EXPECT_THROW(calc_two_sided_z(1.0), std::invalid_argument);
  EXPECT_THROW(calc_two_sided_z(std::nan("")), std::invalid_argument);
}

TEST(Statistics, GroupsAreSortedAndExhaustive) {
  // Two key columns over 8 rows; keys differing only past the 12th significant digit are equal.
  const std::vector<double> a = {2.0, 1.0, 2.0, 1.0, 2.0 + 1e-14, 1.0, kNaN, 0.1 + 0.2};
  const std::vector<double> b = {5.0, 7.0, 3.0, 7.0, 5.0, -0.0, 1.0, 1.0};
  const auto groups = make_groups({a, b});
  ASSERT_EQ(groups.size(), 6u);
  // Ascending lexicographic order over (a, b), NaN last; -0 groups as 0; 0.1 + 0.2 rounds to 0.3.
  EXPECT_EQ(groups[0].key, (std::vector<double>{0.3, 1.0}));
  EXPECT_EQ(groups[0].rows, (std::vector<int>{7}));
  EXPECT_EQ(groups[1].key, (std::vector<double>{1.0, 0.0}));
  EXPECT_FALSE(std::signbit(groups[1].key[1]));
  EXPECT_EQ(groups[1].rows, (std::vector<int>{5}));
  EXPECT_EQ(groups[2].key, (std::vector<double>{1.0, 7.0}));
  EXPECT_EQ(groups[2].rows, (std::vector<int>{1, 3}));
  EXPECT_EQ(groups[3].key, (std::vector<double>{2.0, 3.0}));
  EXPECT_EQ(groups[3].rows, (std::vector<int>{2}));
  EXPECT_EQ(groups[4].key, (std::vector<double>{2.0, 5.0}));
  EXPECT_EQ(groups[4].rows, (std::vector<int>{0, 4}));
  EXPECT_TRUE(std::isnan(groups[5].key[0]));
  EXPECT_EQ(groups[5].rows, (std::vector<int>{6}));

  // Exhaustive on a larger table: every row in exactly one group, groups strictly ascending, keys equal in a group.
  TestRng rng{5};
  std::vector<double> k1(500), k2(500);
  for (std::size_t r = 0; r < k1.size(); ++r) {
    k1[r] = static_cast<double>(rng.next() % 4) * 0.1;
    k2[r] = static_cast<double>(rng.next() % 3) - 1.0;
  }
  const auto g = make_groups({k1, k2});
  EXPECT_EQ(g.size(), 12u);
  std::vector<int> seen(k1.size(), 0);
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (i > 0) {
      EXPECT_TRUE(g[i - 1].key < g[i].key);
    }
    for (std::size_t j = 0; j < g[i].rows.size(); ++j) {
      const int r = g[i].rows[j];
      ++seen[r];
      if (j > 0) {
        EXPECT_LT(g[i].rows[j - 1], r);
      }
      EXPECT_NEAR(k1[r], g[i].key[0], 1e-12);
      EXPECT_EQ(k2[r], g[i].key[1]);
    }
  }
  for (int s : seen) EXPECT_EQ(s, 1);

  EXPECT_TRUE(make_groups({}).empty());
  EXPECT_THROW(make_groups({{1.0, 2.0}, {1.0}}), std::invalid_argument);
}

// The bin of every value of `column` under `edges` (calc_bin_key), grouped: the rows of each bin.
std::vector<Group> bin_groups(const std::vector<double>& column, const std::vector<double>& edges) {
  std::vector<double> key;
  for (double v : column) key.push_back(calc_bin_key(edges, v));
  return make_groups({key});
}

// Every row in exactly one group, no group empty, edges strictly ascending, each finite row inside its bin.
void expect_proper_bins(const std::vector<double>& column, const std::vector<double>& edges) {
  for (std::size_t i = 1; i < edges.size(); ++i) EXPECT_LT(edges[i - 1], edges[i]) << i;
  std::vector<int> seen(column.size(), 0);
  const auto groups = bin_groups(column, edges);
  std::size_t finite_bins = 0;
  for (const auto& g : groups) {
    EXPECT_FALSE(g.rows.empty());
    finite_bins += std::isfinite(g.key[0]);
    for (int r : g.rows) {
      ++seen[r];
      if (!std::isfinite(g.key[0])) continue;
      const auto b = static_cast<std::size_t>(g.key[0]);
      EXPECT_GE(column[r], edges[b]) << r;
      if (b + 2 < edges.size()) {
        EXPECT_LT(column[r], edges[b + 1]) << r;
      } else {
        EXPECT_LE(column[r], edges[b + 1]) << r;
      }
    }
  }
  EXPECT_EQ(finite_bins + 1, edges.size()) << "a quantile bin without rows";
  for (int s : seen) EXPECT_EQ(s, 1);
}

TEST(Binning, QuantileBinsOfOneToHundredHoldTenRowsEach) {
  // 1..100 in a shuffled order: the type-7 percentiles 10 k of 1..100 are 10 k + 1 - 0.1 k.
  std::vector<double> x(100);
  for (int r = 0; r < 100; ++r) x[r] = (r * 37) % 100 + 1;
  const auto edges = calc_bin_edges(x, {});
  EXPECT_EQ(edges, (std::vector<double>{1, 10.9, 20.8, 30.7, 40.6, 50.5, 60.4, 70.3, 80.2, 90.1, 100}));
  const auto groups = bin_groups(x, edges);
  ASSERT_EQ(groups.size(), 10u);
  for (int b = 0; b < 10; ++b) {
    EXPECT_EQ(groups[b].key[0], b);
    ASSERT_EQ(groups[b].rows.size(), 10u) << b;
    for (int r : groups[b].rows) {
      EXPECT_GE(x[r], 10 * b + 1) << b;
      EXPECT_LE(x[r], 10 * b + 10) << b;
    }
  }
  expect_proper_bins(x, edges);
}

TEST(Binning, EqualWidthBinsSplitTheRangeEvenlyAndAnEdgeOpensItsBin) {
  // 0..10 and 2.5, 7.5 once more, in 4 equal-width bins: edges 0, 2.5, 5, 7.5, 10; 10 closes the last.
  std::vector<double> x = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 2.5, 7.5};
  const Binning width{4, Binning::kWidth};
  const auto edges = calc_bin_edges(x, width);
  EXPECT_EQ(edges, (std::vector<double>{0, 2.5, 5, 7.5, 10}));
  const auto groups = bin_groups(x, edges);
  ASSERT_EQ(groups.size(), 4u);
  EXPECT_EQ(groups[0].rows, (std::vector<int>{0, 1, 2}));       // 0, 1, 2
  EXPECT_EQ(groups[1].rows, (std::vector<int>{3, 4, 11}));      // 3, 4, 2.5
  EXPECT_EQ(groups[2].rows, (std::vector<int>{5, 6, 7}));       // 5, 6, 7
  EXPECT_EQ(groups[3].rows, (std::vector<int>{8, 9, 10, 12}));  // 8, 9, 10, 7.5
  // A gap: the empty equal-width bins stay (they make no group); 0.1 + 0.2 lands on the edge 0.3.
  const std::vector<double> gap = {0, 1, 2, 3, 4, 5, 6, 100};
  EXPECT_EQ(calc_bin_edges(gap, width), (std::vector<double>{0, 25, 50, 75, 100}));
  EXPECT_EQ(bin_groups(gap, calc_bin_edges(gap, width)).size(), 2u);
  std::vector<double> tenths;
  for (int i = 0; i <= 20; ++i) tenths.push_back(i * 0.1);
  const auto e = calc_bin_edges(tenths, {10, Binning::kWidth});
  ASSERT_EQ(e.size(), 11u);
  EXPECT_EQ(e[3], 0.6);
  EXPECT_EQ(calc_bin_key(e, 0.1 + 0.2 + 0.3), 3.0) << "0.6000000000000001 is 0.6 to 12 digits: the bin it opens";
}

TEST(Binning, TiesGiveNoEmptyOrRepeatedBin) {
  // 90 zeros and 1..10: the percentiles 10..80 are all 0 and merge; 90 is 0.1; two bins.
  std::vector<double> x(90, 0.0);
  for (int i = 1; i <= 10; ++i) x.push_back(i);
  const auto edges = calc_bin_edges(x, {});
  EXPECT_EQ(edges, (std::vector<double>{0, 0.1, 10}));
  const auto groups = bin_groups(x, edges);
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0].rows.size(), 90u);
  EXPECT_EQ(groups[1].rows.size(), 10u);
  expect_proper_bins(x, edges);
  // Distinct edges can still bound no row: 16 rows, 2 twice; the 10th percentile is 1.5, the 20th 2, so
  // [1.5, 2) holds nothing and merges with the next bin.
  const std::vector<double> y = {0, 1, 2, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14};
  const auto ey = calc_bin_edges(y, {});
  EXPECT_EQ(ey, (std::vector<double>{0, 1.5, 3.5, 5, 6.5, 8, 9.5, 11, 12.5, 14}));
  expect_proper_bins(y, ey);
  // Random columns with many ties, quantile and equal-width: the same properties.
  TestRng rng{11};
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<double> z(1 + rng.next() % 300);
    for (double& v : z) v = static_cast<double>(rng.next() % (2 + trial)) * (rng.next() % 4 == 0 ? 0.0 : 0.25);
    for (int bins : {1, 3, 10}) {
      const auto ez = calc_bin_edges(z, {bins, Binning::kQuantile});
      if (!ez.empty()) {
        expect_proper_bins(z, ez);
      }
      const auto ew = calc_bin_edges(z, {bins, Binning::kWidth});
      for (std::size_t i = 1; i < ew.size(); ++i) EXPECT_LT(ew[i - 1], ew[i]);
      if (!ew.empty()) {
        EXPECT_EQ(ew.size(), static_cast<std::size_t>(bins) + 1);
      }
    }
  }
}

TEST(Binning, NanKeysStayTheirOwnGroupAndFewLevelsAreNotBinned) {
  std::vector<double> x;
  for (int i = 0; i < 20; ++i) x.push_back(i);
  x.insert(x.begin() + 3, kNaN);
  x.push_back(kNaN);
  const auto edges = calc_bin_edges(x, {5, Binning::kWidth});
  EXPECT_EQ(edges, (std::vector<double>{0, 3.8, 7.6, 11.4, 15.2, 19}));
  const auto groups = bin_groups(x, edges);
  ASSERT_EQ(groups.size(), 6u);
  EXPECT_TRUE(std::isnan(groups[5].key[0]));
  EXPECT_EQ(groups[5].rows, (std::vector<int>{3, 21}));
  expect_proper_bins(x, edges);
  // Not binned: at most `bins` distinct values (NaN not counted), bins = 0, or no values.
  EXPECT_TRUE(calc_bin_edges({1, 2, 3, 2, 1, kNaN, kNaN}, {3}).empty());
  EXPECT_TRUE(calc_bin_edges(x, {0}).empty());
  EXPECT_TRUE(calc_bin_edges(x, {20}).empty());
  EXPECT_EQ(calc_bin_edges(x, {19}).size(), 20u);
  EXPECT_TRUE(calc_bin_edges({}, {}).empty());
  EXPECT_TRUE(calc_bin_edges({kNaN, kNaN}, {1}).empty());
  EXPECT_TRUE(std::isnan(calc_bin_key(edges, kNaN)));
  EXPECT_THROW(calc_bin_key(edges, 20.0), std::invalid_argument);
}

}  // namespace
}  // namespace ff
