// kernel/modes.cpp and kernel/model.cpp: the seed's numbers, the reference rig's modes, convergence
// to the continuous Euler-Bernoulli cantilever.
#include "kernel/modes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "common/errors.hpp"
#include "kernel/cantilever.hpp"
#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

Model rig_with(int n) {
  ModelSpec s = test::rig_spec();
  s.segments = n;
  s.simulation.substeps = 1;  // skip the automatic choice: not under test here
  return make_model(s);
}

TEST(Model, SegmentsFollowTheCellLayout) {
  const Model m = rig_with(6);
  EXPECT_NEAR(m.seg_length[0], 0.41656, 1e-12);
  for (int i = 1; i < 5; ++i) EXPECT_NEAR(m.seg_length[i], 0.83312, 1e-12);
  EXPECT_NEAR(m.seg_length[5], 0.41656, 1e-12);
  EXPECT_NEAR(m.joint_k[1], 39.5e3, 1e-9);
  EXPECT_NEAR(m.joint_c[1], 90.4, 1e-12);
  // Other N: k and c scale as 1/l (reference-rig.md).
  const Model m24 = rig_with(24);
  EXPECT_NEAR(m24.joint_k[1], 39.5e3 * 0.83312 / (4.1656 / 23), 1e-6);
}

TEST(Model, BeamMassAndCantileverStiffnessMatchSeed) {
  const BeamSpec b;
  EXPECT_NEAR(calc_area_moment(b), 1.7560e-7, 0.0001e-7);
  EXPECT_NEAR(calc_beam_mass(b), 187.7, 0.3);  // seed: "approximately 187.7 kg"; exact 187.45
  EXPECT_NEAR(calc_cantilever_stiffness(b, 0.83312) / 1e3, 131.1, 0.3);  // seed eq. 5: 131.1 kN m/rad
  EXPECT_NEAR(calc_cantilever_stiffness(b, 4.1656) / 1e3, 26.2, 0.05);   // 26.2 kN m/rad
  // The seed's joint stiffness lies between them, as a series combination must.
  EXPECT_GT(39.5e3, calc_cantilever_stiffness(b, 4.1656));
  EXPECT_LT(39.5e3, calc_cantilever_stiffness(b, 0.83312));
}

TEST(Model, AnAutomaticStepBeyondAHundredThousandSubstepsIsAnErrorOfTheSubsteps) {
  // A payload of 4e38 kg (found by fuzz_set) puts a mode at ~1e71 rad/s: the substep count no longer
  // fits an int. One error naming simulation.substeps, not undefined behaviour in the cast.
  ModelSpec s = test::rig_spec();
  s.payload_mass = 4e38;
  s.notch.enabled = true;
  s.notch.order = 2;
  try {
    make_model(s);
    FAIL() << "accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("simulation.substeps"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("more than 100000"), std::string::npos) << e.what();
  }
}

TEST(Modes, ClampedModesMatchPaper) {
  const auto modes = calc_clamped_modes(rig_with(6));
  ASSERT_GE(modes.size(), 2u);
  EXPECT_NEAR(modes[0].frequency_hz(), 0.300, 0.0005);  // reference-rig.md: 0.300 Hz (seed: ~0.3)
  EXPECT_NEAR(modes[1].frequency_hz(), 2.300, 0.0005);  // 2.300 Hz (seed: ~2.3)
  EXPECT_TRUE(modes[0].oscillatory);
  EXPECT_LT(modes[0].zeta, 0.01);
}

TEST(Modes, ClosedLoopModesMatchReferenceRig) {
  const Model m = rig_with(6);
  const auto res = calc_closed_loop_resonances(m);
  ASSERT_GE(res.size(), 2u);
  EXPECT_NEAR(res[0] / kTwoPi, 0.274, 0.0005);
  EXPECT_NEAR(res[1] / kTwoPi, 2.289, 0.0005);
  const auto modes = calc_closed_loop_modes(m);
  EXPECT_NEAR(modes[0].zeta, 0.045, 0.001);  // reference-rig.md: zeta ~ 0.045
  // The notch filter takes its zeros from here when enabled.
  ModelSpec s = test::rig_spec();
  s.notch.enabled = true;
  const Model mn = make_model(s);
  EXPECT_DOUBLE_EQ(mn.omega_z[0], res[0]);
  EXPECT_DOUBLE_EQ(mn.omega_z[1], res[1]);
}

TEST(Modes, IntegralActionAddsASlowRealPoleNearTheOrigin) {
  ModelSpec s = test::rig_spec();
  s.controller.ki = 1e3;
  const auto modes = calc_closed_loop_modes(make_model(s));
  const auto base = calc_closed_loop_modes(rig_with(6));
  EXPECT_EQ(modes.size(), base.size() + 1);
  EXPECT_LT(modes[0].omega_n, 0.05);  // ~ ki / kp = 0.01 1/s
}

// (#32.14) A free hub (kp = kd = 0): its rigid-body mode is zero to the eigen-solve's resolution at every
// N (omega 0: free), not a slow or unstable pole of round-off, and the beam's modes stay (at N = 96 the
// dampers' real poles reach 1e7 rad/s: no scale for it). The threshold is relative: 1.5e-6 of the
// stiffness scale sqrt(|M^-1 K|).
TEST(Modes, AFreeHubsRigidModeIsZeroAtEveryN) {
  for (int n : {6, 24, 64, 96}) {
    ModelSpec s = test::rig_spec();
    s.segments = n;
    s.simulation.substeps = 1;
    s.controller.kp = s.controller.kd = 0.0;
    const std::vector<Mode> modes = calc_closed_loop_modes(make_model(s));
    int free = 0;
    for (const Mode& m : modes) free += m.omega_n == 0.0;
    EXPECT_GE(free, 1) << "N = " << n;
    EXPECT_LE(free, 2) << "N = " << n;  // the hub's angle and rate: a double zero
    const Mode& first = modes[static_cast<std::size_t>(free)];
    EXPECT_TRUE(first.oscillatory) << "N = " << n;
    EXPECT_GT(first.frequency_hz(), 0.3) << "N = " << n;  // the free beam's first bending mode
    EXPECT_GT(first.zeta, 0.0) << "N = " << n;
  }
  EXPECT_TRUE(is_zero_eigenvalue(0.004, 1e5));
  EXPECT_FALSE(is_zero_eigenvalue(0.2, 1e5));
  EXPECT_TRUE(is_zero_eigenvalue(0.0, 0.0));
}

// The segmented beam is a cantilever of flexural rigidity kappa EI with kappa = k l / (E I).
CantileverSpec continuous_rig() {
  const Model m = rig_with(6);
  const auto& b = m.spec.beam;
  const double kappa = m.joint_k[1] * m.cell / (b.youngs_modulus * calc_area_moment(b));
  return {kappa * b.youngs_modulus * calc_area_moment(b), b.density * b.height * b.thickness, b.length,
          m.spec.payload_mass, m.spec.payload_inertia};
}

TEST(Modes, ClampedModesConvergeToEulerBernoulliCantilever) {
  const auto exact = calc_cantilever_frequencies(continuous_rig(), 2);
  double prev_err[2] = {1e9, 1e9};
  for (int n : {6, 12, 24, 48}) {
    const auto modes = calc_clamped_modes(rig_with(n));
    for (int j = 0; j < 2; ++j) {
      const double err = std::fabs(modes[j].omega_n - exact[j]) / exact[j];
      EXPECT_LT(err, prev_err[j]) << "N = " << n << ", mode " << j + 1;
      if (n > 6) {
        EXPECT_GT(prev_err[j] / err, 3.0) << "second-order convergence, N = " << n;
      }
      prev_err[j] = err;
    }
  }
  EXPECT_LT(prev_err[0], 2e-4);
  EXPECT_LT(prev_err[1], 2e-4);
  // N = 48: 0.2985 Hz and 2.275 Hz (reference-rig.md).
  const auto m48 = calc_clamped_modes(rig_with(48));
  EXPECT_NEAR(m48[0].frequency_hz(), 0.2985, 0.00005);
  EXPECT_NEAR(m48[1].frequency_hz(), 2.275, 0.0005);
}

TEST(Modes, AutoSubstepsResolveTheFastestMode) {
  EXPECT_EQ(calc_auto_substeps(rig_with(6)), 1);
  const Model m24 = rig_with(24);
  const int n = calc_auto_substeps(m24);
  double fastest = 0.0;
  for (const auto& md : calc_clamped_modes(m24)) fastest = std::max(fastest, md.oscillatory ? md.omega_n : md.omega_n / 2.5);
  EXPECT_LE(fastest * m24.control_period / n, 1.0);
  EXPECT_GT(n, 1);
}

TEST(Modes, MidpointTakesOneStepPerSampleAtSixSegments) {
  Model m6 = rig_with(6);
  EXPECT_EQ(calc_auto_substeps(calc_clamped_modes(m6), m6.control_period, Integrator::kMidpoint), 1);
  EXPECT_EQ(calc_auto_substeps(calc_closed_loop_modes(m6), m6.control_period, Integrator::kMidpoint), 1);
  // At N = 24 the stiff, damped modes need h |lambda| <= 4: more steps than SDIRK2, fewer than RK4.
  const Model m24 = rig_with(24);
  const int mid = calc_auto_substeps(calc_clamped_modes(m24), m24.control_period, Integrator::kMidpoint);
  EXPECT_GT(mid, calc_auto_substeps(calc_clamped_modes(m24), m24.control_period, Integrator::kSdirk2));
  EXPECT_LT(mid, calc_auto_substeps(calc_clamped_modes(m24), m24.control_period, Integrator::kRk4));
}

}  // namespace
}  // namespace ff
