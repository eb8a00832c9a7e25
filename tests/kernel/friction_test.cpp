// Hub friction (kernel/dynamics.cpp, calc_hub_friction): viscous, Coulomb, Stribeck; regularised.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "kernel/dynamics.hpp"
#include "common/errors.hpp"
#include "kernel/fixed_step.hpp"
#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

ModelSpec friction_rig() {
  ModelSpec s = test::rig_spec();
  s.friction.viscous = 50.0;
  s.friction.coulomb = 400.0;
  s.friction.stiction = 600.0;
  s.friction.stribeck_velocity = 0.02;
  s.friction.smoothing = 1e-3;
  return s;
}

TEST(Friction, NeverAddsEnergyAndMatchesItsLaw) {
  const Model m = make_model(friction_rig());
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  for (double w = -2.0; w <= 2.0; w += 0.001) EXPECT_LE(calc_hub_friction(bm, 0, 0.0, w) * w, 0.0) << w;
  EXPECT_EQ(calc_hub_friction(bm, 0, 0.0, 0.0), 0.0);
  // Well above the Stribeck velocity: Coulomb plus viscous.
  EXPECT_NEAR(calc_hub_friction(bm, 0, 0.0, 1.0), -(400.0 + 50.0), 1e-6);
  // Near the Stribeck peak (w >> eps, w << vs): the stiction level.
  EXPECT_NEAR(calc_hub_friction(bm, 0, 0.0, 0.005), -(50.0 * 0.005 + (400.0 + 200.0 * std::exp(-0.0625)) * std::tanh(5.0)),
              1e-9);
}

// The hub displacement after 2 s under a constant hub torque (no controller), on a stiff arm; `worn`
// changes the spec first.
double slide(double torque, void (*worn)(ModelSpec&) = nullptr) {
  ModelSpec s = friction_rig();
  if (worn) worn(s);
  s.joints.stiffness *= 100.0;
  const Model m = make_model(s);
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  BatchState st = make_state(bm);
  Workspace ws = make_workspace(bm);
  st.tau[0] = torque;
  for (int k = 0; k < 20000; ++k) step_rk4(bm, st, ws, 1e-4);
  return st.q[0];
}

TEST(Friction, BreaksAwayAtTheStictionTorque) {
  // Below the breakaway torque the regularised model only creeps (w ~ eps atanh(0.9) = 1.5 mrad/s);
  // above it the arm slides, accelerating at about (660 - 600) / J.
  const double below = slide(0.9 * 600.0), above = slide(1.1 * 600.0);
  EXPECT_LT(std::fabs(below), 0.005);
  EXPECT_GT(above, 0.03);
  EXPECT_GT(above, 10.0 * below);
  EXPECT_DOUBLE_EQ(slide(-1.1 * 600.0), -above);  // symmetric
}

// A worn gear's friction levels times 1 + a cos(p q) + b sin(p q): at q = 0 a = -0.5 halves the breakaway
// torque Fs to 300 N m, so 540 N m slides the arm that held at 600; a = +0.5 raises it to 900, and 660 N m,
// which slid the unworn arm, only creeps. The sine term is zero at q = 0: b moves nothing.
TEST(Friction, AWornGearBreaksAwayAtTheCoulombLevelOfItsAngle) {
  const auto low = [](ModelSpec& s) {
    s.friction.position_waves = 25;
    s.friction.position_cos = -0.5;
    s.friction.position_sin = 0.3;
  };
  const auto high = [](ModelSpec& s) {
    s.friction.position_waves = 25;
    s.friction.position_cos = 0.5;
  };
  EXPECT_GT(slide(0.9 * 600.0, low), 0.03);
  EXPECT_LT(std::fabs(slide(1.1 * 600.0, high)), 0.005);
  // The law itself at three angles, well above the Stribeck velocity.
  const Model m = make_model([] {
    ModelSpec s = friction_rig();
    s.friction.position_waves = 25;
    s.friction.position_cos = 0.3;
    s.friction.position_sin = -0.2;
    return s;
  }());
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  for (double q : {0.0, 0.05, 0.3})
    EXPECT_NEAR(calc_hub_friction(bm, 0, q, 1.0), -(50.0 + 400.0 * (1.0 + 0.3 * std::cos(25 * q) - 0.2 * std::sin(25 * q))),
                1e-6)
        << q;
}

// Steep maps (smoothing 1e-4 and 1e-5 rad/s: F_s / (eps J) up to ~1e6 /s) under the PD loop through a
// move and its hold, where the hub sticks. RK4 needs hundreds of substeps for them; SDIRK and the
// midpoint rule take the map linearly implicit, at a fiftieth of that or less, and follow CVODE
// (tolerances 1e-8) to micro-radians on the hub and ten micrometres at the tip.
TEST(Friction, SteepMapImplicitInTheMidpointAndSdirkStepsFollowsCvode) {
  for (double eps : {1e-4, 1e-5}) {
    ModelSpec s = friction_rig();
    s.trajectory.moves = {{0.5, 3.0}};
    s.friction.smoothing = eps;
    s.simulation.integrator = Integrator::kRk4;
    const int rk4_substeps = make_model(s).substeps;
    s.simulation.integrator = Integrator::kCvodeDense;
    const BatchRun cv = test::run_one(make_model(s));
    ASSERT_EQ(cv.status[0], LaneStatus::kOk);
    for (Integrator kind : {Integrator::kMidpoint, Integrator::kSdirk2}) {
      SCOPED_TRACE(std::string(kind == Integrator::kMidpoint ? "midpoint" : "sdirk2") + ", eps " + std::to_string(eps));
      s.simulation.integrator = kind;
      const Model m = make_model(s);
      EXPECT_LE(50 * m.substeps, std::max(rk4_substeps, 50)) << "RK4 takes " << rk4_substeps;
      const BatchRun run = test::run_one(m);
      ASSERT_EQ(run.status[0], LaneStatus::kOk);
      double angle = 0.0, tip = 0.0;
      for (std::size_t k = 0; k < run.traces[0].t.size(); ++k) {
        angle = std::max(angle, std::abs(run.traces[0].hub_angle[k] - cv.traces[0].hub_angle[k]));
        tip = std::max(tip, std::abs(run.traces[0].tip_deflection[k] - cv.traces[0].tip_deflection[k]));
      }
      std::printf("eps %g, %d substeps (RK4 %d): hub angle within %.2e rad, tip within %.2e m\n", eps, m.substeps,
                  rk4_substeps, angle, tip);
      EXPECT_LT(angle, 1e-5);
      EXPECT_LT(tip, 3e-5);
    }
  }
}

TEST(Friction, StictionBelowCoulombIsRejected) {
  ModelSpec s = friction_rig();
  s.friction.stiction = 100.0;
  EXPECT_THROW(make_model(s), ConfigError);
}

}  // namespace
}  // namespace ff
