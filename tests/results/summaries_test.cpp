// results/summaries.cpp: group-by and Monte Carlo tables of a result table whose settling times are
// right-censored at their horizons (not settled), and what they print for them.
#include "results/summaries.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>


namespace ff {
namespace {

const double kNaN = std::nan("");

// 10 runs of one move: tip settling 1..7 s, three not settled (NaN) with horizon 8 s; overshoot 1..10 %.
ResultTable censored_table(bool with_horizon = true) {
  ResultTable t;
  t.params = {"x"};
  t.columns = {"m1_tip_settling_s", "m1_tip_overshoot_pct"};
  if (with_horizon) t.columns.push_back("m1_settling_horizon_s");
  const double settle[] = {1, 2, kNaN, 3, 4, kNaN, 5, 6, kNaN, 7};
  for (int i = 0; i < 10; ++i) {
    ResultRow r;
    r.eval_id = i;
    r.label = "run " + std::to_string(i);
    r.status = std::isnan(settle[i]) ? "not_settled" : "ok";
    r.params = {static_cast<double>(i % 2)};
    r.values = {settle[i], i + 1.0};
    if (with_horizon) r.values.push_back(8.0);
    t.rows.push_back(r);
  }
  return t;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

TEST(Summaries, MonteCarloTableReportsNotSettledAboveTheHorizon) {
  const std::string md = format_monte_carlo_md(censored_table(), {"m1_tip_settling_s", "m1_tip_overshoot_pct"},
                                               {{"m1_tip_settling_s", 3.0}}, 7);
  const auto lines = lines_of(md);
  ASSERT_GE(lines.size(), 4u) << md;
  const std::string& settle = lines[2];
  EXPECT_EQ(settle.rfind("| m1_tip_settling_s | 10 | 3 (horizon 8 s) | 0 | 5.2 [", 0), 0u) << settle;
  EXPECT_NE(settle.find("restricted to 8 s"), std::string::npos) << settle;
  // p5 and p50 are numbers, p95 lies above the horizon; 7 of 10 miss "<= 3" (4, 5, 6, 7 and the 3 not settled).
  EXPECT_NE(settle.find("| 1 ["), std::string::npos) << settle;
  EXPECT_NE(settle.find("| 5 ["), std::string::npos) << settle;
  EXPECT_NE(settle.find("| > 8 (not settled) | <= 3 | 0.700 ["), std::string::npos) << settle;
  // Overshoot has no horizon: no censoring, its usual numbers; a note explains the censored row.
  EXPECT_EQ(lines[3].rfind("| m1_tip_overshoot_pct | 10 | 0 | 0 | 5.5 [", 0), 0u) << lines[3];
  EXPECT_NE(md.find("restricted mean up to the largest horizon"), std::string::npos) << md;
}

TEST(Summaries, GroupByCsvKeepsNumbersAndNamesTheCensoredStatistics) {
  const std::string csv = format_groupby_csv(censored_table(), {}, {"m1_tip_settling_s", "m1_tip_overshoot_pct"},
                                             {{"m1_tip_settling_s", 3.0}});
  const auto lines = lines_of(csv);
  ASSERT_EQ(lines.size(), 3u) << csv;
  EXPECT_EQ(lines[0],
            "metric,count,\"not settled\",missing,horizon,mean,min,p5,p50,p95,max,\"P(miss spec)\",\"95% CI\",censored");
  // p95 and max hold the horizon 8; the `censored` cell says which cells are bounds (and that the mean is restricted).
  EXPECT_EQ(lines[1].rfind("m1_tip_settling_s,7,3,0,8,5.2,1,1,5,8,8,0.700,", 0), 0u) << lines[1];
  EXPECT_EQ(lines[1].substr(lines[1].rfind(',') + 1), "\"mean p95 max\"") << lines[1];
  EXPECT_EQ(lines[2].rfind("m1_tip_overshoot_pct,10,0,0,,5.5,1,", 0), 0u) << lines[2];
  EXPECT_EQ(lines[2].back(), ',') << "nothing censored: an empty last cell; " << lines[2];
}

TEST(Summaries, GroupByMarkdownShowsBoundsPerGroup) {
  // Group x = 0 holds runs 0, 2, 4, 6, 8: settled 1, 4, 5, censored 2 of 5 (mean 0.2 (1 + 4 + 5) + 0.4 x 8).
  const std::string md = format_groupby_md(censored_table(), {"x"}, {"m1_tip_settling_s"}, {});
  const auto lines = lines_of(md);
  ASSERT_EQ(lines.size(), 4u) << md;
  EXPECT_EQ(lines[0], "| x | metric | count | not settled | missing | horizon | mean | min | p5 | p50 | p95 | max | "
                      "P(miss spec) | 95% CI |");
  EXPECT_EQ(lines[2].rfind("| 0 | m1_tip_settling_s | 3 | 2 | 0 | 8 | > 5.2 | 1 | 1 | 5 | > 8 | > 8 |", 0), 0u) << lines[2];
}

// (#32.11) The mean of a group with runs not settled is the restricted mean, a lower bound: "> x" in
// Markdown, never a bare number beside "> H" (an all-censored group's mean is its horizon); a group that
// settled keeps its plain mean; CSV keeps the number and names it in `censored`.
TEST(Summaries, TheMeanOfAGroupWithRunsNotSettledIsALowerBound) {
  ResultTable t;
  t.params = {"x"};
  t.columns = {"m1_tip_settling_s", "m1_settling_horizon_s"};
  t.rows.push_back({0, 0, "a", "not_settled", {0}, {kNaN, 3.791}});
  t.rows.push_back({1, 0, "b", "not_settled", {0}, {kNaN, 3.791}});
  t.rows.push_back({2, 0, "c", "ok", {1}, {2.0, 3.791}});
  t.rows.push_back({3, 0, "d", "ok", {1}, {3.0, 3.791}});
  const auto lines = lines_of(format_groupby_md(t, {"x"}, {"m1_tip_settling_s"}, {}));
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[2].rfind("| 0 | m1_tip_settling_s | 0 | 2 | 0 | 3.791 | > 3.791 | > 3.791 | > 3.791 |", 0), 0u) << lines[2];
  EXPECT_EQ(lines[3].rfind("| 1 | m1_tip_settling_s | 2 | 0 | 0 | - | 2.5 | 2 |", 0), 0u) << lines[3];
  const auto csv = lines_of(format_groupby_csv(t, {"x"}, {"m1_tip_settling_s"}, {}));
  EXPECT_EQ(csv[1].rfind("0,m1_tip_settling_s,0,2,0,3.791,3.791,3.791,", 0), 0u) << csv[1];
  EXPECT_EQ(csv[1].substr(csv[1].rfind(',') + 1), "\"mean min p5 p50 p95 max\"") << csv[1];
}

// 40 runs, x = 1..40 (shuffled), tip settling x / 4 s except every fifth run, not settled (horizon 8 s);
// one more run with no x (NaN).
ResultTable binned_table() {
  ResultTable t;
  t.params = {"x"};
  t.columns = {"m1_tip_settling_s", "m1_settling_horizon_s"};
  for (int i = 0; i <= 40; ++i) {
    const double x = i == 40 ? kNaN : (i * 17) % 40 + 1;
    t.rows.push_back({i, 0, "run " + std::to_string(i), "ok", {x}, {i % 5 == 0 ? kNaN : x / 4, 8.0}});
  }
  return t;
}

// The cells of a Markdown or CSV line after its first `skip` (the key).
std::string after_key(const std::string& line, const std::string& sep, int skip) {
  std::size_t at = sep == " | " ? 2 : 0;
  for (int i = 0; i < skip; ++i) at = line.find(sep, at) + sep.size();
  return line.substr(at);
}

TEST(Summaries, GroupByBinsAColumnWithManyValuesAndEachBinSummarisesItsRows) {
  // 4 quantile bins of x = 1..40: edges 1, 10.75, 20.5, 30.25, 40; NaN its own group, last.
  const ResultTable t = binned_table();
  const std::string md = format_groupby_md(t, {"x"}, {"m1_tip_settling_s"}, {{"m1_tip_settling_s", 5.0}}, {4});
  const auto lines = lines_of(md);
  ASSERT_EQ(lines.size(), 9u) << md;
  const char* keys[] = {"[1, 10.75)", "[10.75, 20.5)", "[20.5, 30.25)", "[30.25, 40]", "-"};
  for (int b = 0; b < 5; ++b) EXPECT_EQ(lines[2 + b].rfind(std::string("| ") + keys[b] + " | m1_tip_settling_s | ", 0), 0u) << lines[2 + b];
  EXPECT_EQ(lines[8], "Binned: x (40 values) in 4 quantile bins (about equal numbers of rows); [a, b) holds a <= value < b, "
                      "the last bin [a, b] its upper end too.");
  // The same rows grouped by hand (x replaced by its bin, 0..3): the same censored statistics.
  ResultTable by_hand = t;
  for (auto& r : by_hand.rows)
    if (!std::isnan(r.params[0])) r.params[0] = std::floor((r.params[0] - 1) / 10);
  const auto hand = lines_of(format_groupby_md(by_hand, {"x"}, {"m1_tip_settling_s"}, {{"m1_tip_settling_s", 5.0}}, {0}));
  ASSERT_EQ(hand.size(), 7u);
  for (int g = 2; g < 7; ++g) EXPECT_EQ(after_key(lines[g], " | ", 1), after_key(hand[g], " | ", 1)) << g;
  // The first bin: 8 settled (0.5..2.5 s), 2 not settled.
  EXPECT_EQ(after_key(lines[2], " | ", 1).rfind("m1_tip_settling_s | 8 | 2 | 0 | 8 |", 0), 0u) << lines[2];
  // Binning off, or a column with few values: one group per value, and no note.
  EXPECT_EQ(lines_of(format_groupby_md(t, {"x"}, {"m1_tip_settling_s"}, {}, {0})).size(), 43u);
  EXPECT_EQ(lines_of(format_groupby_md(t, {"x"}, {"m1_tip_settling_s"}, {}, {40})).size(), 43u);
  EXPECT_EQ(lines_of(format_groupby_md(t, {"x"}, {"m1_tip_settling_s"}, {})).size(), 15u) << "10 bins by default";
}

TEST(Summaries, GroupByCsvGivesABinItsIntervalAndItsEdges) {
  const ResultTable t = binned_table();
  const std::string csv = format_groupby_csv(t, {"x"}, {"m1_tip_settling_s"}, {}, {4, Binning::kWidth});
  const auto lines = lines_of(csv);
  ASSERT_EQ(lines.size(), 6u) << csv;
  EXPECT_EQ(lines[0].rfind("x,x_lo,x_hi,metric,count,", 0), 0u) << lines[0];
  // Equal width over 1..40: edges 1, 10.75, 20.5, 30.25, 40 too (the values are evenly spread).
  EXPECT_EQ(lines[1].rfind("\"[1, 10.75)\",1,10.75,m1_tip_settling_s,8,2,0,8,", 0), 0u) << lines[1];
  EXPECT_EQ(lines[4].rfind("\"[30.25, 40]\",30.25,40,m1_tip_settling_s,", 0), 0u) << lines[4];
  EXPECT_EQ(lines[5].rfind(",,,m1_tip_settling_s,", 0), 0u) << "a NaN key: no interval, no edges; " << lines[5];
  // The edges are the rows' bounds to 12 digits; the interval's text has the fewest digits from 6 on
  // that tell neighbouring edges apart (here 9: 1, 1.00000001, 1.00000002, ...).
  ResultTable fine = t;
  for (auto& r : fine.rows) r.params[0] = 1 + r.params[0] * 1e-9;
  const auto fl = lines_of(format_groupby_csv(fine, {"x"}, {"m1_tip_settling_s"}, {}, {4, Binning::kWidth}));
  EXPECT_EQ(fl[1].rfind("\"[1, 1.00000001)\",1.000000001,1.00000001075,", 0), 0u) << fl[1];
  // A case is a label: never binned, however many.
  ResultTable cases = t;
  cases.params = {"case"};
  for (auto& r : cases.rows) r.label = "c" + std::to_string(r.eval_id % 12) + " | x";
  for (auto& r : cases.rows) r.params[0] = r.eval_id % 12;
  EXPECT_EQ(lines_of(format_groupby_csv(cases, {"case"}, {"m1_tip_settling_s"}, {})).size(), 13u);
}

TEST(Summaries, TableWithoutHorizonsCountsNotSettledAsMissing) {
  // A results.csv written before the horizon column: NaN stays "missing", statistics over the settled runs.
  const std::string csv = format_groupby_csv(censored_table(false), {}, {"m1_tip_settling_s"}, {});
  const auto lines = lines_of(csv);
  ASSERT_EQ(lines.size(), 2u) << csv;
  EXPECT_EQ(lines[1].rfind("m1_tip_settling_s,7,0,3,,4,1,", 0), 0u) << lines[1];
}

}  // namespace
}  // namespace ff

namespace ff {
namespace {

// min(T, tau) with tau the smallest horizon of the not-settled runs: known for every run.
TEST(Summaries, RestrictedResponseIsKnownForEveryRun) {
  ResultTable t;
  t.params = {"x"};
  t.columns = {"m1_tip_settling_s", "m1_settling_horizon_s"};
  const double settle[] = {1.0, kNaN, 7.5, kNaN, 3.0, kNaN};
  const double horizon[] = {9.0, 5.0, 9.0, 6.0, 9.0, kNaN};  // the last: no horizon, a diverged run
  for (int i = 0; i < 6; ++i) t.rows.push_back({i, 0, "", "", {0.0}, {settle[i], horizon[i]}});
  double tau = 0;
  const auto y = calc_restricted_values(t, "m1_tip_settling_s", &tau);
  EXPECT_EQ(tau, 5.0);
  const double want[] = {1.0, 5.0, 5.0, 5.0, 3.0};
  for (int i = 0; i < 5; ++i) EXPECT_EQ(y[i], want[i]) << i;
  EXPECT_TRUE(std::isnan(y[5])) << "a run with no value and no horizon stays unknown";
  // Nothing censored: the values themselves.
  ResultTable u = t;
  u.rows.resize(1);
  EXPECT_EQ(calc_restricted_values(u, "m1_tip_settling_s", &tau), std::vector<double>{1.0});
  EXPECT_TRUE(std::isnan(tau));
}

// Morris on a settling time T = 10 x0 that does not settle (horizon 5 s) where x0 > 0.5, and does
// not depend on x1: the restricted response min(10 x0, 5) keeps every trajectory, so x0's mu* is its
// known mean elementary effect over the grid and x1's is 0. Dropping the not-settled runs instead
// would leave only the trajectories that never cross x0 = 0.5.
TEST(Summaries, MorrisOfACensoredResponseUsesEveryRun) {
  ResultTable t;
  t.params = {"x0", "x1"};
  t.columns = {"m1_tip_settling_s", "m1_settling_horizon_s"};
  // Two trajectories on the p = 4 grid (Delta = 2/3): x0 moves 0 -> 2/3, then x1; and the reverse order.
  const std::vector<std::vector<double>> x = {{0, 0}, {2.0 / 3, 0}, {2.0 / 3, 2.0 / 3},
                                              {1.0 / 3, 0}, {1.0 / 3, 2.0 / 3}, {1, 2.0 / 3}};
  for (int i = 0; i < 6; ++i) {
    const double T = 10.0 * x[i][0];
    t.rows.push_back({i, 0, "", "", x[i], {T > 5.0 ? kNaN : T, 5.0}});
  }
  const auto idx = calc_morris_for(t, {"m1_tip_settling_s"}, x);
  ASSERT_EQ(idx.size(), 1u);
  EXPECT_EQ(idx.begin()->first, "m1_tip_settling_s (restricted to 5 s)");
  const MorrisIndices& m = idx.begin()->second;
  // Elementary effects of x0: (min(20/3, 5) - 0) / (2/3) = 7.5 and (5 - 10/3) / (2/3) = 2.5.
  EXPECT_NEAR(m.mu_star[0], 5.0, 1e-12);
  EXPECT_NEAR(m.mu_star[1], 0.0, 1e-12);
}

}  // namespace
}  // namespace ff
