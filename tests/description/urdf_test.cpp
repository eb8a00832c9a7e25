// Tests of URDF import (description/urdf.hpp): the 6-DOF arm of tests/data/urdf against its tree-YAML
// twin, URDF's frame and rpy conventions against closed forms, the Gazebo and sidecar additions, and
// every bad file rejected with one ConfigError line naming the file, the line and the element.
#include "description/urdf.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <string>

#include "description/tree_yaml.hpp"
#include "common/errors.hpp"
#include "common/yaml_reader.hpp"
#include "multibody/algorithms.hpp"
#include "tests/description/test_support.hpp"
#include "tests/temp_dir.hpp"

namespace {

using ff::test::config_error;
using ff::test::with_line;

const std::string kData = std::string(FLEXFARM_SOURCE_DIR) + "/tests/data/urdf/";
constexpr double kPi = std::numbers::pi;

// A two-link arm; the tests change one numbered line.
const std::string kTwoLink = R"(<?xml version="1.0"?>
<robot name="two">
  <link name="base_link"/>
  <joint name="shoulder" type="revolute">
    <parent link="base_link"/>
    <child link="upper_arm"/>
    <origin xyz="0 0 0.5" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="100" velocity="2"/>
  </joint>
  <link name="upper_arm">
    <inertial>
      <origin xyz="0.2 0 0" rpy="0 0 0"/>
      <mass value="2.0"/>
      <inertia ixx="0.01" iyy="0.05" izz="0.05" ixy="0" ixz="0" iyz="0"/>
    </inertial>
  </link>
  <joint name="elbow" type="revolute">
    <parent link="upper_arm"/>
    <child link="forearm"/>
    <origin xyz="0.4 0 0" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="50" velocity="3"/>
  </joint>
  <link name="forearm">
    <inertial>
      <origin xyz="0.15 0 0"/>
      <mass value="1.0"/>
      <inertia ixx="0.004" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/>
    </inertial>
  </link>
</robot>
)";

ff::ConfigError urdf_error(const std::string& xml) {
  return config_error([&] { ff::parse_urdf(xml, "arm.urdf"); });
}

// --- the arm and its twin ------------------------------------------------------------------------

TEST(Urdf, SixDofArmGivesTheTreeOfItsYamlTwinBodyByBodyAndInItsMassMatrix) {
  const ff::TreeDescription urdf = ff::load_urdf(kData + "arm6.urdf", kData + "arm6_sidecar.yaml");
  const ff::TreeDescription yaml = ff::load_tree_yaml(kData + "arm6.yaml");
  const ff::Tree a = ff::make_tree(urdf.spec);
  const ff::Tree b = ff::make_tree(yaml.spec);
  ASSERT_EQ(a.num_bodies(), 7);
  ASSERT_EQ(a.nv(), 6);
  ff::test::expect_same_tree(a, b, 1e-12);
  EXPECT_EQ(urdf.dof_index, yaml.dof_index);
  EXPECT_EQ(urdf.body_index, yaml.body_index);
  ASSERT_EQ(urdf.joints.size(), yaml.joints.size());
  for (std::size_t i = 0; i < urdf.joints.size(); ++i) {
    EXPECT_EQ(urdf.joints[i].name, yaml.joints[i].name);
    EXPECT_EQ(urdf.joints[i].lower, yaml.joints[i].lower);
    EXPECT_EQ(urdf.joints[i].upper, yaml.joints[i].upper);
    EXPECT_EQ(urdf.joints[i].effort, yaml.joints[i].effort);
    EXPECT_EQ(urdf.joints[i].velocity, yaml.joints[i].velocity);
    EXPECT_EQ(urdf.joints[i].friction, yaml.joints[i].friction);
  }

  // M(q) and C(q, qd) + g(q) at random states (a fixed seed; the values span every joint's range).
  ff::TreeWorkspace wa(a), wb(b);
  std::srand(7);
  auto uniform = [](double lo, double hi) { return lo + (hi - lo) * std::rand() / static_cast<double>(RAND_MAX); };
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd q(6), qd(6);
    for (int k = 0; k < 6; ++k) {
      q[k] = uniform(-kPi, kPi);
      qd[k] = uniform(-2.0, 2.0);
    }
    Eigen::MatrixXd Ma(6, 6), Mb(6, 6);
    ff::calc_mass_matrix(a, q, Ma, wa);
    ff::calc_mass_matrix(b, q, Mb, wb);
    EXPECT_LE((Ma - Mb).cwiseAbs().maxCoeff(), 1e-12) << "q = " << q.transpose();
    EXPECT_GT(Ma.diagonal().minCoeff(), 0.1);  // armature on every diagonal entry
    Eigen::VectorXd ca(6), cb(6);
    ff::calc_bias_forces(a, q, qd, ca, wa);
    ff::calc_bias_forces(b, q, qd, cb, wb);
    EXPECT_LE((ca - cb).cwiseAbs().maxCoeff(), 1e-12) << "q = " << q.transpose();
  }
}

TEST(Urdf, ReadsTheLimitsAndTheContinuousJointAsARevoluteOneWithoutPositionLimits) {
  const ff::TreeDescription d = ff::load_urdf(kData + "arm6.urdf");
  const ff::JointInfo& pan = d.joints.at(0);
  EXPECT_EQ(pan.name, "shoulder_pan");
  EXPECT_EQ(pan.lower, -6.2832);
  EXPECT_EQ(pan.upper, 6.2832);
  EXPECT_EQ(pan.effort, 150.0);
  EXPECT_EQ(pan.velocity, 3.15);
  const int wrist_3 = d.body_index.at("wrist_3_link");
  EXPECT_EQ(d.spec.bodies.at(wrist_3).joint, ff::JointType::kRevolute);
  EXPECT_EQ(d.joints.at(wrist_3).name, "wrist_3");
  EXPECT_EQ(d.joints.at(wrist_3).lower, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(d.joints.at(wrist_3).upper, std::numeric_limits<double>::infinity());
  EXPECT_EQ(d.joints.at(wrist_3).effort, 28.0);
  EXPECT_EQ(d.joints.at(wrist_3).velocity, 3.2);
  EXPECT_EQ(d.dof_index.at("wrist_3"), 5);
  EXPECT_EQ(d.spec.bodies.at(d.body_index.at("tool0")).joint, ff::JointType::kFixed);
  EXPECT_EQ(d.dof_index.count("tool0_fixed"), 0u);
  EXPECT_EQ(d.base, "base_link");
}

TEST(Urdf, GazeboSpringsAndDynamicsDampingGoToTheJointsSpringDamper) {
  const ff::TreeDescription d = ff::load_urdf(kData + "arm6.urdf");
  const ff::BodySpec& elbow = d.spec.bodies.at(d.body_index.at("forearm_link"));
  EXPECT_EQ(elbow.stiffness, 120.0);
  EXPECT_EQ(elbow.spring_reference, 0.25);
  EXPECT_EQ(elbow.damping, 0.0);
  const ff::BodySpec& wrist_2 = d.spec.bodies.at(d.body_index.at("wrist_2_link"));
  EXPECT_EQ(wrist_2.stiffness, 15.0);
  EXPECT_EQ(wrist_2.spring_reference, -0.1);
  const int lift = d.body_index.at("upper_arm_link");
  EXPECT_EQ(d.spec.bodies.at(lift).damping, 2.5);
  EXPECT_EQ(d.spec.bodies.at(lift).stiffness, 0.0);
  EXPECT_EQ(d.joints.at(lift).friction, 0.8);
  EXPECT_EQ(d.spec.bodies.at(lift).armature, 0.0);  // armature comes from the sidecar only
}

TEST(Urdf, TheRootLinkIsTheFixedBaseAndItsInertialIsIgnoredWithANote) {
  const ff::TreeDescription d = ff::load_urdf(kData + "arm6.urdf");
  EXPECT_EQ(d.body_index.count("base_link"), 0u);
  EXPECT_EQ(d.spec.bodies.at(0).parent, -1);
  ASSERT_EQ(d.notes.size(), 1u);
  EXPECT_EQ(d.notes[0], kData + "arm6.urdf:9: link \"base_link\": the root link is the fixed base: its inertial (4 kg) is ignored");
}

// --- conventions ---------------------------------------------------------------------------------

TEST(Urdf, ARpyYawOfAQuarterTurnTurnsXIntoY) {
  const ff::Mat3 R = ff::rpy_rotation(0.0, 0.0, kPi / 2);
  EXPECT_LE((R * ff::Vec3::UnitX() - ff::Vec3::UnitY()).norm(), 1e-15);
  EXPECT_LE((R * ff::Vec3::UnitY() + ff::Vec3::UnitX()).norm(), 1e-15);
  // Fixed axes, roll first: rpy (pi/2, pi/2, 0) = Ry(pi/2) Rx(pi/2) takes x to -z, y to x, z to -y
  // (the other order, Rx Ry, would take x to y).
  const ff::Mat3 Q = ff::rpy_rotation(kPi / 2, kPi / 2, 0.0);
  EXPECT_LE((Q * ff::Vec3::UnitX() + ff::Vec3::UnitZ()).norm(), 1e-15);
  EXPECT_LE((Q * ff::Vec3::UnitY() - ff::Vec3::UnitX()).norm(), 1e-15);
  EXPECT_LE((Q * ff::Vec3::UnitZ() + ff::Vec3::UnitY()).norm(), 1e-15);
  // The general closed form, Rz(yaw) Ry(pitch) Rx(roll).
  const double r = 0.3, p = -0.7, y = 1.9;
  const ff::Mat3 E = (Eigen::AngleAxisd(y, ff::Vec3::UnitZ()) * Eigen::AngleAxisd(p, ff::Vec3::UnitY()) *
                      Eigen::AngleAxisd(r, ff::Vec3::UnitX())).toRotationMatrix();
  EXPECT_LE((ff::rpy_rotation(r, p, y) - E).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(Urdf, TheJointOriginPlacesTheChildLinkFrameWhichTheJointThenTurnsAboutItsAxis) {
  // The shoulder's origin: 0.5 m up, yawed a quarter turn; the upper arm's x axis then points along y.
  const std::string xml = with_line(kTwoLink, 7, R"(    <origin xyz="0 0 0.5" rpy="0 0 1.5707963267948966"/>)");
  const ff::Tree tree = ff::make_tree(ff::parse_urdf(xml, "arm.urdf").spec);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(2);
  // The upper arm's centre of mass, 0.2 m along its x axis.
  EXPECT_LE((ff::calc_point_position(tree, q, 0, {0.2, 0, 0}) - ff::Vec3(0, 0.2, 0.5)).norm(), 1e-15);
  // The elbow (0.4 m along the upper arm's x) at shoulder q = pi/2: a further quarter turn about z.
  q[0] = kPi / 2;
  EXPECT_LE((ff::calc_body_pose(tree, q, 1).position - ff::Vec3(-0.4, 0, 0.5)).norm(), 1e-15);
}

TEST(Urdf, TheInertialFrameTurnsTheTensorIntoTheLinkFrameAndItsXyzIsTheCentreOfMass) {
  const double r = 0.3, p = -0.5, y = 1.1;
  const std::string xml = with_line(kTwoLink, 13, R"(      <origin xyz="0.2 0.01 -0.03" rpy="0.3 -0.5 1.1"/>)");
  const ff::BodySpec b = ff::parse_urdf(xml, "arm.urdf").spec.bodies.at(0);
  const ff::Mat3 R = (Eigen::AngleAxisd(y, ff::Vec3::UnitZ()) * Eigen::AngleAxisd(p, ff::Vec3::UnitY()) *
                      Eigen::AngleAxisd(r, ff::Vec3::UnitX())).toRotationMatrix();
  const ff::Mat3 I = ff::Vec3(0.01, 0.05, 0.05).asDiagonal();
  EXPECT_LE((b.inertia - R * I * R.transpose()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LE((b.com - ff::Vec3(0.2, 0.01, -0.03)).norm(), 1e-15);
  EXPECT_EQ(b.mass, 2.0);
  // The principal axis of the smallest moment is the inertial frame's x axis, R e_x.
  EXPECT_LE((b.inertia * (R * ff::Vec3::UnitX()) - 0.01 * (R * ff::Vec3::UnitX())).norm(), 1e-15);
}

TEST(Urdf, BodiesAreListedParentsFirstWithSiblingsInTheOrderOfTheirJoints) {
  // A fork: the joints written children first, the two fingers' in the order b, a.
  const std::string xml = R"(<robot name="fork">
  <link name="palm"/> <link name="finger_a"/> <link name="finger_b"/> <link name="root"/>
  <joint name="to_b" type="revolute"><parent link="palm"/><child link="finger_b"/><limit effort="1" velocity="1"/></joint>
  <joint name="to_a" type="prismatic"><parent link="palm"/><child link="finger_a"/><limit effort="1" velocity="1"/></joint>
  <joint name="wrist" type="fixed"><parent link="root"/><child link="palm"/></joint>
</robot>)";
  const ff::TreeDescription d = ff::parse_urdf(xml, "fork.urdf");
  ASSERT_EQ(d.spec.bodies.size(), 3u);
  EXPECT_EQ(d.base, "root");
  EXPECT_EQ(d.spec.bodies[0].name, "palm");
  EXPECT_EQ(d.spec.bodies[1].name, "finger_b");
  EXPECT_EQ(d.spec.bodies[2].name, "finger_a");
  EXPECT_EQ(d.spec.bodies[1].parent, 0);
  EXPECT_EQ(d.spec.bodies[2].parent, 0);
  EXPECT_EQ(d.spec.bodies[2].joint, ff::JointType::kPrismatic);
  EXPECT_EQ(d.spec.bodies[2].axis, ff::Vec3::UnitX());  // URDF's default axis
  EXPECT_EQ(d.dof_index.at("to_b"), 0);
  EXPECT_EQ(d.dof_index.at("to_a"), 1);
  EXPECT_NO_THROW(ff::make_tree(d.spec));  // massless bodies are allowed
}

TEST(Urdf, AMimicTagAndDampingOnAFixedJointAreNotedAsIgnored) {
  std::string xml = with_line(kTwoLink, 23, R"(    <limit lower="-2" upper="2" effort="50" velocity="3"/>
    <mimic joint="shoulder" multiplier="2"/>)");
  const ff::TreeDescription d = ff::parse_urdf(xml, "arm.urdf");
  ASSERT_EQ(d.notes.size(), 1u);
  EXPECT_EQ(d.notes[0], "arm.urdf:24: joint \"elbow\": <mimic joint=\"shoulder\"> ignored: the joints move independently");
  xml = with_line(with_line(kTwoLink, 18, R"(  <joint name="elbow" type="fixed">)"), 23, R"(    <dynamics damping="1"/>)");
  const ff::TreeDescription f = ff::parse_urdf(xml, "arm.urdf");
  ASSERT_EQ(f.notes.size(), 1u);
  EXPECT_EQ(f.notes[0], "arm.urdf:23: joint \"elbow\": a fixed joint has no damping or friction: <dynamics> ignored");
}

// --- the sidecar ---------------------------------------------------------------------------------

TEST(Urdf, TheSidecarOverridesOnlyTheValuesItGives) {
  ff::TreeDescription d = ff::parse_urdf(kTwoLink, "arm.urdf");
  ff::apply_urdf_sidecar(d, ff::load_yaml_text("joints:\n  elbow: {armature: 0.2, stiffness: 40}\n", "arm.yaml"),
                         "arm.yaml");
  EXPECT_EQ(d.spec.bodies[1].armature, 0.2);
  EXPECT_EQ(d.spec.bodies[1].stiffness, 40.0);
  EXPECT_EQ(d.spec.bodies[1].damping, 0.0);
  EXPECT_EQ(d.spec.bodies[0].armature, 0.0);
}

TEST(Urdf, TheSidecarRejectsAnUnknownJointAFixedOneAnUnknownKeyAndANegativeValue) {
  auto sidecar_error = [](const std::string& xml, const std::string& yaml) {
    return config_error([&] {
      ff::TreeDescription d = ff::parse_urdf(xml, "arm.urdf");
      ff::apply_urdf_sidecar(d, ff::load_yaml_text(yaml, "arm.yaml"), "arm.yaml");
    });
  };
  EXPECT_STREQ(sidecar_error(kTwoLink, "joints:\n  wrist: {armature: 1}\n").what(),
               "arm.yaml:2: joints.wrist: no joint named 'wrist' in the URDF");
  EXPECT_STREQ(sidecar_error(kTwoLink, "joints:\n  elbwo: {armature: 1}\n").what(),
               "arm.yaml:2: joints.elbwo: no joint named 'elbwo' in the URDF (did you mean `elbow`?)");
  EXPECT_STREQ(sidecar_error(with_line(kTwoLink, 18, R"(  <joint name="elbow" type="fixed">)"),
                             "joints:\n  shoulder: {armature: 1}\n  elbow: {armature: 1}\n").what(),
               "arm.yaml:3: joints.elbow: joint 'elbow' is fixed: it has no degree of freedom for these values");
  EXPECT_STREQ(sidecar_error(kTwoLink, "joints:\n  elbow:\n    armature: 1\n    stifness: 3\n").what(),
               "arm.yaml:4: joints.elbow.stifness: unknown key (did you mean `stiffness`?)");
  EXPECT_STREQ(sidecar_error(kTwoLink, "joints:\n  elbow:\n    damping: -3\n").what(),
               "arm.yaml:3: joints.elbow.damping: must be >= 0, got -3");
  EXPECT_STREQ(sidecar_error(kTwoLink, "joint:\n  elbow: {damping: 3}\n").what(), "arm.yaml:1: joint: unknown key (did you mean `joints`?)");
}

// --- errors: one line each -----------------------------------------------------------------------

TEST(Urdf, AMissingFileIsOneErrorNamingIt) {
  EXPECT_STREQ(config_error([] { ff::load_urdf("/nonexistent/arm.urdf"); }).what(),
               "/nonexistent/arm.urdf: cannot open file");
  EXPECT_STREQ(config_error([] { ff::load_urdf(kData + "arm6.urdf", "/nonexistent/arm.yaml"); }).what(),
               "/nonexistent/arm.yaml: cannot open file");
}

TEST(Urdf, MalformedXmlNamesTheLineTinyXmlStoppedAt) {
  const ff::ConfigError e = urdf_error(with_line(kTwoLink, 21, R"(    <origin xyz="0.4 0 0 rpy="0 0 0"/>)"));
  EXPECT_EQ(e.line(), 21);
  EXPECT_EQ(std::string(e.what()).rfind("arm.urdf:21: malformed XML: ", 0), 0u) << e.what();
  const ff::ConfigError unclosed = urdf_error(with_line(kTwoLink, 24, "  </jont>"));
  EXPECT_EQ(std::string(unclosed.what()).rfind("arm.urdf:24: malformed XML: ", 0), 0u) << unclosed.what();
  EXPECT_STREQ(urdf_error("").what(), "arm.urdf: malformed XML: Error document empty.");
  EXPECT_STREQ(urdf_error("<robot name=\"x\"/>\n").what(), "arm.urdf:1: no <link> in <robot>");
  EXPECT_STREQ(urdf_error("<?xml version=\"1.0\"?>\n<sdf/>\n").what(), "arm.urdf:2: the root element is <sdf>, not <robot>");
}

TEST(Urdf, AJointWhoseParentLinkDoesNotExistNamesTheParentElement) {
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 19, R"(    <parent link="upperarm"/>)")).what(),
               "arm.urdf:19: joint \"elbow\": parent link \"upperarm\" does not exist");
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 20, R"(    <child link="upper_arm"/>)")).what(),
               "arm.urdf:18: joint \"elbow\": joins link \"upper_arm\" to itself");
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 20, R"(    <child/>)")).what(),
               "arm.urdf:20: joint \"elbow\": <child> has no link=\"...\"");
}

TEST(Urdf, AFloatingOrPlanarJointIsRejectedAsUnsupported) {
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 18, R"(  <joint name="elbow" type="floating">)")).what(),
               "arm.urdf:18: joint \"elbow\": a floating joint is not supported: the base is fixed and every joint has "
               "one degree of freedom (revolute, continuous, prismatic) or none (fixed)");
  EXPECT_EQ(urdf_error(with_line(kTwoLink, 4, R"(  <joint name="shoulder" type="planar">)")).line(), 4);
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 4, R"(  <joint name="shoulder" type="hinge">)")).what(),
               "arm.urdf:4: joint \"shoulder\": unknown joint type \"hinge\" (revolute, continuous, prismatic, fixed)");
}

TEST(Urdf, AZeroAxisNamesTheAxisElement) {
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 22, R"(    <axis xyz="0 0 0"/>)")).what(),
               "arm.urdf:22: joint \"elbow\": axis is zero");
}

TEST(Urdf, ANegativeMassNamesTheMassElementAndABadTensorTheInertiaElement) {
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 28, R"(      <mass value="-1"/>)")).what(),
               "arm.urdf:28: link \"forearm\": mass -1 kg is negative");
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 29, R"(      <inertia ixx="0.004" iyy="0.02" izz="0.03" ixy="0" ixz="0" iyz="0"/>)")).what(),
               "arm.urdf:29: link \"forearm\": inertia tensor violates the triangle inequality I_a + I_b >= I_c "
               "(principal moments 0.004, 0.02, 0.03 kg·m²)");
}

TEST(Urdf, WhatLiburdfdomRejectsIsLocatedToTheElementAndPrintsNothing) {
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  const ff::ConfigError origin = urdf_error(with_line(kTwoLink, 21, R"(    <origin xyz="0.4 0 zero" rpy="0 0 0"/>)"));
  const ff::ConfigError limit = urdf_error(with_line(kTwoLink, 23, ""));
  const ff::ConfigError mass = urdf_error(with_line(kTwoLink, 14, R"(      <mass value="two"/>)"));
  const ff::ConfigError version = urdf_error(with_line(kTwoLink, 2, R"(<robot name="two" version="2">)"));
  const ff::ConfigError inertial = urdf_error(with_line(kTwoLink, 13, R"(      <origin xyz="0.2 0 0" rpy="0 0"/>)"));
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");

  EXPECT_EQ(origin.line(), 21);
  EXPECT_EQ(origin.key(), "joint \"elbow\"");
  EXPECT_NE(origin.message().find("[zero]"), std::string::npos) << origin.what();
  EXPECT_EQ(limit.line(), 18);
  EXPECT_NE(limit.message().find("does not specify limits"), std::string::npos) << limit.what();
  EXPECT_EQ(mass.line(), 14);
  EXPECT_EQ(mass.key(), "link \"upper_arm\"");
  EXPECT_EQ(version.line(), 2);
  EXPECT_NE(version.message().find("version"), std::string::npos) << version.what();
  EXPECT_EQ(inertial.line(), 13);
  EXPECT_NE(inertial.message().find("3 expected"), std::string::npos) << inertial.what();
  for (const auto* e : {&origin, &limit, &mass, &version, &inertial})
    EXPECT_EQ(std::string(e->what()).find('\n'), std::string::npos) << e->what();
}

TEST(Urdf, TheTreeStructureIsCheckedWithLines) {
  // A link that is the child of two joints.
  EXPECT_STREQ(urdf_error(with_line(with_line(kTwoLink, 19, R"(    <parent link="base_link"/>)"), 20,
                                    R"(    <child link="upper_arm"/>)")).what(),
               "arm.urdf:20: joint \"elbow\": link \"upper_arm\" is already the child of joint \"shoulder\" (line 4): "
               "a link has one parent");
  // A second root (the forearm's joint gone).
  const std::string two_roots = with_line(with_line(kTwoLink, 18, "<!--"), 24, "-->");
  EXPECT_STREQ(urdf_error(two_roots).what(),
               "arm.urdf:25: link \"forearm\": a second root link (the first is \"base_link\", line 3): every link but "
               "the root must be the child of a joint");
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 25, R"(  <link name="upper_arm">)")).what(),
               "arm.urdf:25: link \"upper_arm\": defined twice (first at line 11)");
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 23, R"(    <limit lower="2" upper="-2" effort="50" velocity="3"/>)")).what(),
               "arm.urdf:23: joint \"elbow\": limit upper -2 is below lower 2");
}

TEST(Urdf, GazeboSpringTagsAreReadStrictly) {
  auto gazebo = [](const std::string& tags) { return with_line(kTwoLink, 32, tags + "\n</robot>"); };
  EXPECT_STREQ(urdf_error(gazebo(R"(  <gazebo reference="wrist"><springStiffness>3</springStiffness></gazebo>)")).what(),
               "arm.urdf:32: gazebo reference=\"wrist\": no joint named \"wrist\"");
  EXPECT_STREQ(urdf_error(gazebo(R"(  <gazebo reference="forearm"><springStiffness>3</springStiffness></gazebo>)")).what(),
               "arm.urdf:32: gazebo reference=\"forearm\": names a link: springs belong to joints");
  EXPECT_STREQ(urdf_error(gazebo("  <gazebo reference=\"elbow\">\n    <springStiffness>stiff</springStiffness>\n  </gazebo>")).what(),
               "arm.urdf:33: gazebo reference=\"elbow\": <springStiffness> 'stiff' is not a finite number");
  EXPECT_STREQ(urdf_error(gazebo(R"(  <gazebo reference="elbow"><springStiffness>-3</springStiffness></gazebo>)")).what(),
               "arm.urdf:32: joint \"elbow\": springStiffness -3 is negative");
  const ff::TreeDescription d = ff::parse_urdf(
      gazebo("  <gazebo reference=\"elbow\">\n    <springReference> 0.5 </springReference>\n  </gazebo>"), "arm.urdf");
  EXPECT_EQ(d.spec.bodies[1].spring_reference, 0.5);
  EXPECT_EQ(d.spec.bodies[1].stiffness, 0.0);
}

TEST(Urdf, EveryTruncatedFileIsOneConfigErrorNeverACrash) {
  testing::internal::CaptureStderr();
  const std::size_t end = kTwoLink.find("</robot>") + 7;  // every prefix shorter than the whole is malformed
  for (std::size_t n = 0; n < end; n += 5) {
    try {
      ff::parse_urdf(kTwoLink.substr(0, n), "arm.urdf");
      ADD_FAILURE() << "accepted the first " << n << " characters";
    } catch (const ff::ConfigError& e) {
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(Urdf, AChainOfMoreLinksThanATreeMayHaveIsRefusedAtTheFirstLinkPastTheLimit) {
  // 10,000 links (ran past 100 s at 2.5 GB): refused before liburdfdom reads them, at link 1001's line.
  std::string xml = "<robot name=\"chain\">\n<link name=\"l0\"/>\n";
  for (int i = 1; i <= 10000; ++i)
    xml += "<link name=\"l" + std::to_string(i) + "\"/><joint name=\"j" + std::to_string(i) + "\" type=\"fixed\"><parent link=\"l" +
           std::to_string(i - 1) + "\"/><child link=\"l" + std::to_string(i) + "\"/></joint>\n";
  EXPECT_STREQ(urdf_error(xml + "</robot>\n").what(),
               "arm.urdf:1003: link \"l1001\": the tree has 10000 bodies (flexible links' segments and joint bodies "
               "counted), over the limit of 1000");
}

// --- nesting: refused before TinyXML's recursive parse -------------------------------------------

// `depth` elements nested in <robot>, one a line from line 3, each opened with `open` and closed with
// `close` (a valid file's tail after them).
std::string nested_urdf(int depth, const std::string& open = "<link>", const std::string& close = "</link>") {
  std::string xml = "<?xml version=\"1.0\"?>\n<robot name=\"deep\">\n";
  xml.reserve(static_cast<std::size_t>(depth) * (open.size() + close.size() + 2) + 200);
  for (int i = 0; i < depth; ++i) xml += open + "\n";
  for (int i = 0; i < depth; ++i) xml += close;
  return xml + "\n  <link name=\"base\"/>\n</robot>\n";
}

TEST(Urdf, FiftyThousandNestedElementsAreRefusedAtTheFirstTooDeepOneBeforeParsing) {
  // robot is level 1 (line 2), the k-th <link> level k + 1 (line k + 2): level 101 is line 102.
  const ff::ConfigError e = urdf_error(nested_urdf(50000));
  EXPECT_STREQ(e.what(), "arm.urdf:102: <link>: elements nested more than 100 deep (a URDF nests about 5): "
                         "refused before parsing");
  // Through a file, as a study's arm names it.
  const ff::test::TempDir dir("urdf_depth");
  const std::string path = dir.write("deep.urdf", nested_urdf(50000));
  EXPECT_EQ(config_error([&] { ff::load_urdf(path); }).line(), 102);
}

TEST(Urdf, NestingUpToTheLimitIsParsedAndOneLevelMoreIsRefused) {
  // At the limit TinyXML reads the file: it then fails on what the elements are, not on their depth.
  EXPECT_STREQ(urdf_error(nested_urdf(ff::kMaxUrdfDepth - 1)).what(), "arm.urdf:3: link: <link> has no name=\"...\"");
  EXPECT_EQ(urdf_error(nested_urdf(ff::kMaxUrdfDepth)).line(), ff::kMaxUrdfDepth + 2);
  // Self-closed elements, comments, CDATA and quoted values do not nest.
  std::string opens;
  for (int i = 0; i < 2 * ff::kMaxUrdfDepth; ++i) opens += "<a>";
  std::string base = "  <link name=\"base_link\"><!-- " + opens + " --><![CDATA[" + opens + "]]><foo n=\"" + opens + "\"/>";
  for (int i = 0; i < 2 * ff::kMaxUrdfDepth; ++i) base += "<bar/>";
  EXPECT_EQ(ff::parse_urdf(with_line(kTwoLink, 3, base + "</link>"), "arm.urdf").base, "base_link");
}

TEST(Urdf, NestingHiddenFromANaiveTagCountIsStillCounted) {
  // TinyXML reads "&#x</link>x1;" as one character reference and a byte-order mark inside a tag as white
  // space: neither closes an element, so both files nest 50,000 deep.
  EXPECT_EQ(urdf_error(nested_urdf(50000, "<link>&#x</link>x1;")).line(), 102);
  EXPECT_EQ(urdf_error(nested_urdf(50000, "<link \xEF\xBB\xBF>")).line(), 102);
  EXPECT_EQ(urdf_error(nested_urdf(50000, "<link a=\"&#</link>#1;\">")).line(), 102);
}

TEST(Urdf, AByteThatIsNotUtf8IsRefusedWithItsLine) {
  EXPECT_STREQ(urdf_error(with_line(kTwoLink, 3, "  <link name=\"base\xE9link\"/>")).what(),
               "arm.urdf:3: byte 0xE9 is not UTF-8 text (a URDF is UTF-8)");
  // A lead byte would make TinyXML read the '<' after it as part of one character.
  EXPECT_EQ(urdf_error(nested_urdf(50000, "<link>\xE0</link>")).line(), 3);
}

}  // namespace
