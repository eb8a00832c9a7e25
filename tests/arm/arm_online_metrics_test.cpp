// Tests of arm/arm_online_metrics: the arm metrics accumulated while the arms run (simulate_arms's
// ArmRunOptions::online) are calc_arm_metrics's on the stored trace, bit for bit, on random runs of
// several arms; a failed lane gives all NaN.
#include "arm/arm_online_metrics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "arm/arm_metrics.hpp"
#include "arm/arm_simulate.hpp"
#include "arm/arm_yaml.hpp"
#include "common/yaml_reader.hpp"
#include "tests/arm/test_support.hpp"
#include "tests/results/test_rng.hpp"

namespace ff {
namespace {

using test::TestRng;

const std::string kConfigs = std::string(FLEXFARM_SOURCE_DIR) + "/configs/";

// The same doubles, bit for bit (NaN == NaN, -0 != +0), column by column.
void expect_same_bits(const std::vector<std::string>& columns, const std::vector<double>& stored,
                      const std::vector<double>& online, const char* what) {
  ASSERT_EQ(stored.size(), columns.size());
  ASSERT_EQ(online.size(), columns.size());
  for (std::size_t i = 0; i < columns.size(); ++i)
    EXPECT_EQ(std::bit_cast<std::uint64_t>(stored[i]), std::bit_cast<std::uint64_t>(online[i]))
        << what << " " << columns[i] << ": stored " << stored[i] << ", online " << online[i];
}

// A stored trace's rows, one sample at a time, into a fresh accumulator.
OnlineArmRun feed_trace(const ArmModel& m, const ArmTrace& tr) {
  OnlineArmRun run(m);
  std::vector<double> row(tr.columns.size());
  for (std::size_t k = 0; k < tr.t().size(); ++k) {
    for (std::size_t c = 0; c < row.size(); ++c) row[c] = tr.columns[c][k];
    run.add(row.data(), 1);
  }
  return run;
}

// How many metrics of each kind the random runs gave, to check they cover what they should.
struct Coverage {
  int settled = 0, not_settled = 0, tool_settled = 0, tool_not_settled = 0, overshoot = 0, failed = 0;
};

// simulate_arms on `lanes` twice, with traces and with online metrics: the same statuses, no traces on
// the online run, and each lane's online metrics (and those of its stored trace fed row by row) the
// stored trace's bits.
void expect_online_matches_stored(const std::vector<ArmModel>& lanes, Coverage& seen) {
  const ArmRun stored = simulate_arms(lanes);
  std::vector<OnlineArmRun> online;
  for (const ArmModel& m : lanes) online.emplace_back(m);
  const ArmRun run = simulate_arms(lanes, {.online = &online});
  EXPECT_TRUE(run.traces.empty());
  ASSERT_EQ(run.status, stored.status);
  for (std::size_t l = 0; l < lanes.size(); ++l) {
    const std::vector<std::string> columns = arm_metric_columns(lanes[l]);
    const std::vector<double> v = calc_arm_metrics(lanes[l], stored.traces[l], stored.status[l]);
    SCOPED_TRACE(testing::Message() << "lane " << l);
    expect_same_bits(columns, v, online[l].result(run.status[l]), "simulate_arms's online");
    expect_same_bits(columns, v, feed_trace(lanes[l], stored.traces[l]).result(stored.status[l]), "the trace fed");
    if (stored.status[l] != LaneStatus::kOk) ++seen.failed;
    for (std::size_t i = 0; i < columns.size(); ++i) {
      if (columns[i].ends_with("_settling_s")) (std::isnan(v[i]) ? seen.not_settled : seen.settled) += 1;
      for (const ArmTool& tool : lanes[l].tools)
        if (columns[i] == tool.name + "_settling_s") (std::isnan(v[i]) ? seen.tool_not_settled : seen.tool_settled) += 1;
      if (columns[i].ends_with("_overshoot_pct") && v[i] > 0.0) ++seen.overshoot;
    }
  }
}

// Each joint's gains scaled: kp by 0.3 to 2, kd by 0.1 to 1.5 (some runs ring and overshoot, some are
// slow to settle).
void scale_gains(YAML::Node doc, TestRng& rng) {
  for (auto j : doc["joints"]) {
    YAML::Node c = j.second["controller"];
    c["kp"] = c["kp"].as<double>() * (0.3 + 1.7 * rng.uniform());
    c["kd"] = c["kd"].as<double>() * (0.1 + 1.4 * rng.uniform());
  }
}

// `batches` batches of `width` lanes of the arm in `file`, each checked by expect_online_matches_stored:
// each lane's gains scaled and `draw` applied to its document; the time to settle drawn per batch (its
// lanes share a duration).
template <class Draw>
void run_random_batches(const std::string& file, int batches, int width, std::uint64_t seed, Coverage& seen,
                        Draw draw) {
  TestRng rng{seed};
  for (int b = 0; b < batches; ++b) {
    const double settle = 0.5 + 2.5 * rng.uniform();  // s after the move: some runs do not settle in it
    std::vector<ArmModel> lanes;
    for (int l = 0; l < width; ++l) {
      YAML::Node doc = load_yaml_file(kConfigs + file);
      scale_gains(doc, rng);
      draw(doc, rng);
      doc["simulation"]["settle"] = settle;
      lanes.push_back(parse_arm(doc, kConfigs + file));
    }
    SCOPED_TRACE(testing::Message() << file << " batch " << b);
    expect_online_matches_stored(lanes, seen);
  }
}

TEST(ArmOnlineMetrics, EqualTheStoredTraceMetricsBitForBitOnRandomRuns) {
  // Four arms, each in batches of 3 lanes with every joint's gains drawn and a drawn time to settle.
  Coverage seen;
  // The two-link flexible arm (two flexible links, one tool): its payload drawn.
  run_random_batches("two_link_flexible.yaml", 2, 3, 1, seen, [](YAML::Node doc, TestRng& rng) {
    doc["bodies"][1]["flexible"]["payload"]["mass"] = 0.05 + 0.6 * rng.uniform();
  });
  // The rigid 6-DOF arm from URDF (two waypoints, IK at plan time).
  run_random_batches("arm6.yaml", 2, 3, 2, seen, [](YAML::Node, TestRng&) {});
  // The two-link arm with a hydraulic shoulder: the forearm's mass (it carries the tool) drawn.
  run_random_batches("hydraulic_arm.yaml", 2, 3, 3, seen, [](YAML::Node doc, TestRng& rng) {
    doc["bodies"][1]["mass"] = 10.0 + 40.0 * rng.uniform();
  });
  // The dual-arm machine (two tools, 17 joints): its first move alone (both tools, Cartesian) in 1 s, the
  // right hand's mass drawn.
  run_random_batches("sers.yaml", 1, 3, 4, seen, [](YAML::Node doc, TestRng& rng) {
    YAML::Node first = YAML::Clone(doc["trajectory"]["waypoints"][0]);
    first["time"] = 1.0;
    YAML::Node waypoints(YAML::NodeType::Sequence);
    waypoints.push_back(first);
    doc["trajectory"]["waypoints"] = waypoints;
    doc["simulation"]["integrator"] = "rk4";
    doc["simulation"]["substeps"] = 4;
    doc["bodies"][doc["bodies"].size() - 1]["mass"] = 4.0 + 8.0 * rng.uniform();  // the right hand
  });
  RecordProperty("settled", seen.settled);
  RecordProperty("not_settled", seen.not_settled);
  RecordProperty("overshoot", seen.overshoot);
  RecordProperty("tool_settled", seen.tool_settled);
  RecordProperty("tool_not_settled", seen.tool_not_settled);
  EXPECT_GT(seen.settled, 0);
  EXPECT_GT(seen.not_settled, 0);
  EXPECT_GT(seen.tool_settled, 0);
  EXPECT_GT(seen.tool_not_settled, 0);
  EXPECT_GT(seen.overshoot, 0);
}

// The pendulum of test_support.hpp moved 0.5 rad in 0.5 s, gravity compensated, run for 3 s; gains `kp`
// and `kd`, RK4 at one substep.
ArmModel pendulum(double kp, double kd) {
  return test::arm_from(test::pendulum_arm("tool: {body: arm, point: [0.5, 0, 0]}\n"
                                           "controller: {rate: 1000}\n"
                                           "joints:\n  arm: {controller: {kp: " + std::to_string(kp) +
                                           ", kd: " + std::to_string(kd) + ", gravity_compensation: 1}}\n"
                                           "trajectory:\n  waypoints:\n    - {time: 0.5, joints: {arm: 0.5}}\n"
                                           "simulation: {duration: 3.0, integrator: rk4, substeps: 1}\n"));
}

// (#32.13) Out to 0.6 rad and part way back to 0.2: the joint's overshoot is its last move's (0.6 -> 0.2,
// from its start at 0.5 s on), not the start pose 0 lying 0.2 rad past 0.2 (50 % of the 0.4 rad move);
// the tool's is along the reference's last move (from where it is at 0.5 s). Stored and online agree.
TEST(ArmOnlineMetrics, AnOvershootIsOfTheLastMoveFromItsStart) {
  const std::vector<ArmModel> lanes{test::arm_from(test::pendulum_arm(
      "tool: {body: arm, point: [0.5, 0, 0]}\ncontroller: {rate: 1000}\n"
      "joints:\n  arm: {controller: {kp: 400, kd: 40, gravity_compensation: 1}}\n"
      "trajectory:\n  waypoints:\n    - {time: 0.5, joints: {arm: 0.6}}\n    - {time: 1.0, joints: {arm: 0.2}}\n"
      "simulation: {duration: 3.0, integrator: rk4, substeps: 1}\n"))};
  const ArmModel& m = lanes[0];
  const ArmJointMoves mv = calc_arm_joint_moves(m, 0);
  EXPECT_EQ(mv.start, 0.6);
  EXPECT_EQ(mv.target, 0.2);
  EXPECT_EQ(mv.t_start, 0.5);
  EXPECT_EQ(calc_arm_last_move_start(m), 0.5);
  Coverage seen;
  expect_online_matches_stored(lanes, seen);
  const ArmRun run = simulate_arms(lanes);
  const ArmTrace& tr = run.traces[0];
  const std::vector<double>& t = tr.t();
  const std::vector<double> v = calc_arm_metrics(m, tr, run.status[0]);
  const std::vector<std::string> columns = arm_metric_columns(m);
  const auto value = [&](const std::string& c) { return v[static_cast<std::size_t>(std::find(columns.begin(), columns.end(), c) - columns.begin())]; };
  // The joint: below 0.2 (the move's direction) from 0.5 s on, % of 0.4 rad.
  const std::vector<double>& q = tr.column("arm.q");
  double past = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k)
    if (t[k] >= 0.5) past = std::max(past, 0.2 - q[k]);
  EXPECT_DOUBLE_EQ(value("arm_overshoot_pct"), 100.0 * past / 0.4);
  EXPECT_LT(value("arm_overshoot_pct"), 10.0);  // was 50: the start pose, 0, counted
  // The tool: past its resting point along the reference from 0.5 s to the end, after the last waypoint.
  const auto at = [&](const char* p, std::size_t k) { return Vec3(tr.column(std::string(p) + "x")[k], tr.column(std::string(p) + "y")[k],
                                                                   tr.column(std::string(p) + "z")[k]); };
  const std::size_t start = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), 0.5) - t.begin()), n = t.size();
  const Vec3 begin = at("tool.ref_", start), target = at("tool.ref_", n - 1), rest = at("tool.", n - 1);
  const Vec3 dir = (target - begin).normalized();
  double over = 0.0;
  for (std::size_t k = 0; k < n; ++k)
    if (t[k] >= 1.0) over = std::max(over, dir.dot(at("tool.", k) - rest));
  EXPECT_DOUBLE_EQ(value("tool_overshoot_pct"), 100.0 * over / (target - begin).norm());

  // A step below kArmMoveTolerance (arm6's wrists, moved 1e-17 rad by the inverse kinematics) is no move:
  // the last move is 0 -> 0.5, not 0.5 -> 0.5 + 1e-15 (overshoot 1e11 %, a settling band of 2e-17 rad).
  const std::vector<ArmModel> tiny{test::arm_from(test::pendulum_arm(
      "tool: {body: arm, point: [0.5, 0, 0]}\ncontroller: {rate: 1000}\n"
      "joints:\n  arm: {controller: {kp: 400, kd: 40, gravity_compensation: 1}}\n"
      "trajectory:\n  waypoints:\n    - {time: 0.5, joints: {arm: 0.5}}\n    - {time: 1.0, joints: {arm: 0.500000000000001}}\n"
      "simulation: {duration: 3.0, integrator: rk4, substeps: 1}\n"))};
  const ArmJointMoves small = calc_arm_joint_moves(tiny[0], 0);
  EXPECT_EQ(small.start, 0.0);
  EXPECT_EQ(small.target, 0.5);
  EXPECT_EQ(small.largest, 0.5);
  EXPECT_EQ(small.t_start, 0.0);
  expect_online_matches_stored(tiny, seen);
  const ArmRun tiny_run = simulate_arms(tiny);
  const std::vector<double> w = calc_arm_metrics(tiny[0], tiny_run.traces[0], tiny_run.status[0]);
  EXPECT_LT(w[1], 10.0);          // arm_overshoot_pct
  EXPECT_FALSE(std::isnan(w[0]));  // arm_settling_s: settled
}

TEST(ArmOnlineMetrics, AFailedLaneGivesAllNaNAndItsNeighboursTheirStoredBits) {
  // The middle lane diverges (kp 1e12 on one explicit step a period).
  const std::vector<ArmModel> lanes{pendulum(400, 40), pendulum(1e12, 40), pendulum(100, 2)};
  Coverage seen;
  expect_online_matches_stored(lanes, seen);
  EXPECT_EQ(seen.failed, 1);
  std::vector<OnlineArmRun> online;
  for (const ArmModel& m : lanes) online.emplace_back(m);
  const ArmRun run = simulate_arms(lanes, {.online = &online});
  ASSERT_EQ(run.status[1], LaneStatus::kNonfinite);
  for (double v : online[1].result(run.status[1])) EXPECT_TRUE(std::isnan(v));
  for (double v : online[0].result(LaneStatus::kSolverFail)) EXPECT_TRUE(std::isnan(v));
  EXPECT_FALSE(std::isnan(online[0].result(run.status[0]).front()));  // the stable lane settles
}

TEST(ArmOnlineMetrics, SimulateArmsWantsOneAccumulatorPerLane) {
  const std::vector<ArmModel> lanes{pendulum(400, 40), pendulum(400, 40)};
  std::vector<OnlineArmRun> one{OnlineArmRun(lanes[0])};
  EXPECT_THROW(simulate_arms(lanes, {.online = &one}), std::invalid_argument);
}

}  // namespace
}  // namespace ff
