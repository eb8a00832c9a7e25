// Arm measurement records (validate/arm_record.hpp) and compare on arm models (validate/arm_compare.hpp):
// the replay hook against the model's own trajectory, a model against its own record (exact without
// noise, the noise's fit with it), a heavier payload seen on the right channels, a resampled record,
// and the record's checks naming the file, line 1 and the column.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "arm/arm_simulate.hpp"
#include "common/errors.hpp"
#include "sweep/paths.hpp"
#include "tests/temp_dir.hpp"
#include "validate/arm_compare.hpp"
#include "validate/arm_record.hpp"
#include "validate/residuals.hpp"

namespace ff {
namespace {

const std::string kArm = std::string(FLEXFARM_SOURCE_DIR) + "/configs/two_link_flexible.yaml";
// 3 s: the 1.5 s move and half its settling, 1501 samples at 500 Hz.
const std::string kDuration = "simulation.duration=3.0";

ArmModel two_link(std::vector<std::string> sets = {}) {
  sets.insert(sets.begin(), kDuration);
  return load_arm_with(kArm, sets);
}

// The record written with every digit and read back as `flexfarm compare` reads it.
Record written_and_read(const Record& r, const ArmModel& m, const test::TempDir& dir) {
  const std::string path = (dir.path / "rec.csv").string();
  write_record_csv(r, arm_record_columns(m), path, 17);
  Record back = read_record_csv(path, {});
  check_arm_record(back, m);
  return back;
}

const ChannelCompare& channel(const ArmCompareResult& r, const std::string& name) {
  for (const auto& c : r.channels)
    if (c.name == name) return c;
  throw std::out_of_range("no channel " + name);
}

std::string check_error(const Record& r, const ArmModel& m) {
  try {
    check_arm_record(r, m);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ArmReplay, TheSampledReferenceWithDifferencedFeedForwardFollowsTheAnalyticRun) {
  // The replay hook's one approximation: r' and r'' of the feed-forward from central differences of the
  // controller samples instead of the trajectory's own. On the two-link arm (feed-forward 1, a quintic
  // 1.5 s move at 500 Hz) the runs agree to 2-3 micro-radians in the joint angles and 4 micrometres at
  // the tool; the torques differ most (5 mN m, 1 % of the peak) at the first sample, where the
  // differences see the start at rest (r'' = r[1] / T^2, the quintic's 0).
  const ArmModel m = two_link();
  const ArmRun analytic = simulate_arms(std::span<const ArmModel>(&m, 1));
  const auto ref = sample_arm_reference(m);
  ArmRunOptions o;
  o.reference = &ref;
  const ArmRun replayed = simulate_arms(std::span<const ArmModel>(&m, 1), o);
  ASSERT_EQ(replayed.status[0], LaneStatus::kOk);
  for (const char* c : {"shoulder.q", "elbow.q", "shoulder.torque", "elbow.torque", "tool.x", "tool.y"}) {
    const auto& a = analytic.traces[0].column(c);
    const auto& b = replayed.traces[0].column(c);
    double worst = 0.0;
    for (std::size_t k = 0; k < a.size(); ++k) worst = std::max(worst, std::abs(a[k] - b[k]));
    RecordProperty(std::string(c) + "_max_difference", std::to_string(worst));
    EXPECT_GT(calc_fit(a, b).percent, 99.98) << c;
    if (std::string(c).find("torque") == std::string::npos) {
      EXPECT_LT(worst, 1e-5) << c;
    }
  }
  // The reference itself is the same.
  EXPECT_EQ(analytic.traces[0].column("elbow.ref"), replayed.traces[0].column("elbow.ref"));
  // A reference of the wrong shape is refused.
  const std::vector<std::vector<double>> one{ref[0]};
  o.reference = &one;
  EXPECT_THROW(simulate_arms(std::span<const ArmModel>(&m, 1), o), std::invalid_argument);
}

TEST(ArmCompare, AModelAgainstItsOwnNoiseFreeRecordFitsExactly) {
  const test::TempDir dir("ff_arm_record");
  const ArmModel m = two_link();
  const Record r = written_and_read(make_arm_record(m, {}, 1), m, dir);
  EXPECT_TRUE(is_arm_record(r));
  EXPECT_EQ(r.size(), 1501u);
  const ArmCompareResult c = compare_arm_record(m, r);
  EXPECT_TRUE(c.ok);
  EXPECT_FALSE(c.resampled);
  // Angles, torques, the tool in the plane, both links' in-plane deflection; z is constant (planar).
  ASSERT_EQ(c.channels.size(), 8u) << format_arm_fit_table(c);
  for (const auto& ch : c.channels) {
    EXPECT_EQ(ch.fit_free.percent, 100.0) << ch.name;
    EXPECT_EQ(ch.fit_free.rmse, 0.0) << ch.name;
  }
  EXPECT_EQ(c.constant, (std::vector<std::string>{"tool.z", "upper_arm.deflection_z", "forearm.deflection_z"}));
  EXPECT_NE(format_arm_compare_report(c).find("the residual is zero"), std::string::npos);
}

TEST(ArmCompare, NoiseLowersTheFitAsItsLevelPredicts) {
  // Noise of deviation s on a channel of deviation sd about its mean: fit = 100 (1 - s / sd) and RMSE = s,
  // to the sampling error of 1501 draws (a few %).
  const test::TempDir dir("ff_arm_record");
  const ArmModel m = two_link();
  ArmRecordNoise noise;
  noise.angle = 2e-3;   // rad
  noise.torque = 0.05;  // N m
  noise.position = 1e-4;
  const Record clean = make_arm_record(m, {}, 7);
  const Record r = written_and_read(make_arm_record(m, noise, 7), m, dir);
  const ArmCompareResult c = compare_arm_record(m, r);
  for (const char* name : {"shoulder.angle", "elbow.angle", "shoulder.torque", "elbow.torque", "tool.x"}) {
    const std::string n = name;
    const double s = n.find("angle") != std::string::npos ? noise.angle : n.find("torque") != std::string::npos ? noise.torque : noise.position;
    const double expected = 100.0 * (1.0 - s / calc_standard_deviation(clean.at(n)));
    const ChannelCompare& ch = channel(c, n);
    RecordProperty(n + "_fit", std::to_string(ch.fit_free.percent));
    RecordProperty(n + "_expected", std::to_string(expected));
    EXPECT_NEAR(ch.fit_free.rmse, s, 0.06 * s) << n;
    EXPECT_NEAR(100.0 - ch.fit_free.percent, 100.0 - expected, 0.06 * (100.0 - expected)) << n;
  }
  EXPECT_GT(channel(c, "shoulder.angle").fit_free.percent, 99.0);
  EXPECT_GT(channel(c, "elbow.angle").fit_free.percent, 99.0);
  // The residual is the noise: white.
  EXPECT_TRUE(channel(c, "elbow.angle").free_analysis.failure.white);
}

TEST(ArmCompare, AHeavierPayloadLowersTheFitOfTheTorquesAndTheForearmDeflection) {
  // The record from the arm with the forearm's tip payload 25 % heavier (0.2 -> 0.25 kg), compared with
  // the nominal model: the drives' torques and the links' bending show it most (fits in the 60s-70s, the
  // joint angles in the 90s).
  const test::TempDir dir("ff_arm_record");
  const ArmModel nominal = two_link();
  const ArmModel heavy = two_link({"bodies[forearm].flexible.payload.mass=0.25"});
  ArmRecordNoise noise;
  noise.angle = 1e-4;
  noise.torque = 1e-3;
  const Record r = written_and_read(make_arm_record(heavy, noise, 3), nominal, dir);
  const ArmCompareResult same = compare_arm_record(heavy, r), other = compare_arm_record(nominal, r);
  for (const char* n : {"shoulder.torque", "elbow.torque", "forearm.deflection_y", "shoulder.angle", "elbow.angle"}) {
    RecordProperty(std::string(n) + "_fit_same", std::to_string(channel(same, n).fit_free.percent));
    RecordProperty(std::string(n) + "_fit_nominal", std::to_string(channel(other, n).fit_free.percent));
  }
  for (const char* n : {"shoulder.torque", "elbow.torque", "forearm.deflection_y"}) {
    EXPECT_GT(channel(same, n).fit_free.percent, 99.0) << n;
    EXPECT_LT(channel(other, n).fit_free.percent, 85.0) << n;
  }
  // The angles less so: the controllers hold them.
  for (const char* n : {"shoulder.angle", "elbow.angle"}) {
    EXPECT_GT(channel(other, n).fit_free.percent, channel(other, "elbow.torque").fit_free.percent + 10.0) << n;
    EXPECT_LT(channel(other, n).fit_free.percent, 99.0) << n;
  }
}

TEST(ArmCompare, ARecordAtAnotherRateIsResampledToTheControllerRate) {
  // The model's own record at 500 Hz, replayed by the same arm with a 1 kHz controller: the references
  // interpolated at 1 kHz, the outputs back at the record's times; a different controller, so a near fit.
  const test::TempDir dir("ff_arm_record");
  const ArmModel m = two_link();
  Record r = written_and_read(make_arm_record(m, {}, 1), m, dir);
  const ArmModel fast = two_link({"controller.rate=1000"});
  const ArmCompareResult c = compare_arm_record(fast, r);
  EXPECT_TRUE(c.resampled);
  EXPECT_TRUE(c.ok);
  for (const char* n : {"shoulder.angle", "elbow.angle", "tool.x", "tool.y"}) {
    RecordProperty(std::string(n) + "_fit", std::to_string(channel(c, n).fit_free.percent));
    EXPECT_GT(channel(c, n).fit_free.percent, 98.0) << n;
  }
}

TEST(ArmCompare, TheReplayStartsAtTheRecordsFirstReferencesAndTheSagThere) {
  // Recorded from another start pose (shoulder 0.4 rad, elbow -0.3 rad, the same waypoint) and at
  // another clock (the record's t from 10 s): the model with the default start, replayed, starts where
  // the record does, the links at their static sag there, and fits the record to the statics' tolerance.
  const test::TempDir dir("ff_arm_record");
  const ArmModel moved = two_link({"trajectory.start={shoulder: 0.4, elbow: -0.3}"});
  Record r = make_arm_record(moved, {}, 1);
  for (double& t : r.t) t += 10.0;
  r = written_and_read(r, moved, dir);
  const ArmCompareResult c = compare_arm_record(two_link(), r);
  EXPECT_FALSE(c.resampled);
  for (const auto& ch : c.channels) {
    RecordProperty(ch.name + "_fit", std::to_string(ch.fit_free.percent));
    EXPECT_GT(ch.fit_free.percent, 99.9) << ch.name;
  }
}

// joints.NAME.sensors.angle.logged: a late, quantised shoulder encoder. Logged as read (the default) the
// record's .angle is the controller's input (the trace's .q_measured) and the model predicts it so, exactly;
// logged on time it is the joint's coordinate itself.
TEST(ArmRecord, AnAngleLoggedAsReadIsTheControllersInputAndIsPredictedSo) {
  const std::vector<std::string> late = {"joints.shoulder.sensors.angle.delay=4",
                                         "joints.shoulder.sensors.angle.resolution=1e-4"};
  const ArmModel m = two_link(late);
  const Record r = make_arm_record(m, ArmRecordNoise{}, 1);
  ArmRunOptions o;
  const std::vector<std::vector<double>> ref = sample_arm_reference(m);
  o.reference = &ref;
  const ArmTrace tr = simulate_arms(std::span<const ArmModel>(&m, 1), o).traces[0];
  EXPECT_EQ(r.at("shoulder.angle"), tr.column("shoulder.q_measured"));
  const std::vector<double>& q = tr.column("shoulder.q");
  for (std::size_t k = 0; k < q.size(); ++k)
    ASSERT_EQ(r.at("shoulder.angle")[k], 1e-4 * std::nearbyint(q[k >= 4 ? k - 4 : 0] / 1e-4)) << k;
  const ArmReplay p = replay_arm_record(m, r);
  ASSERT_TRUE(p.ok);
  EXPECT_EQ(p.at_record.at("shoulder.angle"), r.at("shoulder.angle"));
  // The same arm logged on time: the column is the coordinate, and the late record is missed by the delay.
  std::vector<std::string> on_time = late;
  on_time.push_back("joints.shoulder.sensors.angle.logged=true");
  const ArmModel t = two_link(on_time);
  EXPECT_EQ(make_arm_record(t, ArmRecordNoise{}, 1).at("shoulder.angle"), q);
  EXPECT_EQ(replay_arm_record(t, r).at_record.at("shoulder.angle"), q);
}

TEST(ArmRecordCheck, AMissingOrUnknownJointColumnIsNamedWithTheFileLineOneAndTheColumn) {
  const ArmModel m = two_link();
  Record r = make_arm_record(m, {}, 1);
  r.source = "rec.csv";
  EXPECT_EQ(check_error(r, m), "no error");
  Record missing = r;
  missing.columns.erase("elbow.angle");
  EXPECT_EQ(check_error(missing, m), "rec.csv:1: elbow.angle: missing column 'elbow.angle', needed for an arm model");
  Record unknown = r;
  unknown.columns["wrist.angle"] = r.at("elbow.angle");
  EXPECT_EQ(check_error(unknown, m),
            "rec.csv:1: wrist.angle: 'wrist' is not an actuated joint of the model (its actuated joints: shoulder, elbow)");
  Record link = r;
  link.columns["hand.deflection_y"] = r.at("elbow.angle");
  EXPECT_EQ(check_error(link, m), "rec.csv:1: hand.deflection_y: 'hand' is not a flexible link of the model (its "
                                  "flexible links: upper_arm, forearm)");
  Record rig;
  rig.source = "rig.csv";
  rig.t = r.t;
  rig.columns["ref"] = rig.columns["hub_angle"] = r.at("elbow.angle");
  EXPECT_FALSE(is_arm_record(rig));
  EXPECT_EQ(check_error(rig, m), "rig.csv:1: shoulder.ref: missing column 'shoulder.ref', needed for an arm model (this "
                                 "record is in the reference rig's form: ref, hub_angle, ...)");
  EXPECT_EQ(arm_record_unit(m, "elbow.torque"), "N m");
  EXPECT_EQ(arm_record_unit(m, "forearm.deflection_y"), "m");
}


TEST(ArmRecordCheck, TheTwoToolMachinesRecordHasEachToolsChannelsAndARigidForearmNoDeflection) {
  // configs/sers.yaml: tools left and right; its forearms rigid (one segment), then flexible.
  const std::string sers = std::string(FLEXFARM_SOURCE_DIR) + "/configs/sers.yaml";
  const ArmModel rigid = load_arm_with(sers, {"simulation.duration=0.5"});
  const std::vector<std::string> c = arm_record_columns(rigid);
  for (const char* k : {"left.x", "left.y", "left.z", "right.x", "right.y", "right.z"})
    EXPECT_NE(std::find(c.begin(), c.end(), k), c.end()) << k;
  EXPECT_EQ(std::find(c.begin(), c.end(), "left_forearm.deflection_y"), c.end());
  EXPECT_TRUE(is_arm_tool_column(rigid, "right.z"));
  EXPECT_FALSE(is_arm_tool_column(rigid, "tool.x"));
  const ArmModel flexible = load_arm_with(sers, {"simulation.duration=0.5", "bodies[left_forearm].flexible.segments=4"});
  const std::vector<std::string> f = arm_record_columns(flexible);
  EXPECT_NE(std::find(f.begin(), f.end(), "left_forearm.deflection_y"), f.end());
  EXPECT_EQ(std::find(f.begin(), f.end(), "right_forearm.deflection_y"), f.end());
  // A model against its own record: every tool channel exact; a misspelt tool column named.
  Record r = make_arm_record(rigid, {}, 1);
  r.source = "rec.csv";
  const ArmCompareResult cmp = compare_arm_record(rigid, r);
  ASSERT_TRUE(cmp.ok);
  for (const char* k : {"left.x", "right.y"}) EXPECT_EQ(channel(cmp, k).fit_free.rmse, 0.0) << k;
  r.columns["right.w"] = r.at("right.x");
  EXPECT_EQ(check_error(r, rigid), "rec.csv:1: right.w: unknown tool column (right.x, right.y, right.z: the tool point, base frame, m)");
}

}  // namespace
}  // namespace ff
