// Hub friction (kernel/dynamics.cpp, calc_hub_friction): viscous, Coulomb, Stribeck; regularised.
#include <gtest/gtest.h>

#include <cmath>

#include "kernel/dynamics.hpp"
#include "kernel/errors.hpp"
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
  for (double w = -2.0; w <= 2.0; w += 0.001) EXPECT_LE(calc_hub_friction(bm, 0, w) * w, 0.0) << w;
  EXPECT_EQ(calc_hub_friction(bm, 0, 0.0), 0.0);
  // Well above the Stribeck velocity: Coulomb plus viscous.
  EXPECT_NEAR(calc_hub_friction(bm, 0, 1.0), -(400.0 + 50.0), 1e-6);
  // Near the Stribeck peak (w >> eps, w << vs): the stiction level.
  EXPECT_NEAR(calc_hub_friction(bm, 0, 0.005), -(50.0 * 0.005 + (400.0 + 200.0 * std::exp(-0.0625)) * std::tanh(5.0)),
              1e-9);
}

// The hub displacement after 2 s under a constant hub torque (no controller), on a stiff arm.
double slide(double torque) {
  ModelSpec s = friction_rig();
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

TEST(Friction, StictionBelowCoulombIsRejected) {
  ModelSpec s = friction_rig();
  s.friction.stiction = 100.0;
  EXPECT_THROW(make_model(s), ConfigError);
}

}  // namespace
}  // namespace ff
