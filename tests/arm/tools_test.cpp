// Several tool points (`tools:`): `tool:` alone is the one tool named "tool", its columns and metrics
// today's to the bit; a two-tool Cartesian waypoint reaches both targets through the stacked IK; bad
// `tools` input is named at its file, line and key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "arm/arm_metrics.hpp"
#include "arm/arm_simulate.hpp"
#include "arm/arm_yaml.hpp"
#include "multibody/algorithms.hpp"
#include "tests/arm/test_support.hpp"

namespace ff {
namespace {

using test::arm_error;
using test::arm_from;

// The pendulum of test_support.hpp moved 0.6 rad in 1 s, its tool block given.
std::string pendulum(const std::string& tool_block) {
  return test::pendulum_arm(tool_block + R"(
controller: {rate: 1000}
joints:
  arm: {controller: {kp: 400, kd: 40}}
trajectory:
  waypoints:
    - {time: 1.0, joints: {arm: 0.6}}
simulation: {duration: 2.0}
)");
}

TEST(ArmTools, AToolBlockAloneIsTheToolNamedToolWithTodaysColumnsMetricsAndBits) {
  const ArmModel one = arm_from(pendulum("tool: {body: arm, point: [0.5, 0, 0]}"));
  const ArmModel named = arm_from(pendulum("tools:\n  tool: {body: arm, point: [0.5, 0, 0]}"));
  ASSERT_EQ(one.tools.size(), 1u);
  EXPECT_EQ(one.tools[0].name, "tool");
  // The trace's and the metrics' names as they were before `tools` existed.
  EXPECT_EQ(arm_trace_names(one),
            (std::vector<std::string>{"t", "arm.ref", "arm.q", "arm.qd", "arm.torque", "tool.x", "tool.y", "tool.z",
                                      "tool.ref_x", "tool.ref_y", "tool.ref_z", "arm.q_measured", "arm.qd_measured"}));
  EXPECT_EQ(arm_metric_columns(one),
            (std::vector<std::string>{"arm_settling_s", "arm_overshoot_pct", "arm_peak_torque_Nm", "arm_peak_speed",
                                      "tool_settling_s", "tool_overshoot_pct", "tool_peak_error_m",
                                      "tool_final_error_m", "tool_sag_m", "settling_horizon_s"}));
  const ArmRun a = simulate_arms(std::span<const ArmModel>(&one, 1));
  const ArmRun b = simulate_arms(std::span<const ArmModel>(&named, 1));
  ASSERT_EQ(a.status[0], LaneStatus::kOk);
  EXPECT_EQ(a.traces[0].names, b.traces[0].names);
  EXPECT_EQ(a.traces[0].columns, b.traces[0].columns);  // bit for bit
  const std::vector<double> va = calc_arm_metrics(one, a.traces[0], a.status[0]);
  const std::vector<double> vb = calc_arm_metrics(named, b.traces[0], b.status[0]);
  for (std::size_t i = 0; i < va.size(); ++i)
    if (!std::isnan(va[i])) EXPECT_EQ(va[i], vb[i]) << arm_metric_columns(one)[i];
  // The tool point is the bob: 0.5 m out on the link, at the end of the move at (0.5 cos q, 0, -0.5 sin q).
  const double q = a.traces[0].column("arm.q").back();
  EXPECT_NEAR(a.traces[0].column("tool.x").back(), 0.5 * std::cos(q), 1e-15);
  EXPECT_NEAR(a.traces[0].column("tool.z").back(), -0.5 * std::sin(q), 1e-15);
  // With no tool given, the last body's origin, named "tool".
  const ArmModel none = arm_from(pendulum(""));
  EXPECT_EQ(arm_trace_names(none), arm_trace_names(one));
}

// Two 3-DOF arms (yaw z, pitch y, pitch y; links 0.5 and 0.4 m along x) on a torso held 0.4 m to either
// side of a yaw joint, in the horizontal plane of gravity's normal; a tool 0.1 m beyond each wrist.
std::string two_arms(const std::string& tools, const std::string& waypoints) {
  std::string arm;
  for (const char* side : {"left", "right"}) {
    const std::string s = side, y = s == "left" ? "0.4" : "-0.4";
    arm += "  - {name: " + s + "_turret, parent: torso, joint: {name: " + s + "_yaw, axis: [0, 0, 1], position: [0, " + y +
           ", 0.3], armature: 0.2, lower: -3, upper: 3}, mass: 3.0, inertia: {ixx: 0.02, iyy: 0.02, izz: 0.02}}\n"
           "  - {name: " + s + "_upper, parent: " + s + "_turret, joint: {name: " + s + "_shoulder, axis: [0, 1, 0], "
           "armature: 0.2, lower: -2, upper: 2}, mass: 2.0, com: [0.25, 0, 0], inertia: {ixx: 0.002, iyy: 0.04, izz: 0.04}}\n"
           "  - {name: " + s + "_fore, parent: " + s + "_upper, joint: {name: " + s + "_elbow, axis: [0, 1, 0], position: "
           "[0.5, 0, 0], armature: 0.2, lower: -2.5, upper: 2.5}, mass: 1.5, com: [0.2, 0, 0], inertia: {ixx: 0.001, iyy: 0.02, izz: 0.02}}\n";
  }
  std::string joints;
  for (const char* j : {"waist", "left_yaw", "left_shoulder", "left_elbow", "right_yaw", "right_shoulder", "right_elbow"})
    joints += std::string("  ") + j + ": {controller: {kp: 300, kd: 20, feedforward: 1, gravity_compensation: 1}}\n";
  return "gravity: [0, 0, -9.81]\nbodies:\n"
         "  - {name: torso, parent: base, joint: {name: waist, axis: [0, 0, 1], position: [0, 0, 1.0], armature: 0.5}, mass: 20.0, "
         "inertia: {ixx: 0.5, iyy: 0.5, izz: 0.5}}\n" +
         arm + tools + "\ncontroller: {rate: 500}\njoints:\n" + joints +
         "trajectory:\n  start: {left_shoulder: 0.3, left_elbow: 0.6, right_shoulder: 0.3, right_elbow: 0.6}\n"
         "  waypoints:\n" + waypoints + "simulation: {duration: 2.5, integrator: rk4}\n";
}
std::string sci(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3e", v);
  return b;
}

const std::string kTwoTools =
    "tools:\n  left: {body: left_fore, point: [0.5, 0, 0]}\n  right: {body: right_fore, point: [0.5, 0, 0]}\n";

TEST(ArmTools, ATwoToolCartesianWaypointReachesBothTargetsThroughTheStackedIk) {
  // Both tools to targets at once, the waist fixed by the waypoint's joints: IK over the six arm joints.
  const Vec3 left(0.7, 0.55, 0.9), right(0.6, -0.5, 1.1);
  const ArmModel m = arm_from(two_arms(kTwoTools,
                                       "    - {time: 1.5, joints: {waist: 0.2}, tools: {left: [0.7, 0.55, 0.9], right: [0.6, -0.5, 1.1]}}\n"));
  ASSERT_EQ(m.tools.size(), 2u);
  EXPECT_EQ(m.tools[0].name, "left");
  EXPECT_EQ(m.tools[1].name, "right");
  // The planned pose (the rigid arm at the waypoint) puts each tool on its target; the waist where the
  // waypoint fixed it.
  Eigen::VectorXd pose = Eigen::VectorXd::Zero(m.tree.nv());
  for (std::size_t j = 0; j < m.actuated.size(); ++j) pose[m.actuated[j].dof] = m.trajectory.waypoints[0].q[j];
  EXPECT_EQ(pose[m.actuated[0].dof], 0.2);
  const double el = (calc_point_position(m.tree, pose, m.tools[0].body, m.tools[0].point) - left).norm();
  const double er = (calc_point_position(m.tree, pose, m.tools[1].body, m.tools[1].point) - right).norm();
  RecordProperty("left_ik_error_m", sci(el));
  RecordProperty("right_ik_error_m", sci(er));
  EXPECT_LT(el, 1e-9);  // IkOptions::tolerance
  EXPECT_LT(er, 1e-9);
  // Simulated: the trace's reference columns at the waypoint are the targets, and both tools settle there
  // (rigid arms with the exact feed-forward: only the hold's lag remains).
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1));
  ASSERT_EQ(run.status[0], LaneStatus::kOk);
  const ArmTrace& tr = run.traces[0];
  const std::size_t end = tr.t().size() - 1;
  for (const auto& [name, target] : {std::pair{std::string("left"), left}, std::pair{std::string("right"), right}}) {
    EXPECT_NEAR(tr.column(name + ".ref_x")[end], target.x(), 1e-9) << name;
    EXPECT_NEAR(tr.column(name + ".ref_y")[end], target.y(), 1e-9) << name;
    EXPECT_NEAR(tr.column(name + ".ref_z")[end], target.z(), 1e-9) << name;
    const Vec3 at(tr.column(name + ".x")[end], tr.column(name + ".y")[end], tr.column(name + ".z")[end]);
    EXPECT_LT((at - target).norm(), 1e-5) << name;
  }
  // Metrics per tool, under its name.
  const std::vector<std::string> c = arm_metric_columns(m);
  for (const char* k : {"left_settling_s", "left_peak_error_m", "right_sag_m", "right_final_error_m"})
    EXPECT_NE(std::find(c.begin(), c.end(), k), c.end()) << k;
  EXPECT_EQ(arm_tool_names(c), (std::vector<std::string>{"left", "right"}));
  EXPECT_EQ(calc_arm_status(m, run.status[0], c, calc_arm_metrics(m, tr, run.status[0])), "ok");
}

TEST(ArmTools, BadToolsInputIsNamedAtItsFileLineAndKey) {
  const std::string wp = "    - {time: 1.0, joints: {left_elbow: 0.9}}\n";
  // Both blocks: the error is at `tools` (line 11 here).
  EXPECT_EQ(arm_error(two_arms("tool: {body: left_fore}\n" + kTwoTools, wp)),
            "arm.yaml:11: tools: give either `tool` (one tool point) or `tools` (several, by name), not both");
  std::string bad_body = kTwoTools;
  bad_body.replace(bad_body.find("right_fore"), 10, "right_hnd");
  EXPECT_EQ(arm_error(two_arms(bad_body, wp)), "arm.yaml:12: tools.right.body: no body named 'right_hnd'");
  EXPECT_EQ(arm_error(two_arms("tools:\n  left: {body: left_fore, pont: [0, 0, 0]}\n", wp)),
            "arm.yaml:11: tools.left.pont: unknown key (did you mean `point`?)");
  EXPECT_EQ(arm_error(two_arms("tools:\n  left_elbow: {body: left_fore}\n", wp)),
            "arm.yaml:11: tools.left_elbow: an actuated joint has that name: its columns and metrics would clash");
  EXPECT_EQ(arm_error(two_arms("tools:\n  left.tip: {body: left_fore}\n", wp)),
            "arm.yaml:11: tools.left.tip: a tool's name heads its columns (NAME.x) and metrics: no dots, spaces, commas or quotes");
  EXPECT_EQ(arm_error(two_arms("tools: []\n", wp)), "arm.yaml:10: tools: expected a map from tool name to its {body, point}");
  // Waypoints: an unknown tool, a target not a 3-vector, out of reach, `tool` on an arm with several.
  const int line = 26;  // the waypoint's line
  const std::string at = "arm.yaml:" + std::to_string(line) + ": trajectory.waypoints[0].";
  EXPECT_EQ(arm_error(two_arms(kTwoTools, "    - {time: 1.0, tools: {middle: [0.5, 0, 1]}}\n")),
            at + "tools.middle: no tool of that name (tools: left, right)");
  EXPECT_EQ(arm_error(two_arms(kTwoTools, "    - {time: 1.0, tools: {left: [0.5, 0]}}\n")),
            at + "tools.left: expected a list of 3 numbers");
  const std::string far = arm_error(two_arms(kTwoTools, "    - {time: 1.0, joints: {waist: 0}, tools: {left: [0.6, 0.5, 1.0], right: [3.0, -0.4, 1.3]}}\n"));
  EXPECT_EQ(far.rfind(at + "tools: the tools cannot reach them: right: target ", 0), 0u) << far;
  EXPECT_NE(far.find("beyond reach"), std::string::npos) << far;
  EXPECT_EQ(arm_error(two_arms(kTwoTools, "    - {time: 1.0, tool: [0.5, 0, 1]}\n")),
            at + "tool: this arm has several tools (left, right): give `tools: {NAME: [x, y, z], ...}`");
  EXPECT_EQ(arm_error(two_arms(kTwoTools,
                               "    - {time: 1.0, joints: {waist: 0, left_yaw: 0, left_shoulder: 0, left_elbow: 0, right_yaw: 0, "
                               "right_shoulder: 0, right_elbow: 0}, tools: {left: [0.6, 0.5, 1.0]}}\n")),
            at + "tools: `joints` fixes every actuated joint: none is left for the tools");
}

}  // namespace
}  // namespace ff
