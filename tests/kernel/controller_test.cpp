// kernel/controller.cpp: PID with derivative on the measured rate, torque limit, anti-windup,
// load-compensation feed-forward, notch on the reference.
#include "kernel/controller.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

struct Loop {
  Model m;
  BatchModel bm;
  BatchState s;
  explicit Loop(const ModelSpec& spec) : m(make_model(spec)), bm(make_batch(std::span<const Model>(&m, 1))), s(make_state(bm)) {
    const double r0 = 0.0;
    reset_controller(bm, s, &r0);
  }
  double sample(double r, double r_accel = 0.0) {
    double rf = 0.0;
    compute_control(bm, s, &r, &r_accel, &rf);
    return s.tau[0];
  }
};

TEST(Controller, PdLawOnErrorAndMeasuredRate) {
  Loop loop(test::rig_spec());
  loop.s.q[0] = 0.1;
  loop.s.v[0] = 0.2;
  // tau = kp (r - theta) - kd omega = 1e5 (0.3 - 0.1) - 3e4 * 0.2
  EXPECT_DOUBLE_EQ(loop.sample(0.3), 1e5 * 0.2 - 3e4 * 0.2);
}

TEST(Controller, TorqueLimitSaturatesBothWays) {
  ModelSpec s = test::rig_spec();
  s.controller.torque_limit = 5000.0;
  Loop loop(s);
  EXPECT_DOUBLE_EQ(loop.sample(1.0), 5000.0);
  EXPECT_DOUBLE_EQ(loop.sample(-1.0), -5000.0);
  EXPECT_DOUBLE_EQ(loop.sample(0.01), 1000.0);
}

TEST(Controller, IntegralAccumulatesErrorTimesPeriod) {
  ModelSpec s = test::rig_spec();
  s.controller.ki = 2e4;
  Loop loop(s);
  for (int k = 0; k < 10; ++k) loop.sample(0.01);
  EXPECT_NEAR(loop.s.integral[0], 10 * 0.01 * 1e-3, 1e-15);
  // Forward Euler: the 11th sample uses the integral of the first 10.
  EXPECT_NEAR(loop.sample(0.01), 1e5 * 0.01 + 2e4 * 1e-4, 1e-9);
}

TEST(Controller, AntiWindupFreezesIntegralWhileSaturated) {
  ModelSpec s = test::rig_spec();
  s.controller.ki = 2e4;
  s.controller.torque_limit = 1000.0;
  Loop loop(s);
  for (int k = 0; k < 1000; ++k) loop.sample(0.5);  // kp e = 5e4 >> limit
  EXPECT_DOUBLE_EQ(loop.s.integral[0], 0.0);
  // Error reversing out of saturation integrates again at once.
  loop.sample(-0.001);
  EXPECT_NEAR(loop.s.integral[0], -1e-6, 1e-18);
}

TEST(Controller, LoadCompensationOpposesRootBendingMoment) {
  ModelSpec s = test::rig_spec();
  s.controller.load_compensation = 0.5;
  Loop loop(s);
  loop.s.q[1] = 0.01;  // root joint bent: the beam pushes the hub with k1 q1
  EXPECT_DOUBLE_EQ(loop.sample(0.0), -0.5 * 39.5e3 * 0.01);
}

TEST(Controller, FeedForwardTorqueEntersWithItsGain) {
  ModelSpec s = test::rig_spec();
  s.controller.feedforward = 1.0;
  Loop loop(s);
  // tau = kp (r - theta) + f * (feed-forward torque at unit gain).
  EXPECT_NEAR(loop.sample(0.0, 1234.0), 1234.0, 1e-9);
  EXPECT_GT(loop.m.rigid_inertia, 6000.0);  // hub 50 + beam ~1085 + payload ~5822 kg m^2
}

TEST(Controller, FeedForwardMakesANearlyRigidArmTrackItsMove) {
  // The feed-forward is the rigid arm's inverse dynamics plus kd r': on a (nearly) rigid arm the PD has
  // almost nothing left to correct, while PD alone lags by kd r'/kp + J r''/kp, ~0.08 rad here.
  ModelSpec spec = test::rig_spec(0.5, 1.0);
  spec.joints.stiffness *= 1000.0;
  spec.simulation.integrator = Integrator::kSdirk2;
  auto worst_error = [&](double gain) {
    spec.controller.feedforward = gain;
    const auto tr = test::run_one(make_model(spec)).traces[0];
    double worst = 0.0;
    for (std::size_t k = 0; k < tr.t.size() && tr.t[k] <= 3.0; ++k)
      worst = std::max(worst, std::fabs(tr.ref[k] - tr.hub_angle[k]));
    return worst;
  };
  const double pd = worst_error(0.0), ff = worst_error(1.0);
  EXPECT_GT(pd, 0.07);
  EXPECT_LT(ff, 0.05 * pd);
}

TEST(Controller, NotchHoldsAConstantReferenceExactly) {
  ModelSpec s = test::rig_spec();
  s.notch.enabled = true;
  Loop loop(s);
  double rf = 0.0, r = 0.0;
  const double acc = 0.0;
  for (int k = 0; k < 5000; ++k) compute_control(loop.bm, loop.s, &r, &acc, &rf);
  EXPECT_EQ(rf, 0.0);
  // A step in the reference is smoothed: the first filtered sample is a small fraction of it.
  r = 1.0;
  compute_control(loop.bm, loop.s, &r, &acc, &rf);
  EXPECT_GT(rf, 0.0);
  EXPECT_LT(rf, 0.01);
}

}  // namespace
}  // namespace ff
