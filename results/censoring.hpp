// Right-censored responses: a settling time that a run could not confirm is not missing, it is
// known only to exceed the largest value that run could confirm (its horizon). Kaplan–Meier
// product-limit estimate, its percentiles and restricted mean, summaries and bootstrap intervals
// that count the censored entries (statistics.hpp holds the uncensored ones).
//
// A sample is two vectors of equal length: entry i is settled at values[i] when that is a number;
// when values[i] is NaN it is censored at horizons[i] (known only to be > horizons[i]) if that is a
// number, else missing (no information at all, e.g. a diverged run). Empty horizons: nothing is
// censored, every NaN is missing. Other lengths: std::invalid_argument.
//
// A statistic that lies above the horizon (a percentile the data never reach, the maximum) is
// +inf: read "> horizon (not settled)". Deterministic like statistics.hpp: fixed-order reductions,
// resamples from draw_index.
#pragma once

#include <cstdint>
#include <vector>

#include "results/statistics.hpp"

namespace ff {

// Kaplan–Meier product-limit estimate (Kaplan & Meier 1958): at each distinct settled time t_i,
// S(t_i) = prod_{t_j <= t_i} (1 - d_j / n_j), with d_j settled at t_j and n_j still at risk (not
// settled and not censored before t_j); an entry censored at t_j is still at risk at t_j (settled
// entries count before censored ones at equal times, Kaplan & Meier 1958, sec. 2).
struct KaplanMeier {
  std::vector<double> time;      // distinct settled times, ascending
  std::vector<double> survival;  // S just after time[i]: the fraction not yet settled
  std::vector<int> at_risk, events;
  double end = kStatsNaN;      // last settled or censored time: S is estimated up to here
  double horizon = kStatsNaN;      // largest horizon among the censored entries; NaN when none is censored
  double horizon_min = kStatsNaN;  // smallest one
  int count = 0, censored = 0, missing = 0;
};
KaplanMeier calc_kaplan_meier(const std::vector<double>& values, const std::vector<double>& horizons);

// S(t), right-continuous: 1 before the first settled time, held at its last value beyond `end`.
// NaN for an empty estimate.
double calc_km_survival(const KaplanMeier& km, double t);

// p-th percentile of the settling time, p in [0, 100] (else std::invalid_argument): the smallest
// settled time with 1 - S >= p/100 (Klein & Moeschberger 2003, sec. 4.5; as R's quantile.survfit
// without its midpoint rule and lifelines' percentile). +inf when the curve never gets there (the
// percentile lies beyond `end`); NaN for an empty estimate. Without censoring this is the inverse
// empirical CDF (Hyndman & Fan type 1).
double calc_km_percentile(const KaplanMeier& km, double p);

// Restricted mean up to tau: E[min(T, tau)] = integral_0^tau S(t) dt for T >= 0 (Irwin 1949; Royston
// & Parmar 2013), summed over the jumps of the curve as sum_j min(t_j, tau) (S(t_{j-1}) - S(t_j)) +
// tau S(tau), with S held flat beyond `end`. Without censoring and tau >= every value: the sample mean.
double calc_km_restricted_mean(const KaplanMeier& km, double tau);

// Summary of a censored sample: count = settled, censored, missing; horizon, horizon_min as in KaplanMeier.
// Nothing censored: exactly calc_summary(values). Otherwise mean = the restricted mean up to the
// horizon (the area under the Kaplan–Meier curve), std = NaN, min = the first settled time (+inf if
// none), p5/p50/p95 = calc_km_percentile (+inf above the horizon), max = +inf.
Summary calc_summary(const std::vector<double>& values, const std::vector<double>& horizons);

// Percentile bootstrap of the summary's mean and of its p-th percentile over a censored sample:
// resamples draw (value, horizon) pairs of the non-missing entries, censored ones too (Efron 1981,
// "Censored data and the bootstrap"), and each resample's Kaplan–Meier curve gives the statistic;
// the restricted mean keeps the sample's horizon. Bounds of +inf: above the horizon. Nothing
// censored: exactly calc_bootstrap_mean / calc_bootstrap_percentile of `values`. Same arguments
// and errors as those; draw j of resample b is entry draw_index(seed, b n + j, n) of the n
// non-missing entries in index order.
Interval calc_bootstrap_mean(const std::vector<double>& values, const std::vector<double>& horizons, int resamples,
                             double confidence, std::uint64_t seed);
Interval calc_bootstrap_percentile(const std::vector<double>& values, const std::vector<double>& horizons, double p,
                                   int resamples, double confidence, std::uint64_t seed);

}  // namespace ff
