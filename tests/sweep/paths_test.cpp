// Tests of model parameter paths (sweep/paths.hpp): reading and writing "payload.mass",
// "trajectory.moves[1].target", creating keys, and rejecting paths that cannot exist.
#include "sweep/paths.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>
#include <vector>

#include "arm/arm_simulate.hpp"
#include "kernel/batch.hpp"
#include "kernel/drive.hpp"
#include "common/errors.hpp"
#include "common/yaml_reader.hpp"
#include "kernel/model_io.hpp"
#include "kernel/simulate.hpp"
#include "tests/arm/test_support.hpp"

namespace {

const char* kDoc = R"(
beam:
  length: 4.1656
segments: 6
payload:
  mass: 328.7
  inertia: 118.6
trajectory:
  moves:
    - {target: 0.5, hold: 7.0}
    - {target: 0.0, hold: 45.0}
)";

YAML::Node doc() { return YAML::Load(kDoc); }

// set_path must throw a ConfigError naming `source` and the path; returns it.
ff::ConfigError set_error(YAML::Node& d, const std::string& path, const std::string& value = "1") {
  try {
    ff::set_path(d, path, YAML::Load(value), "study.yaml");
  } catch (const ff::ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "path '" << path << "' was accepted";
  return ff::ConfigError("", 0, "", "");
}

// ---- set_path ----------------------------------------------------------------------------

TEST(SetPath, ReplacesANestedValue) {
  auto d = doc();
  ff::set_path(d, "payload.mass", YAML::Load("400"), "study.yaml");
  EXPECT_DOUBLE_EQ(d["payload"]["mass"].as<double>(), 400.0);
  EXPECT_DOUBLE_EQ(d["payload"]["inertia"].as<double>(), 118.6);  // the sibling is untouched
}

TEST(SetPath, ReplacesATopLevelValue) {
  auto d = doc();
  ff::set_path(d, "segments", YAML::Load("24"), "study.yaml");
  EXPECT_EQ(d["segments"].as<int>(), 24);
}

TEST(SetPath, ReplacesAValueInsideAListElement) {
  auto d = doc();
  ff::set_path(d, "trajectory.moves[1].target", YAML::Load("-0.25"), "study.yaml");
  EXPECT_DOUBLE_EQ(d["trajectory"]["moves"][1]["target"].as<double>(), -0.25);
  EXPECT_DOUBLE_EQ(d["trajectory"]["moves"][1]["hold"].as<double>(), 45.0);
  EXPECT_DOUBLE_EQ(d["trajectory"]["moves"][0]["target"].as<double>(), 0.5);
}

TEST(SetPath, ReplacesAWholeListElement) {
  auto d = doc();
  ff::set_path(d, "trajectory.moves[0]", YAML::Load("{target: 1.0, hold: 2}"), "study.yaml");
  EXPECT_DOUBLE_EQ(d["trajectory"]["moves"][0]["target"].as<double>(), 1.0);
  EXPECT_EQ(d["trajectory"]["moves"].size(), 2u);
}

TEST(SetPath, ReplacesAWholeList) {
  auto d = doc();
  ff::set_path(d, "trajectory.moves", YAML::Load("[{target: 0.2, hold: 2}]"), "study.yaml");
  ASSERT_TRUE(d["trajectory"]["moves"].IsSequence());
  EXPECT_EQ(d["trajectory"]["moves"].size(), 1u);
  EXPECT_DOUBLE_EQ(d["trajectory"]["moves"][0]["target"].as<double>(), 0.2);
}

TEST(SetPath, CreatesAMissingKey) {
  auto d = doc();
  ff::set_path(d, "payload.colour", YAML::Load("red"), "study.yaml");
  EXPECT_EQ(d["payload"]["colour"].as<std::string>(), "red");
}

// `--set notch.enabled=true` works on a model file without a notch: block.
TEST(SetPath, CreatesMissingMapsOnTheWay) {
  auto d = doc();
  ff::set_path(d, "notch.omega_z", YAML::Load("[1.7, 14.4]"), "study.yaml");
  ASSERT_TRUE(d["notch"].IsMap());
  EXPECT_DOUBLE_EQ(d["notch"]["omega_z"][1].as<double>(), 14.4);
  ff::set_path(d, "a.b.c", YAML::Load("3"), "study.yaml");
  EXPECT_EQ(d["a"]["b"]["c"].as<int>(), 3);
}

TEST(SetPath, IndexOutOfRangeIsRejected) {
  auto d = doc();
  const auto e = set_error(d, "trajectory.moves[2].target");
  EXPECT_EQ(e.file(), "study.yaml");
  EXPECT_EQ(e.key(), "trajectory.moves[2].target");
  EXPECT_NE(e.message().find("index [2] is not in the list"), std::string::npos) << e.what();
  EXPECT_EQ(d["trajectory"]["moves"].size(), 2u);  // nothing appended
}

TEST(SetPath, AnIndexBeyondIntsRangeIsOutOfTheListNotACrash) {
  for (const std::string index : {"2147483648", "99999999999", "99999999999999999999999"}) {
    auto d = doc();
    const auto e = set_error(d, "trajectory.moves[" + index + "].target");
    EXPECT_EQ(e.file(), "study.yaml");
    EXPECT_EQ(e.key(), "trajectory.moves[" + index + "].target");
    EXPECT_EQ(e.message(), "index [" + index + "] is not in the list") << e.what();
  }
  // As a --set: the same one error, naming --set and the path (from the command line: exit 2).
  try {
    (void)ff::parse_assignment("trajectory.moves[99999999999].target=1");
    ADD_FAILURE() << "accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_STREQ(e.what(), "--set: trajectory.moves[99999999999].target: index [99999999999] is not in the list");
  }
}

TEST(SetPath, IndexIntoAMapIsRejected) {
  auto d = doc();
  const auto e = set_error(d, "payload[0]");
  EXPECT_EQ(e.key(), "payload[0]");
  EXPECT_NE(e.message().find("not in the list"), std::string::npos) << e.what();
}

TEST(SetPath, KeyInsideANumberIsRejected) {
  auto d = doc();
  const auto e = set_error(d, "payload.mass.value");
  EXPECT_EQ(e.file(), "study.yaml");
  EXPECT_EQ(e.key(), "payload.mass.value");
  EXPECT_NE(e.message().find("'value' is inside a value that is not a map"), std::string::npos) << e.what();
  EXPECT_DOUBLE_EQ(d["payload"]["mass"].as<double>(), 328.7);
}

TEST(SetPath, KeyInsideAListIsRejected) {
  auto d = doc();
  const auto e = set_error(d, "trajectory.moves.target");
  EXPECT_EQ(e.key(), "trajectory.moves.target");
  EXPECT_NE(e.message().find("not a map"), std::string::npos) << e.what();
}

TEST(SetPath, BadSyntaxIsRejected) {
  for (const std::string path : {"", "payload..mass", ".payload", "moves[", "moves[]", "moves[-1]", "moves[1x]"}) {
    auto d = doc();
    const auto e = set_error(d, path);
    EXPECT_EQ(e.file(), "study.yaml") << path;
    EXPECT_EQ(e.key(), path);
    EXPECT_NE(e.message().find("bad parameter path"), std::string::npos) << path << ": " << e.what();
  }
}

TEST(SetPath, AListElementIsFoundByItsName) {
  YAML::Node d = YAML::Load("bodies:\n  - {name: upper, mass: 1}\n  - {name: fore, mass: 2}\n");
  ff::set_path(d, "bodies[fore].mass", YAML::Node(5.0), "--set");
  EXPECT_EQ(d["bodies"][1]["mass"].as<double>(), 5.0);
  EXPECT_EQ(d["bodies"][0]["mass"].as<double>(), 1.0);
  EXPECT_EQ(ff::set_path(d, "bodies[upper].mass", YAML::Node(1.0), "--set"), "bodies[0].mass");
  EXPECT_EQ(ff::get_path(d, "bodies[upper].mass").as<double>(), 1.0);
  EXPECT_TRUE(ff::get_path(d, "bodies[elbow].mass").IsNull());
  try {
    ff::set_path(d, "bodies[elbow].mass", YAML::Node(5.0), "--set");
    ADD_FAILURE() << "no error";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.key(), "bodies[elbow].mass");
    EXPECT_NE(e.message().find("no element of the list is named 'elbow'"), std::string::npos) << e.what();
  }
  try {
    ff::set_path(d, "bodies[foer].mass", YAML::Node(5.0), "--set");
    ADD_FAILURE() << "no error";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.message(), "no element of the list is named 'foer' (did you mean `fore`?)");
  }
}

TEST(LoadModel, AMisspeltParameterPathNamesTheClosestKey) {
  const std::string model = std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml";
  try {
    ff::load_model_with(model, {"notch.ordre=2"});
    ADD_FAILURE() << "no error";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "--set: notch.ordre: unknown key (did you mean `order`?)");
  }
}

TEST(LoadModel, AStudyFileGivenAsAModelIsNamedWithTheVerbThatTakesIt) {
  // `flexfarm simulate configs/studies/fbtb_paper.yaml`: not "beam: missing required value".
  const std::string study = std::string(FLEXFARM_SOURCE_DIR) + "/configs/studies/fbtb_paper.yaml";
  for (const auto& load : {+[](const std::string& p) { ff::load_model_with(p, {}); },
                           +[](const std::string& p) { ff::load_arm_with(p, {}); },
                           +[](const std::string& p) { ff::load_model_source(p, {}); }}) {
    try {
      load(study);
      ADD_FAILURE() << "no error";
    } catch (const ff::ConfigError& e) {
      EXPECT_EQ(std::string(e.what()), study + ":8: model: this is a study file (it names a `model:`), not a model: run it with "
                                       "`flexfarm run " + study + " --out DIR`; this verb takes a model file (the rig's `beam:` "
                                       "or an arm's `bodies:`/`urdf:`)");
    }
  }
  EXPECT_FALSE(ff::is_arm_model_file(study));
  // A URDF sidecar: not "beam: missing required value" either.
  const std::string sidecar = std::string(FLEXFARM_SOURCE_DIR) + "/configs/urdf/arm6_sidecar.yaml";
  try {
    ff::load_model_with(sidecar, {});
    ADD_FAILURE() << "no error";
  } catch (const ff::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("this is a URDF sidecar, not a model: give it with its URDF (`flexfarm modes "
                                         "ROBOT.urdf --sidecar " + sidecar + "`) or as an arm model's `sidecar:`"),
              std::string::npos)
        << e.what();
  }
}

// ---- get_path ----------------------------------------------------------------------------

TEST(GetPath, ReadsNestedKeysAndListElements) {
  const auto d = doc();
  EXPECT_DOUBLE_EQ(ff::get_path(d, "payload.mass").as<double>(), 328.7);
  EXPECT_EQ(ff::get_path(d, "segments").as<int>(), 6);
  EXPECT_DOUBLE_EQ(ff::get_path(d, "trajectory.moves[1].hold").as<double>(), 45.0);
  EXPECT_EQ(ff::get_path(d, "trajectory.moves").size(), 2u);
}

TEST(GetPath, AbsentPathsGiveANullNode) {
  const auto d = doc();
  EXPECT_TRUE(ff::get_path(d, "payload.colour").IsNull());
  EXPECT_TRUE(ff::get_path(d, "trajectory.moves[2].target").IsNull());
  EXPECT_TRUE(ff::get_path(d, "payload.mass.value").IsNull());
  EXPECT_TRUE(ff::get_path(d, "payload[0]").IsNull());
  EXPECT_FALSE(ff::get_path(d, "payload.mass").IsNull());
}

TEST(GetPath, BadSyntaxThrows) {
  EXPECT_THROW(ff::get_path(doc(), "payload..mass"), ff::ConfigError);
}

TEST(GetPath, RoundTripsWithSetPath) {
  auto d = doc();
  ff::set_path(d, "trajectory.moves[0].hold", YAML::Load("3.5"), "study.yaml");
  EXPECT_DOUBLE_EQ(ff::get_path(d, "trajectory.moves[0].hold").as<double>(), 3.5);
}

TEST(GetPath, DoesNotCreateKeys) {
  const auto d = doc();
  (void)ff::get_path(d, "payload.colour");
  (void)ff::get_path(d, "notch.order");
  EXPECT_FALSE(d["payload"]["colour"]);
  EXPECT_FALSE(d["notch"]);
}

// ---- parse_assignment --------------------------------------------------------------------

// A command-line `--set PATH=VALUE`, applied to a document.
void assign(YAML::Node& d, const std::string& text) {
  const ff::Assignment a = ff::parse_assignment(text);
  ff::set_path(d, a.path, a.value, a.source);
}

TEST(ApplyAssignment, SetsAScalar) {
  auto d = doc();
  assign(d, "payload.mass=400");
  EXPECT_DOUBLE_EQ(d["payload"]["mass"].as<double>(), 400.0);
}

TEST(ApplyAssignment, ValueIsYaml) {
  auto d = doc();
  assign(d, "trajectory.moves=[{target: 0.2, hold: 2}]");
  ASSERT_EQ(d["trajectory"]["moves"].size(), 1u);
  EXPECT_DOUBLE_EQ(d["trajectory"]["moves"][0]["hold"].as<double>(), 2.0);
  assign(d, "payload.mass=.nan");  // any YAML value; checking it is parse_model's job
  EXPECT_TRUE(std::isnan(d["payload"]["mass"].as<double>()));
  assign(d, "beam.length=  2.5");
  EXPECT_DOUBLE_EQ(d["beam"]["length"].as<double>(), 2.5);
}

TEST(ApplyAssignment, KeyWrittenTwiceInTheValueIsRejected) {
  try {
    ff::parse_assignment("trajectory.moves=[{target: 0.2, target: 0.3}]");
    ADD_FAILURE() << "a key written twice was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.file(), "--set");
    EXPECT_EQ(e.key(), "trajectory.moves[0].target") << e.what();
    EXPECT_NE(e.message().find("written twice"), std::string::npos) << e.what();
  }
}

// An alias inside the map it names (`&x {a: *x}`) made a cyclic value; checking its keys overflowed
// the stack (found while writing fuzz_set).
TEST(ApplyAssignment, ValueHoldingItselfIsRejected) {
  try {
    ff::parse_assignment("payload=&x {a: *x}");
    ADD_FAILURE() << "a cyclic value was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.file(), "--set");
    EXPECT_EQ(e.key(), "payload.a") << e.what();
    EXPECT_NE(e.message().find("cycle"), std::string::npos) << e.what();
  }
}

TEST(ApplyAssignment, ValueMayContainEqualsSigns) {
  auto d = doc();
  assign(d, "name=a=b");
  EXPECT_EQ(d["name"].as<std::string>(), "a=b");
}

TEST(ApplyAssignment, MissingEqualsIsRejected) {
  auto d = doc();
  for (const std::string a : {"payload.mass", "=400"}) {
    try {
      assign(d, a);
      ADD_FAILURE() << a << " was accepted";
    } catch (const ff::ConfigError& e) {
      EXPECT_EQ(e.file(), "--set");
      EXPECT_EQ(e.key(), a);
      EXPECT_NE(e.message().find("expected PATH=VALUE"), std::string::npos) << e.what();
    }
  }
}

TEST(ApplyAssignment, InvalidYamlValueNamesThePath) {
  auto d = doc();
  try {
    assign(d, "notch.alpha=[1.6");
    FAIL() << "an unclosed list was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.key(), "notch.alpha");
    EXPECT_NE(e.message().find("not valid YAML"), std::string::npos) << e.what();
  }
}

TEST(ApplyAssignment, AValueNestedPastYamlCppsLimitNamesThePath) {
  try {
    (void)ff::parse_assignment("notch.alpha=" + std::string(50000, '['));
    FAIL() << "accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_STREQ(e.what(), "--set: notch.alpha: value is not valid YAML: lists and maps nested more than 499 deep "
                           "(yaml-cpp's limit)");
  }
}

TEST(ApplyAssignment, BadPathIsRejected) {
  auto d = doc();
  EXPECT_THROW(assign(d, "trajectory.moves[9].target=1"), ff::ConfigError);
  EXPECT_THROW(assign(d, "payload..mass=1"), ff::ConfigError);
}

TEST(ApplyAssignment, OverriddenValuesPassTheModelChecks) {
  // A negative mass set on the reference model is caught by parse_model, naming the key.
  auto d = YAML::LoadFile(std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml");
  assign(d, "payload.mass=-3");
  try {
    ff::parse_model(d, "fbtb.yaml");
    FAIL() << "payload.mass=-3 was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.key(), "payload.mass");
    EXPECT_NE(e.message().find(">= 0"), std::string::npos) << e.what();
  }
}

TEST(ApplyAssignment, OverridesReachTheModel) {
  auto d = YAML::LoadFile(std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml");
  assign(d, "segments=11");
  assign(d, "trajectory.moves[0].target=1.0");
  const ff::Model m = ff::parse_model(d, "fbtb.yaml");
  EXPECT_EQ(m.nseg, 11);
  EXPECT_DOUBLE_EQ(m.spec.trajectory.moves[0].target, 1.0);
  EXPECT_NEAR(m.cell, 4.1656 / 10, 1e-12);
}

TEST(ApplyAssignment, SensorAndNotchPlacementParametersAreSweepable) {
  // The reference file has no sensors block: paths create it, every recorded-sensor parameter included.
  auto d = YAML::LoadFile(std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml");
  for (const char* a : {"sensors.strain_gauge.enabled=true", "sensors.strain_gauge.joint=3",
                        "sensors.strain_gauge.noise=5", "sensors.tip_accelerometer.rate=250",
                        "sensors.tip_position.delay=12", "sensors.tip_position.resolution=1e-4",
                        "notch.placement=feedback"})
    assign(d, a);
  const ff::Model m = ff::parse_model(d, "fbtb.yaml");
  EXPECT_TRUE(m.spec.sensors.strain_gauge.enabled);
  EXPECT_EQ(m.spec.sensors.strain_gauge.joint, 3);
  EXPECT_DOUBLE_EQ(m.spec.sensors.strain_gauge.noise, 5.0);
  EXPECT_DOUBLE_EQ(m.spec.sensors.tip_accelerometer.rate, 250.0);
  EXPECT_EQ(m.spec.sensors.tip_position.delay, 12);
  EXPECT_DOUBLE_EQ(m.spec.sensors.tip_position.resolution, 1e-4);
  EXPECT_EQ(m.spec.notch.placement, "feedback");
}

TEST(ApplyAssignment, HydraulicPhysicalParametersAreSweepable) {
  // Every physical key by path; a part of a group, or a second form, is reported at --set.
  const auto file = YAML::LoadFile(std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml");
  std::vector<ff::Assignment> set;
  for (const char* a : {"hydraulics.enabled=true", "hydraulics.discharge_coefficient=0.5", "hydraulics.port_width=0.04",
                        "hydraulics.spool_stroke=1e-3", "hydraulics.oil_density=2048", "hydraulics.piston_area=0.01",
                        "hydraulics.pinion_radius=0.1"})
    set.push_back(ff::parse_assignment(a));
  const ff::Model m = ff::make_model_with(YAML::Clone(file), "fbtb.yaml", set);
  // k_v = 0.5 x 0.04 x 1e-3 x sqrt(2 / 2048) = 6.25e-7 and D = 1e-3: the values reached the model.
  EXPECT_DOUBLE_EQ(ff::calc_valve_coefficient(m.spec.hydraulics), 6.25e-7);
  EXPECT_DOUBLE_EQ(ff::calc_displacement(m.spec.hydraulics), 1e-3);
  auto error_of = [&](const std::vector<std::string>& texts) {
    std::vector<ff::Assignment> s;
    for (const auto& t : texts) s.push_back(ff::parse_assignment(t));
    try {
      ff::make_model_with(YAML::Clone(file), "fbtb.yaml", s);
    } catch (const ff::ConfigError& e) {
      return e;
    }
    ADD_FAILURE() << "accepted";
    return ff::ConfigError("", 0, "", "");
  };
  auto e = error_of({"hydraulics.pinion_radius=0.1"});
  EXPECT_EQ(e.file(), "--set");
  EXPECT_EQ(e.key(), "hydraulics.pinion_radius");
  EXPECT_NE(e.message().find("needs hydraulics.piston_area"), std::string::npos) << e.what();
  e = error_of({"hydraulics.displacement=2.5e-3", "hydraulics.piston_area=0.01", "hydraulics.pinion_radius=0.25"});
  EXPECT_EQ(e.file(), "--set");
  EXPECT_EQ(e.key(), "hydraulics.piston_area");
  EXPECT_NE(e.message().find("given with hydraulics.displacement"), std::string::npos) << e.what();
}

}  // namespace

// A bad value set by a body's name is named where it was set, though the arm's parser names the body
// by its index (bodies[0]): the study's file, line and key, not the model's.
TEST(ApplyAssignment, ABadValueSetByABodysNameIsNamedWhereItWasSet) {
  const std::string model = std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb_titan.yaml";
  ff::Assignment a{"bodies[beam].flexible.planar", YAML::Node(2), "study.yaml", 7,
                   "variables[1] (bodies[beam].flexible.planar)"};
  try {
    ff::make_arm_with(YAML::LoadFile(model), model, {a});
    FAIL() << "planar: 2 was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.file(), "study.yaml");
    EXPECT_EQ(e.line(), 7);
    EXPECT_EQ(e.key(), "variables[1] (bodies[beam].flexible.planar)");
    EXPECT_NE(e.message().find("expected true or false"), std::string::npos) << e.what();
  }
  a.path = "bodies[beam].flexible.section";
  a.key = "set.bodies[beam].flexible.section";
  a.value = YAML::Load("{E: -1, G: 1, density: 1, area: 1, I_y: 1, I_z: 1, J: 1}");
  try {
    ff::make_arm_with(YAML::LoadFile(model), model, {a});
    FAIL() << "E: -1 was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.file(), "study.yaml");
    EXPECT_EQ(e.key(), "set.bodies[beam].flexible.section.E") << e.what();
  }
}

// ---- The controller's model: plant-only assignments (a study's variable or run, diagnose's candidate)
// change the plant, not the feed-forward, gravity compensation or notch (docs/formats.md, "The
// controller's model").
namespace {

// The reference rig (configs/fbtb.yaml) with one 0.5 rad move held 1 s and the feed-forward on.
YAML::Node short_rig(const std::string& controller_model = "nominal") {
  YAML::Node d = ff::load_yaml_file(std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml");
  ff::set_path(d, "trajectory.moves", YAML::Load("[{target: 0.5, hold: 1.0}]"), "test");
  ff::set_path(d, "controller.feedforward", YAML::Node(1.0), "test");
  ff::set_path(d, "controller.model", YAML::Node(controller_model), "test");
  return d;
}

// PATH=VALUE as a study's variable sets it (the plant's alone) or as --set does (the model's).
ff::Assignment plant_set(const std::string& text) { return ff::parse_assignment(text, true); }
ff::Assignment model_set(const std::string& text) { return ff::parse_assignment(text); }

ff::Model rig(const std::vector<ff::Assignment>& set, const std::string& controller_model = "nominal") {
  return ff::make_model_with(short_rig(controller_model), "fbtb.yaml", set);
}

ff::Trace run(const ff::Model& m) { return ff::simulate(ff::make_batch(std::span<const ff::Model>(&m, 1))).traces[0]; }

double max_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) d = std::max(d, std::abs(a[k] - b[k]));
  return d;
}

}  // namespace

TEST(ControllerModel, AVariantsPayloadLeavesTheFeedForwardAtTheNominalInertia) {
  // With the loop open (kp = kd = 0) the torque is the feed-forward alone, J r'' (the plant cannot move it):
  // a payload the plant only has gives the nominal model's torque bit for bit, a payload set in the file
  // (--set) J_400 / J_nominal times it.
  const ff::Assignment open[] = {model_set("controller.kp=0"), model_set("controller.kd=0")};
  const ff::Model nominal = rig({open[0], open[1]});
  const ff::Model variant = rig({open[0], open[1], plant_set("payload.mass=400")});
  const ff::Model known = rig({open[0], open[1], model_set("payload.mass=400")});
  EXPECT_EQ(variant.control_inertia, nominal.rigid_inertia);
  EXPECT_EQ(variant.rigid_inertia, known.rigid_inertia);
  EXPECT_GT(known.rigid_inertia, nominal.rigid_inertia + 1000.0);  // kg m^2: 71.3 kg more at 4.17 m
  const ff::Trace a = run(nominal), b = run(variant), c = run(known);
  EXPECT_EQ(a.torque, b.torque);
  double peak = 0.0;
  for (std::size_t k = 0; k < a.torque.size(); ++k) {
    peak = std::max(peak, std::abs(a.torque[k]));
    EXPECT_NEAR(c.torque[k], a.torque[k] * known.rigid_inertia / nominal.rigid_inertia, 1e-9 * std::abs(c.torque[k]) + 1e-9);
  }
  EXPECT_GT(peak, 1000.0);  // N m: the move's feed-forward is no detail
}

TEST(ControllerModel, AControllerThatDoesNotKnowThePayloadTracksWorseThanOneThatDoes) {
  // Closed loop: the hub's response to a payload the controller does not know differs from the one it
  // does know, and `controller.model: plant` (the controller knows the truth) makes the two one run.
  const ff::Trace unknown = run(rig({plant_set("payload.mass=400")}));
  const ff::Trace known = run(rig({model_set("payload.mass=400")}));
  const double apart = max_difference(unknown.hub_angle, known.hub_angle);
  RecordProperty("hub_angle_difference_rad", std::to_string(apart));
  EXPECT_GT(apart, 1e-4);
  const ff::Trace told = run(rig({plant_set("payload.mass=400")}, "plant"));
  EXPECT_EQ(told.hub_angle, known.hub_angle);
  EXPECT_EQ(told.torque, known.torque);
}

TEST(ControllerModel, TheNotchStaysAtTheNominalResonancesUnderAStiffnessVariant) {
  // The notch's zeros (omega_z 0: at the closed-loop resonances) are the nominal model's when the plant's
  // joints are 25 % softer, and the plant's own with `controller.model: plant`.
  const ff::Assignment notch = model_set("notch.enabled=true");
  const ff::Model nominal = rig({notch});
  const ff::Model softer = rig({notch, plant_set("joints.stiffness=29.6e3")});
  ASSERT_GE(nominal.resonances.size(), 2u);
  ASSERT_GE(softer.resonances.size(), 2u);
  EXPECT_EQ(softer.omega_z[0], nominal.resonances[0]);
  EXPECT_EQ(softer.omega_z[1], nominal.resonances[1]);
  EXPECT_LT(softer.resonances[0], 0.95 * nominal.resonances[0]);  // the plant's own mode is lower (sqrt(0.75) k)
  const ff::Model told = rig({notch, plant_set("joints.stiffness=29.6e3")}, "plant");
  EXPECT_EQ(told.omega_z[0], softer.resonances[0]);
  EXPECT_EQ(told.omega_z[1], softer.resonances[1]);
}

TEST(ControllerModel, AssignmentsToTheControllersOwnPathsChangeTheController) {
  // A plant-only kp is still the controller's kp: the notch sits at the resonances of the loop with it.
  const ff::Model with_kp = rig({model_set("notch.enabled=true"), plant_set("controller.kp=2e5")});
  const ff::Model known_kp = rig({model_set("notch.enabled=true"), model_set("controller.kp=2e5")});
  EXPECT_EQ(with_kp.omega_z[0], known_kp.omega_z[0]);
  EXPECT_EQ(with_kp.spec.controller.kp, 2e5);
  EXPECT_TRUE(ff::is_controller_path("joints.elbow.controller.kp"));
  EXPECT_TRUE(ff::is_controller_path("trajectory.moves[0].target"));
  EXPECT_FALSE(ff::is_controller_path("joints.stiffness"));
  EXPECT_FALSE(ff::is_controller_path("bodies[tool].mass"));
  EXPECT_FALSE(ff::is_controller_path("joints.elbow.friction.coulomb"));
}

TEST(ControllerModel, AnUnknownControllerModelIsNamedAtItsKey) {
  try {
    rig({}, "truth");
    ADD_FAILURE() << "controller.model: truth was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.key(), "controller.model");
    EXPECT_NE(std::string(e.what()).find("nominal, plant"), std::string::npos) << e.what();
  }
  try {
    ff::make_arm_with(ff::load_yaml_text(ff::test::pendulum_arm("controller: {model: truth}\n"), "arm.yaml"), "arm.yaml", {});
    ADD_FAILURE() << "an arm's controller.model: truth was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.key(), "controller.model");
    EXPECT_EQ(e.line(), 9);
  }
}

TEST(ControllerModel, AnArmsGravityCompensationUsesTheNominalMassAndDroopsByTheRest) {
  // The 2 kg pendulum held at q = 0 by PD and gravity compensation at the reference, its bob 3 kg in the
  // plant only: the controller compensates 2 kg, so the arm droops until kp q = (3 cos q - 2) g l
  // (about (m - m_nominal) g l / kp = 0.0123 rad). Told the truth (controller.model: plant), it holds 0.
  const double kp = 400.0, g = 9.81, l = 0.5;
  auto arm = [&](const std::string& controller_model, const ff::Assignment& mass) {
    const std::string text = ff::test::pendulum_arm("tool: {body: arm, point: [0.5, 0, 0]}\ncontroller: {rate: 1000, model: " +
                                                    controller_model + "}\njoints:\n  arm:\n    controller: {kp: 400, kd: 40, "
                                                    "gravity_compensation: 1}\nsimulation: {duration: 6.0}\n");
    return ff::make_arm_with(ff::load_yaml_text(text, "arm.yaml"), "arm.yaml", {mass});
  };
  const ff::ArmModel unknown = arm("nominal", plant_set("bodies[arm].mass=3.0"));
  ASSERT_TRUE(unknown.control);
  EXPECT_EQ(unknown.control->tree.body(0).mass, 2.0);
  EXPECT_EQ(unknown.tree.body(0).mass, 3.0);
  const ff::ArmRun a = ff::simulate_arms(std::span<const ff::ArmModel>(&unknown, 1));
  const double q = a.traces[0].column("arm.q").back();
  EXPECT_GT(q, 0.01);
  EXPECT_NEAR(-kp * q + (3.0 * std::cos(q) - 2.0) * g * l, 0.0, 1e-6 * g * l);
  const ff::ArmModel told = arm("plant", plant_set("bodies[arm].mass=3.0"));
  EXPECT_FALSE(told.control);
  const ff::ArmRun b = ff::simulate_arms(std::span<const ff::ArmModel>(&told, 1));
  EXPECT_NEAR(b.traces[0].column("arm.q").back(), 0.0, 1e-9);
}
