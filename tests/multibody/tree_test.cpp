// multibody/tree: the derived model (coordinates, axes, inertias) and each validation error with
// its message.
#include "multibody/tree.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "multibody/limits.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

// Two bodies on revolute joints, a 1 kg box each: valid as it stands.
TreeSpec two_links() {
  TreeSpec s;
  BodySpec a;
  a.name = "upper";
  a.mass = 1.0;
  a.com = {0.0, 0.0, -0.25};
  a.inertia = test::box_inertia(1.0, 0.05, 0.05, 0.5);
  BodySpec b = a;
  b.name = "lower";
  b.parent = 0;
  b.position = {0.0, 0.0, -0.5};
  b.axis = {0.0, 1.0, 0.0};
  s.bodies = {a, b};
  return s;
}

// make_tree(spec) throws std::invalid_argument whose message holds `what`.
void expect_rejected(const TreeSpec& spec, const std::string& what) {
  try {
    (void)make_tree(spec);
    ADD_FAILURE() << "accepted; expected an error containing: " << what;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << "message: " << e.what();
  }
}

TEST(Tree, CountsOnlyMovingJointsAsCoordinates) {
  TreeSpec s = two_links();
  BodySpec fixed = s.bodies[1];
  fixed.name = "tool";
  fixed.parent = 1;
  fixed.joint = JointType::kFixed;
  fixed.armature = 0.3;  // ignored on a fixed joint
  BodySpec slide = s.bodies[1];
  slide.name = "slide";
  slide.parent = 2;
  slide.joint = JointType::kPrismatic;
  slide.axis = {3.0, 0.0, 4.0};
  s.bodies.push_back(fixed);
  s.bodies.push_back(slide);
  const Tree t = make_tree(s);
  EXPECT_EQ(t.num_bodies(), 4);
  EXPECT_EQ(t.nq(), 3);
  EXPECT_EQ(t.nv(), 3);
  EXPECT_EQ(t.body(0).dof, 0);
  EXPECT_EQ(t.body(1).dof, 1);
  EXPECT_EQ(t.body(2).dof, -1);
  EXPECT_EQ(t.body(3).dof, 2);
  EXPECT_EQ(t.body(2).armature, 0.0);
  EXPECT_EQ(t.body(2).S, SpatialMotion(SpatialMotion::Zero()));
  // The prismatic axis normalised, in the linear half of S; the revolute one in the angular half.
  EXPECT_NEAR(t.body(3).S[3], 0.6, 1e-15);
  EXPECT_NEAR(t.body(3).S[5], 0.8, 1e-15);
  EXPECT_EQ(Vec3(t.body(3).S.head<3>()), Vec3(Vec3::Zero()));
  EXPECT_EQ(Vec3(t.body(1).S.head<3>()), Vec3(Vec3::UnitY()));
  // Default gravity, and the base acceleration that replaces it.
  EXPECT_EQ(t.gravity(), Vec3(0.0, 0.0, -9.81));
  SpatialMotion a0;
  a0 << 0.0, 0.0, 0.0, 0.0, 0.0, 9.81;
  EXPECT_EQ(t.base_acceleration(), a0);
  // The spatial inertia about the body origin: mass block and first moment m c×.
  EXPECT_NEAR(t.body(0).inertia(3, 3), 1.0, 1e-15);
  EXPECT_NEAR(t.body(0).inertia(0, 4), -(-0.25), 1e-15);  // (m c×)_{xy} = -m c_z
}

TEST(Tree, RejectsMoreBodiesThanItsLimit) {
  // A chain of kMaxTreeBodies is a tree; one body more is refused before any body is built.
  TreeSpec s = two_links();
  while (s.bodies.size() < static_cast<std::size_t>(kMaxTreeBodies)) {
    BodySpec b = s.bodies.back();
    b.name = "link" + std::to_string(s.bodies.size());
    b.parent = static_cast<int>(s.bodies.size()) - 1;
    s.bodies.push_back(b);
  }
  EXPECT_EQ(make_tree(s).num_bodies(), 1000);
  s.bodies.push_back(s.bodies.back());
  s.bodies.back().name = "one_too_many";
  expect_rejected(s, "the tree has 1001 bodies (flexible links' segments and joint bodies counted), over the limit of 1000");
  EXPECT_EQ(tree_size_fault(1000), "");
}

TEST(Tree, RejectsAParentAfterItsChild) {
  TreeSpec s = two_links();
  s.bodies[0].parent = 1;
  expect_rejected(s, "tree: body 0 (\"upper\"): parent 1 comes after its child");
  s.bodies[0].parent = 0;  // itself
  expect_rejected(s, "parent 0 comes after its child");
}

TEST(Tree, RejectsAParentOutOfRange) {
  TreeSpec s = two_links();
  s.bodies[1].parent = -2;
  expect_rejected(s, "body 1 (\"lower\"): parent -2 is out of range");
}

TEST(Tree, RejectsAZeroOrNonFiniteJointAxis) {
  TreeSpec s = two_links();
  s.bodies[1].axis = Vec3::Zero();
  expect_rejected(s, "body 1 (\"lower\"): joint axis is zero");
  s.bodies[1].axis = {std::numeric_limits<double>::quiet_NaN(), 0.0, 1.0};
  expect_rejected(s, "joint axis is not finite");
  // A fixed joint has no axis to check.
  s.bodies[1].joint = JointType::kFixed;
  s.bodies[1].axis = Vec3::Zero();
  EXPECT_NO_THROW((void)make_tree(s));
}

TEST(Tree, RejectsANegativeMass) {
  TreeSpec s = two_links();
  s.bodies[1].mass = -0.5;
  expect_rejected(s, "body 1 (\"lower\"): mass -0.5 kg is negative");
  s.bodies[1].mass = std::numeric_limits<double>::infinity();
  expect_rejected(s, "mass is not finite");
}

TEST(Tree, RejectsAnInertiaTensorThatIsNotPositiveDefinite) {
  TreeSpec s = two_links();
  s.bodies[1].inertia = Vec3(0.0, 0.02, 0.02).asDiagonal();  // a thin rod: singular
  expect_rejected(s, "body 1 (\"lower\"): inertia tensor is not positive definite (principal moments 0, 0.02, 0.02");
  s.bodies[1].inertia = Vec3(-0.01, 0.02, 0.02).asDiagonal();
  expect_rejected(s, "inertia tensor is not positive definite");
  // A massive point has no rotational inertia: not positive definite either.
  s.bodies[1].inertia.setZero();
  expect_rejected(s, "inertia tensor is not positive definite");
}

TEST(Tree, RejectsAnInertiaViolatingTheTriangleInequality) {
  TreeSpec s = two_links();
  // Principal moments 0.01, 0.01, 0.05 (0.01 + 0.01 < 0.05), turned off the axes.
  s.bodies[0].inertia = rotx(0.4) * Vec3(0.01, 0.01, 0.05).asDiagonal() * rotx(0.4).transpose();
  expect_rejected(s, "body 0 (\"upper\"): inertia tensor violates the triangle inequality I_a + I_b >= I_c");
  // A flat plate sits on the boundary (I_z = I_x + I_y) and is accepted.
  s.bodies[0].inertia = test::box_inertia(1.0, 0.3, 0.2, 0.0, roty(0.7));
  EXPECT_NO_THROW((void)make_tree(s));
}

TEST(Tree, RejectsANonSymmetricInertia) {
  TreeSpec s = two_links();
  s.bodies[1].inertia(0, 1) = 1e-3;
  expect_rejected(s, "body 1 (\"lower\"): inertia tensor is not symmetric");
}

TEST(Tree, AMasslessBodyMustHaveNoInertia) {
  TreeSpec s = two_links();
  s.bodies[1].mass = 0.0;
  expect_rejected(s, "body 1 (\"lower\"): a massless body must have a zero inertia tensor");
  s.bodies[1].inertia.setZero();
  EXPECT_NO_THROW((void)make_tree(s));
}

TEST(Tree, RejectsARotationThatIsNotProper) {
  TreeSpec s = two_links();
  s.bodies[1].rotation = Vec3(1.0, 1.0, -1.0).asDiagonal();  // a reflection
  expect_rejected(s, "body 1 (\"lower\"): joint frame rotation is not a proper rotation matrix");
  s.bodies[1].rotation = 1.01 * Mat3::Identity();
  expect_rejected(s, "joint frame rotation is not a proper rotation matrix");
}

TEST(Tree, RejectsANegativeArmatureAndNonFiniteValues) {
  TreeSpec s = two_links();
  s.bodies[1].armature = -1.0;
  expect_rejected(s, "body 1 (\"lower\"): armature -1 must be non-negative and finite");
  s = two_links();
  s.bodies[1].position[2] = std::numeric_limits<double>::infinity();
  expect_rejected(s, "joint frame position is not finite");
  s = two_links();
  s.bodies[1].com[0] = std::numeric_limits<double>::quiet_NaN();
  expect_rejected(s, "centre of mass is not finite");
  s = two_links();
  s.gravity[2] = std::numeric_limits<double>::quiet_NaN();
  expect_rejected(s, "tree: gravity is not finite");
}

TEST(Tree, AnUnnamedBodyIsNamedByItsIndex) {
  TreeSpec s = two_links();
  s.bodies[1].name.clear();
  s.bodies[1].mass = -1.0;
  expect_rejected(s, "tree: body 1: mass -1 kg is negative");
}

}  // namespace
}  // namespace ff
