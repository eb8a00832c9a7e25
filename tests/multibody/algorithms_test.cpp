// multibody/algorithms: RNEA, CRBA and ABA against each other on random trees, against closed forms
// (pendulum, slider, bead on a spinning rod), against Jacobians built from the kinematics, and
// energy conservation of a free 3-D pendulum under RK4.
#include "multibody/algorithms.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using Jacobian = Eigen::Matrix<double, 6, Eigen::Dynamic>;

constexpr int kRandomTrees = 60;  // bodies 1..12, cycling
constexpr int kStatesPerTree = 3;

// The body Jacobians built from the kinematics alone: J_i (6 x nv, body i coordinates) has, for
// each moving joint j on the chain from i to the base, the column iX_j S_j = iX_0 (jX_0)^-1 S_j.
std::vector<Jacobian> body_jacobians(const Tree& tree, const VectorXd& q) {
  std::vector<Transform> X0;
  for (int i = 0; i < tree.num_bodies(); ++i) {
    const Pose p = calc_body_pose(tree, q, i);
    X0.push_back(Transform::from_pose(p.rotation, p.position));
  }
  std::vector<Jacobian> J;
  for (int i = 0; i < tree.num_bodies(); ++i) {
    Jacobian Ji = Jacobian::Zero(6, tree.nv());
    for (int j = i; j >= 0; j = tree.body(j).parent) {
      const Body& b = tree.body(j);
      if (b.dof >= 0) Ji.col(b.dof) = (X0[i] * X0[j].inverse()).apply(b.S);
    }
    J.push_back(Ji);
  }
  return J;
}

// sum_i J_i^T I_i J_i + diag(armature).
MatrixXd mass_matrix_from_jacobians(const Tree& tree, const VectorXd& q) {
  const std::vector<Jacobian> J = body_jacobians(tree, q);
  MatrixXd M = MatrixXd::Zero(tree.nv(), tree.nv());
  for (int i = 0; i < tree.num_bodies(); ++i) M += J[i].transpose() * tree.body(i).inertia * J[i];
  for (const Body& b : tree.bodies())
    if (b.dof >= 0) M(b.dof, b.dof) += b.armature;
  return M;
}

VectorXd aba(const Tree& tree, const VectorXd& q, const VectorXd& qd, const VectorXd& tau, TreeWorkspace& ws) {
  VectorXd qdd(tree.nv());
  calc_forward_dynamics(tree, q, qd, tau, qdd, ws);
  return qdd;
}

TEST(Algorithms, AbaMatchesADenseSolveOfTheCrbaMassMatrixAndRneaBiasOnRandomTrees) {
  // M qdd = tau - C - g solved densely (LLT) against the ABA, at random states of 60 random trees.
  test::Rng rng(20261202);
  double worst = 0.0;
  for (int k = 0; k < kRandomTrees; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k % 12);
    TreeWorkspace ws(tree);
    MatrixXd M(tree.nv(), tree.nv());
    VectorXd bias(tree.nv());
    for (int s = 0; s < kStatesPerTree; ++s) {
      const VectorXd q = test::random_q(rng, tree), qd = test::random_vector(rng, tree.nv(), -2.0, 2.0),
                     tau = test::random_vector(rng, tree.nv(), -5.0, 5.0);
      calc_mass_matrix(tree, q, M, ws);
      calc_bias_forces(tree, q, qd, bias, ws);
      const VectorXd dense = M.llt().solve(tau - bias);
      const VectorXd qdd = aba(tree, q, qd, tau, ws);
      const double rel = (qdd - dense).cwiseAbs().maxCoeff() / dense.cwiseAbs().maxCoeff();
      worst = std::max(worst, rel);
      EXPECT_LT(rel, 1e-10) << "tree " << k << " (" << tree.num_bodies() << " bodies), state " << s;
    }
  }
  RecordProperty("worst_relative_difference", test::sci(worst));
}

TEST(Algorithms, RneaOfTheAbaAccelerationsGivesBackTheTorques) {
  test::Rng rng(7);
  for (int k = 0; k < kRandomTrees; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k % 12);
    TreeWorkspace ws(tree);
    VectorXd tau_back(tree.nv());
    for (int s = 0; s < kStatesPerTree; ++s) {
      const VectorXd q = test::random_q(rng, tree), qd = test::random_vector(rng, tree.nv(), -2.0, 2.0),
                     tau = test::random_vector(rng, tree.nv(), -5.0, 5.0);
      const VectorXd qdd = aba(tree, q, qd, tau, ws);
      calc_inverse_dynamics(tree, q, qd, qdd, tau_back, ws);
      EXPECT_LT((tau_back - tau).cwiseAbs().maxCoeff(), 1e-10 * (1.0 + tau.cwiseAbs().maxCoeff()))
          << "tree " << k << ", state " << s;
    }
  }
}

TEST(Algorithms, MassMatrixIsSymmetricPositiveDefinite) {
  test::Rng rng(8);
  for (int k = 0; k < kRandomTrees; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k % 12);
    TreeWorkspace ws(tree);
    MatrixXd M(tree.nv(), tree.nv());
    calc_mass_matrix(tree, test::random_q(rng, tree), M, ws);
    EXPECT_EQ(M, M.transpose()) << "tree " << k;  // both triangles are written from one product
    const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(M, Eigen::EigenvaluesOnly);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0) << "tree " << k;
  }
}

TEST(Algorithms, MassMatrixEqualsTheSumOfJacobianTransposeInertiaJacobian) {
  test::Rng rng(9);
  for (int k = 0; k < kRandomTrees; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k % 12);
    TreeWorkspace ws(tree);
    MatrixXd M(tree.nv(), tree.nv());
    const VectorXd q = test::random_q(rng, tree);
    calc_mass_matrix(tree, q, M, ws);
    EXPECT_LT(test::rel_diff(M, mass_matrix_from_jacobians(tree, q)), 1e-9) << "tree " << k;
  }
}

TEST(Algorithms, BodyJacobiansMatchFiniteDifferencesOfForwardKinematics) {
  // Column j of J_i is body i's velocity [omega; v] (body coordinates) for qd = e_j:
  // [omega]× = R^T dR/dq_j, v = R^T dp/dq_j, by central differences of the poses (h = 1e-6).
  test::Rng rng(10);
  const double h = 1e-6;
  for (int k = 0; k < 12; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k);
    const VectorXd q = test::random_q(rng, tree);
    const std::vector<Jacobian> J = body_jacobians(tree, q);
    for (int i = 0; i < tree.num_bodies(); ++i) {
      const Pose p0 = calc_body_pose(tree, q, i);
      for (int j = 0; j < tree.nv(); ++j) {
        VectorXd qp = q, qm = q;
        qp[j] += h;
        qm[j] -= h;
        const Pose pp = calc_body_pose(tree, qp, i), pm = calc_body_pose(tree, qm, i);
        const Mat3 W = p0.rotation.transpose() * (pp.rotation - pm.rotation) / (2 * h);
        const Vec3 omega{W(2, 1), W(0, 2), W(1, 0)};
        const Vec3 v = p0.rotation.transpose() * (pp.position - pm.position) / (2 * h);
        EXPECT_LT((omega - J[i].col(j).head<3>()).norm(), 1e-7) << "tree " << k << " body " << i << " dof " << j;
        EXPECT_LT((v - J[i].col(j).tail<3>()).norm(), 1e-7) << "tree " << k << " body " << i << " dof " << j;
      }
    }
  }
}

TEST(Algorithms, KineticEnergyIsHalfQdTransposeMQd) {
  test::Rng rng(12);
  for (int k = 0; k < kRandomTrees; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k % 12);
    TreeWorkspace ws(tree);
    MatrixXd M(tree.nv(), tree.nv());
    const VectorXd q = test::random_q(rng, tree), qd = test::random_vector(rng, tree.nv(), -2.0, 2.0);
    calc_mass_matrix(tree, q, M, ws);
    const double T = 0.5 * qd.dot(M * qd);
    EXPECT_NEAR(calc_kinetic_energy(tree, q, qd, ws), T, 1e-12 * T) << "tree " << k;
  }
}

TEST(Algorithms, GravityForcesAreTheGradientOfThePotentialEnergy) {
  // g(q) = bias at qd = 0 = dV/dq, by central differences (h = 1e-6).
  test::Rng rng(13);
  const double h = 1e-6;
  for (int k = 0; k < 24; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k % 12);
    TreeWorkspace ws(tree);
    const VectorXd q = test::random_q(rng, tree);
    VectorXd g(tree.nv());
    calc_bias_forces(tree, q, VectorXd::Zero(tree.nv()), g, ws);
    VectorXd dV(tree.nv());
    for (int j = 0; j < tree.nv(); ++j) {
      VectorXd qp = q, qm = q;
      qp[j] += h;
      qm[j] -= h;
      dV[j] = (calc_potential_energy(tree, qp, ws) - calc_potential_energy(tree, qm, ws)) / (2 * h);
    }
    EXPECT_LT((g - dV).cwiseAbs().maxCoeff(), 1e-6 * (1.0 + g.cwiseAbs().maxCoeff())) << "tree " << k;
  }
}

TEST(Algorithms, RneaWithUnitAccelerationsGivesTheMassMatrixColumns) {
  // M e_j = RNEA(q, 0, e_j) - RNEA(q, 0, 0).
  test::Rng rng(14);
  for (int k = 0; k < 24; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k % 12);
    TreeWorkspace ws(tree);
    const VectorXd q = test::random_q(rng, tree), zero = VectorXd::Zero(tree.nv());
    MatrixXd M(tree.nv(), tree.nv()), cols(tree.nv(), tree.nv());
    calc_mass_matrix(tree, q, M, ws);
    VectorXd g(tree.nv()), tau(tree.nv());
    calc_bias_forces(tree, q, zero, g, ws);
    for (int j = 0; j < tree.nv(); ++j) {
      calc_inverse_dynamics(tree, q, zero, VectorXd::Unit(tree.nv(), j), tau, ws);
      cols.col(j) = tau - g;
    }
    EXPECT_LT(test::rel_diff(cols, M), 1e-12) << "tree " << k;
  }
}

TEST(Algorithms, SinglePendulumMatchesTheClosedForm) {
  // A 2 kg box on a revolute joint about y, its centre l = 0.6 m below the pivot, I = I_yy about
  // the centre: qdd = -(m g l / (I + m l²)) sin q whatever qd, and tau = (I + m l²) qdd + m g l sin q.
  const double m = 2.0, l = 0.6, g = 9.81;
  TreeSpec s;
  BodySpec b;
  b.axis = Vec3::UnitY();
  b.position = {0.1, -0.2, 1.0};  // the pivot's place does not matter
  b.mass = m;
  b.com = {0.0, 0.0, -l};
  b.inertia = test::box_inertia(m, 0.1, 0.08, 0.4);
  s.bodies = {b};
  const Tree tree = make_tree(s);
  TreeWorkspace ws(tree);
  const double I = b.inertia(1, 1);
  for (const double q : {-2.0, -0.5, 0.3, 1.2, 3.0}) {
    for (const double qd : {0.0, 1.7}) {
      VectorXd qdd(1), tau(1);
      calc_forward_dynamics(tree, VectorXd::Constant(1, q), VectorXd::Constant(1, qd), VectorXd::Zero(1), qdd, ws);
      EXPECT_NEAR(qdd[0], -(m * g * l / (I + m * l * l)) * std::sin(q), 1e-13);
      calc_inverse_dynamics(tree, VectorXd::Constant(1, q), VectorXd::Constant(1, qd), VectorXd::Constant(1, 2.0),
                            tau, ws);
      EXPECT_NEAR(tau[0], (I + m * l * l) * 2.0 + m * g * l * std::sin(q), 1e-12);
    }
  }
}

TEST(Algorithms, PrismaticJointUnderGravityAcceleratesAtGAlongItsAxis) {
  // A 3 kg slider on an axis inclined by its joint frame: qdd = (tau + m g . a) / (m + armature),
  // a = R axis in the base frame; g . a = -9.81 a_z.
  TreeSpec s;
  BodySpec b;
  b.joint = JointType::kPrismatic;
  b.axis = Vec3::UnitX();
  b.rotation = roty(-0.6) * rotz(0.3);  // tilts x out of the horizontal plane
  b.mass = 3.0;
  b.com = {0.1, 0.2, -0.1};
  b.inertia = test::box_inertia(3.0, 0.2, 0.1, 0.1, rotx(0.2));
  s.bodies = {b};
  const Vec3 a = b.rotation * b.axis;
  const double ga = Vec3(0.0, 0.0, -9.81).dot(a);
  ASSERT_GT(std::abs(ga), 4.0);
  for (const double armature : {0.0, 1.5}) {
    s.bodies[0].armature = armature;
    const Tree tree = make_tree(s);
    TreeWorkspace ws(tree);
    for (const double tau : {0.0, 7.0}) {
      VectorXd qdd(1);
      calc_forward_dynamics(tree, VectorXd::Constant(1, 0.4), VectorXd::Constant(1, -1.3), VectorXd::Constant(1, tau),
                            qdd, ws);
      EXPECT_NEAR(qdd[0], (tau + 3.0 * ga) / (3.0 + armature), 1e-13);
    }
    // The potential energy falls by m g . a per metre along the axis.
    EXPECT_NEAR(calc_potential_energy(tree, VectorXd::Constant(1, 1.0), ws) -
                    calc_potential_energy(tree, VectorXd::Constant(1, 0.0), ws),
                -3.0 * ga, 1e-12);
  }
}

TEST(Algorithms, BeadOnASpinningRodFeelsTheCentrifugalAndCoriolisTerms) {
  // A hub (J = 0.5 kg·m² about z) spinning at w carries a rod along its x axis; a 0.8 kg bead
  // (I_zz = i) slides freely at r with rate rd, gravity along -z. Polar equations, no torques:
  //   rdd = r w²,   (J + i + m r²) wd = -2 m r rd w.
  const double J = 0.5, m = 0.8, r = 0.7, rd = -0.4, w = 3.0;
  TreeSpec s;
  BodySpec hub;
  hub.axis = Vec3::UnitZ();
  hub.mass = 4.0;
  hub.inertia = Vec3(0.3, 0.3, J).asDiagonal();
  BodySpec bead;
  bead.parent = 0;
  bead.joint = JointType::kPrismatic;
  bead.axis = Vec3::UnitX();
  bead.mass = m;
  bead.inertia = test::box_inertia(m, 0.05, 0.05, 0.05);
  s.bodies = {hub, bead};
  const Tree tree = make_tree(s);
  TreeWorkspace ws(tree);
  const double i = bead.inertia(2, 2);
  VectorXd qdd(2);
  calc_forward_dynamics(tree, Eigen::Vector2d(0.9, r), Eigen::Vector2d(w, rd), VectorXd::Zero(2), qdd, ws);
  EXPECT_NEAR(qdd[1], r * w * w, 1e-13);
  EXPECT_NEAR(qdd[0], -2 * m * r * rd * w / (J + i + m * r * r), 1e-13);
}

TEST(Algorithms, FreeFiveLinkPendulumConservesEnergyUnderRk4) {
  // Five links of 0.3–0.4 m hanging along -z, hinges about y, x, y, z-tilted and x (a 3-D motion),
  // full inertias off the principal axes, gravity, no torques or dissipation. RK4, h = 0.5 ms,
  // 2 s (4000 steps; ~1 s under the sanitizers): the total energy stays within 1e-8 of the largest
  // kinetic energy reached (measured 1.4e-10; RK4's own error, falling as h^4).
  TreeSpec s;
  const Vec3 axes[5] = {Vec3::UnitY(), Vec3::UnitX(), Vec3::UnitY(), Vec3(0.3, 0.0, 1.0), Vec3::UnitX()};
  const double len[5] = {0.4, 0.35, 0.3, 0.35, 0.3};
  for (int i = 0; i < 5; ++i) {
    BodySpec b;
    b.parent = i - 1;
    b.axis = axes[i];
    b.position = i == 0 ? Vec3(Vec3::Zero()) : Vec3(0.02, 0.0, -len[i - 1]);
    b.rotation = rotz(0.3 * i);
    b.mass = 1.0 - 0.1 * i;
    b.com = {0.01, -0.02, -0.5 * len[i]};
    b.inertia = test::box_inertia(b.mass, 0.05, 0.04, len[i], rotx(0.1 * i) * roty(0.2));
    b.armature = i == 2 ? 0.01 : 0.0;
    s.bodies.push_back(b);
  }
  const Tree tree = make_tree(s);
  TreeWorkspace ws(tree);
  const int n = tree.nv();
  VectorXd x(2 * n);
  test::Rk4 rk(tree);  // no springs or dampers: tau = 0
  x << 0.8, -0.5, 0.6, 0.4, -0.7, 1.0, 0.0, -1.5, 2.0, 0.5;
  auto energy = [&](const VectorXd& y) {
    return calc_kinetic_energy(tree, y.head(n), y.tail(n), ws) + calc_potential_energy(tree, y.head(n), ws);
  };
  const double E0 = energy(x);
  const double h = 5e-4;
  double drift = 0.0, T_max = 0.0;
  for (int step = 1; step <= 4000; ++step) {
    rk.step(x, h);
    if (step % 10 == 0) {  // every 5 ms
      drift = std::max(drift, std::abs(energy(x) - E0));
      T_max = std::max(T_max, calc_kinetic_energy(tree, x.head(n), x.tail(n), ws));
    }
  }
  ASSERT_TRUE(x.allFinite());
  EXPECT_GT(T_max, 1.0);  // the motion is not small: joules exchanged
  EXPECT_LT(drift / T_max, 1e-8) << "drift " << drift << " J of " << T_max << " J";
  RecordProperty("relative_energy_drift", test::sci(drift / T_max));
}

TEST(Algorithms, BodyPosesOfTheTreePassMatchTheChainWalk) {
  test::Rng rng(15);
  for (int k = 0; k < 12; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k);
    const VectorXd q = test::random_q(rng, tree);
    std::vector<Pose> poses(static_cast<std::size_t>(tree.num_bodies()));
    calc_body_poses(tree, q, poses);
    for (int i = 0; i < tree.num_bodies(); ++i) {
      const Pose p = calc_body_pose(tree, q, i);
      EXPECT_LT((p.rotation - poses[i].rotation).cwiseAbs().maxCoeff(), 1e-14);
      EXPECT_LT((p.position - poses[i].position).norm(), 1e-14);
      EXPECT_LT((p.rotation.transpose() * p.rotation - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-14);
      const Vec3 c = tree.body(i).com;
      EXPECT_LT((calc_point_position(tree, q, i, c) - (p.position + p.rotation * c)).norm(), 1e-14);
    }
  }
}

TEST(Algorithms, ForwardKinematicsOfATwoLinkArmMatchesTheClosedForm) {
  // Two hinges about y, links l1 = 0.5 m, l2 = 0.3 m hanging along -z at q = 0: the tip at
  // (-l1 sin q1 - l2 sin(q1 + q2), 0, -l1 cos q1 - l2 cos(q1 + q2)) (hinge about y turns z towards -x).
  const double l1 = 0.5, l2 = 0.3;
  TreeSpec s;
  BodySpec a;
  a.axis = Vec3::UnitY();
  a.mass = 1.0;
  a.inertia = test::box_inertia(1.0, 0.1, 0.1, 0.1);
  BodySpec b = a;
  b.parent = 0;
  b.position = {0.0, 0.0, -l1};
  s.bodies = {a, b};
  const Tree tree = make_tree(s);
  const Eigen::Vector2d q(0.4, -1.1);
  const Vec3 tip = calc_point_position(tree, q, 1, Vec3(0.0, 0.0, -l2));
  EXPECT_NEAR(tip.x(), -l1 * std::sin(q[0]) - l2 * std::sin(q[0] + q[1]), 1e-15);
  EXPECT_NEAR(tip.y(), 0.0, 1e-15);
  EXPECT_NEAR(tip.z(), -l1 * std::cos(q[0]) - l2 * std::cos(q[0] + q[1]), 1e-15);
  EXPECT_LT((calc_body_pose(tree, q, 1).rotation - roty(q[0] + q[1])).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(Algorithms, WrongSizesAndAForeignWorkspaceAreRejected) {
  test::Rng rng(16);
  const Tree tree = test::random_tree(rng, 4), other = test::random_tree(rng, 6);
  TreeWorkspace ws(tree), ws_other(other);
  const int n = tree.nv();
  VectorXd q = VectorXd::Zero(n), out(n), wrong(n + 1);
  MatrixXd M(n, n), M_wrong(n + 1, n);
  EXPECT_THROW(calc_forward_dynamics(tree, wrong, q, q, out, ws), std::invalid_argument);
  EXPECT_THROW(calc_forward_dynamics(tree, q, q, q, wrong, ws), std::invalid_argument);
  EXPECT_THROW(calc_inverse_dynamics(tree, q, q, wrong, out, ws), std::invalid_argument);
  EXPECT_THROW(calc_bias_forces(tree, q, wrong, out, ws), std::invalid_argument);
  EXPECT_THROW(calc_mass_matrix(tree, q, M_wrong, ws), std::invalid_argument);
  EXPECT_THROW(calc_mass_matrix(tree, q, M, ws_other), std::invalid_argument);
  EXPECT_THROW((void)calc_body_pose(tree, q, tree.num_bodies()), std::invalid_argument);
  try {
    calc_forward_dynamics(tree, wrong, q, q, out, ws);
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), ("calc_forward_dynamics: q has " + std::to_string(n + 1) + " entries, the tree has " +
                            std::to_string(n)).c_str());
  }
}

}  // namespace
}  // namespace ff
