// configs/fbtb_titan.yaml: the FBTB carrying a Titan-class arm on its end frame. At rest, with the hub
// and the beam held (no acceleration) and the small arm accelerating, the torque the hub must give is
// the small arm's reaction about the hub's vertical axis: the rate of change of its angular momentum,
// sum over its bodies of [c x m a_c + I_world alpha]_z (gravity has no moment about a vertical axis),
// from each body's point Jacobian, against the tree's recursive Newton-Euler.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "arm/arm_yaml.hpp"
#include "common/yaml_reader.hpp"
#include "multibody/algorithms.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

TEST(FbtbTitan, TheHubsTorqueAtRestIsTheSmallArmsReactionAboutItsAxis) {
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb_titan.yaml";
  const ArmModel m = parse_arm(load_yaml_file(path), path);
  const Tree& tree = m.tree;
  const int nv = tree.nv();
  const int hub = m.spec.tree.dof_index.at("hub");
  const int titan = m.spec.tree.body_index.at("titan_base");
  // The small arm: titan_base and its descendants.
  std::vector<int> arm;
  for (int b = 0; b < tree.num_bodies(); ++b)
    for (int a = b; a >= 0; a = tree.body(a).parent)
      if (a == titan) {
        arm.push_back(b);
        break;
      }
  ASSERT_EQ(arm.size(), 6u);
  test::Rng rng(7);
  TreeWorkspace ws(tree);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd q = m.q0, qdd = Eigen::VectorXd::Zero(nv);
    for (int b : arm) {
      q[tree.body(b).dof] += rng.uniform(-0.8, 0.8);
      qdd[tree.body(b).dof] = rng.uniform(-5.0, 5.0);
    }
    Eigen::VectorXd tau(nv);
    calc_inverse_dynamics(tree, q, Eigen::VectorXd::Zero(nv), qdd, tau, ws);
    double reaction = 0.0, scale = 0.0;
    for (int b : arm) {
      const Body& body = tree.body(b);
      Eigen::MatrixXd J(6, nv);
      calc_point_jacobian(tree, q, b, body.com, J, ws);
      const Vec3 alpha = J.topRows(3) * qdd, a = J.bottomRows(3) * qdd;
      const Pose pose = calc_body_pose(tree, q, b);
      const Vec3 c = pose.point(body.com);
      const Mat3 I = pose.rotation * body.inertia_com * pose.rotation.transpose();
      const Vec3 moment = c.cross(body.mass * a) + I * alpha;
      reaction += moment.z();
      scale += moment.norm();
    }
    RecordProperty("hub_torque_" + std::to_string(trial), std::to_string(tau[hub]));
    EXPECT_GT(std::abs(reaction), 1.0);
    EXPECT_NEAR(tau[hub], reaction, 1e-9 * scale) << trial;
  }
}

}  // namespace
}  // namespace ff
