// multibody/lane_integrators: RK4 over lanes against the scalar tree RK4 of the tests, the implicit
// pair's second order and RK4's fourth against a fine reference, the implicit pair stable on a
// stiff 3-D flexible link where RK4 is not, energy of an undamped tree under gravity, and a variant's
// bits the same in any lane.
#include "multibody/lane_integrators.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "common/isa.hpp"
#include "multibody/algorithms.hpp"
#include "multibody/flexible_link.hpp"
#include "multibody/statics.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

using Eigen::VectorXd;
using Stepper = std::function<void(const TreeLanes&, const double*, TreeLanesState&, TreeStepWorkspace&, double)>;

// A shoulder (revolute about z) and an elbow (revolute about y) carrying a 3-D flexible aluminium
// link of N segments under gravity, a payload at the tip; the link's damping time beta (s).
Tree flexible_arm(int segments, double beta, double payload = 1.0) {
  TreeSpec s;
  BodySpec shoulder;
  shoulder.mass = 5.0;
  shoulder.inertia = test::box_inertia(5.0, 0.2, 0.2, 0.3);
  shoulder.damping = 0.5;
  s.bodies.push_back(shoulder);
  BodySpec elbow = shoulder;
  elbow.parent = 0;
  elbow.axis = Vec3::UnitY();
  elbow.position = Vec3(0.0, 0.0, 0.3);
  elbow.mass = 2.0;
  elbow.inertia = test::box_inertia(2.0, 0.1, 0.1, 0.1);
  elbow.stiffness = 200.0;  // a compliant drive holding the elbow against gravity
  elbow.spring_reference = -0.3;
  s.bodies.push_back(elbow);
  FlexibleLinkSpec link;
  link.length = 1.2;
  link.section = {70e9, 26e9, 2700.0, 3.0e-4, 2.5e-9, 1.0e-8, 7.0e-9};  // 30 x 10 mm aluminium bar
  link.segments = segments;
  link.damping_time = beta;
  link.payload.mass = payload;
  append_flexible_link(s, 1, Vec3(0.05, 0.0, 0.0), Mat3::Identity(), link);
  return make_tree(s);
}

// Runs `steps` steps of h from x0 = [q; qd] with no applied force; returns the final [q; qd].
VectorXd run(const Tree& tree, const VectorXd& x0, const Stepper& step, double h, int steps) {
  const TreeLanes tl = make_tree_lanes(std::vector<Tree>{tree});
  TreeLanesState s = make_tree_lanes_state(tl);
  for (int j = 0; j < tl.nv; ++j)
    s.q[static_cast<std::size_t>(j)] = x0[j], s.qd[static_cast<std::size_t>(j)] = x0[tl.nv + j];
  TreeStepWorkspace ws(tl);
  for (int k = 0; k < steps; ++k) step(tl, nullptr, s, ws, h);
  VectorXd x(2 * tl.nv);
  for (int j = 0; j < tl.nv; ++j) x[j] = s.q[static_cast<std::size_t>(j)], x[tl.nv + j] = s.qd[static_cast<std::size_t>(j)];
  return x;
}

// The arm released from a pose with the link straight and the shoulder turning at 1 rad/s: gravity
// and the turning bend and twist the link from rest (no step in the elastic coordinates).
VectorXd start(const Tree& tree) {
  VectorXd x = VectorXd::Zero(2 * tree.nv());
  x[0] = 0.4;
  x[1] = -0.2;
  x[tree.nv()] = 1.0;
  return x;
}

TEST(TreeIntegrators, Rk4OverLanesFollowsTheScalarTreeRk4) {
  const Tree tree = flexible_arm(4, 1e-5);
  const VectorXd x0 = start(tree);
  const double h = 1e-4;  // h omega_max = 1.1
  const int steps = 1000;
  const VectorXd x = run(tree, x0, step_tree_rk4, h, steps);
  test::Rk4 scalar(tree);
  VectorXd y = x0;
  for (int k = 0; k < steps; ++k) scalar.step(y, h);
  EXPECT_LT(test::rel_diff(x, y), 1e-10);
}

TEST(TreeIntegrators, ImplicitPairIsSecondOrderAndRk4FourthOnALightlyDampedFlexibleArm) {
  // Error after 0.2 s against RK4 at h = 1e-5 s, at h = 1e-4 s and h/2, where every mode is
  // resolved (h omega_max = 1.1): the ratio is 2^p.
  const Tree tree = flexible_arm(4, 1e-5);
  const VectorXd x0 = start(tree);
  const double T = 0.2;
  const VectorXd ref = run(tree, x0, step_tree_rk4, 1e-5, 20000);
  auto ratio = [&](const Stepper& step, double h) {
    const int n = static_cast<int>(std::lround(T / h));
    const double e1 = (run(tree, x0, step, h, n) - ref).cwiseAbs().maxCoeff();
    const double e2 = (run(tree, x0, step, h / 2, 2 * n) - ref).cwiseAbs().maxCoeff();
    return e1 / e2;
  };
  const double rm = ratio(step_tree_midpoint, 1e-4), rs = ratio(step_tree_sdirk2, 1e-4), rr = ratio(step_tree_rk4, 1e-4);
  RecordProperty("midpoint_ratio", test::sci(rm));
  RecordProperty("sdirk2_ratio", test::sci(rs));
  RecordProperty("rk4_ratio", test::sci(rr));
  EXPECT_NEAR(rm, 4.0, 0.8);
  EXPECT_NEAR(rs, 4.0, 0.8);
  EXPECT_NEAR(rr, 16.0, 4.0);
}

TEST(TreeIntegrators, ImplicitPairStepsAStiffFlexibleLinkWhereRk4Diverges) {
  // N = 16 with torsion: the stiffest clamped mode omega_max is about 5.8e4 rad/s. At h = 1 ms
  // (h omega_max about 60) RK4 (stable to 2.8) blows up; the implicit pair stays finite and its tip
  // within 0.1 mm of the reference (SDIRK2 at h/64) after 0.3 s.
  const Tree tree = flexible_arm(16, 1e-4);
  TreeWorkspace tws(tree);
  const int nv = tree.nv();
  Eigen::MatrixXd M(nv, nv), K(nv, nv);
  calc_mass_matrix(tree, VectorXd::Zero(nv), M, tws);
  calc_static_stiffness(tree, VectorXd::Zero(nv), K, tws);
  const Eigen::MatrixXd Kc = 0.5 * (K + K.transpose()).bottomRightCorner(nv - 2, nv - 2);  // shoulder, elbow held
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Kc, M.bottomRightCorner(nv - 2, nv - 2));
  const double wmax = std::sqrt(eig.eigenvalues().maxCoeff());
  ASSERT_GT(wmax, 5e4);
  const double h = 1e-3, T = 0.3;
  const int n = static_cast<int>(std::lround(T / h));
  const VectorXd x0 = start(tree);
  const VectorXd ref = run(tree, x0, step_tree_sdirk2, h / 64, 64 * n);
  const int tip = tree.num_bodies() - 1;
  auto tip_of = [&](const VectorXd& x) { return calc_point_position(tree, x.head(tree.nv()), tip, Vec3(0.04, 0, 0)); };
  const VectorXd xr = run(tree, x0, step_tree_rk4, h, n);
  EXPECT_FALSE(xr.allFinite() && xr.cwiseAbs().maxCoeff() < 1e3) << "RK4 did not diverge";
  for (const Stepper& st : {Stepper(step_tree_midpoint), Stepper(step_tree_sdirk2)}) {
    const VectorXd x = run(tree, x0, st, h, n);
    ASSERT_TRUE(x.allFinite());
    EXPECT_LT((tip_of(x) - tip_of(ref)).norm(), 1e-4);
  }
}

TEST(TreeIntegrators, UndampedArmUnderGravityKeepsItsEnergyUnderTheMidpointRule) {
  // No damping anywhere: kinetic + gravitational + spring energy within 1e-4 of its start over 1 s
  // (relative to the largest kinetic energy), at h = 2e-4 s.
  const Tree tree = flexible_arm(4, 0.0);
  TreeSpec spec = test::spec_of(tree);
  for (BodySpec& b : spec.bodies) b.damping = 0.0;
  const Tree free = make_tree(spec);
  TreeWorkspace tws(free);
  auto energy = [&](const VectorXd& x) {
    const int nv = free.nv();
    return calc_kinetic_energy(free, x.head(nv), x.tail(nv), tws) + calc_potential_energy(free, x.head(nv), tws) +
           calc_spring_energy(free, x.head(nv));
  };
  const VectorXd x0 = start(free);
  const double E0 = energy(x0);
  double swing = 0.0, drift = 0.0;
  for (int k = 1; k <= 5; ++k) {  // 0.2, 0.4, ... 1 s
    const VectorXd x = run(free, x0, step_tree_midpoint, 2e-4, 1000 * k);
    const int nv = free.nv();
    swing = std::max(swing, calc_kinetic_energy(free, x.head(nv), x.tail(nv), tws));
    drift = std::max(drift, std::abs(energy(x) - E0));
  }
  RecordProperty("relative_drift", test::sci(drift / swing));
  EXPECT_LT(drift / swing, 1e-4);
}

TEST(TreeIntegrators, AVariantStepsToTheSameBitsInAnyLane) {
  // 200 steps of each method: the variant alone and in lane 3 of 5 among heavier payloads.
  const VectorXd x0 = start(flexible_arm(4, 1e-5));
  for (const Stepper& st : {Stepper(step_tree_rk4), Stepper(step_tree_midpoint), Stepper(step_tree_sdirk2)}) {
    std::vector<Tree> trees;
    for (int l = 0; l < 5; ++l) trees.push_back(flexible_arm(4, 1e-5, l == 3 ? 1.0 : 1.0 + 0.3 * l));
    auto go = [&](const std::vector<Tree>& tr, int at) {
      const TreeLanes tl = make_tree_lanes(tr);
      TreeLanesState s = make_tree_lanes_state(tl);
      for (int j = 0; j < tl.nv; ++j)
        for (int l = 0; l < tl.W; ++l) {
          s.q[static_cast<std::size_t>(j * tl.W + l)] = x0[j] * (l == at ? 1.0 : 0.9);
          s.qd[static_cast<std::size_t>(j * tl.W + l)] = x0[tl.nv + j];
        }
      TreeStepWorkspace ws(tl);
      for (int k = 0; k < 200; ++k) st(tl, nullptr, s, ws, 1e-4);
      std::vector<double> out;
      for (int j = 0; j < tl.nv; ++j) out.push_back(s.q[static_cast<std::size_t>(j * tl.W + at)]);
      for (int j = 0; j < tl.nv; ++j) out.push_back(s.qd[static_cast<std::size_t>(j * tl.W + at)]);
      return out;
    };
    EXPECT_EQ(go({trees[3]}, 0), go(trees, 3));
  }
}

// The tree's lane ABA and steps are compiled for SSE2, AVX2 and AVX-512 (common/isa.hpp): every width
// the CPU runs steps five variants of the flexible arm to the same bits as SSE2 under each method.
TEST(TreeIntegrators, EveryWidthTheCpuRunsStepsToTheSameBits) {
  if (available_isa() == Isa::sse2) GTEST_SKIP() << "this CPU or build runs SSE2 only";
  const Isa was = active_isa();
  const VectorXd x0 = start(flexible_arm(4, 1e-5));
  std::vector<Tree> trees;
  for (int l = 0; l < 5; ++l) trees.push_back(flexible_arm(4, 1e-5, 1.0 + 0.3 * l));
  const TreeLanes tl = make_tree_lanes(trees);
  auto go = [&](const Stepper& st) {
    TreeLanesState s = make_tree_lanes_state(tl);
    for (int j = 0; j < tl.nv; ++j)
      for (int l = 0; l < tl.W; ++l) {
        s.q[static_cast<std::size_t>(j * tl.W + l)] = x0[j] * (1.0 - 0.05 * l);
        s.qd[static_cast<std::size_t>(j * tl.W + l)] = x0[tl.nv + j];
      }
    TreeStepWorkspace ws(tl);
    for (int k = 0; k < 200; ++k) st(tl, nullptr, s, ws, 1e-4);
    std::vector<double> out = s.q;
    out.insert(out.end(), s.qd.begin(), s.qd.end());
    return out;
  };
  for (const Stepper& st : {Stepper(step_tree_rk4), Stepper(step_tree_midpoint), Stepper(step_tree_sdirk2)}) {
    select_isa(Isa::sse2);
    const std::vector<double> base = go(st);
    for (Isa isa : {Isa::avx2, Isa::avx512})
      if (select_isa(isa) == isa) EXPECT_EQ(go(st), base) << isa_name(isa);
  }
  select_isa(was);
}

}  // namespace
}  // namespace ff
