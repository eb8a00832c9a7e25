// diagnose on arm models (validate/arm_diagnose.hpp): an effect hidden at one joint or link of the
// two-link flexible arm is found there, not at the other, with its value; an effect hidden in the URDF
// arm's wrist is found there; nothing hidden is "none" (ArmHiddenEffect, slow); the candidates are named
// after where they act, and what does not apply is refused (ArmDiagnose).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "sweep/paths.hpp"
#include "validate/arm_diagnose.hpp"
#include "validate/arm_record.hpp"

namespace ff {
namespace {

const std::string kTwoLink = std::string(FLEXFARM_SOURCE_DIR) + "/configs/two_link_flexible.yaml";
const std::string kArm6 = std::string(FLEXFARM_SOURCE_DIR) + "/configs/arm6.yaml";

// Noise of a good rig: 0.2 mrad encoders, 1 mrad/s rate, 1 % of the elbow's torque, 0.2 mm positions.
ArmRecordNoise rig_noise() {
  ArmRecordNoise n;
  n.angle = 2e-4;
  n.rate = 1e-3;
  n.torque = 0.01;
  n.position = 2e-4;
  return n;
}

// The diagnosis, over `effects`, of the model `path` (with `base`) on a record of it with `hidden` set too,
// in the plant only (a real arm's controller keeps its nominal model: docs/formats.md, "The controller's model").
Diagnosis diagnose_hidden(const std::string& path, const std::vector<std::string>& base,
                          const std::vector<std::string>& hidden, const std::vector<std::string>& effects,
                          std::uint64_t seed, int iterations = 12) {
  const Record r = make_arm_record(load_arm_with(path, base, hidden), rig_noise(), seed);
  DiagnoseOptions opt;
  opt.max_iterations = iterations;
  opt.only = effects;
  return diagnose_arm(load_arm_source(path, base), r, opt);
}

const EffectFit& ranked(const Diagnosis& d, const std::string& effect) {
  const auto it = std::find_if(d.ranking.begin(), d.ranking.end(), [&](const EffectFit& f) { return f.effect == effect; });
  if (it == d.ranking.end()) throw std::runtime_error("not ranked: " + effect);
  return *it;
}

// 3 s of the two-link arm: its 1.5 s move and half its settling.
const std::vector<std::string> kShort = {"simulation.duration=3.0"};

TEST(ArmHiddenEffect, CoulombFrictionHiddenAtTheElbowIsFoundAtTheElbowWithItsLevel) {
  const Diagnosis d = diagnose_hidden(kTwoLink, kShort, {"joints.elbow.friction.coulomb=0.15"},
                                      {"coulomb_friction@elbow", "coulomb_friction@shoulder", "viscous_friction@elbow",
                                       "torque_offset@elbow", "sensor_delay.elbow_angle"},
                                      11);
  EXPECT_EQ(d.verdict, "coulomb_friction@elbow") << format_diagnosis_text(d);
  const EffectFit& f = ranked(d, "coulomb_friction@elbow");
  EXPECT_NEAR(f.params.at("joints.elbow.friction.coulomb"), 0.15, 0.15 * 0.03) << format_diagnosis_text(d);
  EXPECT_TRUE(f.explained);
  // The same friction at the other joint explains a little of it at most.
  EXPECT_GT(ranked(d, "coulomb_friction@shoulder").delta_bic, 0.1 * f.delta_bic);
}

TEST(ArmHiddenEffect, FreePlayInTheElbowsDriveIsItsBacklash) {
  // The model has the elbow's compliant drive (200 kp, a rotor a ninth of its inertia); the record's
  // drive has 20 mrad of free play besides. The free play, not a softer drive, explains it.
  std::vector<std::string> base = kShort;
  for (const char* s : {"joints.elbow.drive.stiffness=1140", "joints.elbow.drive.damping=1.0", "joints.elbow.drive.rotor_inertia=0.01"})
    base.push_back(s);
  const Diagnosis d = diagnose_hidden(kTwoLink, base, {"joints.elbow.drive.backlash=0.02"},
                                      {"backlash@elbow", "drive_compliance@elbow", "coulomb_friction@elbow",
                                       "sensor_delay.elbow_angle"},
                                      12, 40);
  EXPECT_EQ(d.verdict, "backlash@elbow") << format_diagnosis_text(d);
  EXPECT_NEAR(ranked(d, "backlash@elbow").params.at("joints.elbow.drive.backlash"), 0.02, 0.02 * 0.1)
      << format_diagnosis_text(d);
}

TEST(ArmHiddenEffect, ALateShoulderEncoderIsTheShoulderAngleDelayOfItsSamples) {
  const Diagnosis d = diagnose_hidden(kTwoLink, kShort, {"joints.shoulder.sensors.angle.delay=6"},
                                      {"sensor_delay.shoulder_angle", "sensor_delay.elbow_angle",
                                       "viscous_friction@shoulder", "link_damping@upper_arm"},
                                      12);
  EXPECT_EQ(d.verdict, "sensor_delay.shoulder_angle") << format_diagnosis_text(d);
  EXPECT_EQ(ranked(d, "sensor_delay.shoulder_angle").params.at("joints.shoulder.sensors.angle.delay"), 6.0);
}

// A shoulder angle logged on time by a logger that stamps it 5 samples late (the loop untouched): with the
// model saying the column is on time (logged: true) that is the logger's delay, not the loop's.
TEST(ArmHiddenEffect, AnOnTimeShoulderAngleStampedLateIsTheLoggersDelay) {
  const std::vector<std::string> on_time = {"simulation.duration=3.0", "joints.shoulder.sensors.angle.logged=true"};
  const Diagnosis d = diagnose_hidden(kTwoLink, on_time, {"joints.shoulder.sensors.angle.logged_delay=5"},
                                      {"logger_delay.shoulder_angle", "sensor_delay.shoulder_angle"}, 14);
  EXPECT_EQ(d.verdict, "logger_delay.shoulder_angle") << format_diagnosis_text(d);
  EXPECT_EQ(ranked(d, "logger_delay.shoulder_angle").params.at("joints.shoulder.sensors.angle.logged_delay"), 5.0);
}

TEST(ArmHiddenEffect, AStifferForearmThanModelledIsTheForearmsStiffness) {
  const Diagnosis d = diagnose_hidden(kTwoLink, kShort, {"bodies[forearm].flexible.stiffness_factor=1.6"},
                                      {"link_stiffness@forearm", "link_stiffness@upper_arm", "armature@elbow",
                                       "payload@forearm"},
                                      13);
  EXPECT_EQ(d.verdict, "link_stiffness@forearm") << format_diagnosis_text(d);
  EXPECT_NEAR(ranked(d, "link_stiffness@forearm").params.at("bodies[forearm].flexible.stiffness_factor"), 1.6, 0.05);
}

TEST(ArmHiddenEffect, NothingHiddenIsNone) {
  const Diagnosis d = diagnose_hidden(kTwoLink, kShort, {},
                                      {"coulomb_friction@elbow", "torque_offset@shoulder", "sensor_delay.elbow_angle"}, 14);
  EXPECT_EQ(d.verdict, "none") << format_diagnosis_text(d);
  EXPECT_TRUE(d.base_explained);
  for (const auto& f : d.ranking) EXPECT_FALSE(f.significant) << f.effect;
}

// The URDF arm (its tree in a URDF file: joint-level effects only) with a load torque on its wrist.
TEST(ArmHiddenEffect, ALoadTorqueOnTheURDFArmsWristIsItsTorqueOffset) {
  const std::vector<std::string> base = {"simulation.duration=2.5"};
  const Diagnosis d = diagnose_hidden(kArm6, base, {"joints.wrist_1.torque_offset=-2.5"},
                                      {"torque_offset@wrist_1", "torque_offset@wrist_2", "coulomb_friction@wrist_1"},
                                      15);
  EXPECT_EQ(d.verdict, "torque_offset@wrist_1") << format_diagnosis_text(d);
  EXPECT_NEAR(ranked(d, "torque_offset@wrist_1").params.at("joints.wrist_1.torque_offset"), -2.5, 0.05);
}

// Air in the hydraulic shoulder's oil (a quarter of the modelled bulk modulus): its compressibility there.
TEST(ArmHiddenEffect, AirInTheHydraulicShouldersOilIsItsCompressibility) {
  const std::string arm = std::string(FLEXFARM_SOURCE_DIR) + "/configs/hydraulic_arm.yaml";
  const Diagnosis d = diagnose_hidden(arm, {"simulation.duration=2.5"}, {"joints.shoulder.hydraulics.bulk_modulus=3.5e8"},
                                      {"hydraulic_compressibility@shoulder", "armature@shoulder", "viscous_friction@shoulder",
                                       "sensor_delay.shoulder_angle"},
                                      16);
  EXPECT_EQ(d.verdict, "hydraulic_compressibility@shoulder") << format_diagnosis_text(d);
  const EffectFit& f = ranked(d, "hydraulic_compressibility@shoulder");
  // The oil spring 4 beta D^2 / V is what the record shows: beta / V within 5 % of the truth's.
  const double ratio = f.params.at("joints.shoulder.hydraulics.bulk_modulus") / f.params.at("joints.shoulder.hydraulics.chamber_volume");
  EXPECT_NEAR(ratio / (3.5e8 / 5.0e-4), 1.0, 0.05) << format_diagnosis_text(d);
}

TEST(ArmDiagnose, CandidatesAreNamedAfterTheJointOrLinkTheyActAt) {
  const ModelSource src = load_arm_source(kTwoLink, kShort);
  const ArmModel m = build_arm(src);
  const Record r = make_arm_record(m, {}, 1);
  std::vector<std::string> names;
  for (const Effect& e : make_arm_candidate_effects(m, apply_overrides(src), r)) names.push_back(e.name);
  for (const char* n : {"coulomb_friction@shoulder", "viscous_friction@elbow", "stribeck_friction@elbow",
                        "torque_offset@shoulder", "drive_compliance@elbow", "backlash@shoulder", "torque_saturation@shoulder",
                        "sensor_delay.elbow_angle", "sensor_delay.shoulder_rate", "sensor_quantization@elbow",
                        "armature@shoulder", "link_stiffness@upper_arm", "link_damping@forearm", "extra_mode@forearm",
                        "payload@upper_arm", "payload@forearm"})
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  // A logger's own delay only where the model says the column is on time.
  EXPECT_EQ(std::find(names.begin(), names.end(), "logger_delay.shoulder_angle"), names.end());
  const ModelSource on_time = load_arm_source(kTwoLink, {"simulation.duration=3.0", "joints.shoulder.sensors.angle.logged=true"});
  names.clear();
  for (const Effect& e : make_arm_candidate_effects(build_arm(on_time), apply_overrides(on_time), r)) names.push_back(e.name);
  EXPECT_NE(std::find(names.begin(), names.end(), "logger_delay.shoulder_angle"), names.end());
  EXPECT_EQ(std::find(names.begin(), names.end(), "logger_delay.elbow_angle"), names.end());
  // The URDF arm: no inline bodies, so no armature or link effects; its joints' effects all there.
  const ModelSource urdf = load_arm_source(kArm6, {"simulation.settle=0.5"});
  const ArmModel m6 = build_arm(urdf);
  names.clear();
  for (const Effect& e : make_arm_candidate_effects(m6, apply_overrides(urdf), make_arm_record(m6, {}, 1)))
    names.push_back(e.name);
  EXPECT_EQ(std::count_if(names.begin(), names.end(), [](const std::string& n) { return n.rfind("armature@", 0) == 0; }), 0);
  EXPECT_EQ(std::count_if(names.begin(), names.end(), [](const std::string& n) { return n.rfind("coulomb_friction@", 0) == 0; }), 6);
  // A hydraulic joint: its oil's compressibility, no drive train; the elbow beside it the other way round.
  const ModelSource hyd = load_arm_source(std::string(FLEXFARM_SOURCE_DIR) + "/configs/hydraulic_arm.yaml", {"simulation.duration=1.0"});
  const ArmModel mh = build_arm(hyd);
  names.clear();
  for (const Effect& e : make_arm_candidate_effects(mh, apply_overrides(hyd), make_arm_record(mh, {}, 1))) names.push_back(e.name);
  for (const char* n : {"hydraulic_compressibility@shoulder", "drive_compliance@elbow"})
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  for (const char* n : {"hydraulic_compressibility@elbow", "drive_compliance@shoulder", "backlash@shoulder"})
    EXPECT_EQ(std::find(names.begin(), names.end(), n), names.end()) << n;
}

// A friction's search box holds the model's own tanh smoothing even on a slow joint: the Titan arm's
// elbow moves at 0.05 rad/s RMS, so 1e-2 of its rate (the box's old top) was half the default 1e-3 rad/s
// and the fit of a hidden 15 N m, pinned there, ended at 14.1 with the record unexplained.
TEST(ArmDiagnose, AFrictionsSmoothingRangeHoldsTheModelsOwnOnASlowJoint) {
  const ModelSource src = load_arm_source(std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb_titan.yaml", {"simulation.settle=2"});
  const ArmModel m = build_arm(src);
  const Record r = make_arm_record(m, {}, 1);
  const auto effects = make_arm_candidate_effects(m, apply_overrides(src), r);
  const auto e = std::find_if(effects.begin(), effects.end(), [](const Effect& x) { return x.name == "coulomb_friction@elbow"; });
  ASSERT_NE(e, effects.end());
  const auto smoothing = std::find_if(e->params.begin(), e->params.end(),
                                      [](const EffectParam& q) { return q.path == "joints.elbow.friction.smoothing"; });
  ASSERT_NE(smoothing, e->params.end());
  EXPECT_EQ(smoothing->initial, 1e-3);  // the model's own (FrictionSpec's default)
  EXPECT_GE(smoothing->hi, 2e-3);
  EXPECT_LT(smoothing->lo, 1e-5);
}

TEST(ArmDiagnose, OtherModesThanClosedLoopAndUnknownEffectsAreRefused) {
  const ModelSource src = load_arm_source(kTwoLink, kShort);
  const Record r = make_arm_record(build_arm(src), {}, 1);
  DiagnoseOptions opt;
  opt.mode = ReplayMode::kOpenLoop;
  EXPECT_THROW(diagnose_arm(src, r, opt), std::invalid_argument);
  opt.mode = ReplayMode::kClosedLoop;
  opt.only = {"coulomb_friction"};  // the rig's name: an arm's carries its joint
  EXPECT_THROW(diagnose_arm(src, r, opt), std::invalid_argument);
}

}  // namespace
}  // namespace ff
