// multibody/modes: a lumped cantilever's first three modes converging to the continuous
// Euler–Bernoulli cantilever's, a pendulum's gravity stiffness hanging and inverted, a damped
// spring-inertia joint's omega_n and zeta in closed form (and a PD loop added through the extra
// matrices), locked dofs, the shapes' normalisation, and bad input.
#include "multibody/modes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "multibody/flexible_link.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

using Eigen::VectorXd;

TEST(TreeModes, LumpedCantileverConvergesToTheEulerBernoulliCantilever) {
  // A slender steel strip, 2 m, 40 x 4 mm, bending in its soft plane (planar lumping, kappa = 1):
  // omega_n = (beta_n L)^2 sqrt(EI / (rho A L^4)), beta_n L = 1.875104, 4.694091, 7.854757. The error
  // falls with N; at N = 48 it is below 0.2 % for the first three (the lumped segments' rotary
  // inertia rho I l is (t/L)^2 ~ 4e-6 of the continuous beam's: negligible).
  const double L = 2.0, b = 0.04, t = 0.004, E = 200e9, rho = 7850.0;
  const double A = b * t, I = b * t * t * t / 12.0;
  const double betaL[3] = {1.875104068711961, 4.694091132974175, 7.854757438237613};
  double previous[3] = {1.0, 1.0, 1.0};
  for (int N : {6, 12, 24, 48}) {
    TreeSpec s;
    FlexibleLinkSpec link;
    link.length = L;
    link.section = {E, 80e9, rho, A, I, I, I};
    link.segments = N;
    link.planar = true;
    append_flexible_link(s, -1, Vec3::Zero(), Mat3::Identity(), link);
    s.gravity = Vec3::Zero();
    const Tree tree = make_tree(s);
    const std::vector<TreeMode> modes = calc_tree_modes(tree, VectorXd::Zero(tree.nv()));
    ASSERT_GE(modes.size(), 3u);
    for (int k = 0; k < 3; ++k) {
      const double exact = betaL[k] * betaL[k] * std::sqrt(E * I / (rho * A * std::pow(L, 4)));
      const double err = std::abs(modes[static_cast<std::size_t>(k)].omega_n / exact - 1.0);
      RecordProperty("N" + std::to_string(N) + "_mode" + std::to_string(k + 1), test::sci(err));
      EXPECT_LT(err, previous[k]) << "N " << N << " mode " << k + 1;
      previous[k] = err;
      EXPECT_TRUE(modes[static_cast<std::size_t>(k)].oscillatory);
    }
  }
  for (double e : previous) EXPECT_LT(e, 2e-3);
}

// A point-like bob of mass m at distance l below a revolute joint about y (gravity -z), a torsion
// spring k on the joint.
Tree pendulum(double m, double l, double k, double c = 0.0) {
  TreeSpec s;
  BodySpec bob;
  bob.axis = Vec3::UnitY();
  bob.mass = m;
  bob.com = Vec3(0.0, 0.0, -l);
  bob.inertia = test::box_inertia(m, 1e-3, 1e-3, 1e-3);
  bob.stiffness = k;
  bob.damping = c;
  s.bodies.push_back(bob);
  return make_tree(s);
}

TEST(TreeModes, PendulumHangingHasSqrtGOverLAndInvertedIsAnUnstableRealMode) {
  const double m = 2.0, l = 0.5, g = 9.81, J = m * l * l + m * 1e-6 / 6.0;
  const std::vector<TreeMode> down = calc_tree_modes(pendulum(m, l, 0.0), VectorXd::Zero(1));
  ASSERT_EQ(down.size(), 1u);
  EXPECT_NEAR(down[0].omega_n, std::sqrt(m * g * l / J), 1e-6);
  EXPECT_TRUE(down[0].oscillatory);
  const std::vector<TreeMode> up = calc_tree_modes(pendulum(m, l, 0.0), VectorXd::Constant(1, std::acos(-1.0)));
  ASSERT_EQ(up.size(), 1u);
  EXPECT_FALSE(up[0].oscillatory);
  EXPECT_EQ(up[0].zeta, -1.0);
  EXPECT_NEAR(up[0].omega_n, std::sqrt(m * g * l / J), 1e-6);  // the growth rate, 1/s
}

// A 3 kg box (0.4 x 0.3 x 0.2 m) on a z joint with a 50 N m/rad spring and a 1.2 N m s/rad damper.
BodySpec damped_spring_body() {
  BodySpec b;
  b.axis = Vec3::UnitZ();
  b.mass = 3.0;
  b.inertia = test::box_inertia(3.0, 0.4, 0.3, 0.2);
  b.stiffness = 50.0;
  b.damping = 1.2;
  return b;
}

TEST(TreeModes, DampedJointHasItsClosedFormFrequencyAndDampingAndAPdLoopAddsToThem) {
  // Gravity along the axis: no gravity stiffness. omega_n = sqrt(k/J), zeta = c / (2 sqrt(k J)).
  TreeSpec s;
  s.bodies.push_back(damped_spring_body());
  const Tree tree = make_tree(s);
  const double J = 3.0 * (0.16 + 0.09) / 12.0;
  std::vector<TreeMode> m = calc_tree_modes(tree, VectorXd::Zero(1));
  ASSERT_EQ(m.size(), 1u);
  EXPECT_NEAR(m[0].omega_n, std::sqrt(50.0 / J), 1e-12 * std::sqrt(50.0 / J));
  EXPECT_NEAR(m[0].zeta, 1.2 / (2.0 * std::sqrt(50.0 * J)), 1e-12);
  TreeModeOptions pd;
  pd.extra_stiffness = Eigen::MatrixXd::Constant(1, 1, 30.0);
  pd.extra_damping = Eigen::MatrixXd::Constant(1, 1, 2.0);
  m = calc_tree_modes(tree, VectorXd::Zero(1), pd);
  EXPECT_NEAR(m[0].omega_n, std::sqrt(80.0 / J), 1e-12 * std::sqrt(80.0 / J));
  EXPECT_NEAR(m[0].zeta, 3.2 / (2.0 * std::sqrt(80.0 * J)), 1e-12);
}

// A zero mode either moves the joints (a free joint: nothing resists it) or is an actuator state that
// nothing restores and that moves no joint (a valve-controlled actuator's mean chamber pressure);
// `moves` tells them apart.
// (#32.14) A flexible link on a free revolute hub (no spring, no gain), its cells damped (so the damped
// problem is solved): the hub's rigid-body rotation is zero to the solve's resolution at every N, omega
// 0 (free), never a slow or unstable real pole of round-off (it was 0.004 rad/s, "unstable", at N = 64).
TEST(TreeModes, AFreeHubsRigidModeIsZeroAtEveryN) {
  for (int N : {8, 16, 32, 64}) {
    TreeSpec s;
    FlexibleLinkSpec link;
    link.length = 2.0;
    link.section = {200e9, 80e9, 7850.0, 1.6e-4, 2.13e-10, 2.13e-10, 4.3e-10};
    link.segments = N;
    link.planar = true;
    link.damping_time = 1e-3;
    link.root_joint.type = JointType::kRevolute;
    link.root_joint.armature = 0.5;
    append_flexible_link(s, -1, Vec3::Zero(), Mat3::Identity(), link);
    s.gravity = Vec3::Zero();
    const Tree tree = make_tree(s);
    const std::vector<TreeMode> modes = calc_tree_modes(tree, VectorXd::Zero(tree.nv()));
    int free = 0;
    for (const TreeMode& m : modes) {
      free += m.omega_n == 0.0;
      EXPECT_GE(m.zeta, 0.0) << "N " << N << ": omega " << m.omega_n;  // nothing unstable
    }
    EXPECT_GE(free, 1) << "N " << N;
    EXPECT_LE(free, 2) << "N " << N;
    EXPECT_EQ(modes[0].omega_n, 0.0) << "N " << N;
    EXPECT_NEAR(std::abs(modes[0].shape[0]), 1.0, 1e-6) << "N " << N;  // the whole link turning on the hub
    EXPECT_GT(modes[static_cast<std::size_t>(free)].omega_n, 1.0) << "N " << N;
  }
}

TEST(TreeModes, AnActuatorStateNothingRestoresMovesNoJointButAFreeJointMoves) {
  TreeSpec s;
  BodySpec b = damped_spring_body();
  s.bodies.push_back(b);
  b.parent = 0;
  b.stiffness = 0.0;  // the second joint: free, damped
  b.damping = 0.5;
  s.bodies.push_back(b);
  const Tree tree = make_tree(s);
  TreeModeOptions o;
  // z0: a lag on joint 0's rate that pushes joint 0; z1: a state whose rate is zero and that pushes nothing.
  o.actuator_force = Eigen::MatrixXd::Zero(2, 2);
  o.actuator_force(0, 0) = -4.0;
  o.actuator_q = Eigen::MatrixXd::Zero(2, 2);
  o.actuator_qd = Eigen::MatrixXd::Zero(2, 2);
  o.actuator_qd(0, 0) = 1.0;
  o.actuator_z = Eigen::MatrixXd::Zero(2, 2);
  o.actuator_z(0, 0) = -5.0;
  const std::vector<TreeMode> m = calc_tree_modes(tree, VectorXd::Zero(2), o);
  int neutral = 0, free = 0;
  for (const TreeMode& x : m) {
    if (x.omega_n > 1e-9) {
      EXPECT_TRUE(x.moves) << x.omega_n;
      continue;
    }
    if (x.moves) {
      ++free;
      EXPECT_NEAR(x.shape[0], 0.0, 1e-12);  // the free joint alone
      EXPECT_EQ(x.shape[1], 1.0);
    } else {
      ++neutral;
    }
  }
  EXPECT_EQ(neutral, 1);
  EXPECT_EQ(free, 1);
}

TEST(TreeModes, LockedDofsAreZeroInEveryShapeAndShapesPeakAtPlusOne) {
  test::Rng rng(5);
  TreeSpec s;
  for (int i = 0; i < 4; ++i) {
    const JointType rev = JointType::kRevolute;
    BodySpec b = test::random_body(rng, i - 1, &rev);
    b.stiffness = rng.uniform(10.0, 100.0);
    s.bodies.push_back(b);
  }
  s.gravity = Vec3::Zero();
  const Tree tree = make_tree(s);
  TreeModeOptions o;
  o.locked_dofs = {1};
  const std::vector<TreeMode> modes = calc_tree_modes(tree, VectorXd::Zero(4), o);
  ASSERT_EQ(modes.size(), 3u);
  for (std::size_t k = 0; k < modes.size(); ++k) {
    EXPECT_EQ(modes[k].shape.size(), 4);
    EXPECT_EQ(modes[k].shape[1], 0.0);
    EXPECT_DOUBLE_EQ(modes[k].shape.maxCoeff(), 1.0);
    EXPECT_LE(modes[k].shape.minCoeff(), 1.0);
    EXPECT_GE(modes[k].shape.minCoeff(), -1.0);
    if (k > 0) {
      EXPECT_LE(modes[k - 1].omega_n, modes[k].omega_n);
    }
  }
  EXPECT_THROW(calc_tree_modes(tree, VectorXd::Zero(3)), std::invalid_argument);
  o.locked_dofs = {4};
  EXPECT_THROW(calc_tree_modes(tree, VectorXd::Zero(4), o), std::invalid_argument);
  o.locked_dofs = {0, 0};
  EXPECT_THROW(calc_tree_modes(tree, VectorXd::Zero(4), o), std::invalid_argument);
  o.locked_dofs = {};
  o.extra_damping = Eigen::MatrixXd::Zero(3, 3);
  EXPECT_THROW(calc_tree_modes(tree, VectorXd::Zero(4), o), std::invalid_argument);
}

}  // namespace
}  // namespace ff
