// multibody/tree_cvode: CVODE over tree lanes. An undamped double pendulum keeps its energy to the
// tolerance; on a 3-D flexible arm under gravity with a held torque that jumps, CVODE agrees with the
// lane RK4 at a small step, and dense, KLU and preconditioned GMRES agree; a lane's bits are the same alone and in any
// position of a batch; a lane CVODE fails on reports it and keeps its state, the others go on.
#include "multibody/tree_cvode.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "multibody/algorithms.hpp"
#include "multibody/flexible_link.hpp"
#include "multibody/lane_integrators.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

using Eigen::VectorXd;

// Two rigid links swinging about y under gravity (-z), no springs or dampers.
Tree double_pendulum() {
  TreeSpec s;
  BodySpec a;
  a.axis = Vec3::UnitY();
  a.mass = 1.0;
  a.com = Vec3(0.5, 0.0, 0.0);
  a.inertia = test::box_inertia(1.0, 1.0, 0.05, 0.05);
  s.bodies.push_back(a);
  BodySpec b = a;
  b.parent = 0;
  b.position = Vec3(1.0, 0.0, 0.0);
  b.mass = 0.7;
  b.com = Vec3(0.4, 0.0, 0.0);
  b.inertia = test::box_inertia(0.7, 0.8, 0.05, 0.05);
  s.bodies.push_back(b);
  return make_tree(s);
}

// A shoulder (about z) and an elbow (about y) carrying a 3-D flexible aluminium link of N segments
// under gravity, a payload at the tip (as tests/multibody/lane_integrators_test.cpp).
Tree flexible_arm(int segments, double beta, double payload = 1.0, double gravity = 9.81) {
  TreeSpec s;
  s.gravity = Vec3(0.0, 0.0, -gravity);
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
  elbow.stiffness = 200.0;
  elbow.spring_reference = gravity > 0.0 ? -0.3 : 0.0;
  s.bodies.push_back(elbow);
  FlexibleLinkSpec link;
  link.length = 1.2;
  link.section = {70e9, 26e9, 2700.0, 3.0e-4, 2.5e-9, 1.0e-8, 7.0e-9};
  link.segments = segments;
  link.damping_time = beta;
  link.payload.mass = payload;
  append_flexible_link(s, 1, Vec3(0.05, 0.0, 0.0), Mat3::Identity(), link);
  return make_tree(s);
}

void set_lane(const TreeLanes& tl, TreeLanesState& s, int l, const VectorXd& x) {
  for (int j = 0; j < tl.nv; ++j) {
    s.q[static_cast<std::size_t>(j * tl.W + l)] = x[j];
    s.qd[static_cast<std::size_t>(j * tl.W + l)] = x[tl.nv + j];
  }
}

VectorXd get_lane(const TreeLanes& tl, const TreeLanesState& s, int l) {
  VectorXd x(2 * tl.nv);
  for (int j = 0; j < tl.nv; ++j) {
    x[j] = s.q[static_cast<std::size_t>(j * tl.W + l)];
    x[tl.nv + j] = s.qd[static_cast<std::size_t>(j * tl.W + l)];
  }
  return x;
}

// The arm from a bent pose, the shoulder turning at 1 rad/s.
VectorXd arm_start(int nv) {
  VectorXd x = VectorXd::Zero(2 * nv);
  x[0] = 0.4;
  x[1] = -0.2;
  x[nv] = 1.0;
  return x;
}

// The held torque of sample k: shoulder and elbow, a new value every sample (a jump each time).
void torque_of(int k, int nv, int W, std::vector<double>& tau) {
  tau.assign(static_cast<std::size_t>(nv) * W, 0.0);
  for (int l = 0; l < W; ++l) {
    tau[static_cast<std::size_t>(l)] = 2.0 * std::sin(0.7 * k);
    tau[static_cast<std::size_t>(W + l)] = -5.0 + std::cos(0.3 * k);
  }
}

TEST(TreeCvode, UndampedDoublePendulumKeepsItsEnergyToTheTolerance) {
  const Tree tree = double_pendulum();
  const TreeLanes tl = make_tree_lanes(std::vector<Tree>{tree});
  TreeLanesState s = make_tree_lanes_state(tl);
  s.q = {1.2, -0.5};
  s.qd = {0.0, 1.0};
  TreeWorkspace ws(tree);
  auto energy = [&] {
    const Eigen::Map<const VectorXd> q(s.q.data(), 2), qd(s.qd.data(), 2);
    return calc_kinetic_energy(tree, q, qd, ws) + calc_potential_energy(tree, q, ws);
  };
  const double E0 = energy();
  TreeCvode cv(tl, {TreeCvodeSolver::kDense, 1e-10, 1e-12, 100000});
  std::vector<char> ok;
  double drift = 0.0, swing = 0.0;
  for (int k = 0; k < 500; ++k) {  // 5 s in samples of 10 ms, no force: one BDF history throughout
    cv.advance(tl, nullptr, s, 0.01 * k, 0.01, ok);
    ASSERT_TRUE(ok[0]);
    drift = std::max(drift, std::abs(energy() - E0));
    const Eigen::Map<const VectorXd> q(s.q.data(), 2), qd(s.qd.data(), 2);
    swing = std::max(swing, calc_kinetic_energy(tree, q, qd, ws));
  }
  RecordProperty("relative_drift", test::sci(drift / swing));
  RecordProperty("steps", static_cast<int>(cv.steps(0)));
  EXPECT_LT(drift / swing, 3e-8);  // 1.0e-8 measured: 100 rtol after 5 s (7650 steps)
}

// CVODE over `samples` samples of h_sample with the torque of torque_of held in each.
VectorXd run_cvode(const Tree& tree, const TreeCvodeOptions& opt, double h_sample, int samples, long* steps = nullptr) {
  const TreeLanes tl = make_tree_lanes(std::vector<Tree>{tree});
  TreeLanesState s = make_tree_lanes_state(tl);
  set_lane(tl, s, 0, arm_start(tl.nv));
  TreeCvode cv(tl, opt);
  std::vector<double> tau;
  std::vector<char> ok;
  for (int k = 0; k < samples; ++k) {
    torque_of(k, tl.nv, 1, tau);
    cv.advance(tl, tau.data(), s, k * h_sample, h_sample, ok);
    EXPECT_TRUE(ok[0]) << "sample " << k;
  }
  if (steps) *steps = cv.steps(0);
  return get_lane(tl, s, 0);
}

TEST(TreeCvode, FollowsTheLaneRk4OnAFlexibleArmWithAHeldTorque) {
  // N = 4 with torsion (h omega_max = 1.1 at 1e-4 s): 0.1 s in 10 ms samples, RK4 at 2e-5 s.
  const Tree tree = flexible_arm(4, 1e-5);
  const double hs = 0.01;
  const int samples = 10, sub = 500;
  const TreeLanes tl = make_tree_lanes(std::vector<Tree>{tree});
  TreeLanesState s = make_tree_lanes_state(tl);
  set_lane(tl, s, 0, arm_start(tl.nv));
  TreeStepWorkspace ws(tl);
  std::vector<double> tau;
  for (int k = 0; k < samples; ++k) {
    torque_of(k, tl.nv, 1, tau);
    for (int i = 0; i < sub; ++i) step_tree_rk4(tl, tau.data(), s, ws, hs / sub);
  }
  const VectorXd ref = get_lane(tl, s, 0);
  for (TreeCvodeSolver solver : {TreeCvodeSolver::kDense, TreeCvodeSolver::kGmres}) {
    const std::string name = solver == TreeCvodeSolver::kDense ? "dense" : "gmres";
    long steps = 0;
    const VectorXd x = run_cvode(tree, {solver, 1e-10, 1e-12, 100000}, hs, samples, &steps);
    const double rq = test::rel_diff(x.head(tl.nv), ref.head(tl.nv)), rv = test::rel_diff(x.tail(tl.nv), ref.tail(tl.nv));
    RecordProperty(name + "_rel_q", test::sci(rq));
    RecordProperty(name + "_rel_qd", test::sci(rv));
    RecordProperty(name + "_steps", static_cast<int>(steps));
    EXPECT_LT(rq, 1e-6) << name;
    EXPECT_LT(rv, 1e-6) << name;
  }
}

TEST(TreeCvode, DenseKluAndGmresAgreeToTheTolerance) {
  const Tree tree = flexible_arm(6, 1e-4);
  const VectorXd xd = run_cvode(tree, {TreeCvodeSolver::kDense, 1e-8, 1e-10, 100000}, 0.01, 5);
  const int nv = tree.nv();
  for (TreeCvodeSolver solver : {TreeCvodeSolver::kKlu, TreeCvodeSolver::kGmres}) {
    const std::string name = solver == TreeCvodeSolver::kKlu ? "klu" : "gmres";
    const VectorXd x = run_cvode(tree, {solver, 1e-8, 1e-10, 100000}, 0.01, 5);
    const double rq = test::rel_diff(x.head(nv), xd.head(nv)), rv = test::rel_diff(x.tail(nv), xd.tail(nv));
    RecordProperty(name + "_rel_q", test::sci(rq));
    RecordProperty(name + "_rel_qd", test::sci(rv));
    EXPECT_LT(rq, 1e-5) << name;
    EXPECT_LT(rv, 1e-5) << name;
  }
}

TEST(TreeCvode, ALaneGivesTheSameBitsAloneAndInAnyPositionOfABatch) {
  const std::vector<Tree> others = {flexible_arm(3, 1e-4, 2.0), flexible_arm(3, 1e-4, 0.4)};
  const Tree mine = flexible_arm(3, 1e-4, 1.0);
  for (TreeCvodeSolver solver : {TreeCvodeSolver::kDense, TreeCvodeSolver::kKlu, TreeCvodeSolver::kGmres}) {
    auto go = [&](int at, int W) {
      std::vector<Tree> trees;
      for (int l = 0, o = 0; l < W; ++l) trees.push_back(l == at ? mine : others[static_cast<std::size_t>(o++)]);
      const TreeLanes tl = make_tree_lanes(trees);
      TreeLanesState s = make_tree_lanes_state(tl);
      for (int l = 0; l < W; ++l) set_lane(tl, s, l, arm_start(tl.nv) * (l == at ? 1.0 : 0.8 + 0.1 * l));
      TreeCvode cv(tl, {solver, 1e-7, 1e-9, 100000});
      std::vector<double> tau;
      std::vector<char> ok;
      for (int k = 0; k < 4; ++k) {
        torque_of(k, tl.nv, W, tau);
        for (int l = 0; l < W; ++l) tau[static_cast<std::size_t>(l)] *= (l == at ? 1.0 : 1.5);
        cv.advance(tl, tau.data(), s, 0.01 * k, 0.01, ok);
        for (int l = 0; l < W; ++l) EXPECT_TRUE(ok[static_cast<std::size_t>(l)]);
      }
      const VectorXd x = get_lane(tl, s, at);
      std::vector<double> out(x.data(), x.data() + x.size());
      for (int j = 0; j < tl.nv; ++j) out.push_back(s.a_prev[static_cast<std::size_t>(j * W + at)]);
      out.push_back(static_cast<double>(cv.steps(at)));
      return out;
    };
    const std::vector<double> alone = go(0, 1);
    for (int at = 0; at < 3; ++at) EXPECT_EQ(go(at, 3), alone) << "position " << at;
  }
}

TEST(TreeCvode, AFailedLaneReportsItAndKeepsItsStateWhileTheOthersGoOn) {
  // Lane 0 rests with nothing acting (no gravity, the springs at their references): CVODE crosses a
  // second in a few steps. Lane 1 swings the stiff link and needs far more than 5; lane 2 starts
  // from a non-finite state.
  const std::vector<Tree> trees = {flexible_arm(4, 1e-4, 1.0, 0.0), flexible_arm(4, 1e-4), flexible_arm(4, 1e-4)};
  const TreeLanes tl = make_tree_lanes(trees);
  TreeLanesState s = make_tree_lanes_state(tl);
  set_lane(tl, s, 1, arm_start(tl.nv));
  VectorXd bad = arm_start(tl.nv);
  bad[3] = std::nan("");
  set_lane(tl, s, 2, bad);
  const TreeLanesState before = s;
  for (TreeCvodeSolver solver : {TreeCvodeSolver::kDense, TreeCvodeSolver::kKlu, TreeCvodeSolver::kGmres}) {
    s = before;
    TreeCvode cv(tl, {solver, 1e-8, 1e-10, 5});
    std::vector<char> ok;
    EXPECT_NO_THROW(cv.advance(tl, nullptr, s, 0.0, 1.0, ok));
    ASSERT_EQ(ok.size(), 3u);
    EXPECT_TRUE(ok[0]);
    EXPECT_FALSE(ok[1]);
    EXPECT_FALSE(ok[2]);
    EXPECT_LE(cv.steps(0), 5);
    EXPECT_EQ(get_lane(tl, s, 0), VectorXd::Zero(2 * tl.nv));
    EXPECT_EQ(get_lane(tl, s, 1), get_lane(tl, before, 1));
    const VectorXd x2 = get_lane(tl, s, 2), b2 = get_lane(tl, before, 2);
    for (int i = 0; i < x2.size(); ++i)
      EXPECT_TRUE(x2[i] == b2[i] || (std::isnan(x2[i]) && std::isnan(b2[i])));
    // The failed lane restarts from its kept state at the next advance and fails again the same way.
    cv.advance(tl, nullptr, s, 1.0, 1.0, ok);
    EXPECT_TRUE(ok[0]);
    EXPECT_FALSE(ok[1]);
  }
}

TEST(TreeCvode, RejectsBadOptionsAndShapes) {
  const TreeLanes tl = make_tree_lanes(std::vector<Tree>{double_pendulum()});
  EXPECT_THROW(TreeCvode(tl, {TreeCvodeSolver::kDense, 0.0, 1e-10, 10}), std::invalid_argument);
  EXPECT_THROW(TreeCvode(tl, {TreeCvodeSolver::kDense, 1e-8, -1.0, 10}), std::invalid_argument);
  EXPECT_THROW(TreeCvode(tl, {TreeCvodeSolver::kDense, 1e-8, 1e-10, 0}), std::invalid_argument);
  TreeCvode cv(tl, {});
  TreeLanesState s = make_tree_lanes_state(tl);
  std::vector<char> ok;
  EXPECT_THROW(cv.advance(tl, nullptr, s, 0.0, -0.1, ok), std::invalid_argument);
  const TreeLanes two = make_tree_lanes(std::vector<Tree>{double_pendulum(), double_pendulum()});
  EXPECT_THROW(cv.advance(two, nullptr, s, 0.0, 0.1, ok), std::invalid_argument);
  cv.advance(tl, nullptr, s, 0.0, 0.0, ok);
  EXPECT_TRUE(ok[0]);
}

}  // namespace
}  // namespace ff
