// jobs/runner.cpp: the paper study against its checked-in answer table, and thread-count independence.
#include "jobs/runner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "results/summaries.hpp"
#include "results/table.hpp"
#include "tests/temp_dir.hpp"

namespace ff {
namespace {

const std::string kSource = FLEXFARM_SOURCE_DIR;

std::vector<std::vector<std::string>> parse_csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    bool quoted = false;
    for (char c : line) {
      if (c == '"') quoted = !quoted;
      else if (c == ',' && !quoted) {
        cells.push_back(cell);
        cell.clear();
      } else cell += c;
    }
    cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

TEST(Runner, PaperStudyMatchesItsAnswerTable) {
  // Regression table written by `flexfarm run configs/studies/fbtb_paper.yaml` (tests/data/README.md).
  const Study study = load_study(kSource + "/configs/studies/fbtb_paper.yaml");
  const StudyRun run = run_study(study, EvalOptions{});
  std::ifstream in(kSource + "/tests/data/fbtb_paper_results.csv");
  std::stringstream expected;
  expected << in.rdbuf();
  const auto want = parse_csv(expected.str());
  const auto got = parse_csv(format_results_csv(run.table));
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t r = 0; r < want.size(); ++r) {
    ASSERT_EQ(got[r].size(), want[r].size()) << "row " << r;
    for (std::size_t c = 0; c < want[r].size(); ++c) {
      if (r == 0 || c < 4 || want[r][c].empty()) {
        EXPECT_EQ(got[r][c], want[r][c]) << "row " << r << " column " << want[0][c];
      } else {
        const double w = std::stod(want[r][c]), g = std::stod(got[r][c]);
        EXPECT_NEAR(g, w, 1e-6 * std::max(1.0, std::fabs(w))) << "row " << r << " column " << want[0][c];
      }
    }
  }
}

TEST(Runner, ResultTableIsIdenticalForAnyThreadCountAndLaneWidth) {
  const Study study = load_study(kSource + "/configs/studies/fbtb_paper.yaml");
  EvalOptions one, two;
  one.threads = 1;
  one.lanes = 1;
  two.threads = 2;
  two.lanes = 3;
  EXPECT_EQ(format_results_csv(run_study(study, one).table), format_results_csv(run_study(study, two).table));
}

TEST(Runner, ResultTableWithoutTracesIsTheOneFromTheTraces) {
  // Without traces the metrics accumulate online (kernel/online_metrics.hpp): the same bits.
  const Study study = load_study(kSource + "/configs/studies/fbtb_paper.yaml");
  EvalOptions traces, online;
  traces.keep_traces = true;
  online.keep_traces = false;
  const StudyRun a = run_study(study, traces), b = run_study(study, online);
  EXPECT_EQ(a.traces.size(), study.variants.size());
  EXPECT_TRUE(b.traces.empty());
  EXPECT_EQ(format_results_csv(a.table), format_results_csv(b.table));
}

TEST(Runner, ArmResultTableWithoutTracesIsTheOneFromTheTraces) {
  // Without traces an arm study's metrics accumulate online (arm/arm_online_metrics.hpp): the same
  // bytes. The two-link flexible arm with its payload and gains drawn and 4.5 s to settle (some variants
  // settle, some do not), crossed with a case that diverges (nonfinite, its metrics empty); lanes not
  // dividing the variants.
  const test::TempDir dir("runner_arm_online");
  const Study study = load_study(dir.write("study.yaml", "name: arm online\n"
                                                         "model: " + kSource + "/configs/two_link_flexible.yaml\n"
                                                         "seed: 5\n"
                                                         "set: {simulation.settle: 4.5}\n"
                                                         "cases:\n"
                                                         "  - label: drawn\n"
                                                         "  - label: diverging\n"
                                                         "    set:\n"
                                                         "      joints.shoulder.controller.kp: 1.0e12\n"
                                                         "      simulation.integrator: rk4\n"
                                                         "      simulation.substeps: 1\n"
                                                         "variables:\n"
                                                         "  - path: bodies[forearm].flexible.payload.mass\n"
                                                         "    distribution: {type: uniform, lower: 0.05, upper: 0.6}\n"
                                                         "  - path: joints.shoulder.controller.kd\n"
                                                         "    distribution: {type: uniform, lower: 0.7, upper: 10.0}\n"
                                                         "  - path: joints.elbow.controller.kp\n"
                                                         "    distribution: {type: uniform, lower: 2.0, upper: 10.0}\n"
                                                         "design: {type: monte_carlo, samples: 7}\n"));
  EvalOptions traces, online;
  traces.keep_traces = true;
  online.keep_traces = false;
  traces.lanes = online.lanes = 3;
  traces.threads = online.threads = 2;
  const StudyRun a = run_study(study, traces), b = run_study(study, online);
  EXPECT_EQ(a.arm_traces.size(), study.variants.size());
  EXPECT_TRUE(b.arm_traces.empty());
  const std::string csv = format_results_csv(a.table);
  for (const char* status : {",ok,", ",not_settled,", ",nonfinite,"})
    EXPECT_NE(csv.find(status), std::string::npos) << status << "\n" << csv;
  EXPECT_EQ(format_results_csv(b.table), csv);
}

TEST(Runner, ProgressReachesTheVariantCount) {
  const Study study = load_study(kSource + "/configs/studies/fbtb_paper.yaml");
  EvalOptions opt;
  opt.lanes = 1;
  int last = 0, calls = 0;
  run_study(study, opt, [&](int done, int total) {
    EXPECT_EQ(total, 4);
    EXPECT_EQ(done, last + 1);
    last = done;
    ++calls;
  });
  EXPECT_EQ(calls, 4);
}

// The controller comparison on the hydraulic rig (configs/studies/fbtb_controllers.yaml, docs/controllers.md).
TEST(Runner, ControllerStudyShowsShapersAndNotchesCalmTheArmAndEiIsTheMostRobust) {
  const Study study = load_study(kSource + "/configs/studies/fbtb_controllers.yaml");
  ASSERT_EQ(study.case_labels.size(), 7u);
  const StudyRun run = run_study(study, EvalOptions{});
  const auto& t = run.table;
  const auto residual = column_values(t, "m1_residual_vibration_m");
  const auto settle = column_values(t, "m1_tip_settling_s");
  const int levels = 5, nominal = 2;  // payload levels; the middle one is the design point
  auto at = [&](const std::vector<double>& x, int c, int p) { return x[c * levels + p]; };
  // Every vibration-aware controller leaves at most half of PD's residual vibration at every payload.
  for (int c = 1; c <= 5; ++c)
    for (int p = 0; p < levels; ++p) EXPECT_LT(at(residual, c, p), 0.5 * at(residual, 0, p)) << c << " " << p;
  // On the design point: the notch n = 1 and ZV settle fastest; PD and feed-forward ring on.
  EXPECT_LT(at(settle, 1, nominal), 2.0);
  EXPECT_LT(at(settle, 3, nominal), 2.0);
  EXPECT_TRUE(std::isnan(at(settle, 0, nominal)));
  EXPECT_TRUE(std::isnan(at(settle, 6, nominal)));
  // Robustness: ZV's residual vibration grows 2.5-fold off the design point; EI's settles at every payload.
  EXPECT_GT(at(residual, 3, 4), 2.0 * at(residual, 3, nominal));
  for (int p = 0; p < levels; ++p) EXPECT_FALSE(std::isnan(at(settle, 5, p))) << p;
}

}  // namespace
}  // namespace ff
