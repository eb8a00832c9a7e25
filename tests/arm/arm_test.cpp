// arm/: the per-joint control law against closed forms (a held pendulum's droop kp e = m g l cos q; an
// exact feed-forward tracks with no error but the hold's), a Cartesian waypoint reached through the
// IK, a cantilevered flexible link's initial sag against Euler-Bernoulli, a variant's bits the same in
// any lane of any batch, the metrics of a known trace, and the file's errors at their lines.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "arm/arm_metrics.hpp"
#include "arm/arm_simulate.hpp"
#include "arm/arm_yaml.hpp"
#include "common/errors.hpp"
#include "common/yaml_reader.hpp"
#include "tests/arm/test_support.hpp"
#include "tests/docs_tables.hpp"

namespace ff {
namespace {

using test::arm_error;
using test::arm_from;

// A 2 kg bob 0.5 m out on a hinge about y (gravity -z: at q = 0 the arm is horizontal), rotor 0.05.
std::string pendulum(const std::string& controller, const std::string& waypoints = "") {
  return test::pendulum_arm("tool: {body: arm, point: [0.5, 0, 0]}\ncontroller: {rate: 1000}\njoints:\n  arm:\n    controller: " +
                            controller + "\n" + waypoints + "simulation: {duration: 6.0}\n");
}

TEST(ArmControl, APdHeldPendulumDroopsUntilKpTimesTheErrorCarriesItsWeight) {
  // Static balance at the end: kp (0 - q) = m g l cos q about y (+q turns x towards -z: down).
  const double kp = 400.0, m = 2.0, g = 9.81, l = 0.5;
  const ArmModel arm = arm_from(pendulum("{kp: 400, kd: 40}"));
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&arm, 1));
  ASSERT_EQ(run.status[0], LaneStatus::kOk);
  const double q = run.traces[0].column("arm.q").back();
  EXPECT_GT(q, 0.02);  // m g l / kp = 0.0245 rad
  EXPECT_NEAR(-kp * q + m * g * l * std::cos(q), 0.0, 1e-6 * m * g * l);
  // With gravity compensation at the reference it holds the reference.
  const ArmModel held = arm_from(pendulum("{kp: 400, kd: 40, gravity_compensation: 1}"));
  const ArmRun run2 = simulate_arms(std::span<const ArmModel>(&held, 1));
  EXPECT_NEAR(run2.traces[0].column("arm.q").back(), 0.0, 1e-9);
}

TEST(ArmControl, TheRigidArmsInverseDynamicsFedForwardTracksAQuinticMoveToTheHoldsError) {
  // RNEA feed-forward (one algorithm) driving the ABA plant (another): only the zero-order hold's
  // error remains, O(T) of the move; without it PD lags by tenths of a radian.
  const std::string move = "trajectory:\n  waypoints:\n    - {time: 1.0, joints: {arm: 1.2}}\n";
  const ArmModel ff = arm_from(pendulum("{kp: 400, kd: 40, feedforward: 1, gravity_compensation: 1}", move));
  const ArmModel pd = arm_from(pendulum("{kp: 400, kd: 40}", move));
  const ArmRun a = simulate_arms(std::span<const ArmModel>(&ff, 1));
  const ArmRun b = simulate_arms(std::span<const ArmModel>(&pd, 1));
  auto peak_error = [](const ArmTrace& tr) {
    double e = 0.0;
    for (std::size_t k = 0; k < tr.t().size(); ++k)
      e = std::max(e, std::abs(tr.column("arm.q")[k] - tr.column("arm.ref")[k]));
    return e;
  };
  const double e_ff = peak_error(a.traces[0]), e_pd = peak_error(b.traces[0]);
  RecordProperty("feedforward_peak_error_rad", std::to_string(e_ff));
  RecordProperty("pd_peak_error_rad", std::to_string(e_pd));
  EXPECT_LT(e_ff, 2e-3);
  EXPECT_GT(e_pd, 0.05);
}

TEST(ArmControl, ACartesianWaypointIsReachedThroughTheInverseKinematics) {
  // A 2R arm in the horizontal plane (gravity along the joint axes: no load): the tool goes to (0.3, 0.5).
  const std::string text = R"(gravity: [0, 0, -9.81]
bodies:
  - {name: upper, parent: base, mass: 1.0, com: [0.3, 0, 0], inertia: {ixx: 0.001, iyy: 0.03, izz: 0.03}, joint: {armature: 0.02}}
  - {name: fore, parent: upper, mass: 0.5, com: [0.25, 0, 0], inertia: {ixx: 0.001, iyy: 0.01, izz: 0.01}, joint: {position: [0.6, 0, 0], armature: 0.01}}
tool: {body: fore, point: [0.5, 0, 0]}
joints:
  upper: {controller: {kp: 200, kd: 20, feedforward: 1}}
  fore: {controller: {kp: 100, kd: 10, feedforward: 1}}
trajectory:
  waypoints:
    - {time: 1.5, tool: [0.3, 0.5, 0]}
simulation: {settle: 3}
)";
  const ArmModel arm = arm_from(text);
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&arm, 1));
  const ArmTrace& tr = run.traces[0];
  EXPECT_NEAR(tr.column("tool.ref_x").back(), 0.3, 1e-8);
  EXPECT_NEAR(tr.column("tool.ref_y").back(), 0.5, 1e-8);
  EXPECT_NEAR(tr.column("tool.x").back(), 0.3, 1e-5);
  EXPECT_NEAR(tr.column("tool.y").back(), 0.5, 1e-5);
  const std::vector<double> v = calc_arm_metrics(arm, tr, run.status[0]);
  const std::vector<std::string> c = arm_metric_columns(arm);
  const auto at = [&](const std::string& name) { return v[static_cast<std::size_t>(std::find(c.begin(), c.end(), name) - c.begin())]; };
  EXPECT_LT(at("tool_final_error_m"), 1e-5);
  EXPECT_GE(at("tool_settling_s"), 0.0);
  EXPECT_EQ(calc_arm_status(arm, run.status[0], c, v), "ok");
  // Out of reach (|p| = 1.2 m > 1.1 m): the IK's failure is the waypoint's error.
  std::string far = text;
  far.replace(far.find("[0.3, 0.5, 0]"), 13, "[1.2, 0.0, 0]");
  EXPECT_NE(arm_error(far).find("arm.yaml:11: trajectory.waypoints[0].tool: the tool cannot reach it"), std::string::npos)
      << arm_error(far);
}

TEST(ArmModel, ACantileveredFlexibleLinkStartsAtItsStaticSagUnderGravity) {
  // A horizontal steel strip, 1 m, 40 x 5 mm, flat side up (bends about y), held by its actuated root
  // (a motor with a rotor: without one the PD's kd/J on the root segment alone is far beyond 1/T):
  // its tip sags q L^4 / (8 E I) (Euler-Bernoulli), to the lumping's O(1/N^2) at N = 24.
  const double L = 1.0, b = 0.04, t = 0.005, E = 200e9, rho = 7850.0, g = 9.81;
  const double A = b * t, I_y = b * t * t * t / 12.0;
  const std::string text = R"(gravity: [0, 0, -9.81]
bodies:
  - name: beam
    parent: base
    joint: {axis: [0, 1, 0], armature: 0.1}
    flexible:
      length: 1.0
      segments: 24
      torsion: false
      section: {E: 200e9, G: 80e9, density: 7850, area: 2.0e-4, I_y: 4.1666666666666667e-10, I_z: 2.6666666666666667e-8, J: 1e-9}
joints:
  beam: {controller: {kp: 1000, kd: 10}}
simulation: {duration: 0.01}
)";
  const ArmModel arm = arm_from(text);
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&arm, 1));
  const double sag = -run.traces[0].column("beam.deflection_z").front();
  const double exact = rho * A * g * std::pow(L, 4) / (8.0 * E * I_y);
  RecordProperty("sag_relative_error", std::to_string(sag / exact - 1.0));
  EXPECT_NEAR(sag / exact, 1.0, 5e-3);
  const std::vector<double> v = calc_arm_metrics(arm, run.traces[0], run.status[0]);
  const std::vector<std::string> c = arm_metric_columns(arm);
  EXPECT_NEAR(v[static_cast<std::size_t>(std::find(c.begin(), c.end(), "beam_sag_m") - c.begin())], sag, 1e-15);
}

TEST(ArmSimulate, AVariantGivesTheSameBitsAloneAndInAnyLaneOfABatch) {
  const std::string move = "trajectory:\n  waypoints:\n    - {time: 1.0, joints: {arm: 0.8}}\n";
  std::vector<ArmModel> lanes;
  for (const char* c : {"{kp: 300, kd: 30, ki: 20}", "{kp: 400, kd: 40, feedforward: 1}", "{kp: 500, kd: 20, torque_limit: 30}"})
    lanes.push_back(arm_from(pendulum(c, move)));
  const ArmRun together = simulate_arms(lanes);
  for (std::size_t l = 0; l < lanes.size(); ++l) {
    const ArmRun alone = simulate_arms(std::span<const ArmModel>(&lanes[l], 1));
    EXPECT_EQ(alone.traces[0].columns, together.traces[l].columns) << "lane " << l;
  }
  std::vector<ArmModel> reversed(lanes.rbegin(), lanes.rend());
  const ArmRun back = simulate_arms(reversed);
  EXPECT_EQ(back.traces[0].columns, together.traces[2].columns);
}

TEST(ArmSimulate, KeptJointStatesAreTheTracesInstantsAndChangeNoResult) {
  // A flexible link swung by its root: every dof moves (actuated and elastic). The kept q at sample k
  // puts the tool where the trace says, holds the joint's .q, starts at q0; the trace is the same bits.
  const std::string text = R"(gravity: [0, 0, -9.81]
bodies:
  - name: beam
    parent: base
    joint: {axis: [0, 0, 1], armature: 0.1}
    flexible:
      length: 0.8
      segments: 5
      section: {E: 70e9, G: 26e9, density: 2700, area: 2.0e-4, I_y: 4.2e-10, I_z: 2.7e-8, J: 1.6e-9}
joints:
  beam: {controller: {kp: 200, kd: 20}}
trajectory:
  waypoints:
    - {time: 0.05, joints: {beam: 0.5}}
simulation: {duration: 0.08}
)";
  const ArmModel arm = arm_from(text);
  const ArmRun plain = simulate_arms(std::span<const ArmModel>(&arm, 1));
  const ArmRun kept = simulate_arms(std::span<const ArmModel>(&arm, 1), {.keep_q = true});
  EXPECT_TRUE(plain.q.empty());
  ASSERT_EQ(kept.q.size(), 1u);
  EXPECT_EQ(kept.traces[0].columns, plain.traces[0].columns);
  const ArmTrace& tr = kept.traces[0];
  const Eigen::MatrixXd& q = kept.q[0];
  ASSERT_EQ(q.rows(), arm.tree.nv());
  ASSERT_EQ(static_cast<std::size_t>(q.cols()), tr.t().size());
  EXPECT_EQ(Eigen::VectorXd(q.col(0)), arm.q0);
  const int dof = arm.actuated[0].dof;
  double elastic_motion = 0.0;
  for (Eigen::Index k = 0; k < q.cols(); ++k) {
    const std::size_t ks = static_cast<std::size_t>(k);
    EXPECT_EQ(q(dof, k), tr.column("beam.q")[ks]);
    const Vec3 tool = calc_point_position(arm.tree, q.col(k), arm.tool_body, arm.tool_point);
    EXPECT_NEAR(tool.x(), tr.column("tool.x")[ks], 1e-14);  // (another order of the same products)
    EXPECT_NEAR(tool.y(), tr.column("tool.y")[ks], 1e-14);
    EXPECT_NEAR(tool.z(), tr.column("tool.z")[ks], 1e-14);
    for (int d : arm.links[0].elastic_dofs) elastic_motion = std::max(elastic_motion, std::abs(q(d, k) - q(d, 0)));
  }
  EXPECT_GT(elastic_motion, 1e-6);  // the link bends as it is swung
}

TEST(ArmSimulate, TheFixedStepIntegratorsFollowCvodeOnTheTwoLinkFlexibleArm) {
  // configs/two_link_flexible.yaml (two flexible links, PD with feed-forward, a 1.5 s move): SDIRK2 at
  // its automatic substeps and RK4 against CVODE (BDF, rtol 1e-10), the tool within 0.1 mm throughout.
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/two_link_flexible.yaml";
  auto with = [&](const std::string& integrator, const std::string& extra = "") {
    YAML::Node doc = load_yaml_file(path);
    doc["simulation"]["integrator"] = integrator;
    doc["simulation"]["duration"] = 3.0;
    if (!extra.empty()) doc["simulation"]["rtol"] = 1e-10, doc["simulation"]["atol"] = 1e-12;
    const ArmModel m = parse_arm(doc, path);
    return simulate_arms(std::span<const ArmModel>(&m, 1));
  };
  const ArmRun ref = with("cvode_dense", "tight");
  ASSERT_EQ(ref.status[0], LaneStatus::kOk);
  for (const char* integrator : {"sdirk2", "rk4", "cvode_klu", "cvode_gmres"}) {
    const ArmRun r = with(integrator);
    ASSERT_EQ(r.status[0], LaneStatus::kOk) << integrator;
    double worst = 0.0;
    for (const char* c : {"tool.x", "tool.y"})
      for (std::size_t k = 0; k < r.traces[0].t().size(); ++k)
        worst = std::max(worst, std::abs(r.traces[0].column(c)[k] - ref.traces[0].column(c)[k]));
    RecordProperty(std::string(integrator) + "_tool_error_m", std::to_string(worst));
    EXPECT_LT(worst, 1e-4) << integrator;
  }
}

TEST(ArmYaml, AnUnknownJointAPassiveWaypointAndABadBlockAreNamedAtTheirLines) {
  EXPECT_EQ(arm_error(pendulum("{kp: 400, kq: 1}")), "arm.yaml:13: joints.arm.controller.kq: unknown key (did you mean `kd`?)");
  std::string text = pendulum("{kp: 400}");
  text.replace(text.find("  arm:\n    controller"), 6, "  elbow:");
  EXPECT_NE(arm_error(text).find("arm.yaml:12: joints.elbow: no moving joint of that name"), std::string::npos)
      << arm_error(text);
  EXPECT_NE(arm_error(pendulum("{kp: -1}")).find("joints.arm.controller.kp: must be >= 0"), std::string::npos);
  EXPECT_NE(arm_error(pendulum("{kp: 1}", "trajectory:\n  waypoints:\n    - {time: 1.0, joints: {wrist: 1}}\n"))
                .find("arm.yaml:16: trajectory.waypoints[0].joints.wrist: no moving joint of that name"),
            std::string::npos)
      << arm_error(pendulum("{kp: 1}", "trajectory:\n  waypoints:\n    - {time: 1.0, joints: {wrist: 1}}\n"));
  EXPECT_NE(arm_error(pendulum("{kp: 1}", "trajectory:\n  waypoints:\n    - {time: 2.0, joints: {arm: 1}}\n    - {time: 1.0, joints: {arm: 0}}\n"))
                .find("trajectory.waypoints[1].time: waypoints must be in time order"),
            std::string::npos);
}

TEST(ArmYaml, AMisspeltKeyJointOrBodyIsNamedWithTheClosestValidName) {
  EXPECT_EQ(arm_error(pendulum("{kp: 400, kdd: 1}")), "arm.yaml:13: joints.arm.controller.kdd: unknown key (did you mean `kd`?)");
  std::string text = pendulum("{kp: 400}");
  text.replace(text.find("  arm:\n    controller"), 6, "  amr:");
  EXPECT_EQ(arm_error(text), "arm.yaml:12: joints.amr: no moving joint of that name (did you mean `arm`?) (joints: arm)");
  EXPECT_EQ(arm_error(pendulum("{kp: 1}", "trajectory:\n  waypoints:\n    - {time: 1.0, joints: {amr: 1}}\n")),
            "arm.yaml:16: trajectory.waypoints[0].joints.amr: no moving joint of that name (did you mean `arm`?)");
  EXPECT_EQ(arm_error(pendulum("{kp: 1}", "trajectory:\n  start: {Arm: 0.1}\n  waypoints:\n    - {time: 1.0, joints: {arm: 1}}\n")),
            "arm.yaml:15: trajectory.start.Arm: no moving joint of that name (did you mean `arm`?) (joints: arm)");
  text = pendulum("{kp: 1}");
  text.replace(text.find("body: arm"), 9, "body: amr");
  EXPECT_EQ(arm_error(text), "arm.yaml: tool.body: no body named 'amr' (did you mean `arm`?)");
  text = pendulum("{kp: 1}", "trajectroy:\n  waypoints:\n    - {time: 1.0, joints: {arm: 1}}\n");
  EXPECT_EQ(arm_error(text), "arm.yaml:14: trajectroy: unknown key (did you mean `trajectory`?)");
}

TEST(ArmModel, ARevoluteWaypointOrStartBeyondATurnLooksLikeDegrees) {
  // {arm: 57}: 57 degrees meant; as radians 9 turns. Refused at the waypoint's line, naming the unit.
  const std::string degrees = "trajectory:\n  waypoints:\n    - {time: 1.0, joints: {arm: 57}}\n";
  EXPECT_EQ(arm_error(pendulum("{kp: 1}", degrees)),
            "arm.yaml:16: trajectory.waypoints[0].joints.arm: 57 rad is more than a turn (2 pi): looks like degrees "
            "(57 deg = 0.9948 rad); angles are in radians (if it is meant, set `units_check: false` at the top of the file)");
  EXPECT_NE(arm_error(pendulum("{kp: 1}", "trajectory:\n  start: {arm: -17}\n  waypoints:\n    - {time: 1.0, joints: {arm: 0}}\n"))
                .find("arm.yaml:15: trajectory.start.arm: -17 rad is more than a turn (2 pi): looks like degrees (-17 deg = -0.2967 rad)"),
            std::string::npos);
  // A turn exactly, and the file's own allowance, pass.
  EXPECT_EQ(arm_error(pendulum("{kp: 1}", "trajectory:\n  waypoints:\n    - {time: 1.0, joints: {arm: 6.283185307179586}}\n")), "no error");
  const ArmModel m = test::arm_from("units_check: false\n" + pendulum("{kp: 1}", degrees));
  EXPECT_EQ(m.trajectory.waypoints.at(0).q.at(0), 57.0);
}

TEST(ArmModel, ALimitBeyondItsJointsMessageShowsTheLimits) {
  std::string text = pendulum("{kp: 1}", "trajectory:\n  waypoints:\n    - {time: 1.0, joints: {arm: 3}}\n");
  text.replace(text.find("armature: 0.05}"), 15, "armature: 0.05, lower: -1.5, upper: 1.5}");
  EXPECT_EQ(arm_error(text), "arm.yaml:16: trajectory.waypoints[0]: joint arm at 3 is beyond its limits [-1.5, 1.5] (rad or m)");
}

TEST(ArmModel, ASagThatRaisesTheMassCentreIsRefusedNamingTheUnits) {
  // configs/flex100.yaml's left arm with E = 70 Pa (70 GPa meant) and the unit check off: the lumped
  // link folds back on itself, its tip 298 mm up; that "equilibrium" is no sag, and is refused.
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/flex100.yaml";
  YAML::Node doc = load_yaml_file(path);
  doc["units_check"] = false;
  for (YAML::Node b : doc["bodies"])
    if (b["name"].as<std::string>() == "left_arm") b["flexible"]["section"]["E"] = 70.0;
  try {
    parse_arm(doc, path);
    ADD_FAILURE() << "accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ": the static sag under gravity moved the arm's mass centre up by ", 0), 0u) << what;
    EXPECT_NE(what.find("mm, against gravity: links far too soft for their load; check the flexible links' E and G (Pa, "
                        "not GPa) and density (kg/m³)"),
              std::string::npos)
        << what;
  }
}

TEST(ArmYaml, DocsListEveryKeyWithTheReadersUnitRequirementAndDefault) {
  test::expect_documented("Arm models", arm_yaml_keys());
}

}  // namespace
}  // namespace ff

namespace ff {
namespace {

TEST(ArmUrdf, TheWorkedExampleFromUrdfReachesItsToolTargetAndHoldsTheRigidArmExactly) {
  // configs/arm6.yaml: the UR5-like URDF with its sidecar, a tool waypoint (IK) at 2 s, back at 4 s.
  // Rigid links, gravity and the joint springs fed forward exactly: at rest the tool is where the
  // reference puts it, and at 2 s the reference puts it on the target.
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/arm6.yaml";
  const ArmModel m = parse_arm(load_yaml_file(path), path);
  EXPECT_EQ(m.actuated.size(), 6u);
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1));
  ASSERT_EQ(run.status[0], LaneStatus::kOk);
  const ArmTrace& tr = run.traces[0];
  const std::size_t at2 = static_cast<std::size_t>(std::lround(2.0 / m.control_period));
  EXPECT_NEAR(tr.column("tool.ref_x")[at2], 0.35, 1e-8);
  EXPECT_NEAR(tr.column("tool.ref_y")[at2], 0.25, 1e-8);
  EXPECT_NEAR(tr.column("tool.ref_z")[at2], 0.45, 1e-8);
  const std::vector<double> v = calc_arm_metrics(m, tr, run.status[0]);
  const std::vector<std::string> c = arm_metric_columns(m);
  const double final_error = v[static_cast<std::size_t>(std::find(c.begin(), c.end(), "tool_final_error_m") - c.begin())];
  RecordProperty("tool_final_error_m", std::to_string(final_error));
  EXPECT_LT(final_error, 1e-9);
}

}  // namespace
}  // namespace ff
