// Tests of model YAML parsing (kernel/model_io.hpp, common/yaml_reader.hpp, validate() in kernel/model.cpp):
// every bad document is configs/fbtb.yaml with one line changed, and must be rejected with one
// ConfigError naming the file, the exact line and the full dotted key, saying what is wrong.
#include "kernel/model_io.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "common/errors.hpp"
#include "tests/docs_tables.hpp"
#include "tests/temp_dir.hpp"

namespace {

namespace fs = std::filesystem;

const std::string kReference = std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml";

// The reference file, one string per line.
std::vector<std::string> reference_lines() {
  std::ifstream in(kReference);
  std::vector<std::string> lines;
  for (std::string s; std::getline(in, s);) lines.push_back(s);
  return lines;
}

std::string join(const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  return text;
}

// The reference text with line `n` (1-based) replaced by `text`; the line count is unchanged.
std::string with_line(int n, const std::string& text) {
  auto lines = reference_lines();
  EXPECT_GE(n, 1);
  EXPECT_LE(n, static_cast<int>(lines.size()));
  lines.at(n - 1) = text;
  return join(lines);
}

// The reference text with lines first..last blanked (line numbers of the rest unchanged).
std::string without_lines(int first, int last) {
  auto lines = reference_lines();
  for (int n = first; n <= last; ++n) lines.at(n - 1) = "";
  return join(lines);
}

// Parses `text` as "bad.yaml"; it must fail. Returns the error for further checks.
ff::ConfigError parse_error(const std::string& text) {
  try {
    ff::parse_model(YAML::Load(text), "bad.yaml");
  } catch (const ff::ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "the document was accepted:\n" << text;
  return ff::ConfigError("", 0, "", "");
}

// One rejection: file, line, key and the gist of the message, and what() carrying all of them.
void expect_rejected(const std::string& text, int line, const std::string& key, const std::string& gist) {
  const auto e = parse_error(text);
  EXPECT_EQ(e.file(), "bad.yaml");
  EXPECT_EQ(e.line(), line) << e.what();
  EXPECT_EQ(e.key(), key) << e.what();
  EXPECT_NE(e.message().find(gist), std::string::npos) << "message '" << e.message() << "' lacks '" << gist << "'";
  const std::string prefix = "bad.yaml:" + std::to_string(line) + ": " + key + ": ";
  EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what();
  EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line: " << e.what();
}

// A fresh directory, removed with its contents.
struct TempDir : ff::test::TempDir {
  TempDir() : ff::test::TempDir("ff_model_io") {}
};

// ---- the reference file ----------------------------------------------------------------

TEST(ModelIo, ReferenceLinesAreWhereTheseTestsExpect) {
  // The line numbers below are those of configs/fbtb.yaml; fail loudly if the file moves them.
  const auto l = reference_lines();
  ASSERT_GE(l.size(), 50u);
  EXPECT_EQ(l[4 - 1].rfind("beam:", 0), 0u);
  EXPECT_EQ(l[5 - 1].rfind("  length: 4.1656", 0), 0u);
  EXPECT_EQ(l[6 - 1].rfind("  height: 0.3048", 0), 0u);
  EXPECT_EQ(l[8 - 1].rfind("  density: 7750", 0), 0u);
  EXPECT_EQ(l[11 - 1].rfind("segments: 6", 0), 0u);
  EXPECT_EQ(l[15 - 1].rfind("  damping: 90.4", 0), 0u);
  EXPECT_EQ(l[19 - 1].rfind("  inertia: 50.0", 0), 0u);
  EXPECT_EQ(l[21 - 1].rfind("payload:", 0), 0u);
  EXPECT_EQ(l[22 - 1].rfind("  mass: 328.7", 0), 0u);
  EXPECT_EQ(l[23 - 1].rfind("  inertia: 118.6", 0), 0u);
  EXPECT_EQ(l[24 - 1], "");
  EXPECT_EQ(l[29 - 1].rfind("  kd: 3.0e4", 0), 0u);
  EXPECT_EQ(l[34 - 1].rfind("  enabled: false", 0), 0u);
  EXPECT_EQ(l[35 - 1].rfind("  order: 1", 0), 0u);
  EXPECT_EQ(l[36 - 1].rfind("  alpha: [1.6, 1.6]", 0), 0u);
  EXPECT_EQ(l[43 - 1].rfind("    - {target: 0.5, hold: 7.0}", 0), 0u);
  EXPECT_EQ(l[44 - 1].rfind("    - {target: 0.0, hold: 45.0}", 0), 0u);
  EXPECT_EQ(l[47 - 1].rfind("  integrator: rk4", 0), 0u);
}

TEST(ModelIo, ReferenceFileParsesToTheSeedRig) {
  const ff::Model m = ff::load_model(kReference);
  EXPECT_EQ(m.nseg, 6);
  EXPECT_DOUBLE_EQ(m.spec.beam.length, 4.1656);
  EXPECT_DOUBLE_EQ(m.spec.beam.height, 0.3048);
  EXPECT_DOUBLE_EQ(m.spec.beam.thickness, 0.01905);
  EXPECT_DOUBLE_EQ(m.spec.beam.density, 7750.0);
  EXPECT_DOUBLE_EQ(m.spec.beam.youngs_modulus, 207.0e9);
  EXPECT_NEAR(m.cell, 0.83312, 1e-12);
  // N = 6 is the reference cell, so the joints keep the file's k and c.
  EXPECT_NEAR(m.joint_k[1], 39500.0, 1e-6);
  EXPECT_NEAR(m.joint_c[1], 90.4, 1e-9);
  EXPECT_EQ(m.joint_k[0], 0.0);
  EXPECT_DOUBLE_EQ(m.spec.hub_inertia, 50.0);
  EXPECT_DOUBLE_EQ(m.spec.payload_mass, 328.7);
  EXPECT_DOUBLE_EQ(m.spec.payload_inertia, 118.6);
  EXPECT_DOUBLE_EQ(m.control_period, 1e-3);
  EXPECT_DOUBLE_EQ(m.spec.controller.kp, 1.0e5);
  EXPECT_DOUBLE_EQ(m.spec.controller.kd, 3.0e4);
  EXPECT_FALSE(m.spec.notch.enabled);
  EXPECT_EQ(m.spec.notch.order, 1);
  EXPECT_DOUBLE_EQ(m.spec.notch.alpha[1], 1.6);
  ASSERT_EQ(m.spec.trajectory.moves.size(), 2u);
  EXPECT_DOUBLE_EQ(m.spec.trajectory.moves[0].target, 0.5);
  EXPECT_DOUBLE_EQ(m.spec.trajectory.moves[1].hold, 45.0);
  EXPECT_DOUBLE_EQ(m.duration, 3.0 + 7.0 + 3.0 + 45.0);
  EXPECT_EQ(m.spec.simulation.integrator, ff::Integrator::kRk4);
  EXPECT_STREQ(ff::integrator_name(m.spec.simulation.integrator), "rk4");
  // Closed-loop resonances: 0.274 Hz and 2.289 Hz.
  ASSERT_GE(m.resonances.size(), 2u);
  EXPECT_NEAR(m.resonances[0] / (2 * std::numbers::pi), 0.2740, 5e-4);
  EXPECT_NEAR(m.resonances[1] / (2 * std::numbers::pi), 2.2892, 5e-4);
  // Total mass: beam plus payload.
  double mass = 0;
  for (const auto& b : m.body) mass += b.mass;
  EXPECT_NEAR(mass, ff::calc_beam_mass(m.spec.beam) + 328.7, 1e-9);
}

TEST(ModelIo, ReferenceTextParsesIdenticallyFromMemory) {
  const ff::Model m = ff::parse_model(YAML::Load(join(reference_lines())), "bad.yaml");
  EXPECT_EQ(m.nseg, 6);
  EXPECT_NEAR(m.joint_k[1], 39500.0, 1e-6);
}

// ---- unknown keys ------------------------------------------------------------------------

TEST(ModelIo, UnknownTopLevelKeyIsRejectedWithItsLine) {
  expect_rejected(with_line(3, "gravity: 9.81"), 3, "gravity", "unknown key");
}

// (#32.14) A rig with no inertia (a massless beam, no payload, no hub inertia) has a singular mass matrix
// (modes of 0 Hz, no dynamics): one line naming the keys. A massless beam of several segments too (its
// joints carry nothing); one rigid massless segment on a hub with inertia is the EMPS axis.
TEST(ModelIo, ARigWithNoInertiaIsRejectedNamingTheKeys) {
  auto lines = reference_lines();
  lines.at(8 - 1) = "  density: 0";
  lines.at(11 - 1) = "segments: 1";
  lines.at(19 - 1) = "  inertia: 0";
  lines.at(22 - 1) = "  mass: 0";
  lines.at(23 - 1) = "  inertia: 0";
  expect_rejected(join(lines), 8, "beam.density",
                  "the rig has no inertia: beam.density, hub.inertia, payload.mass and payload.inertia are all 0");
  lines.at(19 - 1) = "  inertia: 50.0";
  EXPECT_NO_THROW(ff::parse_model(YAML::Load(join(lines)), "ok.yaml"));
  lines.at(11 - 1) = "segments: 6";
  lines.at(22 - 1) = "  mass: 328.7";
  expect_rejected(join(lines), 8, "beam.density", "0 (a massless beam) needs segments: 1");
}

TEST(ModelIo, UnknownNestedKeyNamesFullPath) {
  expect_rejected(with_line(24, "  colour: red"), 24, "payload.colour", "unknown key");
}

TEST(ModelIo, MisspeltOptionalKeyIsAnUnknownKey) {
  expect_rejected(with_line(29, "  kdd: 3.0e4"), 29, "controller.kdd", "unknown key");
}

TEST(ModelIo, MisspeltRequiredKeyIsTheUnknownKeyWithTheClosestValidName) {
  // "hieght" for "height", "stifness" for "stiffness": not "missing required value" for the key meant.
  expect_rejected(with_line(6, "  hieght: 0.3048"), 6, "beam.hieght", "unknown key (did you mean `height`?)");
  expect_rejected(with_line(14, "  stifness: 39.5e3"), 14, "joints.stifness", "unknown key (did you mean `stiffness`?)");
  // An optional key misspelt, and a key near none: the closest, or none named.
  expect_rejected(with_line(29, "  kdd: 3.0e4"), 29, "controller.kdd", "unknown key (did you mean `kd`?)");
  EXPECT_EQ(parse_error(with_line(24, "  colour: red")).message(), "unknown key");
}

TEST(ModelIo, ATargetBeyondATurnAModulusInGpaOrADensityInGPerCm3IsAUnitMistake) {
  expect_rejected(with_line(43, "    - {target: 30, hold: 7.0}"), 43, "trajectory.moves[0].target",
                  "30 rad is more than a turn (2 pi): looks like degrees (30 deg = 0.5236 rad)");
  expect_rejected(with_line(9, "  youngs_modulus: 207.0"), 9, "beam.youngs_modulus",
                  "207 Pa is far below any engineering material (1e6 to 2e12 Pa): looks like GPa (207 GPa = 2.07e+11 Pa)");
  expect_rejected(with_line(9, "  youngs_modulus: 207000"), 9, "beam.youngs_modulus", "looks like MPa (2.07e+05 MPa = 2.07e+11 Pa)");
  expect_rejected(with_line(8, "  density: 7.75"), 8, "beam.density",
                  "7.75 kg/m³ is far below any engineering material (50 to 25000 kg/m³): looks like g/cm³ (7.75 g/cm³ = 7750 kg/m³)");
  // The file's own allowance, for a model that means it.
  const ff::Model m = ff::parse_model(YAML::Load("units_check: false\n" + with_line(43, "    - {target: 30, hold: 7.0}")), "bad.yaml");
  EXPECT_EQ(m.spec.trajectory.moves.at(0).target, 30.0);
}

TEST(ModelIo, MisspeltKeyInAMoveIsAnUnknownKey) {
  expect_rejected(with_line(43, "    - {target: 0.5, hodl: 7.0}"), 43, "trajectory.moves[0].hodl", "unknown key (did you mean `hold`?)");
}

// ---- wrong types -------------------------------------------------------------------------

TEST(ModelIo, SegmentsAsWordIsNotAnInteger) {
  expect_rejected(with_line(11, "segments: six"), 11, "segments", "expected an integer, got 'six'");
}

TEST(ModelIo, SegmentsAsFractionIsNotAnInteger) {
  expect_rejected(with_line(11, "segments: 6.5"), 11, "segments", "expected an integer, got '6.5'");
}

TEST(ModelIo, BeamLengthAsListIsNotANumber) {
  expect_rejected(with_line(5, "  length: [1, 2]"), 5, "beam.length", "expected a number");
}

TEST(ModelIo, PayloadMassAsWordIsNotANumber) {
  expect_rejected(with_line(22, "  mass: heavy"), 22, "payload.mass", "expected a number, got 'heavy'");
}

TEST(ModelIo, NotchEnabledMaybeIsNotABoolean) {
  expect_rejected(with_line(34, "  enabled: maybe"), 34, "notch.enabled", "expected true or false");
}

TEST(ModelIo, NotchAlphaListOfWrongLengthIsRejected) {
  expect_rejected(with_line(36, "  alpha: [1.6, 1.6, 1.6]"), 36, "notch.alpha", "list of 2 numbers");
}

TEST(ModelIo, BeamAsNumberIsNotAMap) {
  // Line 4 becomes "beam: 5"; lines 5-9 are then indented children of nothing, so blank them.
  auto lines = reference_lines();
  lines[4 - 1] = "beam: 5";
  for (int n = 5; n <= 9; ++n) lines[n - 1] = "";
  expect_rejected(join(lines), 4, "beam", "expected a map");
}

TEST(ModelIo, MovesAsMapIsNotAList) {
  auto lines = reference_lines();
  lines[42 - 1] = "  moves: {target: 1}";
  lines[43 - 1] = lines[44 - 1] = "";
  expect_rejected(join(lines), 42, "trajectory.moves", "expected a list");
}

// ---- missing values ----------------------------------------------------------------------

TEST(ModelIo, MissingBeamHeightNamesKey) {
  const auto e = parse_error(with_line(6, ""));
  EXPECT_EQ(e.file(), "bad.yaml");
  EXPECT_EQ(e.key(), "beam.height");
  EXPECT_NE(e.message().find("missing required value"), std::string::npos) << e.what();
  // No line of its own: the error points at the beam block (its key or its first entry).
  EXPECT_TRUE(e.line() == 4 || e.line() == 5) << e.what();
}

TEST(ModelIo, MissingPayloadBlockNamesKey) {
  const auto e = parse_error(without_lines(21, 23));
  EXPECT_EQ(e.file(), "bad.yaml");
  EXPECT_EQ(e.key(), "payload");
  EXPECT_NE(e.message().find("missing required value"), std::string::npos) << e.what();
}

TEST(ModelIo, EmptyValueForRequiredKeyIsRejected) {
  expect_rejected(with_line(22, "  mass:"), 22, "payload.mass", "expected a number");
}

TEST(ModelIo, MoveWithoutTargetIsRejected) {
  expect_rejected(with_line(44, "    - {hold: 45.0}"), 44, "trajectory.moves[1].target", "missing required value");
}

TEST(ModelIo, EmptyDocumentIsRejected) {
  const auto e = parse_error("# nothing here\n");
  EXPECT_EQ(e.file(), "bad.yaml");
  EXPECT_NE(e.message().find("empty"), std::string::npos) << e.what();
}

TEST(ModelIo, DocumentThatIsAListIsRejected) {
  const auto e = parse_error("- 1\n- 2\n");
  EXPECT_EQ(e.file(), "bad.yaml");
  EXPECT_EQ(e.line(), 1);
  EXPECT_NE(e.message().find("expected a map"), std::string::npos) << e.what();
}

// ---- non-physical values -----------------------------------------------------------------

TEST(ModelIo, NegativePayloadMassNamesKeyAndLine) {
  expect_rejected(with_line(22, "  mass: -328.7"), 22, "payload.mass", ">= 0");
}

TEST(ModelIo, OneSegmentIsTooFew) {
  expect_rejected(with_line(11, "segments: 0"), 11, "segments", "must be >= 1 (1 = a rigid arm), got 0");
}

TEST(ModelIo, ZeroBeamLengthIsRejected) {
  expect_rejected(with_line(5, "  length: 0"), 5, "beam.length", "> 0");
}

TEST(ModelIo, NanDensityIsRejected) {
  expect_rejected(with_line(8, "  density: .nan"), 8, "beam.density", "finite");
}

TEST(ModelIo, InfiniteStiffnessIsRejected) {
  expect_rejected(with_line(14, "  stiffness: .inf"), 14, "joints.stiffness", "finite");
}

TEST(ModelIo, NanInsideAListNamesTheElement) {
  const auto e = parse_error(with_line(36, "  alpha: [1.6, .nan]"));
  EXPECT_EQ(e.key(), "notch.alpha[1]");
  EXPECT_NE(e.message().find("finite"), std::string::npos) << e.what();
  EXPECT_EQ(e.line(), 36) << e.what();
}

TEST(ModelIo, NegativeJointDampingIsRejected) {
  expect_rejected(with_line(15, "  damping: -90.4"), 15, "joints.damping", ">= 0");
}

TEST(ModelIo, NegativeHubInertiaIsRejected) {
  expect_rejected(with_line(19, "  inertia: -50.0"), 19, "hub.inertia", ">= 0");
}

TEST(ModelIo, ZeroAmplitudeMoveIsRejected) {
  // The second move goes back to 0.5, where the first one ended.
  expect_rejected(with_line(44, "    - {target: 0.5, hold: 45.0}"), 44, "trajectory.moves[1].target",
                  "zero amplitude");
}

TEST(ModelIo, NegativeHoldIsRejected) {
  expect_rejected(with_line(43, "    - {target: 0.5, hold: -7.0}"), 43, "trajectory.moves[0].hold", ">= 0");
}

TEST(ModelIo, NotchOrderZeroIsRejected) {
  expect_rejected(with_line(35, "  order: 0"), 35, "notch.order", "between 1 and 8, got 0");
}

TEST(ModelIo, NegativeNotchAlphaIsRejected) {
  expect_rejected(with_line(36, "  alpha: [1.6, -1.6]"), 36, "notch.alpha", "> 0");
}

TEST(ModelIo, UnknownIntegratorIsRejected) {
  expect_rejected(with_line(47, "  integrator: euler"), 47, "simulation.integrator", "unknown integrator 'euler'");
}

TEST(ModelIo, ZeroControllerRateIsRejected) {
  expect_rejected(with_line(26, "  rate: 0"), 26, "controller.rate", "> 0");
}

// ---- recorded sensors and the notch placement ---------------------------------------------

// Line 12 of the reference file is blank and at the top level: room for a one-line sensors block.
std::string with_sensors(const std::string& flow_map) { return with_line(12, "sensors: " + flow_map); }

TEST(ModelIo, RecordedSensorBlocksParse) {
  const ff::Model m = ff::parse_model(
      YAML::Load(with_sensors("{strain_gauge: {enabled: true, joint: 4, resolution: 0.5, noise: 2, delay: 1, "
                              "rate: 500}, tip_accelerometer: {enabled: true, rate: 0}, "
                              "tip_position: {delay: 40, rate: 25}}")),
      "good.yaml");
  const auto& g = m.spec.sensors.strain_gauge;
  EXPECT_TRUE(g.enabled);
  EXPECT_EQ(g.joint, 4);
  EXPECT_DOUBLE_EQ(g.resolution, 0.5);
  EXPECT_DOUBLE_EQ(g.noise, 2.0);
  EXPECT_EQ(g.delay, 1);
  EXPECT_DOUBLE_EQ(g.rate, 500.0);
  EXPECT_TRUE(m.spec.sensors.tip_accelerometer.enabled);
  EXPECT_FALSE(m.spec.sensors.tip_position.enabled);
  EXPECT_EQ(m.spec.sensors.tip_position.delay, 40);
  EXPECT_DOUBLE_EQ(m.spec.sensors.tip_position.rate, 25.0);
  EXPECT_EQ(m.spec.notch.placement, "reference");
}

TEST(ModelIo, OutputChannelBlocksParse) {
  const ff::Model m = ff::parse_model(
      YAML::Load(with_sensors("{hub_torque: {delay: 7, noise: 3}, tip_deflection: {delay: 45, rate: 100}, "
                              "pressure_a: {resolution: 1000}}")),
      "good.yaml");
  EXPECT_EQ(m.spec.sensors.hub_torque.delay, 7);
  EXPECT_DOUBLE_EQ(m.spec.sensors.hub_torque.noise, 3.0);
  EXPECT_EQ(m.spec.sensors.tip_deflection.delay, 45);
  EXPECT_DOUBLE_EQ(m.spec.sensors.tip_deflection.rate, 100.0);
  EXPECT_DOUBLE_EQ(m.spec.sensors.pressure_a.resolution, 1000.0);
}

TEST(ModelIo, OutputChannelRateMustDivideTheControllerRate) {
  expect_rejected(with_sensors("{tip_deflection: {rate: 300}}"), 12, "sensors.tip_deflection.rate", "must divide");
}

TEST(ModelIo, NegativeRecordedNoiseIsRejected) {
  expect_rejected(with_sensors("{tip_position: {noise: -0.001}}"), 12, "sensors.tip_position.noise", ">= 0");
}

TEST(ModelIo, StrainGaugeJointOutsideTheBeamIsRejected) {
  expect_rejected(with_sensors("{strain_gauge: {enabled: true, joint: 6}}"), 12, "sensors.strain_gauge.joint",
                  "beam joint 1..5, got 6");
  expect_rejected(with_sensors("{strain_gauge: {joint: 0}}"), 12, "sensors.strain_gauge.joint", "got 0");
}

TEST(ModelIo, SensorRateNotDividingTheControllerRateIsRejected) {
  expect_rejected(with_sensors("{tip_accelerometer: {rate: 300}}"), 12, "sensors.tip_accelerometer.rate",
                  "must divide controller.rate = 1000 Hz");
  expect_rejected(with_sensors("{tip_accelerometer: {rate: 2000}}"), 12, "sensors.tip_accelerometer.rate",
                  "must divide controller.rate");
}

TEST(ModelIo, ControllerSensorRatesParse) {
  const ff::Model m =
      ff::parse_model(YAML::Load(with_sensors("{hub_angle: {rate: 250, delay: 1}, hub_rate: {rate: 500}}")), "good.yaml");
  EXPECT_DOUBLE_EQ(m.spec.sensors.hub_angle.rate, 250.0);
  EXPECT_EQ(m.spec.sensors.hub_angle.delay, 1);
  EXPECT_DOUBLE_EQ(m.spec.sensors.hub_rate.rate, 500.0);
}

TEST(ModelIo, ControllerSensorRateNotDividingTheControllerRateIsRejected) {
  expect_rejected(with_sensors("{hub_angle: {rate: 300}}"), 12, "sensors.hub_angle.rate",
                  "must divide controller.rate = 1000 Hz a whole number of times, got 300 Hz");
  expect_rejected(with_sensors("{hub_rate: {rate: -250}}"), 12, "sensors.hub_rate.rate", ">= 0");
}

TEST(ModelIo, LoggedSaysWhatTheRecordsColumnOfAnInLoopChannelIs) {
  const ff::Model m = ff::parse_model(YAML::Load(with_sensors("{hub_angle: {logged: true, logged_delay: 4}}")), "good.yaml");
  EXPECT_EQ(m.spec.sensors.hub_angle.logged, "true");
  EXPECT_EQ(m.spec.sensors.hub_angle.logged_delay, 4);
  EXPECT_EQ(m.spec.sensors.hub_rate.logged, "read");  // the default: what the controller read
  expect_rejected(with_sensors("{hub_rate: {logged: late}}"), 12, "sensors.hub_rate.logged",
                  "unknown value 'late' (read: what the controller read, true: on time)");
  expect_rejected(with_sensors("{hub_angle: {logged_delay: -1}}"), 12, "sensors.hub_angle.logged_delay",
                  "must be between 0 and 10000 samples");
  // Only the channels the controller reads have a logged column to describe.
  expect_rejected(with_sensors("{hub_torque: {logged: true}}"), 12, "sensors.hub_torque.logged", "unknown key");
}

TEST(ModelIo, EnabledKeyBelongsToTheRecordedSensorsOnly) {
  expect_rejected(with_sensors("{hub_angle: {enabled: true}}"), 12, "sensors.hub_angle.enabled", "unknown key");
}

TEST(ModelIo, NegativeRecordedDelayIsRejected) {
  expect_rejected(with_sensors("{strain_gauge: {delay: -1}}"), 12, "sensors.strain_gauge.delay", "between 0 and 10000");
}

TEST(ModelIo, JointKeyBelongsToTheStrainGaugeOnly) {
  expect_rejected(with_sensors("{tip_position: {joint: 2}}"), 12, "sensors.tip_position.joint", "unknown key");
}

TEST(ModelIo, UnknownNotchPlacementIsRejected) {
  expect_rejected(with_line(38, "  placement: sideways"), 38, "notch.placement", "unknown placement 'sideways'");
}

// ---- review findings: the key's own line, once --------------------------------------------

TEST(ModelIo, ShaperVtolOutsideItsRangeNamesItsLineAndKeyOnce) {
  // shaper: at line 52, vtol at line 56; the message is the key's, without a repeated "shaper:".
  expect_rejected(with_line(56, "  vtol: 0.7"), 56, "shaper.vtol", "must be in (0, 0.5), got 0.7");
  EXPECT_EQ(parse_error(with_line(56, "  vtol: 0.7")).message().find("shaper"), std::string::npos);
  expect_rejected(with_line(55, "  damping: 1.5"), 55, "shaper.damping", "must be < 1");
  expect_rejected(with_line(54, "  frequency: -3"), 54, "shaper.frequency", ">= 0");
}

TEST(ModelIo, LugreWithoutCoulombNamesTheModelLine) {
  // friction: {model: lugre} and no coulomb: the line that asks for LuGre, naming what it needs.
  expect_rejected(with_line(12, "friction: {model: lugre}"), 12, "friction.model", "needs friction.coulomb > 0");
  expect_rejected(with_line(12, "friction:\n  model: lugre\n  coulomb: 0"), 13, "friction.model", "got 0.0");
}

TEST(ModelIo, AKeyLeftAtItsDefaultIsReportedAtItsBlock) {
  // omega_z not given, and the closed loop of a rigid arm has no resonances to place the notch at.
  auto lines = reference_lines();
  lines[11 - 1] = "segments: 1";
  lines[34 - 1] = "  enabled: true";
  const auto e = parse_error(join(lines));
  EXPECT_EQ(e.key(), "notch.omega_z") << e.what();
  EXPECT_EQ(e.line(), 33) << e.what();
}

TEST(ModelIo, MisspeltPayloadEventKeyIsAnUnknownKey) {
  expect_rejected(with_line(24, "  events: [{time: 2.0, mas: 0.0, inertia: 0.0}]"), 24, "payload.events[0].mas",
                  "unknown key (did you mean `mass`?)");
}

TEST(ModelIo, DisabledDriveAndHydraulicsValuesAreCheckedToo) {
  // Like the recorded sensors: a value is checked whether its block is enabled or not.
  expect_rejected(with_line(12, "drive: {enabled: false, ratio: 0}"), 12, "drive.ratio", "> 0");
  expect_rejected(with_line(12, "hydraulics: {rated_flow: -1}"), 12, "hydraulics.rated_flow", "> 0");
}

TEST(ModelIo, HydraulicPhysicalFormsParse) {
  const auto m = ff::parse_model(
      YAML::Load(with_line(12, "hydraulics: {discharge_coefficient: 0.61, port_width: 0.02, spool_stroke: 1.0e-3, "
                               "oil_density: 850, piston_area: 0.0125, pinion_radius: 0.2}")),
      "ok.yaml");
  const auto& h = m.spec.hydraulics;
  EXPECT_EQ(h.discharge_coefficient, 0.61);
  EXPECT_EQ(h.port_width, 0.02);
  EXPECT_EQ(h.spool_stroke, 1.0e-3);
  EXPECT_EQ(h.oil_density, 850.0);
  EXPECT_EQ(h.piston_area, 0.0125);
  EXPECT_EQ(h.pinion_radius, 0.2);
  // Zero is "not given": next to the rated form it is no second form.
  EXPECT_NO_THROW(
      ff::parse_model(YAML::Load(with_line(12, "hydraulics: {rated_flow: 1.0e-3, oil_density: 0}")), "ok.yaml"));
}

TEST(ModelIo, PartOfAPhysicalGroupNamesTheKeyGivenAndWhatIsMissing) {
  expect_rejected(with_line(12, "hydraulics: {port_width: 0.02, discharge_coefficient: 0.61}"), 12,
                  "hydraulics.discharge_coefficient", "needs hydraulics.spool_stroke, hydraulics.oil_density too");
  expect_rejected(with_line(12, "hydraulics:\n  enabled: false\n  pinion_radius: 0.1"), 14, "hydraulics.pinion_radius",
                  "needs hydraulics.piston_area too (D = A r");
  expect_rejected(with_line(12, "hydraulics:\n  piston_area: 0.01\n  pinion_radius: -0.25"), 14,
                  "hydraulics.pinion_radius", ">= 0");
}

TEST(ModelIo, BothFormsOfAHydraulicQuantityAreRejectedAtThePhysicalKey) {
  expect_rejected(with_line(12, "hydraulics:\n  rated_flow: 1.6e-3\n  discharge_coefficient: 0.61\n  port_width: 0.02\n"
                                "  spool_stroke: 1.0e-3\n  oil_density: 850"),
                  14, "hydraulics.discharge_coefficient", "given with hydraulics.rated_flow: k_v comes from");
  expect_rejected(with_line(12, "hydraulics:\n  discharge_coefficient: 0.61\n  port_width: 0.02\n"
                                "  spool_stroke: 1.0e-3\n  oil_density: 850\n  rated_drop: 3.5e6"),
                  13, "hydraulics.discharge_coefficient", "given with hydraulics.rated_drop");
  expect_rejected(with_line(12, "hydraulics: {displacement: 2.5e-3, piston_area: 0.01, pinion_radius: 0.25}"), 12,
                  "hydraulics.piston_area", "given with hydraulics.displacement: D is displacement or piston_area");
}

// ---- files -------------------------------------------------------------------------------

TEST(ModelIo, BadIndentationNamesTheFileAndLine) {
  TempDir dir;
  // "height" indented by one space more than "length": not valid YAML at line 6.
  const auto path = dir.write("indent.yaml", with_line(6, "   height: 0.3048"));
  try {
    ff::load_model(path);
    FAIL() << "bad indentation was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), 6) << e.what();
    EXPECT_FALSE(e.message().empty());
    EXPECT_EQ(std::string(e.what()).rfind(path + ":6: ", 0), 0u) << e.what();
  }
}

TEST(ModelIo, UnclosedListNamesTheFile) {
  TempDir dir;
  const auto path = dir.write("unclosed.yaml", with_line(36, "  alpha: [1.6, 1.6"));
  try {
    ff::load_model(path);
    FAIL() << "an unclosed list was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_GE(e.line(), 36) << e.what();
  }
}

TEST(ModelIo, LoadModelErrorsNameThePathGiven) {
  TempDir dir;
  const auto path = dir.write("neg.yaml", with_line(22, "  mass: -1"));
  try {
    ff::load_model(path);
    FAIL() << "negative mass was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), 22);
    EXPECT_EQ(e.key(), "payload.mass");
  }
}

TEST(ModelIo, MissingFileIsRejected) {
  TempDir dir;
  const std::string path = (dir.path / "no_such_model.yaml").string();
  try {
    ff::load_model(path);
    FAIL() << "a missing file was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), 0);
    EXPECT_NE(e.message().find("cannot open"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
  }
}

// ---- the error itself --------------------------------------------------------------------

TEST(ConfigError, WhatReadsFileLineKeyMessage) {
  EXPECT_STREQ(ff::ConfigError("a.yaml", 12, "payload.mass", "bad").what(), "a.yaml:12: payload.mass: bad");
  EXPECT_STREQ(ff::ConfigError("a.yaml", 0, "payload.mass", "bad").what(), "a.yaml: payload.mass: bad");
  EXPECT_STREQ(ff::ConfigError("a.yaml", 0, "", "cannot open file").what(), "a.yaml: cannot open file");
}

}  // namespace

namespace {

TEST(ModelIo, EveryIntegratorNameParsesBack) {
  for (auto i : {ff::Integrator::kRk4, ff::Integrator::kSdirk2, ff::Integrator::kCvodeDense, ff::Integrator::kCvodeKlu,
                 ff::Integrator::kMidpoint}) {
    const std::string text = with_line(47, std::string("  integrator: ") + ff::integrator_name(i));
    EXPECT_EQ(ff::parse_model(YAML::Load(text), "m.yaml").spec.simulation.integrator, i) << ff::integrator_name(i);
  }
}

}  // namespace

// ---- keys written twice ----------------------------------------------------------------

TEST(ModelIo, KeyWrittenTwiceIsAnErrorNamingBothLines) {
  TempDir dir;
  auto lines = reference_lines();
  ASSERT_EQ(lines.at(10).rfind("segments: 6", 0), 0u);
  lines.push_back("segments: 7");
  const std::string path = dir.write("twice.yaml", join(lines));
  const int last = static_cast<int>(lines.size());
  try {
    ff::load_model(path);
    ADD_FAILURE() << "a key written twice was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), last);
    EXPECT_EQ(e.key(), "segments");
    EXPECT_NE(e.message().find("lines 11 and " + std::to_string(last)), std::string::npos) << e.what();
  }
}

TEST(ModelIo, NestedKeyWrittenTwiceNamesItsFullPath) {
  TempDir dir;
  auto lines = reference_lines();
  lines.push_back("extra: {a: [{b: 1, b: 2}]}");
  try {
    ff::load_model(dir.write("nested.yaml", join(lines)));
    ADD_FAILURE() << "a nested key written twice was accepted";
  } catch (const ff::ConfigError& e) {
    EXPECT_EQ(e.key(), "extra.a[0].b") << e.what();
    EXPECT_EQ(e.line(), static_cast<int>(lines.size()));
  }
}

// ---- docs/formats.md ---------------------------------------------------------------------

TEST(ModelIo, DocsListEveryKeyWithTheReadersUnitRequirementAndDefault) {
  ff::test::expect_documented("Model (`configs/fbtb.yaml`)", ff::rig_model_keys());
}
