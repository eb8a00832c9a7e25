// multibody/statics and the point loads of multibody/algorithms: the point Jacobian against finite
// differences of the kinematics and against virtual work, the static equilibrium of a spring-loaded
// pendulum against its closed form, and the failure results of the solver.
#include "multibody/statics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "multibody/algorithms.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

TEST(PointLoad, PointJacobianMatchesFiniteDifferencesOfTheKinematics) {
  // Rows 3-5: d p / d q_j of calc_point_position; rows 0-2: omega with [omega]x = (dR/dq_j) R^T, both in
  // base coordinates (central differences, h = 1e-6), on random trees with every joint type.
  test::Rng rng(21);
  const double h = 1e-6;
  for (int k = 0; k < 12; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k);
    TreeWorkspace ws(tree);
    const VectorXd q = test::random_q(rng, tree);
    const int body = rng.index(tree.num_bodies());
    const Vec3 point = rng.vec3(-0.4, 0.4);
    MatrixXd J(6, tree.nv());
    calc_point_jacobian(tree, q, body, point, J, ws);
    const Mat3 R = calc_body_pose(tree, q, body).rotation;
    for (int j = 0; j < tree.nv(); ++j) {
      VectorXd qp = q, qm = q;
      qp[j] += h;
      qm[j] -= h;
      const Vec3 v = (calc_point_position(tree, qp, body, point) - calc_point_position(tree, qm, body, point)) / (2 * h);
      const Mat3 W = (calc_body_pose(tree, qp, body).rotation - calc_body_pose(tree, qm, body).rotation) / (2 * h) *
                     R.transpose();
      EXPECT_LT((v - J.col(j).tail<3>()).norm(), 1e-7) << "tree " << k << " dof " << j;
      EXPECT_LT((Vec3(W(2, 1), W(0, 2), W(1, 0)) - J.col(j).head<3>()).norm(), 1e-7) << "tree " << k << " dof " << j;
    }
  }
}

TEST(PointLoad, GeneralisedForcesDoTheLoadsVirtualWork) {
  // tau . qd = f . v_p + n . omega for every qd: tau = J^T [n; f], accumulated onto what tau held.
  test::Rng rng(22);
  for (int k = 0; k < 24; ++k) {
    const Tree tree = test::random_tree(rng, 1 + k % 12);
    TreeWorkspace ws(tree);
    const VectorXd q = test::random_q(rng, tree), qd = test::random_vector(rng, tree.nv(), -2.0, 2.0);
    const int body = rng.index(tree.num_bodies());
    const Vec3 point = rng.vec3(-0.4, 0.4), force = rng.vec3(-10.0, 10.0), moment = rng.vec3(-3.0, 3.0);
    const VectorXd before = test::random_vector(rng, tree.nv(), -1.0, 1.0);
    VectorXd tau = before;
    add_point_load(tree, q, body, point, force, moment, tau, ws);
    MatrixXd J(6, tree.nv());
    calc_point_jacobian(tree, q, body, point, J, ws);
    const Eigen::Matrix<double, 6, 1> vel = J * qd;
    const double power = moment.dot(vel.head<3>()) + force.dot(vel.tail<3>());
    EXPECT_NEAR((tau - before).dot(qd), power, 1e-12 * (1.0 + std::abs(power))) << "tree " << k;
  }
}

TEST(PointLoad, WrongSizesAndBodiesAreRejected) {
  test::Rng rng(23);
  const Tree tree = test::random_tree(rng, 4);
  TreeWorkspace ws(tree);
  const int n = tree.nv();
  const VectorXd q = VectorXd::Zero(n);
  VectorXd tau(n), wrong(n + 1);
  MatrixXd J(6, n), J_wrong(3, n);
  EXPECT_THROW(calc_point_jacobian(tree, q, 0, Vec3::Zero(), J_wrong, ws), std::invalid_argument);
  EXPECT_THROW(calc_point_jacobian(tree, q, 4, Vec3::Zero(), J, ws), std::invalid_argument);
  EXPECT_THROW(add_point_load(tree, q, -1, Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), tau, ws), std::invalid_argument);
  EXPECT_THROW(add_point_load(tree, q, 0, Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), wrong, ws), std::invalid_argument);
  EXPECT_THROW(add_point_load(tree, wrong, 0, Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), tau, ws), std::invalid_argument);
}

// A 2 kg bob on a hinge about y, its centre of mass l = 0.4 m out along x (horizontal at q = 0),
// gravity -z, a spring k = 12 N·m/rad with reference 0: V = -m g l sin q + k q²/2, so the
// equilibrium solves k q = m g l cos q and the static stiffness is k + m g l sin q.
Tree spring_pendulum(double k) {
  TreeSpec s;
  BodySpec b;
  b.axis = Vec3::UnitY();
  b.mass = 2.0;
  b.com = {0.4, 0.0, 0.0};
  b.inertia = test::box_inertia(2.0, 0.05, 0.05, 0.05);
  b.stiffness = k;
  s.bodies = {b};
  return make_tree(s);
}

TEST(Statics, SpringLoadedPendulumSettlesWhereTheSpringBalancesGravity) {
  const double m = 2.0, g = 9.81, l = 0.4, k = 12.0;
  const Tree tree = spring_pendulum(k);
  const StaticEquilibriumResult res = solve_static_equilibrium(tree, VectorXd::Zero(1), VectorXd::Zero(1));
  ASSERT_TRUE(res.converged()) << res.message;
  const double q = res.q[0];
  EXPECT_GT(q, 0.4);  // a large, nonlinear sag (measured 0.4838 rad)
  EXPECT_NEAR(k * q, m * g * l * std::cos(q), 1e-10 * m * g * l);
  EXPECT_LE(res.iterations, 8);
  EXPECT_NE(res.message.find("converged"), std::string::npos);
  TreeWorkspace ws(tree);
  MatrixXd K(1, 1);
  calc_static_stiffness(tree, res.q, K, ws);
  EXPECT_NEAR(K(0, 0), k + m * g * l * std::sin(q), 1e-6);
  // An applied torque tau shifts it: k q + tau... = m g l cos q + tau.
  const StaticEquilibriumResult loaded = solve_static_equilibrium(tree, res.q, VectorXd::Constant(1, 1.5));
  ASSERT_TRUE(loaded.converged()) << loaded.message;
  EXPECT_NEAR(k * loaded.q[0], m * g * l * std::cos(loaded.q[0]) + 1.5, 1e-10 * m * g * l);
  RecordProperty("equilibrium_rad", test::sci(q));
}

TEST(Statics, ALockedJointHoldsItsAngleAndTheSpringJointOutboardBalancesGravityAboutIt) {
  // A hub joint about y (no spring) locked at 0.3 rad carrying the spring pendulum: alone it is
  // falls (nothing holds the hub); locked, the outer joint balances k q2 = m g l cos(q1 + q2).
  const double m = 2.0, g = 9.81, l = 0.4, k = 12.0;
  TreeSpec s;
  BodySpec hub;
  hub.axis = Vec3::UnitY();
  hub.mass = 1.0;
  hub.inertia = test::box_inertia(1.0, 0.1, 0.1, 0.1);
  BodySpec arm;
  arm.parent = 0;
  arm.axis = Vec3::UnitY();
  arm.mass = m;
  arm.com = {l, 0.0, 0.0};
  arm.inertia = test::box_inertia(m, 0.05, 0.05, 0.05);
  arm.stiffness = k;
  s.bodies = {hub, arm};
  s.gravity = {0.0, 0.0, -g};
  const Tree tree = make_tree(s);
  VectorXd q0 = VectorXd::Zero(2);
  q0[0] = -0.3;  // about +y: turns x towards +z, against the sag
  EXPECT_FALSE(solve_static_equilibrium(tree, q0, VectorXd::Zero(2)).converged());  // it falls
  StaticEquilibriumOptions held;
  held.locked_dofs = {0};
  const StaticEquilibriumResult res = solve_static_equilibrium(tree, q0, VectorXd::Zero(2), held);
  ASSERT_TRUE(res.converged()) << res.message;
  EXPECT_EQ(res.q[0], -0.3);
  EXPECT_NEAR(k * res.q[1], m * g * l * std::cos(res.q[0] + res.q[1]), 1e-10 * m * g * l);
}

TEST(Statics, FailuresAreResultsWithAStatusAndAMessageNotExceptions) {
  // A hub about the vertical axis with no spring under a torque: nothing holds it (singular).
  TreeSpec s;
  BodySpec hub;
  hub.mass = 1.0;
  hub.com = {0.3, 0.0, 0.0};
  hub.inertia = test::box_inertia(1.0, 0.1, 0.1, 0.1);
  s.bodies = {hub};
  const Tree free_hub = make_tree(s);
  const StaticEquilibriumResult singular = solve_static_equilibrium(free_hub, VectorXd::Zero(1), VectorXd::Ones(1));
  EXPECT_FALSE(singular.converged());
  EXPECT_EQ(singular.status, StaticStatus::kSingular);
  EXPECT_NE(singular.message.find("singular"), std::string::npos) << singular.message;
  EXPECT_EQ(singular.q[0], 0.0);  // the last iterate: where it started
  EXPECT_DOUBLE_EQ(singular.residual, 1.0);

  // The iteration limit.
  StaticEquilibriumOptions one;
  one.max_iterations = 1;
  const StaticEquilibriumResult limited = solve_static_equilibrium(spring_pendulum(12.0), VectorXd::Zero(1),
                                                                   VectorXd::Zero(1), one);
  EXPECT_EQ(limited.status, StaticStatus::kMaxIterations);
  EXPECT_EQ(limited.iterations, 1);
  EXPECT_NE(limited.message.find("iteration limit"), std::string::npos) << limited.message;

  // Wrong sizes and options are the caller's errors: those throw.
  EXPECT_THROW(solve_static_equilibrium(free_hub, VectorXd::Zero(2), VectorXd::Zero(1)), std::invalid_argument);
  EXPECT_THROW(solve_static_equilibrium(free_hub, VectorXd::Zero(1), VectorXd::Zero(3)), std::invalid_argument);
  StaticEquilibriumOptions bad;
  bad.tolerance = 0.0;
  EXPECT_THROW(solve_static_equilibrium(free_hub, VectorXd::Zero(1), VectorXd::Zero(1), bad), std::invalid_argument);
}

}  // namespace
}  // namespace ff
