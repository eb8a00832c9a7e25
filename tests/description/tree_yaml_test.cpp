// Tests of tree YAML (description/tree_yaml.hpp): every key read into the TreeSpec, the defaults, and
// every bad document (the three-body arm below with one line changed) rejected with one ConfigError
// naming the file, the exact line and the full key path; and docs/formats.md held to the field tables.
#include "description/tree_yaml.hpp"
#include "tests/docs_tables.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <numbers>
#include <set>
#include <sstream>
#include <string>

#include "description/urdf.hpp"
#include "common/errors.hpp"
#include "common/yaml_reader.hpp"
#include "tests/description/test_support.hpp"
#include "tests/temp_dir.hpp"

namespace {

using ff::test::config_error;
using ff::test::with_line;

// Three bodies: two revolute joints and a fixed tool; the tests change one numbered line.
const std::string kArm = R"(gravity: [0, 0, -9.81]
bodies:
  - name: upper_arm
    parent: base
    joint:
      name: shoulder
      type: revolute
      axis: [0, 0, 1]
      position: [0, 0, 0.5]
      rpy: [0, 0, 0]
      armature: 0.1
    mass: 2.0
    com: [0.2, 0, 0]
    inertia: {ixx: 0.01, iyy: 0.05, izz: 0.05}
  - name: forearm
    parent: upper_arm
    joint: {name: elbow, axis: [0, 0, 2], position: [0.4, 0, 0], stiffness: 20, damping: 0.5, spring_reference: 0.1}
    mass: 1.0
    com: [0.15, 0, 0]
    inertia: {ixx: 0.004, iyy: 0.02, izz: 0.02, ixy: 0.001}
  - name: tool
    parent: forearm
    joint: {name: tool_mount, type: fixed, position: [0.3, 0, 0], rpy: [0, 0, 1.5707963267948966]}
    mass: 0.5
    com: [0, 0, 0.02]
    inertia: {ixx: 0.0002, iyy: 0.0002, izz: 0.0001}
)";

ff::TreeDescription parse(const std::string& text) {
  return ff::parse_tree_yaml(ff::load_yaml_text(text, "arm.yaml"), "arm.yaml");
}

std::string yaml_error(const std::string& text) {
  return config_error([&] { parse(text); }).what();
}

TEST(TreeYaml, ReadsEveryKeyIntoTheSpecTheJointInfoAndTheNameMaps) {
  const ff::TreeDescription d = parse(kArm);
  ASSERT_EQ(d.spec.bodies.size(), 3u);
  EXPECT_EQ(d.spec.gravity, ff::Vec3(0, 0, -9.81));
  EXPECT_EQ(d.base, "base");
  const ff::BodySpec& upper = d.spec.bodies[0];
  EXPECT_EQ(upper.name, "upper_arm");
  EXPECT_EQ(upper.parent, -1);
  EXPECT_EQ(upper.joint, ff::JointType::kRevolute);
  EXPECT_EQ(upper.position, ff::Vec3(0, 0, 0.5));
  EXPECT_EQ(upper.rotation, ff::Mat3::Identity());
  EXPECT_EQ(upper.armature, 0.1);
  EXPECT_EQ(upper.mass, 2.0);
  EXPECT_EQ(upper.com, ff::Vec3(0.2, 0, 0));
  EXPECT_EQ(upper.inertia, ff::Vec3(0.01, 0.05, 0.05).asDiagonal().toDenseMatrix());
  const ff::BodySpec& fore = d.spec.bodies[1];
  EXPECT_EQ(fore.parent, 0);
  EXPECT_EQ(fore.axis, ff::Vec3(0, 0, 2));  // as written; make_tree normalises it
  EXPECT_EQ(fore.stiffness, 20.0);
  EXPECT_EQ(fore.damping, 0.5);
  EXPECT_EQ(fore.spring_reference, 0.1);
  EXPECT_EQ(fore.inertia(0, 1), 0.001);
  EXPECT_EQ(fore.inertia(1, 0), 0.001);
  const ff::BodySpec& tool = d.spec.bodies[2];
  EXPECT_EQ(tool.joint, ff::JointType::kFixed);
  EXPECT_EQ(tool.parent, 1);
  EXPECT_LE((tool.rotation * ff::Vec3::UnitX() - ff::Vec3::UnitY()).norm(), 1e-15);  // a yaw of 90° turns x into y
  EXPECT_EQ(d.joints[2].name, "tool_mount");
  EXPECT_EQ(d.body_index, (std::map<std::string, int>{{"upper_arm", 0}, {"forearm", 1}, {"tool", 2}}));
  EXPECT_EQ(d.dof_index, (std::map<std::string, int>{{"shoulder", 0}, {"elbow", 1}}));
  EXPECT_TRUE(d.notes.empty());
}

TEST(TreeYaml, AnOmittedKeyTakesItsDocumentedDefault) {
  const ff::TreeDescription d = parse("bodies:\n  - {name: link, parent: base, joint: {}, mass: 0}\n");
  const ff::BodySpec& b = d.spec.bodies.at(0);
  EXPECT_EQ(d.spec.gravity, ff::Vec3(0, 0, -9.81));
  EXPECT_EQ(b.joint, ff::JointType::kRevolute);
  EXPECT_EQ(b.axis, ff::Vec3::UnitZ());
  EXPECT_EQ(b.position, ff::Vec3::Zero());
  EXPECT_EQ(b.rotation, ff::Mat3::Identity());
  EXPECT_EQ(b.com, ff::Vec3::Zero());
  EXPECT_EQ(b.inertia, ff::Mat3::Zero());
  EXPECT_EQ(b.armature + b.stiffness + b.damping + b.spring_reference, 0.0);
  EXPECT_EQ(d.joints.at(0).name, "link");  // a joint is named after its body
  EXPECT_EQ(d.joints.at(0).lower, -ff::JointInfo::kNone);
  EXPECT_EQ(d.joints.at(0).upper, ff::JointInfo::kNone);
  EXPECT_EQ(d.joints.at(0).effort, ff::JointInfo::kNone);
  EXPECT_EQ(d.dof_index.at("link"), 0);
}

TEST(TreeYaml, LimitsAndFrictionAreKeptBesideTheTree) {
  const ff::TreeDescription e =
      parse(with_line(kArm, 11, "      lower: -1.5\n      upper: 2\n      effort: 80\n      velocity: 3\n      friction: 0.4"));
  EXPECT_EQ(e.joints[0].lower, -1.5);
  EXPECT_EQ(e.joints[0].upper, 2.0);
  EXPECT_EQ(e.joints[0].effort, 80.0);
  EXPECT_EQ(e.joints[0].velocity, 3.0);
  EXPECT_EQ(e.joints[0].friction, 0.4);
}

// --- errors: one line each, at the key ------------------------------------------------------------

TEST(TreeYaml, AnUnknownKeyIsNamedEvenWhenItIsAMisspeltRequiredOne) {
  EXPECT_EQ(yaml_error(with_line(kArm, 13, "    cog: [0.2, 0, 0]")), "arm.yaml:13: bodies[0].cog: unknown key (did you mean `com`?)");
  EXPECT_EQ(yaml_error(with_line(kArm, 12, "    mas: 2.0")), "arm.yaml:12: bodies[0].mas: unknown key (did you mean `mass`?)");
  EXPECT_EQ(yaml_error(with_line(kArm, 11, "      armatur: 0.1")), "arm.yaml:11: bodies[0].joint.armatur: unknown key (did you mean `armature`?)");
  EXPECT_EQ(yaml_error(with_line(kArm, 20, "    inertia: {ixx: 0.004, iyy: 0.02, izz: 0.02, ixz: 0, iyx: 0}")),
            "arm.yaml:20: bodies[1].inertia.iyx: unknown key (did you mean `ixx`?)");
  EXPECT_EQ(yaml_error(with_line(kArm, 1, "gravity: [0, 0, -9.81]\nunits: SI")), "arm.yaml:2: units: unknown key");
}

TEST(TreeYaml, AMisspeltParentNamesTheClosestEarlierBody) {
  EXPECT_EQ(yaml_error(with_line(kArm, 16, "    parent: uper_arm")),
            "arm.yaml:16: bodies[1].parent: no body named 'uper_arm' (did you mean `upper_arm`?) (a parent is `base` or "
            "the name of an earlier body)");
  EXPECT_EQ(yaml_error(with_line(kArm, 4, "    parent: bsae")),
            "arm.yaml:4: bodies[0].parent: no body named 'bsae' (did you mean `base`?) (a parent is `base` or the name of "
            "an earlier body)");
}

TEST(TreeYaml, ARevoluteLimitOrSpringReferenceBeyondATurnLooksLikeDegrees) {
  EXPECT_EQ(yaml_error(with_line(kArm, 11, "      armature: 0.1\n      lower: -170")),
            "arm.yaml:12: bodies[0].joint.lower: -170 rad is more than a turn (2 pi): looks like degrees (-170 deg = -2.967 rad); "
            "angles are in radians (if it is meant, set `units_check: false` at the top of the file)");
  EXPECT_NE(yaml_error(with_line(kArm, 17, "    joint: {name: elbow, axis: [0, 0, 2], position: [0.4, 0, 0], spring_reference: 45}"))
                .find("arm.yaml:17: bodies[1].joint.spring_reference: 45 rad is more than a turn"),
            std::string::npos);
  // A prismatic joint's limits are metres; a file may allow the unusual case.
  EXPECT_NO_THROW(parse(with_line(kArm, 11, "      armature: 0.1\n      lower: -170").replace(0, 0, "units_check: false\n")));
  EXPECT_NO_THROW(parse(with_line(with_line(kArm, 7, "      type: prismatic"), 11, "      armature: 0.1\n      upper: 8")));
}

TEST(TreeYaml, AValueOfTheWrongTypeOrAMissingOneIsNamed) {
  EXPECT_EQ(yaml_error(with_line(kArm, 12, "    mass: heavy")), "arm.yaml:12: bodies[0].mass: expected a number, got 'heavy'");
  EXPECT_EQ(yaml_error(with_line(kArm, 8, "      axis: 1")), "arm.yaml:8: bodies[0].joint.axis: expected a list of 3 numbers");
  EXPECT_EQ(yaml_error(with_line(kArm, 9, "      position: [0, 0, .nan]")),
            "arm.yaml:9: bodies[0].joint.position[2]: must be a finite number, got '.nan'");
  EXPECT_EQ(yaml_error(with_line(kArm, 12, "")), "arm.yaml:3: bodies[0].mass: missing required value");
  EXPECT_EQ(yaml_error(with_line(kArm, 20, "    inertia: {iyy: 0.02, izz: 0.02}")),
            "arm.yaml:20: bodies[1].inertia.ixx: missing required value");
  EXPECT_EQ(yaml_error(with_line(kArm, 7, "      type: ball")),
            "arm.yaml:7: bodies[0].joint.type: unknown joint type 'ball' (revolute, prismatic or fixed)");
  EXPECT_EQ(yaml_error("gravity: [0, 0, -9.81]\n"), "arm.yaml:1: bodies: missing required value");
  EXPECT_EQ(yaml_error("bodies: []\n"), "arm.yaml:1: bodies: expected a list of at least one body");
  EXPECT_EQ(yaml_error(""), "arm.yaml: bodies: the file is empty");
}

TEST(TreeYaml, ANegativeMassIsNamedAtItsLine) {
  EXPECT_EQ(yaml_error(with_line(kArm, 18, "    mass: -1")), "arm.yaml:18: bodies[1].mass: must be >= 0, got -1");
  EXPECT_EQ(yaml_error(with_line(kArm, 11, "      armature: -0.1")),
            "arm.yaml:11: bodies[0].joint.armature: must be >= 0, got -0.1");
}

TEST(TreeYaml, MakeTreesChecksAreNamedAtTheLineOfWhatTheyConcern) {
  EXPECT_EQ(yaml_error(with_line(kArm, 8, "      axis: [0, 0, 0]")),
            "arm.yaml:8: bodies[0].joint.axis: is zero: an axis needs a direction");
  EXPECT_EQ(yaml_error(with_line(kArm, 20, "    inertia: {ixx: 0.004, iyy: 0.02, izz: 0.03}")),
            "arm.yaml:20: bodies[1].inertia: inertia tensor violates the triangle inequality I_a + I_b >= I_c "
            "(principal moments 0.004, 0.02, 0.03 kg·m²)");
  EXPECT_EQ(yaml_error(with_line(kArm, 20, "")),
            "arm.yaml:15: bodies[1].inertia: missing: a body with mass needs its inertia about the centre of mass");
  EXPECT_EQ(yaml_error(with_line(kArm, 8, "      axis: [0, 0, 1.0e-13]")), "arm.yaml:5: bodies[0].joint: joint axis is zero");
  EXPECT_EQ(yaml_error(with_line(kArm, 24, "    mass: 0")),
            "arm.yaml:26: bodies[2].inertia: a massless body must have a zero inertia tensor");
}

TEST(TreeYaml, ADuplicateBodyOrJointNameIsNamedWithTheFirstOnesLine) {
  EXPECT_EQ(yaml_error(with_line(kArm, 21, "  - name: upper_arm")),
            "arm.yaml:21: bodies[2].name: 'upper_arm' is already the name of bodies[0] (line 3)");
  EXPECT_EQ(yaml_error(with_line(kArm, 23, "    joint: {name: elbow, type: fixed}")),
            "arm.yaml:23: bodies[2].joint.name: 'elbow' is already the name of the joint of bodies[1] (line 17)");
  EXPECT_EQ(yaml_error(with_line(kArm, 21, "  - name: base")),
            "arm.yaml:21: bodies[2].name: 'base' names the fixed base; a body needs another name");
}

TEST(TreeYaml, AParentDefinedLaterOrNotAtAllIsNamed) {
  EXPECT_EQ(yaml_error(with_line(kArm, 16, "    parent: tool")),
            "arm.yaml:16: bodies[1].parent: 'tool' is defined later (bodies[2], line 21): list a parent before its children");
  EXPECT_EQ(yaml_error(with_line(kArm, 16, "    parent: forearm")),
            "arm.yaml:16: bodies[1].parent: 'forearm' is defined later (bodies[1], line 15): list a parent before its "
            "children");
}

TEST(TreeYaml, AFixedJointTakesNoDegreeOfFreedomKeys) {
  EXPECT_EQ(yaml_error(with_line(kArm, 23, "    joint: {name: tool_mount, type: fixed, stiffness: 5}")),
            "arm.yaml:23: bodies[2].joint.stiffness: a fixed joint has no degree of freedom: remove this key");
  EXPECT_EQ(yaml_error(with_line(kArm, 23, "    joint: {name: tool_mount, type: fixed, axis: [1, 0, 0]}")),
            "arm.yaml:23: bodies[2].joint.axis: a fixed joint has no degree of freedom: remove this key");
  EXPECT_EQ(yaml_error(with_line(kArm, 11, "      lower: 1\n      upper: 0.5")),
            "arm.yaml:12: bodies[0].joint.upper: is below lower (0.5 < 1)");
}

TEST(TreeYaml, AFileErrorNamesTheFile) {
  EXPECT_STREQ(config_error([] { ff::load_tree_yaml("/nonexistent/arm.yaml"); }).what(),
               "/nonexistent/arm.yaml: cannot open file");
  const ff::test::TempDir dir("tree_yaml");
  const std::string path = dir.write("arm.yaml", with_line(kArm, 13, "    com: [0.2, 0, 0]\n    mass: 3"));
  EXPECT_EQ(config_error([&] { ff::load_tree_yaml(path); }).what(),
            path + ":14: bodies[0].mass: written twice (lines 12 and 14)");
  EXPECT_EQ(ff::load_tree_yaml(dir.write("ok.yaml", kArm)).spec.bodies.size(), 3u);
}

// --- the docs ------------------------------------------------------------------------------------

TEST(TreeYaml, DocsListEveryKeyWithTheReadersUnitRequirementAndDefault) {
  std::vector<ff::KeyDoc> all = ff::tree_yaml_keys();
  for (const auto& k : ff::urdf_sidecar_keys()) all.push_back(k);
  ff::test::expect_documented("Kinematic trees (YAML) and URDF", all);
}

TEST(TreeYaml, ABodiesListOverTheLimitIsRefusedBeforeItsBodiesAreRead) {
  std::string text = "bodies:\n";
  for (int i = 0; i < 1001; ++i)
    text += "  - {name: b" + std::to_string(i) + ", parent: " + (i ? "b" + std::to_string(i - 1) : std::string("base")) +
            ", joint: {name: j" + std::to_string(i) + ", type: fixed}, mass: 1, inertia: {ixx: 1, iyy: 1, izz: 1}}\n";
  EXPECT_EQ(yaml_error(text),
            "arm.yaml:1: bodies: the tree has 1001 bodies (flexible links' segments and joint bodies counted), over the "
            "limit of 1000");
}

}  // namespace
