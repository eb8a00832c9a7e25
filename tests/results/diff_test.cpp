// results/diff.cpp: which input keys changed, whether a metric's move is beyond Monte Carlo noise (the
// bootstrap's false-alarm rate on two samples of one distribution, the power pairing gives), the
// censored comparison at a common horizon, and what a diff calls a regression.
#include "results/diff.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "test_rng.hpp"
#include "tests/docs_tables.hpp"

namespace ff {
namespace {

const double kNaN = std::nan("");

// A table of n variants (eval_id i, seed 1000 + i, parameter i) with one metric "m_x" = values[i].
ResultTable one_metric(const std::vector<double>& values, const std::string& name = "m_x") {
  ResultTable t;
  t.params = {"p"};
  t.columns = {name};
  for (std::size_t i = 0; i < values.size(); ++i)
    t.rows.push_back({static_cast<int>(i), 1000u + i, "v" + std::to_string(i), std::isnan(values[i]) ? "nonfinite" : "ok",
                      {static_cast<double>(i)}, {values[i]}});
  return t;
}

// n standard normal draws (Box-Muller on the test's own generator).
std::vector<double> normals(std::uint64_t seed, int n, double mean = 0.0) {
  test::TestRng rng{seed};
  std::vector<double> x;
  for (int i = 0; i < n; ++i) {
    const double u = 1.0 - rng.uniform(), v = rng.uniform();
    x.push_back(mean + std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * M_PI * v));
  }
  return x;
}

TEST(DiffYaml, ChangedAddedAndRemovedKeysAreNamedByTheirPath) {
  const auto keys = diff_yaml_text("beam: {length: 4.1, damping: 0.01}\nmoves:\n  - {to: 0.5}\n  - {to: 1.0}\naxis: [0, 0, 1]\n",
                                   "beam: {length: 4.1, damping: 0.02}\nmoves:\n  - {to: 0.5}\n  - {to: 1.5}\naxis: [0, 1, 0]\n"
                                   "payload: {mass: 300}\n");
  ASSERT_EQ(keys.size(), 4u);
  EXPECT_EQ(keys[0].key, "axis");
  EXPECT_EQ(keys[0].a, "[0, 0, 1]");
  EXPECT_EQ(keys[0].b, "[0, 1, 0]");
  EXPECT_EQ(keys[1].key, "beam.damping");
  EXPECT_EQ(keys[2].key, "moves[1].to");
  EXPECT_EQ(keys[2].b, "1.5");
  EXPECT_EQ(keys[3].key, "payload.mass");
  EXPECT_EQ(keys[3].a, "");  // absent before
  EXPECT_TRUE(diff_yaml_text("a: 1\n", "a: 1\n").empty());
  // Comments and layout are not keys.
  EXPECT_TRUE(diff_yaml_text("a: 1  # one\n", "a:    1\n").empty());
}

TEST(MetricChange, IdenticalRunsAreIdenticalAndNotBeyondNoise) {
  const ResultTable a = one_metric(normals(1, 100));
  const MetricChange c = compare_metric(a, a, "m_x", "mean", true, 0.95, 7);
  EXPECT_TRUE(c.identical);
  EXPECT_FALSE(c.beyond_noise);
  EXPECT_EQ(c.change, 0.0);
}

TEST(MetricChange, PairingSeesAShiftOfEveryVariantThatTheUnpairedTestCannot) {
  // b = a + 0.05 variant by variant: the paired change is exactly 0.05 in every resample; unpaired, the
  // spread of N(0, 1) over 200 values (se of the difference sqrt(2/200) = 0.1) hides it.
  std::vector<double> x = normals(2, 200), y = x;
  for (double& v : y) v += 0.05;
  const ResultTable a = one_metric(x), b = one_metric(y);
  ASSERT_TRUE(same_variants(a, b));
  const MetricChange paired = compare_metric(a, b, "m_x", "mean", true, 0.95, 7);
  EXPECT_NEAR(paired.change, 0.05, 1e-12);
  EXPECT_NEAR(paired.lower, 0.05, 1e-12);
  EXPECT_NEAR(paired.upper, 0.05, 1e-12);
  EXPECT_TRUE(paired.beyond_noise);
  const MetricChange unpaired = compare_metric(a, b, "m_x", "mean", false, 0.95, 7);
  EXPECT_NEAR(unpaired.change, 0.05, 1e-12);
  EXPECT_LT(unpaired.lower, 0.0);
  EXPECT_GT(unpaired.upper, 0.0);
  EXPECT_FALSE(unpaired.beyond_noise);
  // The unpaired interval's half-width is about 1.96 x 0.1.
  EXPECT_NEAR(0.5 * (unpaired.upper - unpaired.lower), 1.96 * std::sqrt(2.0 / 200.0), 0.05);
}

TEST(MetricChange, TwoSamplesOfOneDistributionAreCalledBeyondNoiseAboutOneTimeInTwenty) {
  // 300 pairs of independent samples (n = 100) of one exponential distribution: the 95 % interval of the
  // change in the mean, and of the p50, should exclude 0 in about 5 % of them (15, binomial sd 3.8).
  for (const char* stat : {"mean", "p50"}) {
    int alarms = 0;
    for (int k = 0; k < 300; ++k) {
      test::TestRng rng{static_cast<std::uint64_t>(9000 + k)};
      std::vector<double> x, y;
      for (int i = 0; i < 100; ++i) x.push_back(rng.exponential());
      for (int i = 0; i < 100; ++i) y.push_back(rng.exponential());
      alarms += compare_metric(one_metric(x), one_metric(y), "m_x", stat, false, 0.95, 11 + k).beyond_noise;
    }
    EXPECT_GE(alarms, 6) << stat;   // 2 %
    EXPECT_LE(alarms, 27) << stat;  // 9 %
  }
}

TEST(MetricChange, NotSettledRunsCountAtTheSmallerOfTheTwoLeastHorizons) {
  // Settling times with horizons: a has one not settled at 8 s, b one at 6 s; tau = 6: a's 7 s becomes 6.
  auto table = [](std::vector<double> settle, std::vector<double> horizon) {
    ResultTable t;
    t.params = {"p"};
    t.columns = {"m1_tip_settling_s", "m1_settling_horizon_s"};
    for (std::size_t i = 0; i < settle.size(); ++i)
      t.rows.push_back({static_cast<int>(i), i, "v", "ok", {0.0}, {settle[i], horizon[i]}});
    return t;
  };
  const ResultTable a = table({1, 7, kNaN, 3}, {8, 8, 8, 8});
  const ResultTable b = table({1, 2, 3, kNaN}, {9, 9, 9, 6});
  const MetricChange c = compare_metric(a, b, "m1_tip_settling_s", "mean", true, 0.95, 3);
  EXPECT_DOUBLE_EQ(c.horizon, 6.0);
  EXPECT_DOUBLE_EQ(c.a, (1 + 6 + 6 + 3) / 4.0);
  EXPECT_DOUBLE_EQ(c.b, (1 + 2 + 3 + 6) / 4.0);
  EXPECT_EQ(c.n_a, 4);
  // The share not settled: one of four in each.
  const MetricChange share = compare_metric(a, b, "m1_tip_settling_s", "not_settled", true, 0.95, 3);
  EXPECT_DOUBLE_EQ(share.a, 0.25);
  EXPECT_DOUBLE_EQ(share.b, 0.25);
  EXPECT_EQ(describe_statistic(share), "share not settled");
  // A diff of the two lists the mean and, the metric being censored, the share not settled.
  RunDir ra, rb;
  ra.table = a;
  rb.table = b;
  const RunDiff d = diff_runs(ra, rb, {});
  ASSERT_GE(d.metrics.size(), 2u);
  EXPECT_EQ(d.metrics[0].statistic, "mean");
  EXPECT_EQ(d.metrics[1].statistic, "not_settled");
}

TEST(MetricChange, DivergedVariantsAreLeftOutOfBothSidesWhenPaired) {
  const MetricChange c = compare_metric(one_metric({1, kNaN, 3, 4}), one_metric({2, 5, kNaN, 5}), "m_x", "mean", true, 0.95, 3);
  EXPECT_EQ(c.n_a, 2);  // variants 0 and 3
  EXPECT_DOUBLE_EQ(c.a, 2.5);
  EXPECT_DOUBLE_EQ(c.b, 3.5);
}

TEST(MetricChange, TheMissProbabilityCountsRowsAboveTheSpecAndRowsWithoutAValue) {
  // Spec 3: a misses at 4 and the diverged row (2 of 4), b at 5, 5 and the diverged row (3 of 4).
  const MetricChange c =
      compare_metric(one_metric({1, 2, kNaN, 4}), one_metric({5, 5, 3, kNaN}), "m_x", "p_miss", true, 0.95, 3, 3.0);
  EXPECT_DOUBLE_EQ(c.a, 0.5);
  EXPECT_DOUBLE_EQ(c.b, 0.75);
  EXPECT_EQ(c.n_a, 4);  // every row counts
  EXPECT_EQ(describe_statistic(c), "P(miss: > 3 or no value)");
}

RunDir run_of(const ResultTable& t, const std::string& model_text, std::vector<Verdict> verdicts = {}) {
  RunDir d;
  d.table = t;
  d.record.model_text = model_text;
  d.record.study_text = "model: m.yaml\n";
  d.record.variants = static_cast<int>(t.rows.size());
  d.record.status = count_statuses(t);
  d.record.verdicts = std::move(verdicts);
  return d;
}

TEST(RunDiff, AToleratedMetricThatRoseBeyondItsToleranceAndNoiseIsARegression) {
  const std::vector<double> x = normals(5, 300, 10.0);
  std::vector<double> small = x, large = x;
  for (double& v : small) v += 0.01;  // beyond noise (paired) but within a tolerance of 0.05
  for (double& v : large) v += 0.2;   // beyond both
  Tolerance tol;
  tol.metric = "m_x";
  tol.increase = 0.05;
  const RunDir a = run_of(one_metric(x), "k: 1\n");
  const RunDiff within = diff_runs(a, run_of(one_metric(small), "k: 1\n"), {tol});
  ASSERT_EQ(within.metrics.size(), 1u);
  EXPECT_TRUE(within.metrics[0].beyond_noise);
  EXPECT_FALSE(within.metrics[0].regression);
  EXPECT_TRUE(within.regressions.empty());
  EXPECT_NE(format_diff_md(within).find("Nothing got worse."), std::string::npos);

  const RunDiff worse = diff_runs(a, run_of(one_metric(large), "k: 2\n"), {tol});
  EXPECT_TRUE(worse.paired);
  ASSERT_EQ(worse.model.size(), 1u);
  EXPECT_EQ(worse.model[0].key, "k");
  ASSERT_EQ(worse.regressions.size(), 1u);
  EXPECT_NE(worse.regressions[0].find("m_x: mean rose"), std::string::npos) << worse.regressions[0];
  // A relative tolerance: 0.2 on a mean of about 10 is 2 %, inside 5 % and beyond 1 %.
  tol.increase = 0.05;
  tol.increase_relative = true;
  EXPECT_TRUE(diff_runs(a, run_of(one_metric(large), "k: 2\n"), {tol}).regressions.empty());
  tol.increase = 0.01;
  EXPECT_EQ(diff_runs(a, run_of(one_metric(large), "k: 2\n"), {tol}).regressions.size(), 1u);
  // A fall is no regression for an increase tolerance.
  EXPECT_TRUE(diff_runs(run_of(one_metric(large), ""), a, {tol}).regressions.empty());
}

TEST(RunDiff, MoreFailedVariantsAndAWorseVerdictAreRegressions) {
  // Verdicts as each run recorded them (no requirements given to the diff).
  const auto verdict = [](const char* requirement, const char* v) {
    Verdict x;
    x.requirement = requirement;
    x.verdict = v;
    return x;
  };
  const RunDir a = run_of(one_metric({1, 2, 3}), "", {verdict("P(m_x <= 3) >= 0.9", "pass"), verdict("mean(m_x) <= 5", "undecided")});
  const RunDir b = run_of(one_metric({1, kNaN, 3}), "", {verdict("P(m_x <= 3) >= 0.9", "undecided"), verdict("mean(m_x) <= 5", "pass")});
  const RunDiff d = diff_runs(a, b, {});
  ASSERT_EQ(d.verdicts.size(), 2u);
  EXPECT_TRUE(d.verdicts[0].worse);
  EXPECT_FALSE(d.verdicts[1].worse);
  ASSERT_EQ(d.regressions.size(), 2u);
  EXPECT_NE(d.regressions[0].find("requirement P(m_x <= 3) >= 0.9: pass before, undecided now"), std::string::npos);
  EXPECT_NE(d.regressions[1].find("failed variants (nonfinite, solver_fail, invalid) rose from 0 to 1"), std::string::npos);
}

TEST(Tolerances, AreReadWithTheirDirectionAndStatisticAndBadOnesNameTheLine) {
  auto read = [](const std::string& yaml) {
    YamlReader top(load_yaml_text(yaml, "study.yaml"), "study.yaml", "", nullptr);
    return read_tolerances(top);
  };
  const auto t = read("tolerances:\n  m1_tip_settling_s: {increase: 0.05}\n  min_clearance_m: {decrease: 5%, statistic: p5}\n");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t[0].increase, 0.05);
  EXPECT_TRUE(std::isnan(t[0].decrease));
  EXPECT_EQ(t[0].statistic, "mean");
  EXPECT_DOUBLE_EQ(t[1].decrease, 0.05);
  EXPECT_TRUE(t[1].decrease_relative);
  EXPECT_EQ(t[1].statistic, "p5");
  EXPECT_EQ(t[1].describe(), "p5 decrease > 5 %");
  const std::pair<const char*, const char*> bad[] = {
      {"tolerances:\n  m: {increase: fast}\n", "study.yaml:2: tolerances.m.increase: expected an amount"},
      {"tolerances:\n  m: {statistic: p99, increase: 1}\n", "study.yaml:2: tolerances.m.statistic: expected mean, p5, p50, p95, p_miss or not_settled"},
      {"tolerances:\n  m: {}\n", "tolerances.m"},
      {"tolerances:\n  m: {increse: 1}\n", "study.yaml:2: tolerances.m.increse: unknown key (did you mean `increase`?)"},
      {"tolerances:\n  m: {increase: -1}\n", "tolerances.m.increase: expected an amount >= 0"},
  };
  for (const auto& [yaml, message] : bad) {
    try {
      read(yaml);
      ADD_FAILURE() << "no error for " << yaml;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

TEST(Tolerances, TheirKeysAreDocumented) { test::expect_documented("Study tolerances", tolerance_keys()); }

}  // namespace
}  // namespace ff
