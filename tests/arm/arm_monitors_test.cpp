// Tests of the safety monitors (`monitors:`, arm_model.hpp's ArmMonitor, evaluated in arm_simulate.cpp's
// sample loop; metrics MonitorMetrics). Closed forms: a body falling freely on a vertical slide
// (q = g t^2 / 2, qd = g t) trips a speed monitor at the first sample past v / g, a brake stops it in
// v^2 / (2 (F_b / m - g)); a controlled stop's reference has the second difference -a T^2; a command
// trips at its time and a delay holds the action back by whole samples. Invariants: the same bits in any
// lane of a batch, online metrics the stored ones; every YAML mistake named by its key and line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "arm/arm_metrics.hpp"
#include "arm/arm_online_metrics.hpp"
#include "arm/arm_simulate.hpp"
#include "arm/arm_yaml.hpp"
#include "tests/arm/test_support.hpp"

namespace ff {
namespace {

using test::arm_error;
using test::arm_from;
using test::pendulum_arm;

constexpr double kG = 9.81, kT = 1e-3;

// Monitor lines indented under `monitors:`.
std::string indented(const std::string& lines) {
  std::string out = "  ";
  for (char c : lines) out += c == '\n' ? std::string("\n  ") : std::string(1, c);
  return out.substr(0, out.size() - 2);
}

// A 1 kg body on a vertical slide (q down, the tool at the body), no control: it falls freely from rest.
std::string falling_body(const std::string& monitors, double duration = 0.5) {
  return R"(gravity: [0, 0, -9.81]
bodies:
  - name: body
    parent: base
    mass: 1.0
    inertia: {ixx: 0.001, iyy: 0.001, izz: 0.001}
    joint: {type: prismatic, axis: [0, 0, -1]}
controller: {rate: 1000}
joints:
  body: {controller: {kp: 0}}
simulation: {duration: )" +
         std::to_string(duration) + R"(}
monitors:
)" + indented(monitors);
}

// The tracking pendulum with its tool at its end, 1 m out, moving to q_end; `more` blocks after.
std::string moving_pendulum(double q_end, const std::string& more) {
  return test::tracking_pendulum(q_end, "tool: {point: [1, 0, 0]}\n", more);
}

// To 1 rad, with `monitors`.
std::string swinging_pendulum(const std::string& monitors) {
  return moving_pendulum(1.0, monitors.empty() ? "" : "monitors:\n" + indented(monitors));
}

struct Result {
  ArmTrace trace;
  std::vector<std::string> columns;
  std::vector<double> values;
  double metric(const std::string& name) const {
    const auto it = std::find(columns.begin(), columns.end(), name);
    EXPECT_NE(it, columns.end()) << name;
    return it == columns.end() ? std::nan("") : values[static_cast<std::size_t>(it - columns.begin())];
  }
};

Result run(const ArmModel& m) {
  ArmRun r = simulate_arms(std::span<const ArmModel>(&m, 1));
  EXPECT_EQ(r.status[0], LaneStatus::kOk);
  Result out{std::move(r.traces[0]), arm_metric_columns(m), {}};
  out.values = calc_arm_metrics(m, out.trace, r.status[0]);
  return out;
}

// The first sample at which a column is 1.
std::size_t first_one(const std::vector<double>& x) {
  std::size_t k = 0;
  while (k < x.size() && x[k] != 1.0) ++k;
  return k;
}

TEST(ArmMonitors, AJointSpeedMonitorTripsAtTheFirstSampleAfterAFreeFallReachesItsLimit) {
  const double v = 2.0;
  const Result r = run(arm_from(falling_body("fast: {type: joint_speed, joint: body, limit: 2.0}\n")));
  const std::vector<double>&t = r.trace.t(), &qd = r.trace.column("body.qd"), &tripped = r.trace.column("fast.tripped");
  // The free fall: qd = g t at every sample.
  for (std::size_t k = 0; k < t.size(); k += 50) ASSERT_NEAR(qd[k], kG * t[k], 1e-12) << k;
  const double expected = std::ceil(v / kG / kT) * kT;  // v / g = 0.2039 s: sample 204
  EXPECT_NEAR(r.metric("fast_trip_s"), expected, 1e-12);
  EXPECT_EQ(r.metric("trip_s"), r.metric("fast_trip_s"));
  EXPECT_EQ(r.metric("trip_cause"), 1.0);
  const std::size_t k = first_one(tripped);
  EXPECT_NEAR(t[k], expected, 1e-12);
  EXPECT_GT(qd[k], v);
  EXPECT_LE(qd[k - 1], v);
  for (std::size_t i = k; i < t.size(); ++i) ASSERT_EQ(tripped[i], 1.0) << i;  // 1 from the trip on
  // `record`: nothing changes; the body falls on, 0.5 m/s... past 1 mm/s at the end: no stop time.
  EXPECT_NEAR(qd.back(), kG * 0.5, 1e-12);
  EXPECT_TRUE(std::isnan(r.metric("stop_time_s")));
  // The stopping distance is the tool's path from the trip to the end: g (0.5^2 - t_trip^2) / 2.
  EXPECT_NEAR(r.metric("stopping_distance_m"), 0.5 * kG * (0.25 - expected * expected), 1e-9);
}

TEST(ArmMonitors, AToolSpeedMonitorTripsWhereTheToolsStepOverASampleFirstExceedsItsLimit) {
  const double v = 2.0;
  const Result r = run(arm_from(falling_body("fast: {type: tool_speed, limit: 2.0}\n")));
  // |z_k - z_(k-1)| / T = g (k - 1/2) T > v: k > v / (g T) + 1/2, sample 205.
  const double expected = std::ceil(v / (kG * kT) + 0.5) * kT;
  EXPECT_NEAR(r.metric("fast_trip_s"), expected, 1e-12);
  const std::vector<double>& z = r.trace.column("tool.z");
  const std::size_t k = first_one(r.trace.column("fast.tripped"));
  EXPECT_GT(std::abs(z[k] - z[k - 1]) / kT, v);
  EXPECT_LE(std::abs(z[k - 1] - z[k - 2]) / kT, v);
}

TEST(ArmMonitors, ABrakeStopsAFallingBodyInTheDistanceItsNetDecelerationGives) {
  // F_b = 3 m g: a net deceleration of F_b / m - g = 2 g.
  const double fb = 3 * kG, decel = fb - kG;
  const Result r = run(arm_from(falling_body("fast: {type: joint_speed, joint: body, limit: 2.0, action: brake, brake_torque: " +
                                             std::to_string(fb) + "}\n",
                                             0.35)));
  const std::vector<double>&qd = r.trace.column("body.qd"), &torque = r.trace.column("body.torque");
  const std::size_t k = first_one(r.trace.column("fast.tripped"));
  EXPECT_EQ(torque[k - 1], 0.0);
  EXPECT_NEAR(torque[k], -fb, 1e-12);  // saturated at once
  const double v0 = qd[k];
  EXPECT_NEAR(r.metric("stopping_distance_m"), v0 * v0 / (2 * decel), v0 * kT);
  EXPECT_NEAR(r.metric("stopping_distance_m"), 2.0 * 2.0 / (2 * decel), v0 * kT);
  // The brake holds the body against gravity but for a creep of g T (its rate gain is m / T).
  EXPECT_NEAR(qd.back(), kG * kT, 1e-9);
}

TEST(ArmMonitors, AControlledStopDeceleratesTheReferenceAtItsRateAndTheArmComesToRest) {
  const double a = 4.0;
  const Result r = run(arm_from(swinging_pendulum("halt: {type: command, time: 0.4, action: stop, deceleration: 4}\n")));
  const std::vector<double>&ref = r.trace.column("arm.ref"), &q = r.trace.column("arm.q"), &qd = r.trace.column("arm.qd");
  const std::size_t k0 = 400;
  EXPECT_NEAR(r.metric("halt_trip_s"), 0.4, 1e-12);
  EXPECT_EQ(first_one(r.trace.column("halt.tripped")), k0);
  // The quintic's rate at 0.4 s: 30 u^2 (1 - u)^2 = 1.728 rad/s; the stop takes v0 / a = 0.432 s.
  const double v0 = 30 * 0.16 * 0.36;
  const std::size_t stop = k0 + static_cast<std::size_t>(v0 / a / kT);
  for (std::size_t k = k0 + 1; k < stop; ++k)
    ASSERT_NEAR((ref[k + 1] - 2 * ref[k] + ref[k - 1]) / (kT * kT), -a, 1e-5) << k;
  // Then held where the rate reached zero: r0 + v0^2 / (2 a).
  const double r0 = ref[k0], rest = r0 + v0 * v0 / (2 * a);
  for (std::size_t k = stop + 2; k < ref.size(); ++k) ASSERT_NEAR(ref[k], rest, 1e-9) << k;
  EXPECT_LT(rest, 1.0);  // short of the move's target
  EXPECT_NEAR(q.back(), rest, 1e-4);
  EXPECT_LT(std::abs(qd.back()), 1e-3);
  // The tool came to rest: a stop time about the reference's, a distance about the arc it travelled.
  EXPECT_GT(r.metric("stop_time_s"), 0.4);
  EXPECT_LT(r.metric("stop_time_s"), 0.8);
  EXPECT_NEAR(r.metric("stopping_distance_m"), rest - q[k0], 0.01);  // 1 m from the hinge: the arc in rad
}

TEST(ArmMonitors, AHoldFreezesTheReferenceAndADelayPostponesItByTheRoundedUpSamples) {
  const Result free = run(arm_from(swinging_pendulum("")));
  // 0.25 s, and 10.5 samples later: the action from sample 261.
  const Result held = run(arm_from(swinging_pendulum("halt: {type: command, time: 0.25, action: hold, delay: 0.0105}\n")));
  EXPECT_NEAR(held.metric("halt_trip_s"), 0.25, 1e-12);
  EXPECT_EQ(first_one(held.trace.column("halt.tripped")), 250u);
  const std::vector<double>&r = held.trace.column("arm.ref"), &r_free = free.trace.column("arm.ref");
  for (std::size_t k = 0; k <= 261; ++k) ASSERT_EQ(r[k], r_free[k]) << k;
  EXPECT_GT(r_free[262], r_free[261]);
  for (std::size_t k = 262; k < r.size(); ++k) ASSERT_EQ(r[k], r_free[261]) << k;
  // The trip's before the action: the stopping distance is counted from the action's start.
  EXPECT_NEAR(held.metric("trip_s"), 0.25, 1e-12);
  EXPECT_GT(held.metric("stopping_distance_m"), 0.0);
  EXPECT_FALSE(std::isnan(held.metric("stop_time_s")));
  // A `record` monitor changes nothing; a later one acts (the first whose action is not record).
  const Result both = run(arm_from(swinging_pendulum("look: {type: command, time: 0.2}\n"
                                                     "halt: {type: command, time: 0.25, action: hold, delay: 0.0105}\n")));
  EXPECT_EQ(both.trace.column("arm.ref"), r);
  EXPECT_EQ(both.metric("trip_cause"), 1.0);
  EXPECT_NEAR(both.metric("trip_s"), 0.2, 1e-12);
  EXPECT_EQ(both.metric("stopping_distance_m"), held.metric("stopping_distance_m"));
}

// The pendulum swinging to 1.2 rad through a floor 0.8 m below the hinge (arm_collision_test.cpp's).
std::string pendulum_over_floor(const std::string& monitors) {
  return moving_pendulum(1.2, "world:\n  floor: {type: plane, position: [0, 0, -0.8]}\ncollision:\n  arm: {radius: 0.05}\n" + monitors);
}

TEST(ArmMonitors, AClearanceMonitorThatStopsPreventsTheContactTheRunWithoutItHas) {
  const Result bare = run(arm_from(pendulum_over_floor("")));
  EXPECT_FALSE(std::isnan(bare.metric("first_contact_s")));
  EXPECT_EQ(bare.metric("contacts"), 1.0);
  const Result guarded =
      run(arm_from(pendulum_over_floor("monitors:\n  guard: {type: clearance, limit: 0.15, action: stop, deceleration: 40}\n")));
  EXPECT_TRUE(std::isnan(guarded.metric("first_contact_s")));
  EXPECT_EQ(guarded.metric("contacts"), 0.0);
  EXPECT_GT(guarded.metric("min_clearance_m"), 0.0);
  EXPECT_LT(guarded.metric("min_clearance_m"), 0.15);
  // It tripped where the clearance first fell below 0.15 m.
  const std::vector<double>& c = guarded.trace.column("clearance");
  const std::size_t k = first_one(guarded.trace.column("guard.tripped"));
  EXPECT_LT(c[k], 0.15);
  EXPECT_GE(c[k - 1], 0.15);
  EXPECT_EQ(guarded.metric("guard_trip_s"), guarded.trace.t()[k]);
  EXPECT_GT(guarded.metric("stopping_distance_m"), 0.0);
  EXPECT_LT(guarded.metric("stop_time_s"), 1.0);
}

TEST(ArmMonitors, ASlippedEncoderOffsetsTheMeasuredAngleFromItsTimeAndASpeedMonitorCatchesTheLurch) {
  const std::string text = pendulum_arm(R"(controller: {rate: 1000}
joints:
  arm:
    controller: {kp: 4000, kd: 120, gravity_compensation: 1}
    sensors: {angle: {fault_time: 0.3, fault_offset: 0.2}}
simulation: {duration: 1.0}
monitors:
  lurch: {type: joint_speed, joint: arm, limit: 0.5, action: brake, brake_torque: 100}
)");
  const Result r = run(arm_from(text));
  const std::vector<double>&q = r.trace.column("arm.q"), &qm = r.trace.column("arm.q_measured");
  for (std::size_t k = 0; k < 300; ++k) ASSERT_EQ(qm[k], q[k]) << k;
  for (std::size_t k = 300; k < q.size(); ++k) ASSERT_NEAR(qm[k] - q[k], 0.2, 1e-15) << k;
  // The controller drives the arm towards -0.2 rad; the monitor brakes it soon after.
  EXPECT_GT(r.metric("lurch_trip_s"), 0.3);
  EXPECT_LT(r.metric("lurch_trip_s"), 0.35);
  EXPECT_GT(q.back(), -0.2);
}

TEST(ArmMonitors, EveryLaneOfABatchTripsAsItDoesAloneAndOnlineMetricsAreTheStoredOnesBits) {
  std::vector<ArmModel> lanes;
  for (int l = 0; l < 4; ++l)
    lanes.push_back(arm_from(pendulum_over_floor(
        "monitors:\n  guard: {type: clearance, limit: " + std::to_string(0.1 + 0.03 * l) +
        ", action: " + (l % 2 ? "stop, deceleration: 40" : "brake, brake_torque: 150") +
        ", delay: " + std::to_string(0.002 * l) + "}\n  fast: {type: joint_speed, joint: arm, limit: " +
        std::to_string(2.0 - 0.2 * l) + "}\n  box: {type: workspace, lower: [-2, -2, -0.6], upper: [2, 2, 2]}\n")));
  std::vector<OnlineArmRun> online;
  for (const ArmModel& m : lanes) online.emplace_back(m);
  const ArmRun batch = simulate_arms(lanes);
  const ArmRun batch_online = simulate_arms(lanes, {.online = &online});
  std::vector<double> trips;
  for (std::size_t l = 0; l < lanes.size(); ++l) {
    const ArmRun alone = simulate_arms(std::span<const ArmModel>(&lanes[l], 1));
    for (const std::string& name : alone.traces[0].names)
      test::expect_same_bits(alone.traces[0].column(name), batch.traces[l].column(name), name + " lane " + std::to_string(l));
    const std::vector<double> stored = calc_arm_metrics(lanes[l], batch.traces[l], batch.status[l]);
    test::expect_same_bits(stored, online[l].result(batch_online.status[l]), "metrics lane " + std::to_string(l));
    const std::vector<std::string> cols = arm_metric_columns(lanes[l]);
    const auto at = [&](const std::string& n) { return stored[static_cast<std::size_t>(std::find(cols.begin(), cols.end(), n) - cols.begin())]; };
    EXPECT_FALSE(std::isnan(at("guard_trip_s"))) << l;
    EXPECT_FALSE(std::isnan(at("stopping_distance_m"))) << l;
    trips.push_back(at("guard_trip_s"));
  }
  // The lanes differ (the limits): so do their trips.
  EXPECT_LT(trips[3], trips[0]);
  // The metric columns: each monitor's, then the four, before settling_horizon_s.
  const std::vector<std::string> cols = arm_metric_columns(lanes[0]);
  const std::vector<std::string> tail(cols.end() - 8, cols.end());
  EXPECT_EQ(tail, (std::vector<std::string>{"guard_trip_s", "fast_trip_s", "box_trip_s", "trip_s", "trip_cause",
                                            "stopping_distance_m", "stop_time_s", "settling_horizon_s"}));
  const std::vector<std::string> names = arm_trace_names(lanes[0]);
  EXPECT_EQ(std::vector<std::string>(names.end() - 3, names.end()),
            (std::vector<std::string>{"guard.tripped", "fast.tripped", "box.tripped"}));
}

TEST(ArmMonitors, TheMonitorsBlockNamesTheKeyAndLineOfEachMistake) {
  // Lines 1-8 the pendulum, 9 joints, 10 trajectory, 11 `monitors:`, 12 the monitor.
  const auto with = [](const std::string& monitor) {
    return arm_error(pendulum_arm("joints: {arm: {controller: {kp: 10}}}\ntrajectory: {waypoints: [{time: 1, joints: {arm: 0.1}}]}\n"
                                  "monitors:\n  m: " + monitor + "\n"));
  };
  const auto expect = [&](const std::string& monitor, const std::string& text) {
    const std::string e = with(monitor);
    EXPECT_NE(e.find("arm.yaml:12: " + text), std::string::npos) << monitor << " -> " << e;
  };
  expect("{type: speed, limit: 1}", "monitors.m.type: unknown monitor type 'speed'");
  expect("{limit: 1}", "monitors.m.type: missing required value");
  expect("{type: joint_speed, joint: arm, limit: 1, link: arm}", "monitors.m.link: is not a key of a joint_speed monitor");
  expect("{type: joint_speed, joint: arm}", "monitors.m.limit: missing: a joint_speed monitor needs it");
  expect("{type: joint_torque, limit: 1}", "monitors.m.joint: missing");
  expect("{type: joint_speed, joint: elbow, limit: 1}", "monitors.m.joint: no actuated joint named 'elbow' (actuated: arm)");
  expect("{type: deflection, link: arm, limit: 1}", "monitors.m.link: no flexible link named 'arm'");
  expect("{type: tool_speed, tool: hand, limit: 1}", "monitors.m.tool: no tool named 'hand'");
  expect("{type: clearance, limit: 0.1}", "monitors.m.type: a clearance monitor needs a world");
  expect("{type: workspace, lower: [0, 0, 0]}", "monitors.m.upper: missing");
  expect("{type: workspace, lower: [0, 0, 0], upper: [1, 0, 1]}", "monitors.m.upper: must exceed lower");
  expect("{type: workspace, lower: [0, 0], upper: [1, 1, 1]}", "monitors.m.lower: expected a list of 3 numbers");
  expect("{type: command}", "monitors.m.time: missing");
  expect("{type: command, time: -1}", "monitors.m.time: must be >= 0");
  expect("{type: command, time: 1, limit: 2}", "monitors.m.limit: is not a key of a command monitor");
  expect("{type: command, time: 1, action: halt}", "monitors.m.action: unknown action 'halt'");
  expect("{type: command, time: 1, action: stop}", "monitors.m.deceleration: missing: a command monitor that stops needs it");
  expect("{type: command, time: 1, action: stop, deceleration: 0}", "monitors.m.deceleration: must be > 0");
  expect("{type: command, time: 1, action: hold, deceleration: 1}", "monitors.m.deceleration: is not a key of a command monitor with action hold");
  expect("{type: command, time: 1, brake_torque: 1}", "monitors.m.brake_torque: is not a key");
  expect("{type: command, time: 1, action: brake}", "monitors.m.brake_torque: missing: joint arm has no torque limit");
  expect("{type: command, time: 1, delay: -0.1}", "monitors.m.delay: must be >= 0");
  expect("{type: command, time: 1, speed: 1}", "monitors.m.speed: unknown key");
  expect("{type: joint_speed, joint: arm, limit: -1}", "monitors.m.limit: must be >= 0");
  EXPECT_NE(arm_error(pendulum_arm("joints: {arm: {controller: {kp: 10}}}\nmonitors:\n  a.b: {type: command, time: 1}\n"))
                .find("no dots"),
            std::string::npos);
  EXPECT_NE(arm_error(pendulum_arm("joints: {arm: {controller: {kp: 10}}}\nmonitors: [1]\n")).find("monitors: expected a map"),
            std::string::npos);
  // The sensor fault's keys.
  EXPECT_NE(arm_error(pendulum_arm("joints: {arm: {sensors: {angle: {fault_time: -1}}}}\n"))
                .find("joints.arm.sensors.angle.fault_time: must be >= 0"),
            std::string::npos);
  EXPECT_NE(arm_error(pendulum_arm("joints: {arm: {sensors: {rate: {fault_time: 1}}}}\n")).find("joints.arm.sensors.rate.fault_time"),
            std::string::npos);
  // Without a monitor, nothing is added.
  const ArmModel none = arm_from(pendulum_arm("joints: {arm: {controller: {kp: 10}}}\n"));
  const std::vector<std::string> cols = arm_metric_columns(none);
  EXPECT_EQ(std::find(cols.begin(), cols.end(), "trip_s"), cols.end());
}

}  // namespace
}  // namespace ff
