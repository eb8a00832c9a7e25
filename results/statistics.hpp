// Summary statistics of a study's responses: percentiles, summaries, bootstrap confidence intervals,
// miss probabilities with Wilson intervals, and group-by over parameter columns.
//
// Every result is deterministic: the same input gives the same bits on any machine and thread count
// (no std:: random distributions; resamples come from a counter-based generator keyed by `seed`;
// every reduction runs in a fixed order).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace ff {

inline constexpr double kStatsNaN = std::numeric_limits<double>::quiet_NaN();

// Percentile by linear interpolation between order statistics (Hyndman & Fan 1996, type 7, as numpy's
// and R's default): with the n sorted values x[0..n), h = (n-1) p/100, x[floor h] + (h - floor h)(x[floor h + 1]
// - x[floor h]). p in [0, 100] (else std::invalid_argument). NaNs are ignored; no values left -> NaN.
double calc_percentile(std::vector<double> values, double p);

// count = non-NaN values, missing = NaN values; the rest is over the non-NaN values (all NaN if count = 0).
// std is the sample standard deviation (divisor count - 1; NaN if count < 2); p5/p50/p95 as calc_percentile.
// censored and horizon(_min): only the censored summary of censoring.hpp sets them (0 and NaN here).
struct Summary {
  int count = 0, censored = 0, missing = 0;
  double mean = kStatsNaN, std = kStatsNaN, min = kStatsNaN, max = kStatsNaN;
  double p5 = kStatsNaN, p50 = kStatsNaN, p95 = kStatsNaN;
  double horizon = kStatsNaN, horizon_min = kStatsNaN;
};
Summary calc_summary(const std::vector<double>& values);

// A statistic with a confidence interval [lower, upper].
struct Interval {
  double estimate = kStatsNaN, lower = kStatsNaN, upper = kStatsNaN;
};

// Percentile bootstrap (Efron & Tibshirani 1993, ch. 13) of the mean, or of the p-th percentile: `estimate` is
// the statistic of the sample, [lower, upper] the (1-confidence)/2 and (1+confidence)/2 type-7 percentiles of
// the statistic over `resamples` resamples drawn with replacement. NaNs are dropped first; no values left ->
// all NaN. resamples >= 1 and confidence in (0, 1), else std::invalid_argument. Deterministic in `seed`:
// draw j of resample b is draw_index(seed, b n + j, n).
Interval calc_bootstrap_mean(const std::vector<double>& values, int resamples, double confidence, std::uint64_t seed);
Interval calc_bootstrap_percentile(const std::vector<double>& values, double p, int resamples, double confidence,
                                   std::uint64_t seed);

// Probability that a response misses its spec: a value misses if value > limit, or if it is NaN (the spec was
// not met, e.g. "not settled"); every entry counts in n. Wilson score interval (Wilson 1927; Brown, Cai &
// DasGupta 2001), exact 0 / 1 bounds when no / every value misses. Empty input -> all NaN.
Interval calc_miss_probability(const std::vector<double>& values, double limit, double confidence);

// Wilson score interval of a proportion k/n at `confidence` (as calc_miss_probability: exact 0 / 1 bounds
// when k = 0 / k = n). k <= n; n = 0 -> all NaN; confidence outside (0, 1): std::invalid_argument.
Interval calc_wilson_interval(std::size_t k, std::size_t n, double confidence);

// Group-by: rows whose keys are equal after rounding each key to 12 significant digits (exact double equality
// of the rounded values; -0 counts as +0, NaN keys equal each other) form a group. `key` holds the rounded key
// values, `rows` the group's rows in ascending order; groups are in ascending key order, lexicographic over the
// key columns, NaN after every number. key_columns[k][row]; all columns the same length (else
// std::invalid_argument); no key columns -> no groups.
struct Group {
  std::vector<double> key;
  std::vector<int> rows;
};
std::vector<Group> make_groups(const std::vector<std::vector<double>>& key_columns);

// Binning of a group-by key column with many levels (a fine grid, a random design), so that a table
// grouped by it stays readable. A column with more than `bins` distinct finite keys (rounded as
// make_groups rounds them) is binned into at most `bins` bins; one with fewer is not (bins <= 0:
// never). Quantile bins: edges at the type-7 percentiles 100 k / bins (k = 0..bins) of every finite
// key of the column, one per row (not per distinct value), so bins hold about equal numbers of rows,
// as pandas.qcut; equal-width bins: min..max in `bins` equal steps. Edges are rounded to 12
// significant digits; equal edges merge, and a quantile bin that holds no key (ties, e.g. 90 zeros
// among 100 rows) merges with the next, so quantile bins are never empty or repeated (an equal-width
// bin can be empty: it makes no group).
struct Binning {
  enum Kind { kQuantile, kWidth };
  int bins = 10;
  Kind kind = kQuantile;
};

// The bin edges e[0] < ... < e[m] (m >= 1 bins, e[0] the least key, e[m] the largest) of a key column,
// or none when it is not binned (see Binning). Bin i is [e[i], e[i+1]), the last one closed [e[m-1], e[m]].
std::vector<double> calc_bin_edges(const std::vector<double>& column, const Binning& binning);

// The bin of `value` (rounded as make_groups rounds keys) under edges from calc_bin_edges: every finite
// value in [e[0], e[m]] lands in exactly one bin, 0..m-1; NaN and +-inf give themselves (NaN stays its
// own group, after every bin). The key column make_groups then groups by.
double calc_bin_key(const std::vector<double>& edges, double value);

// Helpers shared with sensitivity.cpp.

// Counter-based uniform index in [0, n) (n >= 1): SplitMix64 (Steele, Lea & Flood 2014) output number `counter`
// of the stream keyed by SplitMix64(seed), mapped to [0, n) by the high 64 bits of a 128-bit product (Lemire 2019;
// bias <= n / 2^64). A pure function of (seed, counter, n).
std::size_t draw_index(std::uint64_t seed, std::uint64_t counter, std::size_t n);

// Two-sided standard normal critical value z = Phi^-1((1 + confidence) / 2), confidence in (0, 1) (else
// std::invalid_argument): 1.959964 for 0.95. Acklam's rational approximation refined by one Halley step on
// std::erfc (relative error ~1e-15). (common/random.hpp has a full calc_normal_quantile; this one keeps results/
// self-contained.)
double calc_two_sided_z(double confidence);

}  // namespace ff
