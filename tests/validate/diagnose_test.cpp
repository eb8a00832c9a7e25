// diagnose (validate/diagnose.cpp) on particular records: nothing hidden, the independent reference
// trace, re-fits, a fitted value against its truth, the examples (a late tip sensor on an
// independent record, strong stiffening, two effects at once, found in turn), calibrate's set. The randomised acceptance suite is
// hidden_effect_suite_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "validate/diagnose.hpp"
#include "validate/effects.hpp"
#include "tests/validate/truth/truth_sim.hpp"
#include "validate/synthetic.hpp"

namespace ff {
namespace {

const std::string kModel = std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml";

const std::vector<std::string> kShortRun = {"trajectory.moves=[{target: 0.5, hold: 3}]"};

// A record of the independent simulator (tests/validate/truth): one 0.5 rad move held 3 s, recorded at 500 Hz
// with the tip and torque noise of a rig (2 mm, 20 N m), and `fields` set on top.
Record make_truth_record(const std::vector<std::pair<std::string, std::string>>& fields) {
  truth::TruthRig rig;
  set_truth_field(rig, "trajectory.moves", "0.5:3");
  set_truth_field(rig, "sensors.tip_deflection.noise", "0.002");
  set_truth_field(rig, "sensors.hub_torque.noise", "20");
  set_truth_field(rig, "record.decimate", "2");
  for (const auto& [k, v] : fields) set_truth_field(rig, k, v);
  return truth::simulate_truth(rig);
}

// The diagnosis of a record made from the base with `hidden` set, noise seed `seed`.
Diagnosis diagnose_hidden(const std::vector<std::string>& hidden, std::uint64_t seed) {
  std::vector<std::string> truth_set = kShortRun;
  truth_set.insert(truth_set.end(), hidden.begin(), hidden.end());
  const ModelSource truth = load_model_source(kModel, truth_set);
  const Record r = make_synthetic_record(build_model(truth), 0.01, seed, 5);
  const ModelSource base = load_model_source(kModel, kShortRun);
  DiagnoseOptions opt;
  opt.max_iterations = 15;
  return diagnose(base, r, opt);
}

TEST(Diagnose, RecordsWithNothingHiddenGetTheVerdictNone) {
  for (std::uint64_t seed : {7, 8, 9}) {
    const Diagnosis d = diagnose_hidden({}, seed);
    EXPECT_EQ(d.verdict, "none") << seed << ": " << format_diagnosis_text(d);
    // The torque's band power is scored and explained; its samples are not low-passed.
    ASSERT_TRUE(d.base_tests.count("hub_torque.power")) << seed;
    EXPECT_TRUE(d.base_tests.at("hub_torque.power").explained()) << seed << ": " << format_diagnosis_text(d);
    EXPECT_TRUE(std::isnan(d.torque_cutoff_hz)) << seed;
  }
}

// A drive rattling flank to flank in 0.2 mrad of free play (a drive unlike the model's default: a third
// of the hub's inertia on the actuator side), recorded at 500 Hz: no replay follows the rattle's phase
// (the true model replayed fits the torque worse than the model without a drive), but its band power
// tells. The base misses that power, so the torque's samples are scored low-passed, and backlash ranks
// above the drive's compliance alone and the in-loop delay that came first before the band power.
TEST(Diagnose, ADriveRattlingInItsFreePlayIsBacklashByTheTorquesBandPower) {
  const std::vector<std::string> move = {"trajectory.moves=[{target: -0.65, hold: 4.9}]", "trajectory.move_time=4.0"};
  std::vector<std::string> truth = move;
  for (const char* a : {"drive.enabled=true", "drive.inertia=16.726", "hub.inertia=33.274", "drive.stiffness=6.4186e7",
                        "drive.damping=24085", "drive.backlash=0.000203"})
    truth.push_back(a);
  const Record r = make_synthetic_record(build_model(load_model_source(kModel, truth)), 0.006, 1065, 2);
  DiagnoseOptions opt;
  opt.max_iterations = 15;
  opt.only = {"backlash", "drive_compliance", "sensor_delay.hub_angle"};
  const Diagnosis d = diagnose(load_model_source(kModel, move), r, opt);
  EXPECT_NEAR(d.torque_cutoff_hz, 8.25, 0.01);  // 0.264 / 32 ms
  ASSERT_FALSE(d.ranking.empty());
  EXPECT_EQ(d.ranking[0].effect, "backlash") << format_diagnosis_text(d);
  EXPECT_LT(d.ranking[0].delta_bic, kSignificantDeltaBic) << format_diagnosis_text(d);
  EXPECT_GT(d.ranking[0].fit_percent.at("hub_torque.power"), d.base_fit.at("hub_torque.power") + 20.0);
}

TEST(Diagnose, TheIndependentReferenceTraceLacksNothing) {
  // tests/data/reference-traces: the rig computed by another implementation, no noise. Every
  // candidate's ΔBIC on its rounding-level residual means nothing; no fit improves visibly.
  const ModelSource base = load_model_source(kModel, {});
  const Record r = read_record_csv(std::string(FLEXFARM_SOURCE_DIR) + "/tests/data/reference-traces/fbtb_n6_pd_0p5rad.csv",
                                   replay_inputs(ReplayMode::kClosedLoop));
  const Diagnosis d = diagnose(base, r, DiagnoseOptions{});
  EXPECT_EQ(d.verdict, "none");
  EXPECT_GT(d.base_fit.at("tip_deflection"), 99.99);
}

TEST(Diagnose, AutoRefitRetunesTheBeamStiffnessWhileFittingTheEffect) {
  // Truth: Coulomb friction and a 6 % stiffer beam than the model's. `--refit auto` re-fits the joint
  // stiffness (one of the residual's two most sensitive existing parameters) and recovers both.
  std::vector<std::string> truth_set = kShortRun;
  truth_set.insert(truth_set.end(), {"friction.coulomb=300", "joints.stiffness=42000"});
  const Record r = make_synthetic_record(build_model(load_model_source(kModel, truth_set)), 0.01, 5, 5);
  DiagnoseOptions opt;
  opt.only = {"coulomb_friction"};
  opt.refit = {"auto"};
  const Diagnosis d = diagnose(load_model_source(kModel, kShortRun), r, opt);
  // Of the nonzero existing parameters the residual is most sensitive to the payload mass and the
  // joint stiffness; Coulomb friction is fitted with both.
  ASSERT_EQ(d.refit, (std::vector<std::string>{"payload.mass", "joints.stiffness"}));
  ASSERT_EQ(d.verdict, "coulomb_friction");
  EXPECT_NEAR(d.ranking[0].params.at("friction.coulomb"), 300.0, 6.0);
  EXPECT_NEAR(d.ranking[0].params.at("joints.stiffness"), 42000.0, 400.0);
}

TEST(Diagnose, FittedCoulombFrictionMatchesTheTruthWithinItsStandardError) {
  const Diagnosis d = diagnose_hidden({"friction.coulomb=400"}, 11);
  ASSERT_EQ(d.verdict, "coulomb_friction");
  const auto& f = d.ranking[0];
  const double fc = f.params.at("friction.coulomb"), se = f.stderr_.at("friction.coulomb");
  EXPECT_NEAR(fc, 400.0, std::max(4.0 * se, 4.0));
  EXPECT_LT(f.delta_bic, kSignificantDeltaBic);
}

// The first example: a record of the independent simulator (16-bit encoder, tachometer noise
// in the loop) whose tip sensor is 40 ms late. The latency of a recorded-only channel is a candidate,
// found with its delay, and after it the record is explained.
TEST(Diagnose, TipSensorLatencyOnAnIndependentRecordIsFoundWithItsDelay) {
  const Record r = make_truth_record({{"sensors.hub_angle.quantize", "true"},
                                        {"sensors.hub_rate.noise", "5e-4"},
                                        {"sensors.tip_deflection.delay", "40"}});
  const Diagnosis d = diagnose(load_model_source(kModel, kShortRun), r, DiagnoseOptions{});
  ASSERT_EQ(d.verdict, "sensor_delay.tip_deflection") << format_diagnosis_text(d);
  EXPECT_EQ(d.ranking[0].params.at("sensors.tip_deflection.delay"), 40.0);
  EXPECT_FALSE(d.base_explained);
  EXPECT_TRUE(d.ranking[0].explained);
}

// Strong cubic stiffening (k3 = 2500 k): the fit reaches it from a scan over six decades.
TEST(Diagnose, StrongJointStiffeningIsFittedOverDecades) {
  const Diagnosis d = diagnose_hidden({"joints.cubic_stiffness=1e8"}, 21);
  ASSERT_EQ(d.verdict, "joint_stiffening") << format_diagnosis_text(d);
  EXPECT_NEAR(d.ranking[0].params.at("joints.cubic_stiffness"), 1e8, 0.05e8);
}

// A record the model cannot explain with any one candidate (two effects): the verdict says so, and
// names the best partial candidates and where the misfit lives.
// Two effects at once are found as two (forward selection): Coulomb friction first (its misfit masks the
// late tip sensor's), then the delay on top of it, each with its value; the verdict names both.
TEST(Diagnose, TwoHiddenEffectsAreFoundInTurnWithTheirValues) {
  const Diagnosis d = diagnose_hidden({"friction.coulomb=300", "sensors.tip_deflection.delay=30"}, 22);
  const std::string text = format_diagnosis_text(d);
  ASSERT_EQ(d.selected.size(), 2u) << text;
  EXPECT_EQ(d.selected[0].effect, "coulomb_friction") << text;
  EXPECT_EQ(d.selected[1].effect, "sensor_delay.tip_deflection") << text;
  EXPECT_EQ(d.verdict, "coulomb_friction + sensor_delay.tip_deflection") << text;
  EXPECT_NEAR(d.selected[0].params.at("friction.coulomb"), 300.0, 15.0) << text;
  EXPECT_EQ(d.selected[1].params.at("sensors.tip_deflection.delay"), 30.0) << text;
  EXPECT_FALSE(d.selected[0].explained) << text;  // the friction alone leaves the delay's misfit
  EXPECT_TRUE(d.selected[1].explained) << text;
  EXPECT_LT(d.selected[1].delta_bic, kSignificantDeltaBic) << text;  // against the model with the friction
  ASSERT_EQ(d.rounds.size(), 1u) << text;
  EXPECT_NE(text.find("selected in turn"), std::string::npos) << text;
}

// calibrate's set: the two effects fitted in the order given (diagnose's: the friction, then the delay on
// top of it) and combined into one model addition.
TEST(Diagnose, CalibratesSetIsFittedInTurnAndCombined) {
  std::vector<std::string> truth_set = kShortRun;
  for (const char* a : {"friction.coulomb=300", "sensors.tip_deflection.delay=30"}) truth_set.push_back(a);
  const Record r = make_synthetic_record(build_model(load_model_source(kModel, truth_set)), 0.01, 22, 5);
  DiagnoseOptions opt;
  opt.max_iterations = 15;
  const EffectFit f = fit_effects(load_model_source(kModel, kShortRun), r, opt, {"coulomb_friction", "sensor_delay.tip_deflection"});
  EXPECT_EQ(f.effect, "coulomb_friction + sensor_delay.tip_deflection");
  EXPECT_EQ(f.params.at("sensors.tip_deflection.delay"), 30.0);
  EXPECT_NEAR(f.params.at("friction.coulomb"), 300.0, 15.0);
  EXPECT_EQ(f.k, 3);  // the delay (a grid), the Coulomb level and its smoothing
  EXPECT_TRUE(f.explained);
  // Two effects that write the same path cannot both be added.
  EXPECT_THROW(fit_effects(load_model_source(kModel, kShortRun), r, opt, {"coulomb_friction", "stribeck_friction"}),
               std::invalid_argument);
}

// With the one effect that would explain it left out, a record is unexplained, and the report gives the
// best partial candidates and where the misfit lives.
TEST(Diagnose, ARecordNoCandidateExplainsIsUnexplainedWithTheBestPartialCandidates) {
  std::vector<std::string> truth_set = kShortRun;
  truth_set.push_back("friction.coulomb=300");
  const Record r = make_synthetic_record(build_model(load_model_source(kModel, truth_set)), 0.01, 22, 5);
  DiagnoseOptions opt;
  opt.max_iterations = 15;
  opt.only = {"viscous_friction", "torque_offset", "sensor_delay.tip_deflection"};
  const Diagnosis d = diagnose(load_model_source(kModel, kShortRun), r, opt);
  const std::string text = format_diagnosis_text(d);
  EXPECT_EQ(d.verdict, "unexplained") << text;
  ASSERT_FALSE(d.ranking.empty());
  EXPECT_EQ(d.ranking[0].effect, "viscous_friction") << text;
  EXPECT_GT(d.ranking[0].explains, 0.3) << text;
  ASSERT_EQ(d.misfit.size(), d.channels.size());
  EXPECT_NE(text.find("of the misfit"), std::string::npos) << text;
}

// A logger that records what the controller read (the independent simulator's record.as_seen): the hub
// angle 2 samples late in the loop and in the record. The model's column is logged as read (the default),
// so the in-loop delay fits the angle and the tip at once: found to the sample, and it explains the record.
TEST(Diagnose, ALateHubAngleLoggedAsReadIsTheInLoopDelayToTheSample) {
  const Record r = make_truth_record({{"sensors.hub_angle.delay", "2"},
                                        {"sensors.hub_angle.noise", "1e-5"},
                                        {"record.as_seen", "true"}});
  DiagnoseOptions opt;
  opt.only = {"sensor_delay.hub_angle"};
  const Diagnosis d = diagnose(load_model_source(kModel, kShortRun), r, opt);
  ASSERT_EQ(d.verdict, "sensor_delay.hub_angle") << format_diagnosis_text(d);
  EXPECT_EQ(d.ranking[0].params.at("sensors.hub_angle.delay"), 2.0);
  EXPECT_TRUE(d.ranking[0].explained) << format_diagnosis_text(d);
}

// The same loop delay (6 samples) with the column stamped when read (the independent simulator's default), and
// a model that says the column is as read: no one delay of sensor_delay.hub_angle moves the loop and leaves
// the column on time, so loop_delay.hub_angle (the delay with logged: true) is ranked first, found to the
// sample, and explains the record.
TEST(Diagnose, ALoopDelayWithTheColumnOnTimeIsTheLoopDelayNotTheLateEncoder) {
  const Record r = make_truth_record({{"sensors.hub_angle.delay", "6"},
                                        {"sensors.hub_angle.noise", "1e-5"}});
  DiagnoseOptions opt;
  opt.only = {"sensor_delay.hub_angle", "loop_delay.hub_angle"};
  const Diagnosis d = diagnose(load_model_source(kModel, kShortRun), r, opt);
  ASSERT_EQ(d.verdict, "loop_delay.hub_angle") << format_diagnosis_text(d);
  EXPECT_EQ(d.ranking[0].params.at("sensors.hub_angle.delay"), 6.0);
  EXPECT_TRUE(d.ranking[0].explained) << format_diagnosis_text(d);
  ASSERT_EQ(d.ranking[1].effect, "sensor_delay.hub_angle");
  EXPECT_GT(d.ranking[1].delta_bic, d.ranking[0].delta_bic + 100.0) << format_diagnosis_text(d);
}

// An on-time hub angle (logged: true) stamped 12 samples late by its logger, the loop untouched: the
// logger's delay, found to the sample, and not the loop's (which would change the tip and torque too).
TEST(Diagnose, AnOnTimeAngleStampedLateIsTheLoggersDelay) {
  std::vector<std::string> base = kShortRun;
  base.push_back("sensors.hub_angle.logged=true");
  std::vector<std::string> truth = base;
  truth.push_back("sensors.hub_angle.logged_delay=12");
  const Record r = make_synthetic_record(build_model(load_model_source(kModel, truth)), 0.01, 31, 2);
  DiagnoseOptions opt;
  opt.only = {"logger_delay.hub_angle", "sensor_delay.hub_angle"};
  const Diagnosis d = diagnose(load_model_source(kModel, base), r, opt);
  ASSERT_EQ(d.verdict, "logger_delay.hub_angle") << format_diagnosis_text(d);
  EXPECT_EQ(d.ranking[0].params.at("sensors.hub_angle.logged_delay"), 12.0);
  // Logged as read (the default) there is no on-time column to be late: not a candidate.
  const auto names = make_candidate_effects(build_model(load_model_source(kModel, kShortRun)), ReplayMode::kClosedLoop,
                                            EffectScales{}, {"hub_angle"});
  EXPECT_TRUE(std::none_of(names.begin(), names.end(), [](const Effect& e) { return e.name == "logger_delay.hub_angle"; }));
  // Logged on time, the in-loop delay already leaves the column on time: loop_delay is not offered either.
  const auto on_time = make_candidate_effects(build_model(load_model_source(kModel, base)), ReplayMode::kClosedLoop,
                                              EffectScales{}, {"hub_angle"});
  EXPECT_TRUE(std::none_of(on_time.begin(), on_time.end(), [](const Effect& e) { return e.name == "loop_delay.hub_angle"; }));
}

// A worn gear in the independent simulator (its Coulomb level times 1 + 0.5 cos(20 theta + 2), atan-regularised)
// under a model that logs on time as the truth does: worn_gear_friction is ranked above the plain Coulomb
// level it extends, finds the waves within 0.1 and the ripple's a = 0.5 cos 2, b = -0.5 sin 2 within 0.05,
// and explains the record.
TEST(Diagnose, AWornGearsRippleIsFoundWithItsWavesAndPhase) {
  const Record r = make_truth_record({{"friction.coulomb", "300"},
                                        {"friction.position_amplitude", "0.5"},
                                        {"friction.position_waves", "20"},
                                        {"friction.position_phase", "2"},
                                        {"sensors.hub_angle.noise", "1e-5"}});
  std::vector<std::string> set = kShortRun;
  set.push_back("sensors.hub_angle.logged=true");
  DiagnoseOptions opt;
  opt.only = {"coulomb_friction", "worn_gear_friction"};
  const Diagnosis d = diagnose(load_model_source(kModel, set), r, opt);
  ASSERT_EQ(d.verdict, "worn_gear_friction") << format_diagnosis_text(d);
  const auto& p = d.ranking[0].params;
  EXPECT_NEAR(p.at("friction.position_waves"), 20.0, 0.1) << format_diagnosis_text(d);
  EXPECT_NEAR(p.at("friction.position_cos"), 0.5 * std::cos(2.0), 0.05) << format_diagnosis_text(d);
  EXPECT_NEAR(p.at("friction.position_sin"), -0.5 * std::sin(2.0), 0.05) << format_diagnosis_text(d);
  EXPECT_NEAR(p.at("friction.coulomb"), 300.0, 15.0);
}

// A 16-bit encoder quantised in the loop and logged as read, tachometer noise in the loop, nothing else
// hidden: the model that has the encoder's resolution predicts the quantised column as the loop read it;
// the record is not unexplained.
TEST(Diagnose, AnEncoderQuantisedInTheLoopAndLoggedIsNotUnexplained) {
  const Record r = make_truth_record({{"sensors.hub_angle.quantize", "true"},  // 16 bits
                                        {"sensors.hub_rate.noise", "5e-4"},       // tachometer noise in the loop, rad/s
                                        {"record.as_seen", "true"}});
  std::vector<std::string> set = kShortRun;
  set.push_back("sensors.hub_angle.resolution=9.587379924285257e-05");  // 2 pi / 2^16 rad
  DiagnoseOptions opt;
  opt.only = {"sensor_quantization", "sensor_delay.hub_angle"};
  const Diagnosis d = diagnose(load_model_source(kModel, set), r, opt);
  EXPECT_NE(d.verdict, "unexplained") << format_diagnosis_text(d);
  // Scored on the column as the loop read it, the encoder grid finds the rig's own 16 bits (on the column
  // taken as on time it picks 22 bits, 1.5e-6 rad: the quantum no longer shows in the prediction).
  bool found = false;
  for (const auto& f : d.ranking)
    if (f.effect == "sensor_quantization") {
      found = true;
      EXPECT_NEAR(f.params.at("sensors.hub_angle.resolution"), 2.0 * M_PI / 65536.0, 1e-15) << format_diagnosis_text(d);
    }
  EXPECT_TRUE(found) << format_diagnosis_text(d);
}

}  // namespace
}  // namespace ff
