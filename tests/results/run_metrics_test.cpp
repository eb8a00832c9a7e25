// results/run_metrics.cpp: per-move responses of a run, and the seed's headline result.
#include "results/run_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

TEST(RunMetrics, NotchCutsTipSettlingFiveFoldAndUnderThreeSeconds) {
  // The seed: ~10 s without the filter, ~1 s with it (0.5 rad move).
  ModelSpec spec = test::rig_spec(0.5, 50.0);
  const Model pd = make_model(spec);
  spec.notch.enabled = true;
  const Model notch = make_model(spec);
  const auto cols = calc_metric_columns(1);
  const auto v_pd = calc_run_metrics(pd, test::run_one(pd).traces[0]);
  const auto v_notch = calc_run_metrics(notch, test::run_one(notch).traces[0]);
  ASSERT_EQ(cols[0], "m1_tip_settling_s");
  ASSERT_FALSE(std::isnan(v_pd[0]));
  EXPECT_LE(v_notch[0], 3.0);
  EXPECT_GE(v_pd[0] / v_notch[0], 5.0);
}

TEST(RunMetrics, RunEndingMidMoveLeavesTheMoveNotSettled) {
  // simulation.duration = 2 s cuts the 3 s move: no settling and no residual vibration (NaN, status
  // not_settled, as MATLAB's stepinfo for a response that has not settled); overshoot and peaks are
  // those of the part that ran: the arm is still short of the target (overshoot 0).
  ModelSpec spec = test::rig_spec(0.5, 7.0);
  spec.trajectory.moves.push_back({0.0, 45.0});
  spec.simulation.duration = 2.0;
  const Model m = make_model(spec);
  const auto run = test::run_one(m);
  const auto v = calc_run_metrics(m, run.traces[0]);
  const auto cols = calc_metric_columns(2);
  ASSERT_EQ(v.size(), cols.size());  // the second move never starts: its columns are there, with no numbers
  for (std::size_t i = kMoveMetrics.size(); i < v.size(); ++i) EXPECT_TRUE(std::isnan(v[i])) << cols[i];
  EXPECT_TRUE(std::isnan(v[0]));  // m1_tip_settling_s
  EXPECT_EQ(v[1], 0.0);           // m1_tip_overshoot_pct
  EXPECT_TRUE(std::isnan(v[2]));  // m1_hub_settling_s
  EXPECT_GT(v[4], 0.01);          // m1_peak_tip_deflection_m: the arm bends while it moves
  EXPECT_TRUE(std::isnan(v[5]));  // m1_residual_vibration_m
  EXPECT_GT(v[6], 0.0);           // m1_peak_torque_Nm
  EXPECT_EQ(calc_run_status(LaneStatus::kOk, cols, v), "not_settled");
}

TEST(RunMetrics, ColumnsNameEveryMoveMetric) {
  const auto cols = calc_metric_columns(2);
  ASSERT_EQ(cols.size(), 2 * kMoveMetrics.size());
  EXPECT_EQ(cols.front(), "m1_tip_settling_s");
  EXPECT_EQ(cols.back(), "m2_peak_torque_Nm");
}

TEST(RunMetrics, ResponseCaughtInsideTheBandMidSwingIsNotSettled) {
  // PD alone rings at 0.27 Hz with 0.15 rad amplitude through the 7 s hold of the seed's move.
  ModelSpec spec = test::rig_spec(0.5, 7.0);
  spec.trajectory.moves.push_back({0.0, 45.0});
  const Model m = make_model(spec);
  const auto run = test::run_one(m);
  const auto cols = calc_metric_columns(2);
  const auto v = calc_run_metrics(m, run.traces[0]);
  EXPECT_TRUE(std::isnan(v[0]));                    // out move: still ringing when the hold ends
  EXPECT_NEAR(v[7], 40.6, 0.5);                     // return move: settles ~40 s after it ends
  EXPECT_EQ(calc_run_status(run.status[0], cols, v), "not_settled");
  EXPECT_NEAR(v[1], 38.0, 0.5);                     // tip overshoot, %
  EXPECT_NEAR(v[4], 0.664, 0.002);                  // peak tip deflection, m
  EXPECT_NEAR(v[6], 3880, 20);                      // peak torque, N m
}

}  // namespace
}  // namespace ff
