// kernel/controller.cpp: PID with derivative on the measured rate, torque limit, anti-windup,
// load-compensation feed-forward, notch on the reference or on the measured hub angle.
#include "kernel/controller.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "kernel/model_io.hpp"
#include "kernel/notch.hpp"
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

TEST(Controller, LoadCompensationFromHydraulicPressureUsesTheActuatorTorque) {
  // The seed's experimental rig: the load signal is n D (p_a - p_b), not the root moment.
  ModelSpec s = test::rig_spec();
  s.hydraulics.enabled = true;
  s.controller.load_compensation = 0.5;
  s.controller.load_signal = "pressure";
  Loop loop(s);
  loop.s.q[1] = 0.01;  // ignored now
  loop.s.z[loop.bm.layout.pressure] += 2.0;  // p_a - p_b = 2 MPa
  EXPECT_NEAR(loop.sample(0.0), -0.5 * s.hydraulics.displacement * 2.0e6, 1e-6);
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

// ---- notch on the feedback path: e = r - F(theta_m), the rate unfiltered --------------------

// A rig whose notch sits on the measured hub angle, zeros at w1, w2 (rad/s).
ModelSpec feedback_notch_spec(double w1, double w2) {
  ModelSpec s = test::rig_spec();
  s.notch.enabled = true;
  s.notch.placement = "feedback";
  s.notch.omega_z[0] = w1;
  s.notch.omega_z[1] = w2;
  return s;
}

TEST(Controller, FeedbackNotchStartsAtRestOnTheMeasuredAngle) {
  // Hub held at 0.2 rad, commanded 0.2 rad: no error from the first sample on (a filter starting at 0
  // would see a step and command ~kp 0.2).
  Loop loop(feedback_notch_spec(12.0, 40.0));
  loop.s.q[0] = 0.2;
  const double r0 = 0.2;
  reset_controller(loop.bm, loop.s, &r0);
  for (int k = 0; k < 100; ++k) {
    loop.s.sample = k;
    EXPECT_NEAR(loop.sample(0.2), 0.0, 1e-6) << "sample " << k;  // N·m, against ~kp 0.2 = 2e4 from rest at 0
  }
}

// Drives the controller with the plant replaced by theta = c + A sin(w t) (rates consistent) and r = 0;
// returns the largest |e - e_expected(t)| over the last second of 5 s, e = (tau + kd omega) / kp, where
// e_expected = -c - A |F| sin(w t + arg F) with F the discrete filter's response at w.
double worst_error_deviation(const ModelSpec& spec, double c, double A, double w) {
  Loop loop(spec);
  const double T = loop.bm.control_period, kp = spec.controller.kp, kd = spec.controller.kd;
  const auto F = calc_sections_response(make_notch_sections(make_notch_design(loop.m), T), w, T);
  loop.s.q[0] = c;
  const double r0 = 0.0;
  reset_controller(loop.bm, loop.s, &r0);
  double worst = 0.0;
  for (long k = 0; k <= 5000; ++k) {
    const double t = static_cast<double>(k) * T;
    loop.s.sample = k;
    loop.s.q[0] = c + A * std::sin(w * t);
    loop.s.v[0] = A * w * std::cos(w * t);
    const double tau = loop.sample(0.0);
    const double e = (tau + kd * loop.s.v[0]) / kp;  // the derivative path sees the measured rate unfiltered
    const double expected = -c - A * std::abs(F) * std::sin(w * t + std::arg(F));
    if (t >= 4.0) worst = std::max(worst, std::fabs(e - expected));
  }
  return worst;
}

TEST(Controller, FeedbackNotchRemovesAHubSinusoidAtItsZeroFromTheError) {
  // Analytic limit: the Tustin sections are pre-warped so F(exp(j w_z T)) = 0 exactly, and F(1) = 1, so with
  // theta = c + A sin(w_z t) the error tends to -c: the sinusoid is gone from e once the filter's own
  // transient (poles at alpha w_z, zeta = 1: e^{-19 t}) has died.
  const double wz = 12.0, A = 0.05, c = 0.3;
  const ModelSpec spec = feedback_notch_spec(wz, 40.0);
  EXPECT_LT(worst_error_deviation(spec, c, A, wz), 1e-9 * A);
  // The second zero likewise; and off the zeros the error carries exactly A |F(w)| of the sinusoid.
  EXPECT_LT(worst_error_deviation(spec, c, A, 40.0), 1e-9 * A);
  EXPECT_LT(worst_error_deviation(spec, c, A, 0.5 * wz), 1e-9 * A);
  Loop loop(spec);
  const double T = loop.bm.control_period;
  EXPECT_GT(std::abs(calc_sections_response(make_notch_sections(make_notch_design(loop.m), T), 0.5 * wz, T)), 0.5);
}

// Amplitude of the component of y at omega (rad/s) over t0 <= t <= t1: least squares on a + b cos + c sin.
double amplitude_at(const std::vector<double>& t, const std::vector<double>& y, double t0, double t1, double omega) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (t[k] < t0 || t[k] > t1) continue;
    const Eigen::Vector3d row(1.0, std::cos(omega * t[k]), std::sin(omega * t[k]));
    A += row * row.transpose();
    b += row * y[k];
  }
  const Eigen::Vector3d x = A.ldlt().solve(b);
  return std::hypot(x[1], x[2]);
}

// Largest |y| over t0 <= t < t1.
double peak(const std::vector<double>& t, const std::vector<double>& y, double t0, double t1) {
  double p = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k)
    if (t[k] >= t0 && t[k] < t1) p = std::max(p, std::fabs(y[k]));
  return p;
}

TEST(Controller, FeedbackNotchIsStableAndQuietsTheTipOnTheReferenceRig) {
  // configs/fbtb.yaml (N = 6, PD): 0.5 rad and back, then 45 s of hold. With the notch on the measured hub
  // angle (zeros at the closed-loop resonances, 1.72 and 14.4 rad/s) the loop stays stable, the vibration
  // dying out through the hold, and the tip's residual vibration at the first zero is a fifth of PD's
  // (0.048 m against 0.22 m). The loop it makes has a slow, lightly damped mode of its own near 1.2 rad/s.
  ModelSpec spec = load_model(std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml").spec;
  const auto pd = test::run_one(make_model(spec)).traces[0];
  spec.notch.enabled = true;
  spec.notch.placement = "feedback";
  const Model m = make_model(spec);
  const auto run = test::run_one(m);
  ASSERT_EQ(run.status[0], LaneStatus::kOk);
  const auto& fb = run.traces[0];
  EXPECT_LT(peak(fb.t, fb.tip_deflection, 48.0, 58.0), 0.5 * peak(fb.t, fb.tip_deflection, 15.0, 25.0));
  EXPECT_LT(peak(fb.t, fb.hub_angle, 48.0, 58.0), 0.08);  // rad, still swinging slowly about 0
  const double w = m.omega_z[0], t0 = 13.0, t1 = 58.0;  // the final hold
  const double a_pd = amplitude_at(pd.t, pd.tip_deflection, t0, t1, w);
  const double a_fb = amplitude_at(fb.t, fb.tip_deflection, t0, t1, w);
  EXPECT_LT(a_fb, 0.5 * a_pd) << "PD " << a_pd << " m, notch on the feedback " << a_fb << " m";
}

TEST(Controller, FeedbackNotchLeavesTheReferenceUnfiltered) {
  Loop loop(feedback_notch_spec(12.0, 40.0));
  double rf = 0.0, r = 0.37;
  const double acc = 0.0;
  compute_control(loop.bm, loop.s, &r, &acc, &rf);
  EXPECT_EQ(rf, r);
}

}  // namespace
}  // namespace ff
