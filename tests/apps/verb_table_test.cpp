// apps/verb_table.cpp: `flexfarm table` on a results.csv of a fine design (4096 distinct payload
// masses) groups the payload into about ten bins, and into one group per value with --bins 0.
#include <gtest/gtest.h>

#include "tests/apps/cli_fixture.hpp"

#include <string>

namespace {

using namespace ff::test;

class TableCli : public CliFixture {
 protected:
  TableCli() : CliFixture("ff_table_", {}) {}

  // results.csv of 4096 variants: payload.mass 0.5 + i / 4096 kg in a shuffled order, segments 1..4,
  // tip settling 1 + mass s but every seventh not settled (horizon 6 s).
  void SetUp() override {
    CliFixture::SetUp();
    std::string csv = "eval_id,seed,label,status,payload.mass,segments,m1_tip_settling_s,m1_tip_overshoot_pct,"
                      "m1_settling_horizon_s\n";
    for (int i = 0; i < 4096; ++i) {
      const double mass = 0.5 + ((i * 1237) % 4096) / 4096.0;
      const bool settled = i % 7 != 0;
      char row[256];
      std::snprintf(row, sizeof row, "%d,%d,v%d,%s,%.17g,%d,%s,%.17g,6\n", i, i, i, settled ? "ok" : "not_settled", mass,
                    1 + i % 4, settled ? std::to_string(1 + mass).c_str() : "", 2 * mass);
      csv += row;
    }
    fs::create_directories(work / "out");
    write("out/results.csv", csv);
  }

  // The lines of a Markdown table that are groups (neither header nor separator).
  static int group_lines(const Result& r, const std::string& start = "| ") {
    int n = 0;
    for (const auto& l : r.lines()) n += l.rfind(start, 0) == 0 && l.rfind("| payload.mass", 0) != 0 && l.rfind("|---", 0) != 0;
    return n;
  }
};

TEST_F(TableCli, ManyPayloadLevelsGroupIntoTenBinsAndBinsZeroListsEveryLevel) {
  const auto r = run("table out --by payload.mass --metric m1_tip_settling_s --spec m1_tip_settling_s=1.5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(group_lines(r), 10) << r.output;
  EXPECT_EQ(group_lines(r, "| [0.5, 0.599976) | "), 1) << r.output;
  EXPECT_NE(r.output.find(", 1.49976] | m1_tip_settling_s | "), std::string::npos) << "the last bin, closed; " << r.output;
  EXPECT_NE(r.output.find("Binned: payload.mass (4096 values) in 10 quantile bins"), std::string::npos) << r.output;
  // Every bin holds 409 or 410 of the 4096 runs (count + not settled).
  for (const auto& l : r.lines())
    if (l.rfind("| [", 0) == 0) {
      const std::string cells = l.substr(l.find("| m1_tip_settling_s | ") + 22);
      const int count = std::stoi(cells), censored = std::stoi(cells.substr(cells.find(" | ") + 3));
      EXPECT_TRUE(count + censored == 409 || count + censored == 410) << l;
    }

  const auto all = run("table out --by payload.mass --metric m1_tip_settling_s --bins 0");
  ASSERT_EQ(all.exit_code, 0) << all.output;
  EXPECT_EQ(group_lines(all), 4096);
  EXPECT_EQ(all.output.find("Binned"), std::string::npos);

  // Two columns: segments (4 values) as they are, the payload in 5 equal-width bins; CSV with the edges
  // (of the values to 12 digits: the largest, 1.499755859375, is 1.49975585938, so the first edge is
  // 0.5 + 0.99975585938 / 5).
  const auto two = run("table out/results.csv --by payload.mass,segments --metric m1_tip_settling_s --bins 5 "
                       "--binning width --format csv");
  ASSERT_EQ(two.exit_code, 0) << two.output;
  const auto lines = two.lines();
  ASSERT_EQ(lines.size(), 21u) << two.output;
  EXPECT_EQ(lines[0].rfind("payload.mass,payload.mass_lo,payload.mass_hi,segments,metric,count,", 0), 0u) << lines[0];
  EXPECT_EQ(lines[1].rfind("\"[0.5, 0.699951)\",0.5,0.699951171876,1,m1_tip_settling_s,", 0), 0u) << lines[1];
  EXPECT_EQ(lines[20].rfind("\"[1.2998, 1.49976]\",1.2998046875,1.49975585938,4,m1_tip_settling_s,", 0), 0u) << lines[20];
}

TEST_F(TableCli, HelpSaysWhenAColumnIsBinnedAndABadBinningIsRefused) {
  const auto help = run("table --help");
  ASSERT_EQ(help.exit_code, 0) << help.output;
  for (const char* w : {"--bins", "--binning", "more than N distinct values", "quantile", "width"})
    EXPECT_NE(help.output.find(w), std::string::npos) << w << "\n" << help.output;
  EXPECT_NE(run("table out --by payload.mass --binning median").exit_code, 0);
  EXPECT_NE(run("table out --by payload.mass --bins -1").exit_code, 0);
}

// (#32.9) A misspelled name in --spec, --metric or --by is refused (exit 2), naming the option, the
// closest column and the columns there are: a spec that names no column would never miss.
TEST_F(TableCli, AMisspelledSpecMetricOrGroupIsRefusedWithTheClosestColumn) {
  const auto spec = run("table out --by payload.mass --spec m1_tip_setling_s=1.5");
  EXPECT_EQ(spec.exit_code, 2) << spec.output;
  EXPECT_NE(spec.output.find("--spec: 'm1_tip_setling_s' is not a result column (did you mean `m1_tip_settling_s`?) "
                             "(the columns: m1_tip_settling_s, m1_tip_overshoot_pct, m1_settling_horizon_s) of out/results.csv"),
            std::string::npos)
      << spec.output;
  const auto metric = run("table out --metric m1_tip_overshot_pct");
  EXPECT_EQ(metric.exit_code, 2) << metric.output;
  EXPECT_NE(metric.output.find("--metric: 'm1_tip_overshot_pct' is not a result column (did you mean `m1_tip_overshoot_pct`?)"),
            std::string::npos)
      << metric.output;
  const auto by = run("table out --by payload.mas,segments");
  EXPECT_EQ(by.exit_code, 2) << by.output;
  EXPECT_NE(by.output.find("--by: 'payload.mas' is not a parameter or result column (did you mean `payload.mass`?) "
                           "(the parameters and columns: payload.mass, segments, m1_tip_settling_s, "),
            std::string::npos)
      << by.output;
  // A spec's limit must be a number: "1.5s" is not 1.5.
  EXPECT_EQ(run("table out --spec m1_tip_settling_s=1.5s").exit_code, 2);
}

}  // namespace
