// results/table.cpp: the per-run Markdown table writes a move that did not settle with its horizon;
// the results CSV reads back what it wrote, and refuses a malformed line naming it.
#include "results/table.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace ff {
namespace {

const double kNaN = std::nan("");

// What parse_results_csv says of `text`, which it must refuse.
std::string parse_error(const std::string& text) {
  try {
    parse_results_csv(text, "results.csv");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  ADD_FAILURE() << "read: " << text;
  return "";
}

TEST(Table, SettlingTableShowsTheHorizonOfANotSettledMove) {
  ResultTable t;
  t.columns = {"m1_tip_settling_s", "m1_tip_overshoot_pct", "m1_hub_settling_s", "m1_hub_overshoot_pct",
               "m1_peak_tip_deflection_m", "m1_residual_vibration_m", "m1_peak_torque_Nm", "m1_settling_horizon_s"};
  t.rows.resize(2);
  t.rows[0].label = "PD";
  t.rows[0].values = {kNaN, 38.0, 1.5, 6.7, 0.66, 0.62, 3880, 3.35};
  t.rows[1].label = "no horizon";
  t.rows[1].values = {kNaN, 38.0, kNaN, 6.7, 0.66, 0.62, 3880, kNaN};  // e.g. a diverged run: no value (#32.12)
  const std::string md = format_settling_table_md(t, {{"0 -> 0.5 rad"}, {"0 -> 0.5 rad"}});
  EXPECT_NE(md.find("| PD | 0 -> 0.5 rad | > 3.35 (not settled) | 38.0 | 1.50 | 6.7 | 660.0 | 620.00 | 3.88 |"),
            std::string::npos) << md;
  EXPECT_NE(md.find("| no horizon | 0 -> 0.5 rad | - | 38.0 | - |"), std::string::npos) << md;
  EXPECT_EQ(format_metric_cell(kNaN, 2.5, "%.2f"), "> 2.50 (not settled)");
  EXPECT_EQ(format_metric_cell(kNaN, kNaN), "-");
  EXPECT_EQ(format_metric_cell(1.25, 2.5), "1.25");
}

// fuzz_results: the header `...,m1",` opened a quote it never closed, so its last column read as
// `m1,`; the table written from it (names unquoted) read back as two columns.
TEST(Table, ResultsCsvWithAQuoteLeftOpenIsRefusedNamingTheLine) {
  EXPECT_EQ(parse_error("eval_id,seed,label,status,m1\",\n"), "results.csv:1: header: a quote is not closed");
  EXPECT_EQ(parse_error("eval_id,seed,label,status,m1_x\n0,1,\"PD,ok\n"), "results.csv:2: row: a quote is not closed");
}

TEST(Table, NamesAndStatusWithCommasAndQuotesReadBackTheSame) {
  ResultTable t;
  t.params = {"a,b"};
  t.columns = {"m1_\"x\"", "m1_y,z"};
  t.rows.resize(1);
  t.rows[0].eval_id = 3;
  t.rows[0].seed = 18446744073709551615ull;
  t.rows[0].label = "PD, \"n\" = 2";
  t.rows[0].status = "not,settled";
  t.rows[0].params = {0.1};
  t.rows[0].values = {kNaN, -2.5e-300};
  const std::string csv = format_results_csv(t);
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "eval_id,seed,label,status,\"a,b\",\"m1_\"\"x\"\"\",\"m1_y,z\"");
  const ResultTable back = parse_results_csv(csv, "results.csv");
  EXPECT_EQ(back.params, t.params);
  EXPECT_EQ(back.columns, t.columns);
  ASSERT_EQ(back.rows.size(), 1u);
  EXPECT_EQ(back.rows[0].eval_id, 3);
  EXPECT_EQ(back.rows[0].seed, t.rows[0].seed);
  EXPECT_EQ(back.rows[0].label, t.rows[0].label);
  EXPECT_EQ(back.rows[0].status, "not,settled");
  EXPECT_EQ(back.rows[0].params, t.rows[0].params);
  ASSERT_EQ(back.rows[0].values.size(), 2u);
  EXPECT_TRUE(std::isnan(back.rows[0].values[0]));
  EXPECT_EQ(back.rows[0].values[1], -2.5e-300);
}

// fuzz_results: `eval_id,seed,label,status,,m1,` filed the unnamed column after m1 as a parameter
// while its cells went to the metrics; written back, the header's columns moved.
TEST(Table, ResultsCsvColumnWithoutANameIsRefused) {
  EXPECT_EQ(parse_error("eval_id,seed,label,status,,m1,\n9,9,,,,,\n"), "results.csv:1: header: column 5 has no name");
}

TEST(Table, ResultsCsvWithAByteOrderMarkReadsAndTwoColumnsOfOneNameAreRefused) {
  const ResultTable t = parse_results_csv("\xEF\xBB\xBF" "eval_id,seed,label,status,p,m1_a\n3,9,,ok,1,2\n", "results.csv");
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.rows[0].eval_id, 3);
  EXPECT_EQ(t.rows[0].values, std::vector<double>({2.0}));
  EXPECT_EQ(parse_error("eval_id,seed,label,status,m1_a,m1_b,m1_a\n0,1,,ok,1,2,3\n"),
            "results.csv:1: m1_a: columns 5 and 7 are both named 'm1_a': each column needs its own name");
}

TEST(Table, ResultsCsvEvalIdAndSeedAreWholeIntegersInRange) {
  EXPECT_EQ(parse_error("eval_id,seed,label,status,m1_a\n99999999999,1,,ok,1\n"),
            "results.csv:2: eval_id: '99999999999' is not an eval_id (an integer from 0)");
  EXPECT_EQ(parse_error("eval_id,seed,label,status,m1_a\n12abc,1,,ok,1\n"),
            "results.csv:2: eval_id: '12abc' is not an eval_id (an integer from 0)");
  EXPECT_EQ(parse_error("eval_id,seed,label,status,m1_a\n0,-1,,ok,1\n"),
            "results.csv:2: seed: '-1' is not a seed (an unsigned 64-bit integer)");
  EXPECT_EQ(parse_results_csv("eval_id,seed,label,status,m1_a\n0,18446744073709551615,,ok,1\n", "r").rows[0].seed,
            18446744073709551615ull);
}

TEST(Table, EveryColumnFromTheFirstMetricOnIsAMetric) {
  const ResultTable t = parse_results_csv("eval_id,seed,label,status,p,m1_a,q\n9,9,,,1,2,3\n", "results.csv");
  EXPECT_EQ(t.params, std::vector<std::string>({"p"}));
  EXPECT_EQ(t.columns, std::vector<std::string>({"m1_a", "q"}));
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.rows[0].params, std::vector<double>({1.0}));
  EXPECT_EQ(t.rows[0].values, std::vector<double>({2.0, 3.0}));
  EXPECT_EQ(format_results_csv(t), "eval_id,seed,label,status,p,m1_a,q\n9,9,,,1,2,3\n");
}

}  // namespace
}  // namespace ff
