// Tests of flexible bodies in tree YAML and the URDF sidecar (description/tree_yaml.hpp, urdf.hpp,
// make_flexible in tree_description.hpp): the tree the block gives against append_flexible_link by
// hand, the names of the segments and cell joints, the URDF twin, the straight link's geometry (a
// child on the tip point), a cantilever's static deflection against Euler–Bernoulli, and every bad
// block rejected with one ConfigError naming the file, the line and the key path.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "description/tree_yaml.hpp"
#include "description/urdf.hpp"
#include "common/errors.hpp"
#include "common/yaml_reader.hpp"
#include "multibody/algorithms.hpp"
#include "multibody/flexible_link.hpp"
#include "multibody/statics.hpp"
#include "tests/description/test_support.hpp"

namespace {

using ff::test::config_error;
using ff::test::with_line;

const std::string kData = std::string(FLEXFARM_SOURCE_DIR) + "/tests/data/urdf/";
constexpr double kPi = std::numbers::pi;

// A rigid upper arm, a flexible forearm (a 0.6 m aluminium strip, 30 x 6 mm, N = 5, a tip payload) on
// a sprung elbow, and a tool fixed at the forearm's tip; the tests change one numbered line.
const std::string kFlexArm = R"(gravity: [0, 0, -9.81]
bodies:
  - name: upper_arm
    parent: base
    joint: {name: shoulder, axis: [0, 0, 1], position: [0, 0, 0.5], armature: 0.1}
    mass: 2.0
    com: [0.2, 0, 0]
    inertia: {ixx: 0.01, iyy: 0.05, izz: 0.05}
  - name: forearm
    parent: upper_arm
    joint: {name: elbow, position: [0.4, 0, 0], rpy: [0.1, 0, 0], armature: 0.05, stiffness: 2, damping: 0.1}
    flexible:
      length: 0.6
      segments: 5
      stiffness_factor: 0.9
      damping_time: 0.002
      section:
        E: 70.0e9
        G: 26.0e9
        density: 2700
        area: 1.8e-4
        I_y: 5.4e-10
        I_z: 1.35e-8
        J: 1.9e-9
      payload:
        mass: 0.2
        com: [0.01, 0, 0]
        inertia: {ixx: 1.0e-4, iyy: 2.0e-4, izz: 2.0e-4}
  - name: tool
    parent: forearm
    joint: {name: tool_mount, type: fixed, position: [0.6, 0, 0.02], rpy: [0, 0, 1.5707963267948966]}
    mass: 0.1
    com: [0, 0, 0.01]
    inertia: {ixx: 1.0e-5, iyy: 1.0e-5, izz: 1.0e-5}
)";

ff::TreeDescription parse(const std::string& text) {
  return ff::parse_tree_yaml(ff::load_yaml_text(text, "arm.yaml"), "arm.yaml");
}

std::string yaml_error(const std::string& text) {
  return config_error([&] { parse(text); }).what();
}

// kFlexArm's forearm as the multibody API takes it.
ff::FlexibleLinkSpec forearm_link() {
  ff::FlexibleLinkSpec link;
  link.name = "forearm";
  link.root_name = "forearm";
  link.root_joint = {.type = ff::JointType::kRevolute, .axis = ff::Vec3::UnitZ(), .armature = 0.05, .stiffness = 2.0,
                     .damping = 0.1, .spring_reference = 0.0};
  link.length = 0.6;
  link.segments = 5;
  link.stiffness_factor = 0.9;
  link.damping_time = 0.002;
  link.section = {.youngs_modulus = 70e9, .shear_modulus = 26e9, .density = 2700.0, .area = 1.8e-4,
                  .second_moment_y = 5.4e-10, .second_moment_z = 1.35e-8, .torsion_constant = 1.9e-9};
  link.payload.mass = 0.2;
  link.payload.com_offset = {0.01, 0.0, 0.0};
  link.payload.inertia = ff::Vec3(1e-4, 2e-4, 2e-4).asDiagonal();
  return link;
}

TEST(FlexibleYaml, ABodyGivesTheTreeAndMassMatrixOfAppendFlexibleLinkByHand) {
  ff::TreeSpec spec;
  ff::BodySpec upper;
  upper.name = "upper_arm";
  upper.position = {0, 0, 0.5};
  upper.armature = 0.1;
  upper.mass = 2.0;
  upper.com = {0.2, 0, 0};
  upper.inertia = ff::Vec3(0.01, 0.05, 0.05).asDiagonal();
  spec.bodies.push_back(upper);
  const ff::FlexibleLinkSpec link = forearm_link();
  const int tip = ff::append_flexible_link(spec, 0, {0.4, 0, 0}, ff::rpy_rotation(0.1, 0, 0), link);
  ff::BodySpec tool;
  tool.name = "tool";
  tool.parent = tip;
  tool.joint = ff::JointType::kFixed;
  // The tool's 0.6 m in the forearm's frame, from the tip segment's origin at L - l/2 = 0.525 m.
  tool.position = {0.6 - 0.525, 0, 0.02};
  tool.rotation = ff::rpy_rotation(0, 0, kPi / 2);
  tool.mass = 0.1;
  tool.com = {0, 0, 0.01};
  tool.inertia = ff::Vec3(1e-5, 1e-5, 1e-5).asDiagonal();
  spec.bodies.push_back(tool);

  const ff::TreeDescription d = parse(kFlexArm);
  const ff::Tree a = ff::make_tree(d.spec), b = ff::make_tree(spec);
  ASSERT_EQ(a.num_bodies(), 1 + 1 + 4 * 3 + 1);  // upper arm, root segment, 4 cells of 3 bodies, tool
  ASSERT_EQ(a.nv(), 2 + 4 * 3);
  ff::test::expect_same_tree(a, b, 1e-12);

  Eigen::VectorXd q = Eigen::VectorXd::Random(a.nv());  // Eigen's fixed seed: values in [-1, 1] rad
  Eigen::MatrixXd Ma(a.nv(), a.nv()), Mb(b.nv(), b.nv());
  ff::TreeWorkspace wa(a), wb(b);
  ff::calc_mass_matrix(a, q, Ma, wa);
  ff::calc_mass_matrix(b, q, Mb, wb);
  EXPECT_LE((Ma - Mb).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(Ma.cwiseAbs().maxCoeff(), 0.5);  // kg·m²: the arm's, not nothing
}

TEST(FlexibleYaml, NamesEverySegmentAndCellJointAndListsTheLinksElasticDofs) {
  const ff::TreeDescription d = parse(kFlexArm);
  std::map<std::string, int> bodies{{"upper_arm", 0}, {"forearm", 1}, {"tool", 14}};
  std::map<std::string, int> dofs{{"shoulder", 0}, {"elbow", 1}};
  for (int j = 1; j <= 4; ++j) {
    const std::string cell = "forearm.cell" + std::to_string(j);
    bodies[cell + ".z"] = 3 * j - 1;
    bodies[cell + ".y"] = 3 * j;
    bodies["forearm.seg" + std::to_string(j)] = 3 * j + 1;
    dofs[cell + ".z"] = 3 * j - 1;
    dofs[cell + ".y"] = 3 * j;
    dofs[cell + ".x"] = 3 * j + 1;
  }
  EXPECT_EQ(d.body_index, bodies);
  EXPECT_EQ(d.dof_index, dofs);
  ASSERT_EQ(d.joints.size(), 15u);
  EXPECT_EQ(d.joints[1].name, "elbow");
  EXPECT_EQ(d.joints[13].name, "forearm.cell4.x");
  EXPECT_EQ(d.joints[14].name, "tool_mount");

  ASSERT_EQ(d.flexible_links.size(), 1u);
  const ff::FlexibleLinkInfo& f = d.flexible_links[0];
  EXPECT_EQ(f.name, "forearm");
  EXPECT_EQ(f.root_body, 1);
  EXPECT_EQ(f.tip_body, 13);
  EXPECT_EQ(f.tip_point, ff::Vec3(0.075, 0, 0));  // l/2 of the cell l = 0.6 / 4
  EXPECT_EQ(f.dofs, (std::vector<int>{2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13}));
  EXPECT_EQ(f.link.length, 0.6);
  EXPECT_EQ(f.link.segments, 5);
  EXPECT_EQ(f.link.section.second_moment_z, 1.35e-8);
  EXPECT_EQ(f.link.root_joint.type, ff::JointType::kRevolute);
  EXPECT_EQ(f.link.root_joint.stiffness, 2.0);
  EXPECT_EQ(f.link.payload.mass, 0.2);
  EXPECT_EQ(d.spec.bodies[13].name, "forearm.seg4");
  EXPECT_EQ(d.spec.bodies[14].parent, 13);
  // The cell springs: k = kappa E I / l (N·m/rad), c = beta k.
  EXPECT_NEAR(d.spec.bodies[2].stiffness, 0.9 * 70e9 * 1.35e-8 / 0.15, 1e-9);
  EXPECT_NEAR(d.spec.bodies[4].damping, 0.002 * 0.9 * 26e9 * 1.9e-9 / 0.15, 1e-12);
}

TEST(FlexibleYaml, OmittedKeysTakeTheirDefaultsAndPlanarKeepsOneJointPerCell) {
  const ff::TreeDescription d = parse(R"(bodies:
  - name: strip
    parent: base
    joint: {type: fixed}
    flexible:
      length: 1
      planar: true
      section: {E: 2.0e11, density: 7800, area: 1.0e-4, I_y: 1.0e-10, I_z: 2.0e-10}
)");
  ASSERT_EQ(d.flexible_links.size(), 1u);
  const ff::FlexibleLinkSpec& l = d.flexible_links[0].link;
  EXPECT_EQ(l.segments, 6);
  EXPECT_EQ(l.stiffness_factor, 1.0);
  EXPECT_EQ(l.damping_time, 0.0);
  EXPECT_TRUE(l.torsion);
  EXPECT_TRUE(l.planar);
  EXPECT_EQ(l.payload.mass, 0.0);
  EXPECT_EQ(l.root_joint.type, ff::JointType::kFixed);
  EXPECT_EQ(d.spec.bodies.size(), 6u);  // one z-bending joint per cell: the segments alone
  EXPECT_EQ(d.dof_index.size(), 5u);
  EXPECT_EQ(d.dof_index.at("strip.cell5.z"), 4);
  EXPECT_EQ(d.body_index.at("strip.seg5"), 5);
}

TEST(FlexibleYaml, WithoutTorsionACellHasTheTwoBendingJointsNamedZAndY) {
  const ff::TreeDescription d = parse(R"(bodies:
  - name: strip
    parent: base
    joint: {name: hub, axis: [0, 1, 0], armature: 0.01}
    flexible:
      length: 1
      segments: 3
      torsion: false
      section: {E: 2.0e11, density: 7800, area: 1.0e-4, I_y: 1.0e-10, I_z: 2.0e-10}
)");
  EXPECT_EQ(d.body_index, (std::map<std::string, int>{{"strip", 0}, {"strip.cell1.z", 1}, {"strip.seg1", 2},
                                                       {"strip.cell2.z", 3}, {"strip.seg2", 4}}));
  EXPECT_EQ(d.dof_index, (std::map<std::string, int>{{"hub", 0}, {"strip.cell1.z", 1}, {"strip.cell1.y", 2},
                                                      {"strip.cell2.z", 3}, {"strip.cell2.y", 4}}));
  EXPECT_EQ(d.flexible_links.at(0).dofs, (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(d.spec.bodies[0].joint, ff::JointType::kRevolute);  // the hub joint moves the root segment
  EXPECT_EQ(d.spec.bodies[0].axis, ff::Vec3::UnitY());
  EXPECT_EQ(d.spec.bodies[0].armature, 0.01);
  EXPECT_NEAR(d.spec.bodies[0].mass, 7800 * 1.0e-4 * 0.25, 1e-15);  // kg: the root segment, l/2 = 0.25 m
}

// --- geometry ------------------------------------------------------------------------------------

TEST(FlexibleYaml, AChildSitsAtTheFlexibleBodysTipPointAndTheStraightArmIsTheRigidOnesGeometry) {
  // The tool written at [0.6, 0, 0] (the beam's end): at q = 0 its frame origin is the tip point.
  const std::string text = with_line(kFlexArm, 31,
      "    joint: {name: tool_mount, type: fixed, position: [0.6, 0, 0], rpy: [0, 0, 1.5707963267948966]}");
  const ff::TreeDescription d = parse(text);
  const ff::Tree tree = ff::make_tree(d.spec);
  const ff::FlexibleLinkInfo& f = d.flexible_links.at(0);
  const int tool = d.body_index.at("tool");
  Eigen::VectorXd q = Eigen::VectorXd::Zero(tree.nv());
  const ff::Vec3 tip = ff::calc_point_position(tree, q, f.tip_body, f.tip_point);
  EXPECT_LE((ff::calc_body_pose(tree, q, tool).position - tip).norm(), 1e-15);
  EXPECT_LE((tip - ff::Vec3(1.0, 0, 0.5)).norm(), 1e-15);  // 0.4 m upper arm + 0.6 m forearm along x

  // The rigid twin (the forearm's mass instead of `flexible`): with the cells straight, every pose of
  // the tool is the same at any shoulder and elbow angle.
  std::string rigid_text = text;
  for (int n = 28; n >= 13; --n) rigid_text = with_line(rigid_text, n, "");
  rigid_text = with_line(rigid_text, 12, "    mass: 0.5\n    com: [0.3, 0, 0]\n    inertia: {ixx: 1.0e-4, iyy: 0.015, izz: 0.015}");
  const ff::TreeDescription r = parse(rigid_text);
  const ff::Tree rigid = ff::make_tree(r.spec);
  Eigen::VectorXd qr = Eigen::VectorXd::Zero(rigid.nv());
  q[d.dof_index.at("shoulder")] = qr[r.dof_index.at("shoulder")] = 0.7;
  q[d.dof_index.at("elbow")] = qr[r.dof_index.at("elbow")] = -1.1;
  const ff::Pose a = ff::calc_body_pose(tree, q, d.body_index.at("tool"));
  const ff::Pose b = ff::calc_body_pose(rigid, qr, r.body_index.at("tool"));
  EXPECT_LE((a.position - b.position).norm(), 1e-15);
  EXPECT_LE((a.rotation - b.rotation).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_GT((a.position - ff::Vec3(1.0, 0, 0.5)).norm(), 0.1);  // m: the arm has turned
}

TEST(FlexibleYaml, ACantileverUnderGravityDeflectsAsEulerBernoulliPredicts) {
  // A 1 m aluminium strip (30 mm wide along y, 5 mm thick along z) clamped horizontally, N = 24, its
  // own weight q = rho A g bending it about y: delta = q L⁴/(8 E I_y) (Euler–Bernoulli). The lumped
  // chain's error is -1/(2 (N-1)²) = -0.09% relative (flexible_link_test.cpp), the geometric
  // nonlinearity ~(delta/L)² ~ 5e-4.
  const ff::TreeDescription d = parse(R"(bodies:
  - name: beam
    parent: base
    joint: {name: clamp, type: fixed, position: [0, 0, 1]}
    flexible:
      length: 1.0
      segments: 24
      section: {E: 70.0e9, G: 26.0e9, density: 2700, area: 1.5e-4, I_y: 3.125e-10, I_z: 1.125e-8, J: 1.0e-9}
)");
  const ff::Tree tree = ff::make_tree(d.spec);
  const ff::FlexibleLinkInfo& f = d.flexible_links.at(0);
  ASSERT_EQ(tree.nv(), 23 * 3);
  ASSERT_EQ(f.dofs.size(), 69u);
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(tree.nv());
  const ff::StaticEquilibriumResult res = ff::solve_static_equilibrium(tree, q0, Eigen::VectorXd::Zero(tree.nv()));
  ASSERT_TRUE(res.converged()) << res.message;
  const ff::Vec3 tip0 = ff::calc_point_position(tree, q0, f.tip_body, f.tip_point);
  const ff::Vec3 tip = ff::calc_point_position(tree, res.q, f.tip_body, f.tip_point);
  EXPECT_LE((tip0 - ff::Vec3(1, 0, 1)).norm(), 1e-15);
  const double q = 2700 * 1.5e-4 * 9.81, exact = q / (8 * 70e9 * 3.125e-10);  // N/m; 22.7 mm
  const double delta = tip0.z() - tip.z();
  std::printf("  tip deflection %.6f m, Euler-Bernoulli %.6f m (%+.3f%%)\n", delta, exact, 100 * (delta / exact - 1));
  EXPECT_NEAR(delta / exact, 1.0, 0.01);
  EXPECT_LE(std::abs(tip.y()), 1e-9);  // m: no load out of the x-z plane
}

// --- errors: one line each, at the key ------------------------------------------------------------

TEST(FlexibleYaml, FlexibleWithMassComOrInertiaIsNamedAtThatKey) {
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 12, "    mass: 0.5\n    flexible:")),
            "arm.yaml:12: bodies[1].mass: a flexible body's mass is its beam's: give `flexible` or `mass`, not both");
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 12, "    inertia: {ixx: 1, iyy: 1, izz: 1}\n    flexible:")),
            "arm.yaml:12: bodies[1].inertia: a flexible body's mass is its beam's: give `flexible` or `mass`, not both");
}

TEST(FlexibleYaml, AMissingLengthANegativeIzAndAnUnknownSectionKeyAreNamedAtTheirLines) {
  // A missing key is named at the block's line (its first key's), as for any block.
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 13, "")), "arm.yaml:14: bodies[1].flexible.length: missing required value");
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 23, "        I_z: -1.35e-8")),
            "arm.yaml:23: bodies[1].flexible.section.I_z: must be > 0, got -1.35e-08");
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 22, "        I_x: 5.4e-10")),
            "arm.yaml:22: bodies[1].flexible.section.I_x: unknown key (did you mean `I_y`?)");
}

TEST(FlexibleYaml, AModulusInGpaOrADensityInGramsPerCubicCentimetreIsAUnitMistake) {
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 18, "        E: 70.0")),
            "arm.yaml:18: bodies[1].flexible.section.E: 70 Pa is far below any engineering material (1e6 to 2e12 Pa): looks "
            "like GPa (70 GPa = 7e+10 Pa); moduli are in Pa (if it is meant, set `units_check: false` at the top of the file)");
  EXPECT_NE(yaml_error(with_line(kFlexArm, 19, "        G: 26.0")).find("arm.yaml:19: bodies[1].flexible.section.G: 26 Pa is far below"),
            std::string::npos);
  EXPECT_NE(yaml_error(with_line(kFlexArm, 20, "        density: 2.7")).find("looks like g/cm³ (2.7 g/cm³ = 2700 kg/m³)"),
            std::string::npos);
}

TEST(FlexibleYaml, OtherBadValuesAreNamedAtTheirKeys) {
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 14, "      segments: 0")),
            "arm.yaml:14: bodies[1].flexible.segments: must be >= 1, got 0");
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 14, "      segments: 2.5")),
            "arm.yaml:14: bodies[1].flexible.segments: expected an integer, got '2.5'");
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 16, "      damping_time: -1")),
            "arm.yaml:16: bodies[1].flexible.damping_time: must be >= 0, got -1");
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 16, "      torsion: maybe")),
            "arm.yaml:16: bodies[1].flexible.torsion: expected true or false");
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 19, "")),
            "arm.yaml:18: bodies[1].flexible.section.G: missing: required with torsion (or set torsion: false or "
            "planar: true)");
  EXPECT_NO_THROW(parse(with_line(with_line(kFlexArm, 19, ""), 16, "      torsion: false")));
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 28, "        inertia: {ixx: 1.0e-4, iyy: -2.0e-4, izz: 2.0e-4}")),
            "arm.yaml:28: bodies[1].flexible.payload.inertia: is not positive semi-definite");
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 26, "        mas: 0.2")), "arm.yaml:26: bodies[1].flexible.payload.mas: unknown key (did you mean `mass`?)");
  std::string scalar_section = with_line(kFlexArm, 17, "      section: 3");
  for (int n = 18; n <= 24; ++n) scalar_section = with_line(scalar_section, n, "");
  EXPECT_EQ(yaml_error(scalar_section),
            "arm.yaml:17: bodies[1].flexible.section: expected a map of keys");
}

TEST(FlexibleYaml, SegmentsOverTheLimitAreNamedAtTheKeyAndATreeGrownPastItsLimitAtTheLink) {
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 14, "      segments: 1000000")),
            "arm.yaml:14: bodies[1].flexible.segments: must be <= 256 (a flexible link's limit), got 1000000");
  EXPECT_NO_THROW(parse(with_line(kFlexArm, 14, "      segments: 256")));  // 1 + 766 + 1 bodies
  // Two links of 256 segments: 766 bodies each, 1532 in all.
  const std::string link = "    flexible: {length: 1, segments: 256, section: {E: 7.0e10, G: 2.6e10, density: 2700, "
                           "area: 1.8e-4, I_y: 5.4e-10, I_z: 1.35e-8, J: 1.9e-9}}\n";
  EXPECT_EQ(yaml_error("bodies:\n  - name: a\n    parent: base\n    joint: {name: ja, axis: [0, 0, 1]}\n" + link +
                       "  - name: b\n    parent: a\n    joint: {name: jb, axis: [0, 0, 1], position: [1, 0, 0]}\n" + link),
            "arm.yaml:5: bodies[0].flexible: the tree has 1532 bodies (flexible links' segments and joint bodies counted), "
            "over the limit of 1000");
}

TEST(FlexibleYaml, AGeneratedNameThatIsTakenIsNamedAtTheFlexibleBlock) {
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 29, "  - name: forearm.seg2")),
            "arm.yaml:12: bodies[1].flexible: its segment body \"forearm.seg2\" would take the name of another body");
  EXPECT_EQ(yaml_error(with_line(kFlexArm, 31, "    joint: {name: forearm.cell1.x, type: fixed, position: [0.6, 0, 0.02]}")),
            "arm.yaml:12: bodies[1].flexible: its cell joint \"forearm.cell1.x\" would take the name of another joint");
}

// --- URDF ----------------------------------------------------------------------------------------

TEST(FlexibleUrdf, ASidecarFlexibleLinkGivesTheTreeOfItsYamlTwin) {
  const ff::TreeDescription urdf = ff::load_urdf(kData + "two_link.urdf", kData + "two_link_sidecar.yaml");
  const ff::TreeDescription yaml = ff::load_tree_yaml(kData + "two_link.yaml");
  const ff::Tree a = ff::make_tree(urdf.spec), b = ff::make_tree(yaml.spec);
  ASSERT_EQ(a.num_bodies(), 15);
  ff::test::expect_same_tree(a, b, 1e-12);
  EXPECT_EQ(urdf.body_index, yaml.body_index);
  EXPECT_EQ(urdf.dof_index, yaml.dof_index);
  ASSERT_EQ(urdf.joints.size(), yaml.joints.size());
  for (std::size_t i = 0; i < urdf.joints.size(); ++i) {
    EXPECT_EQ(urdf.joints[i].name, yaml.joints[i].name);
    EXPECT_EQ(urdf.joints[i].upper, yaml.joints[i].upper);
  }
  ASSERT_EQ(urdf.flexible_links.size(), 1u);
  ASSERT_EQ(yaml.flexible_links.size(), 1u);
  EXPECT_EQ(urdf.flexible_links[0].root_body, yaml.flexible_links[0].root_body);
  EXPECT_EQ(urdf.flexible_links[0].tip_body, yaml.flexible_links[0].tip_body);
  EXPECT_EQ(urdf.flexible_links[0].tip_point, yaml.flexible_links[0].tip_point);
  EXPECT_EQ(urdf.flexible_links[0].dofs, yaml.flexible_links[0].dofs);
  EXPECT_EQ(urdf.flexible_links[0].link.section.second_moment_z, 1.35e-8);
  EXPECT_EQ(urdf.spec.bodies.at(static_cast<std::size_t>(urdf.body_index.at("forearm"))).armature, 0.05);
  ASSERT_EQ(urdf.notes.size(), 1u);
  EXPECT_EQ(urdf.notes[0], kData + "two_link_sidecar.yaml:7: links.forearm.flexible: link \"forearm\": its <inertial> "
                                   "(0.3 kg) is replaced by the flexible beam");
  // The tool on the beam's tip: 0.6 m beyond the elbow, 0.02 m up, as in the URDF.
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(a.nv());
  EXPECT_LE((ff::calc_body_pose(a, q, urdf.body_index.at("tool")).position - ff::Vec3(1.0, 0, 0.5) -
             ff::rpy_rotation(0.1, 0, 0) * ff::Vec3(0, 0, 0.02)).norm(), 1e-15);
}

TEST(FlexibleUrdf, TheSidecarRejectsAnUnknownLinkTheRootABadKeyAndAMissingBlock) {
  auto sidecar_error = [](const std::string& yaml) {
    return std::string(config_error([&] {
      ff::TreeDescription d = ff::load_urdf(kData + "two_link.urdf");
      ff::apply_urdf_sidecar(d, ff::load_yaml_text(yaml, "arm.yaml"), "arm.yaml");
    }).what());
  };
  const std::string section = "section: {E: 7.0e10, G: 2.6e10, density: 2700, area: 1.8e-4, I_y: 5.4e-10, "
                              "I_z: 1.35e-8, J: 1.9e-9}";
  EXPECT_EQ(sidecar_error("links:\n  forarm:\n    flexible: {length: 0.6, " + section + "}\n"),
            "arm.yaml:2: links.forarm: no link named 'forarm' in the URDF (did you mean `forearm`?)");
  EXPECT_EQ(sidecar_error("links:\n  base_link:\n    flexible: {length: 0.6, " + section + "}\n"),
            "arm.yaml:2: links.base_link: link 'base_link' is the root link, the fixed base: it cannot be flexible");
  EXPECT_EQ(sidecar_error("links:\n  forearm:\n    flexible: {length: 0.6, lenght: 1, " + section + "}\n"),
            "arm.yaml:3: links.forearm.flexible.lenght: unknown key (did you mean `length`?)");
  EXPECT_EQ(sidecar_error("links:\n  forearm:\n    flexibel: {length: 0.6}\n"),
            "arm.yaml:3: links.forearm.flexibel: unknown key (did you mean `flexible`?)");
  EXPECT_EQ(sidecar_error("links:\n  forearm:\n    flexible:\n      length: -0.6\n      " + section + "\n"),
            "arm.yaml:4: links.forearm.flexible.length: must be > 0, got -0.6");
  EXPECT_EQ(sidecar_error("links:\n  forearm: {}\n"), "arm.yaml:2: links.forearm.flexible: missing required value");
  EXPECT_EQ(sidecar_error("units: SI\n"), "arm.yaml:1: units: unknown key");
  EXPECT_EQ(sidecar_error("{}\n"), "arm.yaml:1: joints: missing: a sidecar gives `joints`, `links` or both");
  // A sidecar of links alone is whole.
  ff::TreeDescription d = ff::load_urdf(kData + "two_link.urdf");
  ff::apply_urdf_sidecar(d, ff::load_yaml_text("links:\n  forearm:\n    flexible: {length: 0.6, segments: 3, " +
                                                   section + "}\n", "arm.yaml"), "arm.yaml");
  EXPECT_EQ(d.spec.bodies.size(), 2u + 1u + 2u * 3u);
  EXPECT_EQ(d.dof_index.at("forearm.cell2.x"), 7);
}

}  // namespace
