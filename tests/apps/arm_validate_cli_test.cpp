// End-to-end tests of `flexfarm record`, `compare`, `diagnose` and `calibrate` on arm models
// (validate/arm_record.hpp, arm_compare.hpp, arm_diagnose.hpp): the two-link flexible arm's record
// compared with the arm itself (exactly, and with noise), with a heavier payload; friction hidden at the
// elbow diagnosed there and calibrated in; the URDF arm calibrated into another directory; bad records
// and options refused with one line, exit 2, nothing written.
#include <gtest/gtest.h>

#include "tests/apps/cli_fixture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace ff::test;

// The command line's fixture with the two-link flexible arm in work/configs.
class ArmCli : public CliFixture {
 protected:
  ArmCli() : CliFixture("ff_armcli_", {{"configs/two_link_flexible.yaml", "configs/arm.yaml"}}) {}
};

// 3 s of the arm: its 1.5 s move and half the settling.
const std::string kShort = " --set simulation.duration=3.0";

// compare.json's "fit_percent" of a channel (NaN when absent).
double json_fit(const std::string& json, const std::string& channel) {
  const auto block = json.find("\"fit_percent\": {");
  if (block == std::string::npos) return NAN;
  const auto at = json.find("\"" + channel + "\": ", block);
  if (at == std::string::npos) return NAN;
  return std::strtod(json.c_str() + at + channel.size() + 4, nullptr);
}

TEST_F(ArmCli, RecordWritesTheArmFormAndCompareWithTheSameArmFitsExactly) {
  const auto rec = run("record configs/arm.yaml --out rec.csv" + kShort);
  ASSERT_EQ(rec.exit_code, 0) << rec.output;
  const auto lines = split_lines(read_text(work / "rec.csv"));
  ASSERT_EQ(lines.size(), 1502u);  // the header and 1501 samples at 500 Hz
  EXPECT_EQ(lines[0],
            "t,shoulder.ref,shoulder.angle,shoulder.rate,shoulder.torque,elbow.ref,elbow.angle,elbow.rate,elbow.torque,"
            "tool.x,tool.y,tool.z,upper_arm.deflection_y,upper_arm.deflection_z,forearm.deflection_y,forearm.deflection_z");
  const auto r = run("compare --model configs/arm.yaml --data rec.csv --out cmp" + kShort);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("| shoulder.angle | rad | 100.00 | 0 |"), std::string::npos) << r.output;
  const std::string json = read_text(work / "cmp" / "compare.json");
  for (const char* c : {"shoulder.angle", "elbow.angle", "shoulder.torque", "elbow.torque", "tool.x", "tool.y",
                        "upper_arm.deflection_y", "forearm.deflection_y"})
    EXPECT_EQ(json_fit(json, c), 100.0) << c << "\n" << json;
  EXPECT_NE(json.find("\"not_scored\": [\"tool.z\", \"upper_arm.deflection_z\", \"forearm.deflection_z\"]"),
            std::string::npos) << json;
  EXPECT_NE(read_text(work / "cmp" / "report.md").find("| elbow.torque | N m | 100.00 | 0 |"), std::string::npos);
  for (const char* p : {"overlay_shoulder_angle.png", "overlay_elbow_torque.png", "residual_tool_x.png",
                        "acf_elbow_angle.png", "ccf_forearm_deflection_y.png", "spectrum_shoulder_torque.png"})
    expect_png(work / "cmp" / p);
  for (const auto& f : tree(work)) EXPECT_EQ(f.find(".partial"), std::string::npos) << f;
}

TEST_F(ArmCli, CompareWithKWritesTheKStepColumnsBesideTheFreeRun) {
  // Friction hidden at the elbow (0.15 N m), 0.2 mrad of noise on the angles: the k-step prediction
  // (20 samples, 40 ms) from the observer's estimate fits the elbow's angle and the tool far better
  // than the free run, whose error grows over the move.
  ASSERT_EQ(run("record configs/arm.yaml --out rec.csv --noise-angle 2e-4 --seed 3 --set joints.elbow.friction.coulomb=0.15" +
                kShort).exit_code, 0);
  const auto r = run("compare --model configs/arm.yaml --data rec.csv --out cmp --k 20" + kShort);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("| channel | unit | fit % free run | fit % k-step | RMSE free run | RMSE k-step |"),
            std::string::npos) << r.output;
  const std::string json = read_text(work / "cmp" / "compare.json");
  EXPECT_NE(json.find("\"k\": 20,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"replay_ok\": {\"free_run\": true, \"k_step\": true}"), std::string::npos) << json;
  EXPECT_NE(json.find("\"observer\": {\"ok\": true, \"channels\": [\"shoulder.angle\", \"shoulder.rate\""),
            std::string::npos) << json;
  // compare.json's k-step map, read as the free run's is.
  std::string k_json = json.substr(json.find("\"k_step_fit_percent\": {"));
  k_json.replace(0, 8, "\"");  // "k_step_fit_percent" -> "fit_percent"
  for (const char* c : {"elbow.angle", "tool.x", "tool.y"}) {
    const double free_fit = json_fit(json, c), k_fit = json_fit(k_json, c);
    RecordProperty(std::string(c) + "_free", std::to_string(free_fit));
    RecordProperty(std::string(c) + "_k20", std::to_string(k_fit));
    EXPECT_GT(k_fit, free_fit + 1.0) << c << "\n" << json;
    EXPECT_GT(k_fit, 99.0) << c;
  }
  const std::string report = read_text(work / "cmp" / "report.md");
  EXPECT_NE(report.find("The k-step prediction restarts every 20 controller samples (0.04 s)"), std::string::npos) << report;
  EXPECT_NE(report.find("k-step prediction errors:"), std::string::npos) << report;
  for (const char* p : {"overlay_elbow_angle.png", "residual_tool_x.png", "acf_elbow_angle.png", "spectrum_tool_y.png"})
    expect_png(work / "cmp" / p);
  // Without --k the arm's compare is the free run alone, as before.
  ASSERT_EQ(run("compare --model configs/arm.yaml --data rec.csv --out free" + kShort).exit_code, 0);
  const std::string free_json = read_text(work / "free" / "compare.json");
  EXPECT_NE(free_json.find("\"k\": null"), std::string::npos) << free_json;
  EXPECT_EQ(free_json.find("k_step_fit_percent"), std::string::npos);
  EXPECT_EQ(json_fit(free_json, "elbow.angle"), json_fit(json, "elbow.angle"));
}

TEST_F(ArmCli, NoiseOnTheMeasuredChannelsLowersTheFitOnlyAsMuchAsTheNoise) {
  // 1 mrad on angles (about 1/400 of each joint's swing), 5 mN m on torques (about 1/100 of each's).
  ASSERT_EQ(run("record configs/arm.yaml --out rec.csv --noise-angle 1e-3 --noise-torque 0.005 --seed 5" + kShort).exit_code, 0);
  const auto r = run("compare --model configs/arm.yaml --data rec.csv --out cmp" + kShort);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string json = read_text(work / "cmp" / "compare.json");
  for (const char* c : {"shoulder.angle", "elbow.angle"}) {
    RecordProperty(std::string(c) + "_fit", std::to_string(json_fit(json, c)));
    EXPECT_GT(json_fit(json, c), 99.0) << c << "\n" << json;
    EXPECT_LT(json_fit(json, c), 100.0) << c;
  }
  for (const char* c : {"shoulder.torque", "elbow.torque"}) {
    RecordProperty(std::string(c) + "_fit", std::to_string(json_fit(json, c)));
    EXPECT_GT(json_fit(json, c), 98.0) << c << "\n" << json;
  }
  EXPECT_EQ(json_fit(json, "tool.x"), 100.0);  // no --noise-position
  // The same seed, the same record; another seed, another.
  ASSERT_EQ(run("record configs/arm.yaml --out again.csv --noise-angle 1e-3 --noise-torque 0.005 --seed 5" + kShort).exit_code, 0);
  EXPECT_EQ(read_text(work / "again.csv"), read_text(work / "rec.csv"));
  ASSERT_EQ(run("record configs/arm.yaml --out other.csv --noise-angle 1e-3 --noise-torque 0.005 --seed 6" + kShort).exit_code, 0);
  EXPECT_NE(read_text(work / "other.csv"), read_text(work / "rec.csv"));
}

TEST_F(ArmCli, AHeavierPayloadInTheRecordLowersTheTorqueFits) {
  // Recorded with the forearm's tip payload 25 % heavier (0.25 kg); compared with the nominal arm and with the heavy one.
  const std::string heavy = " --set 'bodies[forearm].flexible.payload.mass=0.25'";
  ASSERT_EQ(run("record configs/arm.yaml --out rec.csv --noise-angle 1e-4 --noise-torque 1e-3" + kShort + heavy).exit_code, 0);
  ASSERT_EQ(run("compare --model configs/arm.yaml --data rec.csv --out nominal" + kShort).exit_code, 0);
  ASSERT_EQ(run("compare --model configs/arm.yaml --data rec.csv --out heavy" + kShort + heavy).exit_code, 0);
  const std::string nominal = read_text(work / "nominal" / "compare.json"), same = read_text(work / "heavy" / "compare.json");
  for (const char* c : {"shoulder.torque", "elbow.torque"}) {
    RecordProperty(std::string(c) + "_fit_nominal", std::to_string(json_fit(nominal, c)));
    RecordProperty(std::string(c) + "_fit_heavy", std::to_string(json_fit(same, c)));
    EXPECT_GT(json_fit(same, c), 99.0) << c;
    EXPECT_LT(json_fit(nominal, c), 85.0) << c;
  }
}

TEST_F(ArmCli, ARecordMissingAJointColumnOrNamingAnUnknownJointIsOneErrorAndWritesNothing) {
  ASSERT_EQ(run("record configs/arm.yaml --out rec.csv" + kShort).exit_code, 0);
  const auto lines = split_lines(read_text(work / "rec.csv"));
  // Without elbow.angle (column 7), and with it renamed wrist.angle.
  auto drop = [](const std::string& line, int col) {
    std::vector<std::string> cells;
    std::stringstream in(line);
    for (std::string c; std::getline(in, c, ',');) cells.push_back(c);
    std::string out;
    for (std::size_t i = 0; i < cells.size(); ++i)
      if (static_cast<int>(i) != col) out += (out.empty() ? "" : ",") + cells[i];
    return out;
  };
  std::string missing, unknown = "t,shoulder.ref,shoulder.angle,shoulder.rate,shoulder.torque,elbow.ref,wrist.angle" +
                                 lines[0].substr(lines[0].find(",elbow.rate")) + "\n";
  for (std::size_t k = 0; k < lines.size(); ++k) {
    missing += drop(lines[k], 6) + "\n";
    if (k > 0) unknown += lines[k] + "\n";
  }
  write("missing.csv", missing);
  write("unknown.csv", unknown);
  const auto before = tree(work);
  const auto a = run("compare --model configs/arm.yaml --data missing.csv --out out");
  EXPECT_EQ(a.exit_code, 2) << a.output;
  expect_one_error_line(a, "missing.csv:1: elbow.angle: missing column 'elbow.angle', needed for an arm model");
  const auto b = run("compare --model configs/arm.yaml --data unknown.csv --out out");
  EXPECT_EQ(b.exit_code, 2) << b.output;
  expect_one_error_line(b, "unknown.csv:1: wrist.angle: 'wrist' is not an actuated joint of the model (its actuated "
                           "joints: shoulder, elbow)");
  // The rig's record form with an arm model, and the rig's options the arm compare has not.
  write("rig.csv", "t,ref,hub_angle\n" + [] {
    std::string s;
    for (int k = 0; k < 30; ++k) s += std::to_string(0.002 * k) + ",0.1,0.0\n";
    return s;
  }());
  const auto c = run("compare --model configs/arm.yaml --data rig.csv --out out");
  EXPECT_EQ(c.exit_code, 2) << c.output;
  expect_one_error_line(c, "rig.csv:1: shoulder.ref: missing column 'shoulder.ref', needed for an arm model (this record "
                           "is in the reference rig's form");
  const auto d = run("compare --model configs/arm.yaml --data rec.csv --process-noise 2 --out out");
  EXPECT_EQ(d.exit_code, 2) << d.output;
  expect_one_error_line(d, "--process-noise: the k-step prediction's option: give --k too");
  auto after = tree(work);
  after.erase(std::remove(after.begin(), after.end(), "rig.csv"), after.end());
  EXPECT_EQ(after, before) << "compare writes nothing";
  // record: the rig's noise option with an arm model, and the arm's with the rig's model.
  const auto e = run("record configs/arm.yaml --out x.csv --noise 0.1");
  EXPECT_EQ(e.exit_code, 2) << e.output;
  expect_one_error_line(e, "--noise: not for an arm model");
  fs::copy_file(kSource + "/configs/fbtb.yaml", work / "configs" / "fbtb.yaml");
  const auto f = run("record configs/fbtb.yaml --out x.csv --noise-angle 0.1");
  EXPECT_EQ(f.exit_code, 2) << f.output;
  expect_one_error_line(f, "--noise-angle: only for an arm model");
  EXPECT_FALSE(fs::exists(work / "x.csv"));
  // diagnose and calibrate on an arm: closed loop only; effects carry their joint.
  const auto g = run("diagnose --model configs/arm.yaml --data rec.csv --json d.json --mode open-loop");
  EXPECT_EQ(g.exit_code, 2) << g.output;
  expect_one_error_line(g, "--mode: an arm model is diagnosed in closed loop only");
  const auto h = run("calibrate --model configs/arm.yaml --data rec.csv --add payload --out m/model.yaml");
  EXPECT_EQ(h.exit_code, 2) << h.output;
  expect_one_error_line(h, "--add: unknown effect 'payload' (this model offers: coulomb_friction@shoulder, worn_gear_friction@shoulder, "
                           "viscous_friction@shoulder,");
  EXPECT_FALSE(fs::exists(work / "d.json"));
  EXPECT_FALSE(fs::exists(work / "m"));
}

// Friction hidden at the elbow: diagnose names it, calibrate adds it with its level, and the ledger
// shows the error falling on every channel that moved.
TEST_F(ArmCli, DiagnoseFindsAPayloadTheControllerDoesNotKnow) {
  // The record of an arm whose forearm carries 0.3 kg while its controller's inverse dynamics keeps the
  // nominal 0.2 kg (--plant-set): diagnose's payload candidate changes the plant only, so it fits 0.3 kg
  // and explains the record (docs/formats.md, "The controller's model"). With --set the controller knows
  // the payload: the recorded torques differ.
  const std::string payload = "'bodies[forearm].flexible.payload.mass=0.3'";
  ASSERT_EQ(run("record configs/arm.yaml --out rec.csv --noise-angle 2e-4 --noise-torque 0.01 --seed 3 --plant-set " + payload +
                kShort).exit_code, 0);
  ASSERT_EQ(run("record configs/arm.yaml --out known.csv --noise-angle 2e-4 --noise-torque 0.01 --seed 3 --set " + payload +
                kShort).exit_code, 0);
  EXPECT_NE(read_text(work / "rec.csv"), read_text(work / "known.csv"));
  const auto d = run("diagnose --model configs/arm.yaml --data rec.csv --json d.json --iterations 10 --effects payload@forearm" +
                     kShort);
  ASSERT_EQ(d.exit_code, 0) << d.output;
  EXPECT_NE(d.output.find("verdict: payload@forearm is missing"), std::string::npos) << d.output;
  const std::string json = read_text(work / "d.json");
  const auto at = json.find("\"bodies[forearm].flexible.payload.mass\": ");
  ASSERT_NE(at, std::string::npos) << json;
  EXPECT_NEAR(std::strtod(json.c_str() + at + 41, nullptr), 0.3, 0.003) << json;
}

TEST_F(ArmCli, DiagnoseFindsFrictionHiddenAtTheElbowAndCalibrateAddsIt) {
  const std::string hidden = " --set joints.elbow.friction.coulomb=0.15";
  ASSERT_EQ(run("record configs/arm.yaml --out rec.csv --noise-angle 2e-4 --noise-torque 0.01 --seed 3" + kShort + hidden)
                .exit_code, 0);
  const auto d = run("diagnose --model configs/arm.yaml --data rec.csv --json d.json --iterations 10 --effects "
                     "coulomb_friction@elbow,coulomb_friction@shoulder,torque_offset@elbow" + kShort);
  ASSERT_EQ(d.exit_code, 0) << d.output;
  EXPECT_NE(d.output.find("verdict: coulomb_friction@elbow is missing"), std::string::npos) << d.output;
  EXPECT_NE(read_text(work / "d.json").find("\"verdict\": \"coulomb_friction@elbow\""), std::string::npos);
  const auto c = run("calibrate --model configs/arm.yaml --data rec.csv --add coulomb_friction@elbow --out cal/arm.yaml "
                     "--iterations 10" + kShort);
  ASSERT_EQ(c.exit_code, 0) << c.output;
  // The calibrated model: the friction at its fitted level, within 3 % of the truth.
  const std::string yaml = read_text(work / "cal" / "arm.yaml");
  const auto at = yaml.find("coulomb: ");
  ASSERT_NE(at, std::string::npos) << yaml;
  EXPECT_NEAR(std::strtod(yaml.c_str() + at + 9, nullptr), 0.15, 0.0045) << yaml;
  EXPECT_NE(c.output.find("2  coulomb_friction@elbow"), std::string::npos) << c.output;  // the ledger's version 2
  EXPECT_TRUE(fs::exists(work / "cal" / "ledger.sqlite.png"));
  // Compared with the record, the calibrated model fits the elbow's torque far better than the base.
  ASSERT_EQ(run("compare --model configs/arm.yaml --data rec.csv --out before" + kShort).exit_code, 0);
  ASSERT_EQ(run("compare --model cal/arm.yaml --data rec.csv --out after").exit_code, 0);
  const double before = json_fit(read_text(work / "before" / "compare.json"), "elbow.torque");
  const double after = json_fit(read_text(work / "after" / "compare.json"), "elbow.torque");
  RecordProperty("elbow_torque_fit_before", std::to_string(before));
  RecordProperty("elbow_torque_fit_after", std::to_string(after));
  EXPECT_LT(before, 90.0);
  EXPECT_GT(after, 95.0);
}

// The URDF arm calibrated into another directory: the written model's urdf and sidecar still resolve.
TEST_F(ArmCli, ACalibratedURDFArmWrittenElsewhereStillFindsItsURDF) {
  fs::create_directories(work / "configs" / "urdf");
  fs::copy_file(kSource + "/configs/arm6.yaml", work / "configs" / "arm6.yaml");
  for (const char* f : {"arm6.urdf", "arm6_sidecar.yaml"})
    fs::copy_file(kSource + "/configs/urdf/" + f, work / "configs" / "urdf" / f);
  const std::string shortrun = " --set simulation.duration=1.0";
  ASSERT_EQ(run("record configs/arm6.yaml --out rec.csv --noise-torque 0.01 --set joints.wrist_1.torque_offset=1.5" + shortrun)
                .exit_code, 0);
  const auto c = run("calibrate --model configs/arm6.yaml --data rec.csv --add torque_offset@wrist_1 --out "
                     "elsewhere/deeper/arm6.yaml --iterations 6" + shortrun);
  ASSERT_EQ(c.exit_code, 0) << c.output;
  const std::string yaml = read_text(work / "elsewhere" / "deeper" / "arm6.yaml");
  EXPECT_NE(yaml.find("urdf: ../../configs/urdf/arm6.urdf"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("sidecar: ../../configs/urdf/arm6_sidecar.yaml"), std::string::npos) << yaml;
  const auto s = run("simulate elsewhere/deeper/arm6.yaml --out sim");
  EXPECT_EQ(s.exit_code, 0) << s.output;
}

}  // namespace
