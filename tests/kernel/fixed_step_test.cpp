// kernel/fixed_step.cpp: the one-pass linearly implicit midpoint step (order, energy, workspace reuse).
// Its closed-loop accuracy against the reference trace and its lanes are in simulate_test.cpp.
#include "kernel/fixed_step.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "kernel/dynamics.hpp"
#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

using test::max_abs_diff;

// Tip deflection trace of the closed loop (N = 6, 0.5 rad move, first 1.5 s) with `integ` at `substeps`.
std::vector<double> tip_trace(Integrator integ, int substeps) {
  ModelSpec spec = test::rig_spec(0.5, 0.0);
  spec.simulation.duration = 1.5;
  spec.simulation.integrator = integ;
  spec.simulation.substeps = substeps;
  return test::run_one(make_model(spec)).traces[0].tip_deflection;
}

TEST(Midpoint, ClosedLoopErrorIsSecondOrderInTheStep) {
  // Against RK4 at h = 1/64 ms (its error there ~1e-13 m); the torque is held per 1 ms sample in all.
  const auto ref = tip_trace(Integrator::kRk4, 64);
  const double e1 = max_abs_diff(tip_trace(Integrator::kMidpoint, 1), ref);
  const double e2 = max_abs_diff(tip_trace(Integrator::kMidpoint, 2), ref);
  const double e4 = max_abs_diff(tip_trace(Integrator::kMidpoint, 4), ref);
  EXPECT_LT(e1, 1e-4);  // m, of ~0.6 m peak deflection
  EXPECT_NEAR(e1 / e2, 4.0, 0.5);
  EXPECT_NEAR(e2 / e4, 4.0, 0.5);
}

TEST(Midpoint, EnergyErrorOfAnUndampedSpinningChainIsSmallAndSecondOrder) {
  // Undamped, uncontrolled: the exact motion keeps its energy; the step's error in it is bounded, O(h^2).
  ModelSpec spec = test::rig_spec();
  spec.joints.damping = 0.0;
  const Model m = make_model(spec);
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  auto worst_error = [&](double h) {
    BatchState s = make_state(bm);
    Workspace ws = make_workspace(bm);
    s.q[1] = 0.05;  // bent at the root joint, hub free
    s.v[0] = 0.8;   // and spinning: centrifugal and Coriolis terms matter
    auto energy = [&] { return calc_kinetic_energy(bm, s.q.data(), s.v.data(), 0) + calc_spring_energy(bm, s.q.data(), 0); };
    const double e0 = energy();
    double worst = 0.0;
    for (long k = 0; k < std::lround(10.0 / h); ++k) {  // 10 s
      step_midpoint(bm, s, ws, h);
      worst = std::max(worst, std::fabs(energy() - e0) / e0);
    }
    return worst;
  };
  const double e1 = worst_error(1e-3), e2 = worst_error(0.5e-3);
  // Measured: 5.9e-5 at 1 ms, 7.9e-6 at 0.5 ms (SDIRK2 at 1 ms: 1.2e-4).
  EXPECT_LT(e1, 1e-4);
  EXPECT_GT(e1 / e2, 3.5);  // at least second order
}

TEST(Midpoint, AWorkspaceUsedBySdirk2FirstGivesTheSameStep) {
  // The joint armature is cached per h gamma in the workspace: switching integrators must rebuild it.
  // (The velocity predictor is state: `scratch` keeps SDIRK2's.)
  const Model m = make_model(test::rig_spec());
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  BatchState s0 = make_state(bm);
  s0.q[2] = 0.05;
  s0.tau[0] = 1e4;
  BatchState fresh = s0, reused = s0, scratch = s0;
  Workspace ws_fresh = make_workspace(bm), ws_reused = make_workspace(bm);
  step_sdirk2(bm, scratch, ws_reused, 1e-3);
  step_midpoint(bm, fresh, ws_fresh, 1e-3);
  step_midpoint(bm, reused, ws_reused, 1e-3);
  EXPECT_EQ(fresh.q, reused.q);
  EXPECT_EQ(fresh.v, reused.v);
}

}  // namespace
}  // namespace ff
