// The nightly workflow end to end (docs/nightly.md): scripts/nightly/nightly.sh runs a Monte Carlo study
// three nights running, the model changed before the second. The first night has nothing to compare
// with (exit 0); the second sees the changed key, the regression past the study's tolerance and the
// verdict that got worse (exit 1), with diff.md and report.html; the third, unchanged, is no worse than
// the second (exit 0). `flexfarm history` lists the three, `flexfarm diff` gives the same answer from
// the directories and from history ids, and exit 2 for a run that is not there.
#include <gtest/gtest.h>

#include <regex>

#include "cli_fixture.hpp"

namespace ff::test {
namespace {

class NightlyCli : public CliFixture {
 protected:
  NightlyCli() : CliFixture("ff_nightly_", {{"configs/fbtb.yaml", "configs/fbtb.yaml"}}) {}

  // The sweep: the robustness study's PD + notch rig, 64 draws; tolerances and one requirement.
  void SetUp() override {
    CliFixture::SetUp();
    write("configs/nightly.yaml", R"(name: nightly
seed: 20261125
model: fbtb.yaml
set:
  trajectory.moves: [{target: 0.5, hold: 12.0}]
  notch.enabled: true
  notch.omega_z: [1.72131, 14.3834]
  simulation.integrator: sdirk2
variables:
  - {path: payload.mass, distribution: {type: truncated_normal, mean: 328.7, std: 40.0, lower: 200.0, upper: 460.0}}
  - {path: joints.stiffness, distribution: {type: normal, mean: 39.5e3, std: 2.0e3}}
design: {type: monte_carlo, samples: 64}
requirements:
  - p95(m1_peak_torque_Nm) <= 1100
tolerances:
  m1_peak_torque_Nm: {increase: 3%}
  m1_tip_settling_s: {increase: 0.5}
)");
  }

  // One night: the script with the built binary and the test's own history.
  Result night(const std::string& name) const {
    return run_shell("FLEXFARM=" + quote(kBinary) + " FLEXFARM_HISTORY=" + quote((base / "history").string()) +
                     " FLEXFARM_NIGHT=" + name + " " + quote(kSource + "/scripts/nightly/nightly.sh") +
                     " configs/nightly.yaml nightly");
  }
  Result flexfarm(const std::string& args) const {
    return run_shell("FLEXFARM_HISTORY=" + quote((base / "history").string()) + " " + quote(kBinary) + " " + args);
  }
};

TEST_F(NightlyCli, TheScriptFlagsTheNightTheModelGotWorseAndNotTheNightsAround) {
  const Result first = night("n1");
  ASSERT_EQ(first.exit_code, 0) << first.output << read_text(work / "nightly/n1.log");
  EXPECT_NE(first.output.find("the first run of configs/nightly.yaml in the history"), std::string::npos) << first.output;
  EXPECT_TRUE(fs::exists(work / "nightly/n1/report.html"));
  EXPECT_FALSE(fs::exists(work / "nightly/n1/diff.md"));
  // (#32.22) flexfarm diff of the study's first run: nothing to compare with, said so, exit 0 (2 is for bad input).
  const Result none = flexfarm("diff nightly/n1 --out first.md");
  EXPECT_EQ(none.exit_code, 0) << none.output;
  EXPECT_EQ(none.output.rfind("# Nothing to compare with\n\nrun 1 (nightly, ", 0), 0u) << none.output;
  EXPECT_NE(none.output.find(" is the first run of " + (work / "configs/nightly.yaml").string() + " in the history " +
                             (base / "history").string() + ": there is no earlier run to compare it with. Nothing got worse.\n"),
            std::string::npos)
      << none.output;
  EXPECT_EQ(read_text(work / "first.md"), none.output);

  // The derivative gain cut by a third: more torque (beyond the 3 % tolerance), the p95 past 1100.
  std::string model = read_text(work / "configs/fbtb.yaml");
  model.replace(model.find("kd: 3.0e4"), 9, "kd: 2.0e4");
  write("configs/fbtb.yaml", model);
  const Result second = night("n2");
  EXPECT_EQ(second.exit_code, 1) << second.output << read_text(work / "nightly/n2.log");
  EXPECT_NE(second.output.find("nightly/n2: REGRESSION, see nightly/n2/diff.md"), std::string::npos) << second.output;
  const std::string diff = read_text(work / "nightly/n2/diff.md");
  EXPECT_NE(diff.find("| controller.kd | 3.0e4 | 2.0e4 |"), std::string::npos) << diff;
  EXPECT_NE(diff.find("Paired by variant: both runs hold the same 64 variants"), std::string::npos) << diff;
  EXPECT_TRUE(std::regex_search(diff, std::regex(R"(- m1_peak_torque_Nm: mean rose from 9\d\d\.?\d* to 1\d{3})"))) << diff;
  EXPECT_NE(diff.find("| p95(m1_peak_torque_Nm) <= 1100 | undecided | fail (worse) |"), std::string::npos) << diff;
  EXPECT_EQ(fs::read_symlink(work / "nightly/latest"), "n2");
  const std::string report = read_text(work / "nightly/n2/report.html");
  // The badge names the regressions (issue 32, item 24).
  EXPECT_TRUE(std::regex_search(report, std::regex(R"(>regressions since the last run \(\d\): [^<]*m1_peak_torque_Nm; [^<]*requirement p95\(m1_peak_torque_Nm\) &lt;= 1100</span>)")))
      << report.substr(report.find("<div class=\"summary\">"), 800);
  EXPECT_NE(report.find("<tr class=\"fail\"><td><code>p95(m1_peak_torque_Nm) &lt;= 1100</code>"), std::string::npos);

  // Unchanged the next night: no worse than the night before.
  const Result third = night("n3");
  EXPECT_EQ(third.exit_code, 0) << third.output;
  EXPECT_NE(third.output.find("nightly/n3: nothing got worse"), std::string::npos) << third.output;
  EXPECT_NE(read_text(work / "nightly/n3/diff.md").find("Model (" + (work / "configs/fbtb.yaml").string() + "): unchanged."),
            std::string::npos);

  // The history holds the three nights, oldest first.
  const Result history = flexfarm("history configs/nightly.yaml");
  ASSERT_EQ(history.exit_code, 0) << history.output;
  const auto lines = history.lines();
  ASSERT_EQ(lines.size(), 5u) << history.output;  // header, separator, three runs
  EXPECT_NE(lines[2].find("| 1 | nightly |"), std::string::npos) << lines[2];
  EXPECT_NE(lines[3].find("0 pass, 1 fail"), std::string::npos) << lines[3];
  EXPECT_NE(lines[4].find((work / "nightly/n3").string()), std::string::npos) << lines[4];

  // flexfarm diff by directories and by ids: the first night against the third is the same regression.
  EXPECT_EQ(flexfarm("diff nightly/n1 nightly/n3").exit_code, 1);
  const Result by_id = flexfarm("diff 1 '#3'");
  EXPECT_EQ(by_id.exit_code, 1) << by_id.output;
  EXPECT_NE(by_id.output.find("# What changed: run 1 (nightly, "), std::string::npos) << by_id.output;
  EXPECT_EQ(flexfarm("diff nightly/n2 nightly/n3").exit_code, 0);
  const Result missing = flexfarm("diff nightly/n9 nightly/n3");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("flexfarm: error: nightly/n9: neither a run's output directory nor a run id"), std::string::npos)
      << missing.output;
  EXPECT_EQ(flexfarm("diff 17 nightly/n3").exit_code, 2);
  EXPECT_EQ(flexfarm("diff --bogus").exit_code, 2);
}

// (#32.9) A recorded study whose tolerance names no result column (a run recorded before the check, here
// its run.yaml edited) is refused by `flexfarm diff`, exit 2, naming the line, the key and the closest
// column: a regression guard that could never fire.
TEST_F(NightlyCli, ADiffRefusesARecordedToleranceThatNamesNoColumn) {
  write("configs/two.yaml", "name: two\nmodel: fbtb.yaml\nset:\n  trajectory.moves: [{target: 0.2, hold: 3}]\n"
                            "runs:\n  - {label: a}\ntolerances:\n  m1_peak_torque_Nm: {increase: 3%}\n");
  ASSERT_EQ(flexfarm("run configs/two.yaml --out a").exit_code, 0);
  ASSERT_EQ(flexfarm("run configs/two.yaml --out b").exit_code, 0);
  EXPECT_EQ(flexfarm("diff a b").exit_code, 0);
  std::string record = read_text(work / "b/run.yaml");
  record.replace(record.find("    m1_peak_torque_Nm: {increase"), 21, "    m1_peak_torqe_Nm");
  write("b/run.yaml", record);
  const Result r = flexfarm("diff a b");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("configs/two.yaml:8: tolerances.m1_peak_torqe_Nm: 'm1_peak_torqe_Nm' is not a result column (did you "
                          "mean `m1_peak_torque_Nm`?)"),
            std::string::npos)
      << r.output;
}

TEST_F(NightlyCli, AHistoryThatCannotBeWrittenIsAWarningAndTheRunStandsAndNoHistoryRecordsNothing) {
  // A history under a file cannot be made: the run warns, writes everything else and exits 0.
  write("not_a_dir", "x");
  const Result r = run_shell("FLEXFARM_HISTORY=not_a_dir/history " + quote(kBinary) + " run configs/nightly.yaml --out a");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("flexfarm: warning: the run history was not updated: "), std::string::npos) << r.output;
  for (const char* f : {"results.csv", "results.sqlite", "run.yaml", "table.md", "report.html"}) EXPECT_TRUE(fs::exists(work / "a" / f)) << f;
  EXPECT_NE(read_text(work / "a/report.html").find("The run history was not updated: "), std::string::npos);
  // --no-history: nothing recorded, and the report says so.
  const Result none = flexfarm("run configs/nightly.yaml --out b --no-history");
  EXPECT_EQ(none.exit_code, 0) << none.output;
  EXPECT_FALSE(fs::exists(base / "history"));
  EXPECT_NE(read_text(work / "b/report.html").find("Not recorded in a run history"), std::string::npos);
  EXPECT_NE(flexfarm("history").output.find("no runs in"), std::string::npos);
}

}  // namespace
}  // namespace ff::test
