// kernel/shaper.cpp: ZV, ZVD and EI input shapers (Singer & Seering 1990; Singhose et al. 1994).
#include "kernel/shaper.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "kernel/trajectory.hpp"
#include "kernel/metrics.hpp"
#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

constexpr ShaperKind kKinds[] = {ShaperKind::kZv, ShaperKind::kZvd, ShaperKind::kEi};

TEST(Shaper, AmplitudesSumToOneAndAreNonNegative) {
  for (auto kind : kKinds)
    for (double zeta : {0.0, 0.045, 0.2}) {
      double sum = 0.0;
      for (const auto& p : make_shaper(kind, 1.7213, zeta)) {
        EXPECT_GT(p.amplitude, 0.0);
        sum += p.amplitude;
      }
      EXPECT_NEAR(sum, 1.0, 1e-14);
    }
}

TEST(Shaper, ZvAndZvdLeaveNoResidualVibrationAtTheDesignFrequency) {
  for (auto kind : {ShaperKind::kZv, ShaperKind::kZvd})
    for (double zeta : {0.0, 0.045, 0.2}) {
      const auto s = make_shaper(kind, 1.7213, zeta);
      EXPECT_LT(calc_residual_vibration(s, 1.7213, zeta), 1e-14);
      EXPECT_NEAR(calc_residual_vibration({{0.0, 1.0}}, 1.7213, zeta), 1.0, 1e-15);  // unshaped
    }
  // ZV undamped: two equal impulses half a period apart.
  const auto zv = make_shaper(ShaperKind::kZv, 2.0, 0.0);
  ASSERT_EQ(zv.size(), 2u);
  EXPECT_DOUBLE_EQ(zv[1].amplitude, 0.5);
  EXPECT_NEAR(zv[1].time, std::numbers::pi / 2.0, 1e-15);
}

TEST(Shaper, EiLeavesExactlyItsToleranceAtTheDesignFrequency) {
  for (double zeta : {0.0, 0.045}) {
    const auto ei = make_shaper(ShaperKind::kEi, 1.7213, zeta, 0.05);
    EXPECT_NEAR(calc_residual_vibration(ei, 1.7213, zeta), 0.05, 1e-10);
  }
}

TEST(Shaper, InsensitivityBandsAtFivePercentMatchTheLiterature) {
  // Width of the 5 % band relative to the design frequency (undamped): ZV 0.064, ZVD 0.287, EI 0.399.
  const double expected[] = {0.064, 0.287, 0.399};
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(calc_insensitivity(make_shaper(kKinds[k], 1.7213, 0.0), 1.7213, 0.0), expected[k], 0.001) << k;
}

TEST(Shaper, BadArgumentsAreRejected) {
  EXPECT_THROW(make_shaper(ShaperKind::kZv, 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(make_shaper(ShaperKind::kZv, 1.0, 1.0), std::invalid_argument);
  EXPECT_THROW(make_shaper(ShaperKind::kEi, 1.0, 0.0, 0.0), std::invalid_argument);
}

TEST(Shaper, ShapedReferenceReachesTheSameTarget) {
  TrajectorySpec traj;
  traj.moves = {{0.5, 10.0}};
  const auto s = make_shaper(ShaperKind::kZvd, 1.7213, 0.045);
  EXPECT_DOUBLE_EQ(calc_shaped_reference(traj, s, 0.0), 0.0);
  EXPECT_NEAR(calc_shaped_reference(traj, s, 12.0), 0.5, 1e-15);
  // Until the second impulse the command is the first impulse's share of the move.
  EXPECT_NEAR(calc_shaped_reference(traj, s, 0.5 * s[1].time), s[0].amplitude * calc_reference(traj, 0.5 * s[1].time), 1e-15);
}

TEST(Shaper, ZvShaperCutsTheClosedLoopResidualVibration) {
  // On the reference rig, a ZV shaper on the first closed-loop mode removes the ringing PD leaves.
  ModelSpec spec = test::rig_spec(0.5, 20.0);
  const Model pd = make_model(spec);
  spec.shaper.type = "zv";
  const Model zv = make_model(spec);
  ASSERT_EQ(zv.shaper.size(), 2u);
  EXPECT_NEAR(zv.shaper[1].time, std::numbers::pi / (zv.resonances[0] * std::sqrt(1 - 0.0446 * 0.0446)), 1e-3);
  // Residual vibration: half the peak-to-peak tip deflection from 5 s (the shaped move is over) on.
  const auto t_pd = test::run_one(pd).traces[0];
  const auto t_zv = test::run_one(zv).traces[0];
  const double r_pd = calc_residual_amplitude(t_pd.t, t_pd.tip_deflection, 5.0, 23.0);
  const double r_zv = calc_residual_amplitude(t_zv.t, t_zv.tip_deflection, 5.0, 23.0);
  EXPECT_GT(r_pd, 0.3);          // PD alone: ~0.6 m of ringing
  EXPECT_LT(r_zv, 0.02 * r_pd);
}

}  // namespace
}  // namespace ff
