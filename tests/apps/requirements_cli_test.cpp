// `flexfarm run` with `requirements:` (docs/formats.md, "Study requirements"): the verdicts at the
// end of the output and in table.md, the early stop of a Monte Carlo study (the same bytes whatever
// the threads, lanes and resume), and a bad block rejected with one line naming file, line and key.
#include <gtest/gtest.h>

#include <string>

#include "tests/apps/cli_fixture.hpp"

namespace {

using ff::test::read_text;
using ff::test::split_lines;
namespace fs = std::filesystem;

class RequirementsCli : public ff::test::CliFixture {
 protected:
  RequirementsCli() : CliFixture("ff_requirements_", {{"configs/fbtb.yaml", "configs/fbtb.yaml"}}) {}

  // A small Monte Carlo study of the reference rig (as tests/data/studies/mc_small.yaml) with `block`
  // as its requirements.
  void write_study(const std::string& name, const std::string& block, int samples = 400,
                   const std::string& design = "monte_carlo") const {
    write(name, "name: proposal\n"
                "seed: 7\n"
                "model: configs/fbtb.yaml\n"
                "set:\n"
                "  trajectory.moves: [{target: 0.5, hold: 8.0}]\n"
                "  simulation.integrator: sdirk2\n"
                "  notch.enabled: true\n"
                "  controller.model: plant\n"  // the notch placed for each variant's rig, as designed per unit
                "variables:\n"
                "  - path: payload.mass\n"
                "    distribution: {type: normal, mean: 328.7, std: 40}\n"
                "  - path: joints.stiffness\n"
                "    distribution: {type: uniform, lower: 30.0e3, upper: 50.0e3}\n"
                "design: {type: " + design + ", samples: " + std::to_string(samples) + "}\n" + block);
  }
};

const std::string kStopping =
    "requirements:\n"
    "  statements:\n"
    "    - P(m1_tip_settling_s <= 8) >= 0.5\n"
    "    - p95(m1_peak_torque_Nm) <= 1e6\n"
    "    - max(m1_tip_overshoot_pct) < 0.0001\n"
    "  stop_when_decided: true\n"
    "  check_every: 20\n";

TEST_F(RequirementsCli, AMonteCarloStudyStopsWhenEveryRequirementIsDecidedTheSameWhateverThreadsLanesAndResume) {
  write_study("study.yaml", kStopping);
  const auto a = run("run study.yaml --out a --threads 1 --lanes 1");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const std::string csv = read_text(work / "a/results.csv");
  const auto rows = static_cast<int>(split_lines(csv).size()) - 1;
  EXPECT_LT(rows, 400);
  EXPECT_EQ(rows % 20, 0) << "stops at a checkpoint";
  EXPECT_NE(a.output.find("stopped early"), std::string::npos) << a.output;
  const std::string md = read_text(work / "a/table.md");
  EXPECT_NE(md.find("## Requirements"), std::string::npos);
  EXPECT_NE(md.find("Stopped early after " + std::to_string(rows) + " of 400 variants: every requirement decided."),
            std::string::npos)
      << md;
  // The verdict lines come last.
  const auto lines = a.lines();
  ASSERT_GE(lines.size(), 3u);
  EXPECT_EQ(lines[lines.size() - 3].rfind("PASS      P(m1_tip_settling_s <= 8) >= 0.5: ", 0), 0u) << a.output;
  EXPECT_EQ(lines[lines.size() - 2].rfind("PASS      p95(m1_peak_torque_Nm) <= 1e6: ", 0), 0u) << a.output;
  EXPECT_EQ(lines[lines.size() - 1].rfind("FAIL      max(m1_tip_overshoot_pct) < 0.0001: ", 0), 0u) << a.output;

  const auto b = run("run study.yaml --out b --threads 2 --lanes 5");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  EXPECT_EQ(read_text(work / "b/results.csv"), csv) << "--threads 2 --lanes 5";
  EXPECT_EQ(read_text(work / "b/table.md"), md);

  // A run cut short: its journal keeps 30 rows (fewer than the stop point), then --resume.
  fs::copy(work / "b", work / "c", fs::copy_options::recursive);
  fs::remove(work / "c/results.csv");
  const auto journal = split_lines(read_text(work / "c/journal-main.csv"));
  ASSERT_GT(journal.size(), 32u);
  std::string cut;
  for (std::size_t i = 0; i < 32; ++i) cut += journal[i] + "\n";
  std::ofstream(work / "c/journal-main.csv", std::ios::binary | std::ios::trunc) << cut;
  const auto c = run("run study.yaml --out c --resume --threads 2 --lanes 3");
  ASSERT_EQ(c.exit_code, 0) << c.output;
  EXPECT_EQ(read_text(work / "c/results.csv"), csv) << "cut and resumed";
  // And one process's journal holding rows past the stop point, merged: the same table.
  const auto m = run("merge study.yaml --out b");
  ASSERT_EQ(m.exit_code, 0) << m.output;
  EXPECT_EQ(read_text(work / "b/results.csv"), csv) << "merge";
}

TEST_F(RequirementsCli, WithoutStopWhenDecidedTheWholeStudyRunsAndAFailingRequirementKeepsExitZero) {
  write_study("study.yaml", "requirements:\n  - max(m1_tip_overshoot_pct) < 0.0001\n  - min(m1_peak_torque_Nm) > 0\n", 24);
  const auto r = run("run study.yaml --out out --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(split_lines(read_text(work / "out/results.csv")).size(), 25u);
  EXPECT_NE(r.output.find("requirements (24 of 24 variants):\nFAIL      max(m1_tip_overshoot_pct) < 0.0001: "), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("\nPASS      min(m1_peak_torque_Nm) > 0: "), std::string::npos) << r.output;
}

TEST_F(RequirementsCli, ABadBlockIsOneErrorLineNamingFileLineAndKeyAndWritesNothing) {
  write_study("statement.yaml", "requirements:\n  - P(m1_tip_settling_s <= 3) >= 0.9\n  - P(m1_tip_settling_s =< 3) >= 0.9\n");
  auto r = run("run statement.yaml --out out");
  expect_one_error_line(r, "statement.yaml:17: requirements[1]: 'P(m1_tip_settling_s =< 3) >= 0.9': at character 21 ");
  EXPECT_EQ(r.exit_code, 2);

  write_study("metric.yaml", "requirements:\n  - p95(tip_settling) <= 3\n");
  r = run("run metric.yaml --out out");
  expect_one_error_line(r, "metric.yaml:16: requirements[0]: 'tip_settling' is not a result column (the columns: m1_tip_settling_s, ");

  write_study("lhs.yaml", "requirements:\n  statements: [\"P(m1_tip_settling_s <= 3) >= 0.9\"]\n  stop_when_decided: true\n", 40,
              "lhs");
  r = run("run lhs.yaml --out out");
  expect_one_error_line(r, "lhs.yaml:17: requirements.stop_when_decided: only for `design: {type: monte_carlo}` without `cases:`");
  EXPECT_FALSE(fs::exists(work / "out"));
}

}  // namespace
