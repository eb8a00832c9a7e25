// jobs/report.cpp: table.md of a grid study over a fine grid groups each parameter into bins.
#include "jobs/report.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "results/run_metrics.hpp"
#include "tests/temp_dir.hpp"

namespace ff {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A 64 x 64 grid (payload.mass x joints.stiffness), as a finished study's result table: tip settling
// 1 + mass / 100 s, not settled (horizon 5 s) where the mass is above 390 kg and the stiffness below 35e3.
ResultTable fine_grid() {
  ResultTable t;
  t.params = {"payload.mass", "joints.stiffness"};
  t.columns = {"m1_tip_settling_s", "m1_tip_overshoot_pct", "m1_settling_horizon_s"};
  for (int i = 0; i < 64 * 64; ++i) {
    const double mass = 164.35 + (i / 64) * (493.05 - 164.35) / 63, k = 31.6e3 + (i % 64) * 250.0;
    const bool settled = !(mass > 390 && k < 35e3);
    t.rows.push_back({i, 0, "v" + std::to_string(i), settled ? "ok" : "not_settled", {mass, k},
                      {settled ? 1 + mass / 100 : NAN, k / 1e4, 5.0}});
  }
  return t;
}

TEST(Report, AFineGridsTableBinsEachParameterIntoTenGroups) {
  const test::TempDir dir("ff_report");
  Study study;
  study.name = "fine";
  study.design.kind = DesignKind::kGrid;
  const ResultTable t = fine_grid();
  const std::string md = write_study_report(study, t, dir.path.string(), make_run_record(study, t, dir.path.string(), {})).md();
  EXPECT_EQ(read_text((dir.path / "table.md").string()), md);
  // The settling table: 10 x 10 bins, two metrics each, not 4096 x 2 lines.
  const auto a = md.find("## Tip settling time by payload.mass and joints.stiffness");
  ASSERT_NE(a, std::string::npos) << md;
  const auto b = md.find("## Every metric", a);
  ASSERT_NE(b, std::string::npos) << md;
  int groups = 0;
  std::istringstream in(md.substr(a, b - a));
  for (std::string line; std::getline(in, line);) groups += line.rfind("| [", 0) == 0;
  EXPECT_EQ(groups, 200) << md;
  // A grid's quantile edges fall on its levels (each level 64 rows): the first bins hold levels 0..5 of
  // each, 36 runs, settling 1 + (164.35 + 2.5 x 5.2175) / 100 s on average.
  EXPECT_NE(md.find("| [164.35, 195.655) | [31600, 33100) | m1_tip_settling_s | 36 | 0 | 0 | - | 2.774 |"), std::string::npos)
      << md;
  // The last bins, closed, with the not-settled runs (mass above 390 kg, stiffness below 35e3).
  EXPECT_NE(md.find(", 493.05] | [33100, 34600) | m1_tip_settling_s | "), std::string::npos) << md;
  EXPECT_NE(md.find(", 47350] | m1_tip_settling_s | "), std::string::npos) << md;
  EXPECT_NE(md.find("Binned: payload.mass (64 values) in 10 quantile bins (about equal numbers of rows); "
                    "joints.stiffness (64 values) in 10 quantile bins"),
            std::string::npos)
      << md;
  // The plots keep every level.
  EXPECT_TRUE(std::filesystem::exists(dir.path / "heatmap_settling.png"));
  EXPECT_TRUE(std::filesystem::exists(dir.path / "settling_vs_payload_mass.png"));
}

// table.md in three parts (issue 32, item 24: report.html showed the title, description and requirements
// twice): the head holds the title and description, the results neither, the requirements their section;
// table.md is the three together.
TEST(Report, TableMdSplitsIntoTheHeadTheResultsAndTheRequirements) {
  const test::TempDir dir("ff_report");
  Study study;
  study.name = "fine";
  study.description = "A fine grid of payloads and stiffnesses.";
  study.design.kind = DesignKind::kGrid;
  study.requirements.statements.push_back(parse_requirement("P(m1_tip_settling_s <= 5) >= 0.5"));
  const ResultTable t = fine_grid();
  RunRecord record = make_run_record(study, t, dir.path.string(), {});
  record.verdicts = {Verdict{.requirement = "P(m1_tip_settling_s <= 5) >= 0.5", .verdict = "pass", .estimate = 0.9,
                             .lower = 0.88, .upper = 0.92, .n = 4096, .more = 0, .evidence = "3700 of 4096 within"}};
  const StudyReport report = write_study_report(study, t, dir.path.string(), record);
  EXPECT_EQ(report.head, "# fine\n\nA fine grid of payloads and stiffnesses.\n\n");
  EXPECT_EQ(report.results.rfind("4096 variants: ", 0), 0u) << report.results.substr(0, 200);
  EXPECT_EQ(report.results.find("A fine grid"), std::string::npos);
  EXPECT_EQ(report.results.find("## Requirements"), std::string::npos);
  EXPECT_NE(report.results.find("## Every metric"), std::string::npos);
  EXPECT_EQ(report.requirements.rfind("\n## Requirements\n\n", 0), 0u) << report.requirements;
  EXPECT_NE(report.requirements.find("| `P(m1_tip_settling_s <= 5) >= 0.5` | pass |"), std::string::npos) << report.requirements;
  EXPECT_EQ(read_text((dir.path / "table.md").string()), report.md());
}

// (#32.12) A listed arm study: a run that diverged has no values ("-"), not "not settled"; one that did
// not settle reads "> H (not settled)" with its horizon H, and its other metrics stay numbers.
TEST(Report, AListedArmStudysDivergedRunHasNoValuesNotNotSettled) {
  const test::TempDir dir("ff_report_arm");
  Study study;
  study.name = "arm";
  study.listed = true;
  study.arm = true;
  ResultTable t;
  t.columns = {"arm_settling_s", "arm_overshoot_pct", "arm_peak_torque_Nm", "arm_peak_speed", "tool_settling_s",
               "tool_overshoot_pct", "tool_peak_error_m", "tool_final_error_m", "tool_sag_m", "settling_horizon_s"};
  t.rows.push_back({0, 0, "settles", "ok", {}, {1.1, 0.5, 4, 1, 1.2, 0.25, 0.02, 0.001, 0, 3}});
  t.rows.push_back({1, 0, "rings", "not_settled", {}, {NAN, 1, 5, 1, NAN, 2.5, 0.01, 0.001, 0, 3}});
  t.rows.push_back({2, 0, "diverged", "nonfinite", {}, std::vector<double>(10, NAN)});
  const std::string md = write_study_report(study, t, dir.path.string(), make_run_record(study, t, dir.path.string(), {})).md();
  EXPECT_NE(md.find("| settles | ok | 1.2 | 0.25 | 0.02 | 0.001 | 4 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| rings | not_settled | > 3 (not settled) | 2.5 | 0.01 | 0.001 | 5 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| diverged | nonfinite | - | - | - | - | - |"), std::string::npos) << md;
}

// (#32.11) A study with cases: a cell where runs did not settle is their restricted mean, a lower bound
// ("> v"; at the horizon when none settled), never a bare number and never a gap; a cell with a run
// that diverged has no value ("-").
TEST(Report, ACasesCellThatDidNotSettleIsALowerBound) {
  const test::TempDir dir("ff_report_cases");
  Study study;
  study.name = "cases";
  study.case_labels = {"PD", "ZV"};
  ResultTable t;
  t.params = {"case", "payload.mass"};
  t.columns = calc_metric_columns(1);
  const auto row = [&](int id, double c, double mass, double settling, double horizon, const char* status) {
    std::vector<double> v(t.columns.size(), 1.0);
    v[0] = settling;
    v[7] = horizon;
    if (std::string(status) == "nonfinite") v.assign(v.size(), NAN);
    t.rows.push_back({id, 0, "r" + std::to_string(id), status, {c, mass}, v});
  };
  row(0, 0, 8, 2.0, 3.0, "ok");
  row(1, 0, 12, NAN, 2.77, "not_settled");  // none settled: > the horizon
  row(2, 1, 8, 1.5, 3.0, "ok");
  row(3, 1, 8, NAN, 3.0, "not_settled");    // half settled: > the restricted mean (1.5 + 3) / 2
  row(4, 1, 12, NAN, NAN, "nonfinite");
  const std::string md = write_study_report(study, t, dir.path.string(), make_run_record(study, t, dir.path.string(), {})).md();
  EXPECT_NE(md.find("| PD | 2.00 | > 2.77 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| ZV | > 2.25 | - |"), std::string::npos) << md;
  EXPECT_NE(md.find("\"> v\": some runs did not settle"), std::string::npos) << md;
  EXPECT_TRUE(std::filesystem::exists(dir.path / "cases_m1_tip_settling_s.png"));
}

}  // namespace
}  // namespace ff
