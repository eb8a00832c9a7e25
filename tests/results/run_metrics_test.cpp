// results/run_metrics.cpp: per-move responses of a run, and the seed's headline result.
#include "results/run_metrics.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

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
  EXPECT_EQ(v[7], 0.0);           // m1_settling_horizon_s: nothing of the hold ran, nothing can be confirmed
  EXPECT_EQ(calc_run_status(LaneStatus::kOk, cols, v), "not_settled");
}

// The row from the online accumulators (simulate's `metrics`) is the row from the trace, bit for bit.
void expect_online_row_is_the_trace_row(const std::vector<Model>& models) {
  const BatchModel bm = make_batch(models);
  const BatchRun traced = simulate(bm);
  std::vector<OnlineRun> metrics;
  for (const Model& m : models) metrics.push_back(make_online_run(m));
  const BatchRun online = simulate(bm, nullptr, nullptr, &metrics);
  EXPECT_TRUE(online.traces.empty());
  for (std::size_t l = 0; l < models.size(); ++l) {
    EXPECT_EQ(online.status[l], traced.status[l]);
    const auto a = calc_run_metrics(models[l], traced.traces[l]), b = calc_run_metrics(models[l], metrics[l]);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i)
      EXPECT_EQ(std::bit_cast<std::uint64_t>(a[i]), std::bit_cast<std::uint64_t>(b[i]))
          << "lane " << l << " column " << calc_metric_columns(static_cast<int>(a.size() / kMoveMetrics.size()))[i]
          << ": trace " << a[i] << ", online " << b[i];
  }
}

TEST(RunMetrics, OnlineRowIsTheTraceRowForEveryIntegratorAndOutcome) {
  // Two moves (up, then down past the start) on rigs of which some settle and some do not, and the
  // same cut short by simulation.duration in the second move, for each fixed-step integrator (CVODE
  // records through the same code).
  for (Integrator integ : {Integrator::kRk4, Integrator::kSdirk2, Integrator::kMidpoint}) {
    for (double duration : {0.0, 10.5}) {
      std::vector<Model> models;
      for (double payload : {200.0, 328.7, 450.0}) {
        ModelSpec spec = test::rig_spec(0.3, 6.0);
        spec.trajectory.moves.push_back({-0.1, 5.0});
        spec.notch.enabled = true;
        spec.payload_mass = payload;
        spec.simulation.integrator = integ;
        spec.simulation.duration = duration;
        models.push_back(make_model(spec));
      }
      SCOPED_TRACE(testing::Message() << "integrator " << static_cast<int>(integ) << " duration " << duration);
      expect_online_row_is_the_trace_row(models);
    }
  }
}

TEST(RunMetrics, OnlineRowOfADivergingLaneIsTheTraceRow) {
  // A lane that stops being finite has no numbers, in both forms.
  ModelSpec good = test::rig_spec(0.5, 2.0);
  good.simulation.substeps = 1;
  ModelSpec bad = good;
  bad.controller.kp = 1e12;  // far beyond what 1 kHz sampling can stabilise
  expect_online_row_is_the_trace_row({make_model(good), make_model(bad)});
}

TEST(RunMetrics, ColumnsNameEveryMoveMetric) {
  const auto cols = calc_metric_columns(2);
  ASSERT_EQ(cols.size(), 2 * kMoveMetrics.size());
  EXPECT_EQ(cols.front(), "m1_tip_settling_s");
  EXPECT_EQ(cols[6], "m1_peak_torque_Nm");
  EXPECT_EQ(cols.back(), "m2_settling_horizon_s");
}

TEST(RunMetrics, SettlingColumnsNameTheirHorizonColumn) {
  EXPECT_EQ(calc_horizon_column("m1_tip_settling_s"), "m1_settling_horizon_s");
  EXPECT_EQ(calc_horizon_column("m12_hub_settling_s"), "m12_settling_horizon_s");
  // An arm's settling columns (arm/arm_metrics.hpp) share one window's horizon.
  for (const char* arm : {"tool_settling_s", "shoulder_settling_s", "mx_tip_settling_s"})
    EXPECT_EQ(calc_horizon_column(arm), "settling_horizon_s") << arm;
  for (const char* other : {"m1_tip_overshoot_pct", "m1_settling_horizon_s", "settling_horizon_s", "payload.mass", ""})
    EXPECT_EQ(calc_horizon_column(other), "") << other;
}

TEST(RunMetrics, ResponseCaughtInsideTheBandMidSwingIsNotSettled) {
  // PD alone rings at 0.27 Hz with 0.15 rad amplitude through the 7 s hold of the seed's move.
  ModelSpec spec = test::rig_spec(0.5, 7.0);
  spec.trajectory.moves.push_back({0.0, 45.0});
  const Model m = make_model(spec);
  const auto run = test::run_one(m);
  const auto cols = calc_metric_columns(2);
  const auto v = calc_run_metrics(m, run.traces[0]);
  const std::size_t m2 = kMoveMetrics.size();      // the return move's first column
  EXPECT_TRUE(std::isnan(v[0]));                    // out move: still ringing when the hold ends
  EXPECT_NEAR(v[m2], 40.6, 0.5);                    // return move: settles ~40 s after it ends
  // Horizons: the hold less one period of the 0.2740 Hz resonance (the dwell the settling rule needs);
  // the out move's settling time is right-censored at 7 - 3.65 s, the return move's lies below 45 - 3.65 s.
  const double dwell = 2.0 * M_PI / m.resonances[0];
  EXPECT_NEAR(dwell, 1.0 / 0.2740, 0.01);
  EXPECT_NEAR(v[7], 7.0 - dwell, 1e-9);
  EXPECT_NEAR(v[m2 + 7], 45.0 - dwell, 1e-9);
  EXPECT_LE(v[m2], v[m2 + 7]);
  EXPECT_EQ(calc_run_status(run.status[0], cols, v), "not_settled");
  EXPECT_NEAR(v[1], 38.0, 0.5);                     // tip overshoot, %
  EXPECT_NEAR(v[4], 0.664, 0.002);                  // peak tip deflection, m
  EXPECT_NEAR(v[6], 3880, 20);                      // peak torque, N m
}

}  // namespace
}  // namespace ff
