// kernel/sensors.cpp: quantised, noisy, delayed measurements of the hub angle and rate.
#include "kernel/sensors.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "kernel/controller.hpp"
#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

struct Rig {
  Model m;
  BatchModel bm;
  BatchState s;
  explicit Rig(const ModelSpec& spec) : m(make_model(spec)), bm(make_batch(std::span<const Model>(&m, 1))), s(make_state(bm)) {}
  // One sample: the true hub angle x at sample k; returns what the controller sees.
  double see(long k, double x) {
    s.sample = k;
    s.q[0] = x;
    double a = 0, r = 0;
    compute_measurements(bm, s, &a, &r);
    return a;
  }
};

TEST(Sensors, EncoderQuantisesTheHubAngle) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.resolution = 0.01;
  Rig rig(spec);
  EXPECT_DOUBLE_EQ(rig.see(0, 0.0149), 0.01);
  EXPECT_DOUBLE_EQ(rig.see(1, 0.0151), 0.02);
  EXPECT_DOUBLE_EQ(rig.see(2, -0.0049), 0.0);
  // And the PD acts on the quantised angle: kp (r - 0.01).
  rig.s.sample = 3;
  rig.s.q[0] = 0.0149;
  double r = 0.05, acc = 0.0, rf = 0.0;
  compute_control(rig.bm, rig.s, &r, &acc, &rf);
  EXPECT_NEAR(rig.s.tau[0], 1e5 * (0.05 - 0.01), 1e-9);
}

TEST(Sensors, NoiseHasItsStandardDeviationAndRepeats) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.noise = 1e-3;
  Rig a(spec), b(spec);
  spec.simulation.seed = 2;
  Rig c(spec);
  double sum = 0, sum2 = 0;
  const int n = 20000;
  bool all_equal = true, any_differs = false;
  for (int k = 0; k < n; ++k) {
    const double x = a.see(k, 0.3) - 0.3;
    sum += x;
    sum2 += x * x;
    all_equal &= b.see(k, 0.3) - 0.3 == x;
    any_differs |= c.see(k, 0.3) - 0.3 != x;
  }
  EXPECT_NEAR(sum / n, 0.0, 5.0 * 1e-3 / std::sqrt(n));  // 5 standard errors
  EXPECT_NEAR(std::sqrt(sum2 / n), 1e-3, 3e-5);
  EXPECT_TRUE(all_equal);    // same seed, same noise
  EXPECT_TRUE(any_differs);  // another seed, other noise
}

TEST(Sensors, DelayShiftsTheMeasurementByWholeSamples) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.delay = 3;
  Rig rig(spec);
  for (long k = 0; k < 10; ++k) {
    const double seen = rig.see(k, 0.1 * static_cast<double>(k));
    EXPECT_DOUBLE_EQ(seen, k >= 3 ? 0.1 * static_cast<double>(k - 3) : 0.0) << "sample " << k;
  }
}

TEST(Sensors, ClosedLoopWithCoarseEncoderStillTracks) {
  // A 1 mrad encoder on the hub: the arm still arrives, within about a quantum, at its target.
  ModelSpec spec = test::rig_spec(0.5, 20.0);
  spec.notch.enabled = true;
  spec.sensors.hub_angle.resolution = 1e-3;
  const auto tr = test::run_one(make_model(spec)).traces[0];
  EXPECT_NEAR(tr.hub_angle.back(), 0.5, 2e-3);
}

}  // namespace
}  // namespace ff
