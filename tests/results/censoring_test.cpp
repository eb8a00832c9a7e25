// results/censoring.cpp: Kaplan–Meier, its percentiles and restricted mean, censored summaries and
// bootstrap intervals, on synthetic samples whose answers are known.
#include "results/censoring.hpp"

#include <gtest/gtest.h>

#include "tests/results/test_rng.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace ff {
namespace {

const double kNaN = std::nan("");
const double kInf = std::numeric_limits<double>::infinity();

using TestRng = ff::test::TestRng;

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(Censoring, KaplanMeierWithoutCensoringIsTheEmpiricalCdf) {
  // 12 values with ties, no NaN: 1 - S at each distinct value is the fraction <= it (k / n).
  const std::vector<double> x = {3.5, 1.0, 2.0, 2.0, 7.25, 0.5, 3.5, 3.5, 9.0, 1.0, 4.0, 6.0};
  const KaplanMeier km = calc_kaplan_meier(x, {});
  const std::vector<double> want_t = {0.5, 1.0, 2.0, 3.5, 4.0, 6.0, 7.25, 9.0};
  const std::vector<int> at_or_below = {1, 3, 5, 8, 9, 10, 11, 12};
  ASSERT_EQ(km.time, want_t);
  for (std::size_t i = 0; i < want_t.size(); ++i)
    EXPECT_NEAR(1.0 - km.survival[i], at_or_below[i] / 12.0, 1e-15) << "t = " << want_t[i];
  EXPECT_EQ(km.survival.back(), 0.0);
  EXPECT_EQ(km.count, 12);
  EXPECT_EQ(km.censored, 0);
  EXPECT_TRUE(std::isnan(km.horizon));
  // Its percentiles are the inverse empirical CDF (type 1): the smallest value with at least p % at or below it.
  EXPECT_EQ(calc_km_percentile(km, 0), 0.5);
  EXPECT_EQ(calc_km_percentile(km, 25), 1.0);   // 3 of 12 <= 1.0 exactly
  EXPECT_EQ(calc_km_percentile(km, 26), 2.0);
  EXPECT_EQ(calc_km_percentile(km, 50), 3.5);
  EXPECT_EQ(calc_km_percentile(km, 100), 9.0);
  // Its restricted mean beyond the largest value is the sample mean; S is a step function.
  EXPECT_NEAR(calc_km_restricted_mean(km, 100.0), 43.25 / 12.0, 1e-14);
  EXPECT_EQ(calc_km_survival(km, 0.4), 1.0);
  EXPECT_NEAR(calc_km_survival(km, 2.0), 7.0 / 12.0, 1e-15);
  EXPECT_NEAR(calc_km_survival(km, 3.49), 7.0 / 12.0, 1e-15);
  // NaN without a horizon is missing, not censored: the estimate of the other values.
  const KaplanMeier with_missing = calc_kaplan_meier({1.0, kNaN, 2.0}, {5.0, kNaN, 5.0});
  EXPECT_EQ(with_missing.missing, 1);
  EXPECT_EQ(with_missing.censored, 0);
  EXPECT_NEAR(with_missing.survival[0], 0.5, 1e-15);
}

TEST(Censoring, KaplanMeierMatchesTheTextbookLeukaemiaExample) {
  // Freireich et al. (1963), 6-MP arm: weeks of remission of 21 leukaemia patients, "+" = censored.
  // Product-limit table in Klein & Moeschberger, "Survival Analysis" (2nd ed. 2003), Table 4.1A, and
  // Kleinbaum & Klein, "Survival Analysis: A Self-Learning Text" (3rd ed. 2012), ch. 2:
  //   t:    6      7      10     13     16     22     23
  //   S(t): 0.857  0.807  0.753  0.690  0.627  0.538  0.448
  // 6, 6, 6, 6+, 7, 9+, 10, 10+, 11+, 13, 16, 17+, 19+, 20+, 22, 23, 25+, 32+, 32+, 34+, 35+.
  const std::vector<double> v = {6, 6, 6, kNaN, 7, kNaN, 10, kNaN, kNaN, 13, 16, kNaN, kNaN, kNaN, 22, 23, kNaN, kNaN,
                                 kNaN, kNaN, kNaN};
  const std::vector<double> h = {kNaN, kNaN, kNaN, 6,    kNaN, 9,    kNaN, 10,   11, kNaN, kNaN,
                                 17,   19,   20,   kNaN, kNaN, 25,   32,   32,   34, 35};
  const KaplanMeier km = calc_kaplan_meier(v, h);
  ASSERT_EQ(km.time, (std::vector<double>{6, 7, 10, 13, 16, 22, 23}));
  const double s[] = {0.857, 0.807, 0.753, 0.690, 0.627, 0.538, 0.448};
  for (std::size_t i = 0; i < km.time.size(); ++i) EXPECT_NEAR(km.survival[i], s[i], 5e-4) << "t = " << km.time[i];
  // Exactly: 18/21, then x 16/17 (the 6+ leaves after the deaths at 6), 14/15, 11/12, 10/11, 6/7, 5/6.
  EXPECT_NEAR(km.survival[1], 18.0 / 21 * 16 / 17, 1e-15);
  EXPECT_NEAR(km.survival.back(), 18.0 / 21 * 16 / 17 * 14 / 15 * 11 / 12 * 10 / 11 * 6 / 7 * 5 / 6, 1e-15);
  EXPECT_EQ(km.at_risk, (std::vector<int>{21, 17, 15, 12, 11, 7, 6}));
  EXPECT_EQ(km.events, (std::vector<int>{3, 1, 1, 1, 1, 1, 1}));
  EXPECT_EQ(km.count, 9);
  EXPECT_EQ(km.censored, 12);
  EXPECT_EQ(km.horizon, 35);
  EXPECT_EQ(km.end, 35);
  // Median 23 weeks (the first S <= 0.5); the curve never falls to 0.4, so the 60th percentile is above 35.
  EXPECT_EQ(calc_km_percentile(km, 50), 23);
  EXPECT_EQ(calc_km_percentile(km, 60), kInf);
  // Restricted mean up to 35 weeks, the area under the tabulated steps: 6 + 1 (18/21) + 3 S(7) + ... + 12 S(23).
  EXPECT_NEAR(calc_km_restricted_mean(km, 35), 23.287395, 1e-6);
}

TEST(Censoring, RestrictedMeanOfCensoredExponentialMatchesAnalyticValue) {
  // T ~ Exp(lambda), every run censored at H: E[min(T, H)] = (1 - exp(-lambda H)) / lambda.
  const double lambda = 0.5, horizon = 2.0;
  const double want = (1.0 - std::exp(-lambda * horizon)) / lambda;  // 1.26424
  TestRng rng{31337};
  const std::size_t n = 20000;
  std::vector<double> v(n), h(n, horizon);
  int censored = 0;
  for (double& x : v) {
    x = rng.exponential() / lambda;
    if (x > horizon) x = kNaN, ++censored;
  }
  EXPECT_NEAR(censored / double(n), std::exp(-lambda * horizon), 0.01);  // 36.8 % not settled
  const Summary s = calc_summary(v, h);
  EXPECT_EQ(s.count + s.censored, static_cast<int>(n));
  EXPECT_EQ(s.horizon, horizon);
  // sd(min(T, H)) < 1 here: 4 standard errors are under 0.03.
  EXPECT_NEAR(s.mean, want, 0.03);
  // Common horizon: the area under the curve is the plain mean of min(T, H).
  double sum = 0.0;
  for (double x : v) sum += std::isnan(x) ? horizon : x;
  EXPECT_NEAR(s.mean, sum / n, 1e-9);
  // Its bootstrap interval resamples the censored runs too and holds the analytic value.
  const Interval ci = calc_bootstrap_mean(v, h, 500, 0.95, 3);
  EXPECT_EQ(ci.estimate, s.mean);
  EXPECT_LT(ci.lower, want);
  EXPECT_GT(ci.upper, want);
  // Width 2 z sd / sqrt(n): sd(min(T, H))^2 = (8 - 16/e) - want^2 = 0.516 for lambda = 0.5, H = 2.
  EXPECT_NEAR(ci.upper - ci.lower, 2 * 1.96 * std::sqrt(8.0 - 16.0 / std::exp(1.0) - want * want) / std::sqrt(double(n)),
              0.003);
  // Survivors only (the old summary) would say 0.84: the bias this module removes.
  EXPECT_LT(calc_summary(v).mean, 0.9);
}

TEST(Censoring, KaplanMeierRecoversExponentialUnderVaryingHorizons) {
  // T ~ Exp(1), each run with its own horizon, uniform on [0.5, 3]: S(t) = exp(-t) up to the horizons.
  TestRng rng{777};
  std::vector<double> v(20000), h(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    h[i] = 0.5 + 2.5 * rng.uniform();
    const double t = rng.exponential();
    v[i] = t <= h[i] ? t : kNaN;
  }
  const KaplanMeier km = calc_kaplan_meier(v, h);
  for (double t : {0.25, 0.5, 1.0, 2.0}) EXPECT_NEAR(calc_km_survival(km, t), std::exp(-t), 0.015) << "t = " << t;
  // Median ln 2, restricted mean up to 2.5: 1 - exp(-2.5).
  EXPECT_NEAR(calc_km_percentile(km, 50), std::log(2.0), 0.03);
  EXPECT_NEAR(calc_km_restricted_mean(km, 2.5), 1.0 - std::exp(-2.5), 0.03);
  // Survivors only would put the median well below ln 2.
  EXPECT_LT(calc_summary(v).p50, 0.6);
}

TEST(Censoring, PercentileAboveTheSettledFractionIsReportedCensored) {
  // 10 runs: 7 settled, 3 not settled at a common horizon 8: p5 and p50 are numbers, p95 and max "> 8".
  const std::vector<double> v = {1, 2, kNaN, 3, 4, kNaN, 5, 6, kNaN, 7};
  const std::vector<double> h(10, 8.0);
  const Summary s = calc_summary(v, h);
  EXPECT_EQ(s.count, 7);
  EXPECT_EQ(s.censored, 3);
  EXPECT_EQ(s.missing, 0);
  EXPECT_EQ(s.horizon, 8.0);
  EXPECT_EQ(s.min, 1.0);
  EXPECT_EQ(s.p5, 1.0);
  EXPECT_EQ(s.p50, 5.0);  // 5 of 10 at or below 5
  EXPECT_EQ(s.p95, kInf);
  EXPECT_EQ(s.max, kInf);
  EXPECT_TRUE(std::isnan(s.std));
  EXPECT_NEAR(s.mean, (28.0 + 3 * 8.0) / 10.0, 1e-12);  // restricted mean: not-settled runs count as 8
  const KaplanMeier km = calc_kaplan_meier(v, h);
  EXPECT_EQ(calc_km_percentile(km, 70), 7.0);   // exactly the settled fraction: still a number
  EXPECT_EQ(calc_km_percentile(km, 70.5), kInf);
  // The bootstrap of p95 is above the horizon at both ends; that of p50 is finite.
  const Interval p95 = calc_bootstrap_percentile(v, h, 95, 200, 0.95, 1);
  EXPECT_EQ(p95.estimate, kInf);
  EXPECT_EQ(p95.upper, kInf);
  const Interval p50 = calc_bootstrap_percentile(v, h, 50, 200, 0.95, 1);
  EXPECT_EQ(p50.estimate, 5.0);
  EXPECT_LE(p50.lower, 5.0);
  // Every run not settled: everything but the mean (= the horizon) lies above it.
  const Summary none = calc_summary({kNaN, kNaN}, {4.0, 4.0});
  EXPECT_EQ(none.count, 0);
  EXPECT_EQ(none.censored, 2);
  EXPECT_EQ(none.mean, 4.0);
  EXPECT_EQ(none.min, kInf);
  EXPECT_EQ(none.p50, kInf);
}

TEST(Censoring, UncensoredSampleGivesTheUncensoredStatisticsExactly) {
  TestRng rng{8};
  std::vector<double> v(300), h(300, 10.0);
  for (double& x : v) x = rng.exponential();
  v[17] = kNaN;  // no horizon: missing
  h[17] = kNaN;
  const Summary a = calc_summary(v, h), b = calc_summary(v);
  EXPECT_TRUE(same_bits(a.mean, b.mean) && same_bits(a.p95, b.p95) && same_bits(a.std, b.std));
  EXPECT_EQ(a.missing, 1);
  EXPECT_EQ(a.censored, 0);
  const Interval m1 = calc_bootstrap_mean(v, h, 100, 0.95, 5), m2 = calc_bootstrap_mean(v, 100, 0.95, 5);
  EXPECT_TRUE(same_bits(m1.lower, m2.lower) && same_bits(m1.upper, m2.upper));
  const Interval q1 = calc_bootstrap_percentile(v, h, 90, 100, 0.95, 5), q2 = calc_bootstrap_percentile(v, 90, 100, 0.95, 5);
  EXPECT_TRUE(same_bits(q1.lower, q2.lower) && same_bits(q1.upper, q2.upper));
}

TEST(Censoring, BootstrapResamplesCensoredEntriesDeterministically) {
  // Half the runs censored at varying horizons: the same seed gives the same bits, another seed another interval.
  TestRng rng{4242};
  std::vector<double> v(400), h(400);
  for (std::size_t i = 0; i < v.size(); ++i) {
    h[i] = 1.0 + rng.uniform();
    const double t = 2.0 * rng.exponential();
    v[i] = t <= h[i] ? t : kNaN;
  }
  const Interval a = calc_bootstrap_mean(v, h, 300, 0.95, 11), b = calc_bootstrap_mean(v, h, 300, 0.95, 11);
  EXPECT_TRUE(same_bits(a.lower, b.lower) && same_bits(a.upper, b.upper));
  const Interval c = calc_bootstrap_mean(v, h, 300, 0.95, 12);
  EXPECT_FALSE(same_bits(a.lower, c.lower) && same_bits(a.upper, c.upper));
  EXPECT_LT(a.lower, a.estimate);
  EXPECT_GT(a.upper, a.estimate);
  EXPECT_LE(a.upper, calc_summary(v, h).horizon);  // a restricted mean never exceeds its horizon
  // Dropping the censored runs (the old way) moves the interval down, clear of this one.
  EXPECT_LT(calc_bootstrap_mean(v, 300, 0.95, 11).upper, a.lower);
  // Errors at the boundary: mismatched lengths, bad p, resamples, confidence.
  EXPECT_THROW(calc_summary(v, {1.0}), std::invalid_argument);
  EXPECT_THROW(calc_bootstrap_percentile(v, h, 101, 10, 0.95, 1), std::invalid_argument);
  EXPECT_THROW(calc_bootstrap_mean(v, h, 0, 0.95, 1), std::invalid_argument);
  EXPECT_THROW(calc_bootstrap_mean(v, h, 10, 1.0, 1), std::invalid_argument);
  EXPECT_THROW(calc_km_percentile(calc_kaplan_meier(v, h), -1), std::invalid_argument);
  EXPECT_TRUE(std::isnan(calc_km_percentile(calc_kaplan_meier({}, {}), 50)));
}

TEST(Censoring, RequirementCountsNotSettledAsMissesOverAllRuns) {
  // P(settling <= 3) over 10 runs: 4 settled within 3 s, 2 settled later, 3 not settled (> 8) and one
  // diverged (no value): 6 misses of 10, and the Wilson interval is over all 10.
  const std::vector<double> v = {1.0, 2.5, 3.0, 0.5, 4.0, 7.9, kNaN, kNaN, kNaN, kNaN};
  const Interval m = calc_miss_probability(v, 3.0, 0.95);
  EXPECT_DOUBLE_EQ(m.estimate, 0.6);
  // Wilson 6 of 10 at 95 %: [0.3127, 0.8318].
  EXPECT_NEAR(m.lower, 0.3126737697, 1e-9);  // the mirror of 4 of 10 in MissProbabilityCountsNanAsMiss
  EXPECT_NEAR(m.upper, 0.8318196703, 1e-9);
  // A limit above every horizon still counts not settled as a miss: the run could not confirm it.
  EXPECT_DOUBLE_EQ(calc_miss_probability(v, 100.0, 0.95).estimate, 0.4);
}

}  // namespace
}  // namespace ff
