// The dual-arm mobile manipulator of configs/sers.yaml (docs/sers.md): two 6-DOF arms on a 5-DOF base.
//   - Momentum: gravity off, the five base joints passive (no control, springs or dampers), the arms
//     moving under their controllers: the linear momentum along the prismatic base axes (x, y, and the
//     lift's z) and the angular momentum about the vertical are conserved. Computed independently of the
//     dynamics, from each body's centre-of-mass velocity (its point Jacobian) and inertia:
//     P = sum m v_c, L_z = e_z . sum (c x m v_c + R I_c R^T omega). (The carriages of x and y are
//     massless and the yaw axis passes through their origin: the base is a free planar body, so L_z is
//     Noether's quantity of rotating the whole machine about a vertical axis.)
//   - Reaction coupling: one arm moves, the other holds; with the platform free on the floor (x, y, yaw
//     passive) the holding arm's tool is carried away by the platform's recoil while the machine's
//     centre of mass stays put horizontally; with the base locked (its joints fixed) the holding arm's
//     tool does not move at all.
//   - Lanes: a flexible-forearm variant's bits alone and in any lane.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "arm/arm_metrics.hpp"
#include "arm/arm_simulate.hpp"
#include "arm/arm_yaml.hpp"
#include "common/yaml_reader.hpp"
#include "multibody/algorithms.hpp"
#include "tests/arm/test_support.hpp"

namespace ff {
namespace {

const std::string kSers = std::string(FLEXFARM_SOURCE_DIR) + "/configs/sers.yaml";
const char* const kBase[] = {"base_x", "base_y", "base_yaw", "lift", "torso"};
const char* const kBaseBodies[] = {"carriage_x", "carriage_y", "platform", "column", "torso"};

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// configs/sers.yaml with the listed base joints' controllers removed (passive), a joint-space move of
// `moves` (joint -> value) in `move_time` s, RK4 at 4 substeps, `duration` s.
YAML::Node sers_doc(const std::vector<std::string>& passive, const std::string& moves, double move_time,
                    double duration) {
  YAML::Node doc = load_yaml_file(kSers);
  for (const std::string& j : passive) doc["joints"].remove(j);
  doc["trajectory"]["waypoints"] = load_yaml_text("[{time: " + fmt(move_time) + ", joints: " + moves + "}]", "test");
  doc["simulation"]["integrator"] = "rk4";
  doc["simulation"]["substeps"] = 4;
  doc["simulation"]["duration"] = duration;
  return doc;
}

// The base locked: each base body's joint made fixed where it stands at the start (its start value
// folded into the joint frame's position: the lift's 0.3 m).
void lock_base(YAML::Node& doc) {
  for (YAML::Node b : doc["bodies"]) {
    const std::string name = b["name"].as<std::string>();
    for (const char* body : kBaseBodies)
      if (name == body) {
        YAML::Node j = b["joint"];
        YAML::Node fixed;
        fixed["name"] = j["name"];
        fixed["type"] = "fixed";
        std::vector<double> p{0.0, 0.0, 0.0};
        if (j["position"]) p = j["position"].as<std::vector<double>>();
        if (j["name"].as<std::string>() == "lift") p[2] += doc["trajectory"]["start"]["lift"].as<double>();
        fixed["position"] = p;
        b["joint"] = fixed;
      }
  }
  for (const char* j : kBase) {
    doc["joints"].remove(j);
    doc["trajectory"]["start"].remove(j);
  }
}

// The machine's momentum at (q, qd): P (base frame) and L about the base frame's origin, and the scale
// sum m |v_c| (how much momentum is moving about inside it), from body velocities and inertias.
struct Momentum {
  Vec3 P = Vec3::Zero(), L = Vec3::Zero(), com = Vec3::Zero();
  double scale = 0.0, mass = 0.0;
};
Momentum calc_momentum(const Tree& tree, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  Momentum out;
  TreeWorkspace ws(tree);
  Eigen::MatrixXd J(6, tree.nv());
  std::vector<Pose> poses(static_cast<std::size_t>(tree.num_bodies()));
  calc_body_poses(tree, q, poses);
  for (int i = 0; i < tree.num_bodies(); ++i) {
    const Body& b = tree.body(i);
    if (b.mass == 0.0) continue;
    calc_point_jacobian(tree, q, i, b.com, J, ws);  // [omega; v] of the body's centre of mass
    const Vec3 w = J.topRows<3>() * qd, v = J.bottomRows<3>() * qd;
    const Pose& p = poses[static_cast<std::size_t>(i)];
    const Vec3 c = p.point(b.com);
    out.P += b.mass * v;
    out.L += c.cross(b.mass * v) + p.rotation * b.inertia_com * p.rotation.transpose() * w;
    out.com += b.mass * c;
    out.mass += b.mass;
    out.scale += b.mass * v.norm();
  }
  out.com /= out.mass;
  return out;
}

TEST(SersMomentum, WithGravityOffAndTheBasePassiveTheBaseAxesMomentaAndTheVerticalAngularMomentumAreConserved) {
  // Both arms swing out and back under their PD and feed-forward (a 0.8 s quintic), the base free.
  YAML::Node doc = sers_doc({kBase, kBase + 5},
                            "{left_shoulder_yaw: 0.7, left_shoulder_pitch: -0.3, left_elbow: 1.5, left_wrist_pitch: -0.6, "
                            "right_shoulder_yaw: 0.2, right_shoulder_pitch: 0.6, right_elbow: 0.4, right_wrist_roll: 1.0}",
                            0.8, 1.6);
  doc["gravity"] = std::vector<double>{0.0, 0.0, 0.0};
  const ArmModel m = parse_arm(doc, kSers);
  ASSERT_EQ(m.actuated.size(), 12u);
  ASSERT_EQ(m.passive_dofs.size(), 5u);
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1), {.keep_q = true});
  ASSERT_EQ(run.status[0], LaneStatus::kOk);
  // Every joint's rate (the base's too) is in the plant state, not the trace: the same run stepped sample
  // by sample (simulate_arms's loop) and its state read at each sample.
  ArmLanes lanes = make_arm_lanes(std::span<const ArmModel>(&m, 1));
  const int nv = m.tree.nv();
  Eigen::VectorXd q(nv), qd(nv);
  std::vector<double> x(static_cast<std::size_t>(calc_arm_state_size(lanes)));
  Momentum first;
  double drift_P = 0.0, drift_L = 0.0, scale = 0.0, swing = 0.0;
  for (long k = 0; k < lanes.samples; ++k) {
    step_arm_controllers(lanes, k);
    get_arm_state(lanes, 0, x.data());
    for (int j = 0; j < nv; ++j) q[j] = x[static_cast<std::size_t>(j)], qd[j] = x[static_cast<std::size_t>(nv + j)];
    ASSERT_EQ(q, run.q[0].col(k)) << "sample " << k;  // the same run
    const Momentum mo = calc_momentum(m.tree, q, qd);
    if (k == 0) first = mo;
    drift_P = std::max(drift_P, (mo.P - first.P).norm());  // x, y (base_x, base_y) and z (the lift)
    drift_L = std::max(drift_L, std::abs(mo.L.z() - first.L.z()));
    scale = std::max(scale, mo.scale);
    for (int d : m.passive_dofs) swing = std::max(swing, std::abs(q[d] - m.q0[d]));
    if (k + 1 < lanes.samples) step_arm_plant(lanes, k);
  }
  // The base moves (recoils by centimetres), while the momenta stay at their start (zero) to the
  // integrator's error: relative to the momentum moving about inside the machine.
  RecordProperty("base_swing", fmt(swing));
  RecordProperty("momentum_scale_kg_m_s", fmt(scale));
  RecordProperty("linear_momentum_drift_relative", fmt(drift_P / scale));
  RecordProperty("angular_momentum_drift_relative", fmt(drift_L / scale));
  EXPECT_GT(swing, 1e-3);
  EXPECT_GT(scale, 10.0);
  EXPECT_LT(first.P.norm(), 1e-12);
  EXPECT_LT(drift_P, 1e-9 * scale);
  EXPECT_LT(drift_L, 1e-9 * scale);  // L_z in kg m²/s against kg m/s x 1 m
}

// The left arm moves (0.8 s), the right holds its start, 2.5 s in all; the right tool's largest
// displacement from its start, and the machine's horizontal centre of mass's.
struct Coupling {
  double right_tool = 0.0, left_tool = 0.0, com = 0.0, platform = 0.0;
  double riding = 0.0;    // |right tool at the end - where the platform's own motion carries its start|, m
  double right_end = 0.0; // |right tool at the end - its start|, m
  std::vector<double> right_x, right_y, right_z;
};
Coupling run_left_move(YAML::Node doc) {
  const ArmModel m = parse_arm(doc, kSers);
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1), {.keep_q = true});
  EXPECT_EQ(run.status[0], LaneStatus::kOk);
  const ArmTrace& tr = run.traces[0];
  Coupling c;
  c.right_x = tr.column("right.x"), c.right_y = tr.column("right.y"), c.right_z = tr.column("right.z");
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(m.tree.nv());
  const Vec3 com0 = calc_momentum(m.tree, run.q[0].col(0), zero).com;
  const int platform = [&] {
    for (int i = 0; i < m.tree.num_bodies(); ++i)
      if (m.tree.body(i).name == "platform") return i;
    return -1;
  }();
  const Vec3 p0 = platform >= 0 ? calc_body_pose(m.tree, run.q[0].col(0), platform).position : Vec3::Zero();
  for (std::size_t k = 0; k < tr.t().size(); ++k) {
    const auto moved = [&](const std::string& t) {
      return Vec3(tr.column(t + ".x")[k] - tr.column(t + ".x")[0], tr.column(t + ".y")[k] - tr.column(t + ".y")[0],
                  tr.column(t + ".z")[k] - tr.column(t + ".z")[0]).norm();
    };
    c.right_tool = std::max(c.right_tool, moved("right"));
    c.left_tool = std::max(c.left_tool, moved("left"));
    const Eigen::VectorXd q = run.q[0].col(static_cast<Eigen::Index>(k));
    c.com = std::max(c.com, (calc_momentum(m.tree, q, zero).com - com0).head<2>().norm());
    if (platform >= 0) c.platform = std::max(c.platform, (calc_body_pose(m.tree, q, platform).position - p0).norm());
  }
  // Where the platform's rigid motion (start to end) carries the right tool's start point.
  const std::size_t n = tr.t().size() - 1;
  const Vec3 r0(c.right_x[0], c.right_y[0], c.right_z[0]), r1(c.right_x[n], c.right_y[n], c.right_z[n]);
  c.right_end = (r1 - r0).norm();
  if (platform >= 0) {
    const Pose a = calc_body_pose(m.tree, run.q[0].col(0), platform);
    const Pose b = calc_body_pose(m.tree, run.q[0].col(static_cast<Eigen::Index>(n)), platform);
    c.riding = (r1 - (b.position + b.rotation * a.rotation.transpose() * (r0 - a.position))).norm();
  }
  return c;
}

const std::string kLeftMove = "{left_shoulder_yaw: 0.9, left_shoulder_pitch: -0.2, left_elbow: 1.4}";
const std::string kStill = "{left_shoulder_yaw: 0.0}";

TEST(SersCoupling, OneArmsMoveCarriesTheOtherArmsToolThroughAFreeBaseAndNotAtAllThroughALockedOne) {
  // Free platform (x, y, yaw passive; lift and torso held by their PD), gravity on.
  const std::vector<std::string> planar{"base_x", "base_y", "base_yaw"};
  const Coupling free = run_left_move(sers_doc(planar, kLeftMove, 0.8, 2.5));
  // Locked base: the same moves with the five base joints fixed; and with the left arm still too.
  YAML::Node locked_doc = sers_doc({}, kLeftMove, 0.8, 2.5), still_doc = sers_doc({}, kStill, 0.8, 2.5);
  lock_base(locked_doc);
  lock_base(still_doc);
  const Coupling locked = run_left_move(locked_doc), still = run_left_move(still_doc);
  RecordProperty("free_base_right_tool_displacement_m", fmt(free.right_tool));
  RecordProperty("free_base_platform_displacement_m", fmt(free.platform));
  RecordProperty("free_base_com_drift_m", fmt(free.com));
  RecordProperty("left_tool_travel_m", fmt(free.left_tool));
  RecordProperty("locked_base_right_tool_displacement_m", fmt(locked.right_tool));
  RecordProperty("free_base_right_tool_off_the_platforms_motion_m", fmt(free.riding));
  // The moving arm's tool travels most of a metre; the platform recoils (a ~72 kg arm against a ~1.5 t
  // machine: centimetres, and it turns, its inertia about the vertical against the arm's), and the
  // holding arm's tool rides it: at the end it is where the platform's rigid motion carries its start
  // (measured: to 1.2e-9 m of 0.12 m; the rest the lift's, torso's and right arm's servo errors).
  EXPECT_GT(free.left_tool, 0.5);
  EXPECT_GT(free.platform, 2e-3);
  EXPECT_GT(free.right_tool, 2e-3);
  EXPECT_LT(free.right_tool, 0.5 * free.left_tool);
  EXPECT_GT(free.right_end, 2e-3);
  EXPECT_LT(free.riding, 1e-4 * free.right_end);
  // No horizontal force acts on the machine: its centre of mass stays where it was (to the integrator's
  // error), which is why the platform must recoil.
  EXPECT_LT(free.com, 1e-7);
  // Locked: the holding arm does not notice: its tool's trace is the one with the left arm still, bit for bit
  // (the tree's ABA sees a fixed torso), and it stays at its start.
  EXPECT_EQ(locked.right_x, still.right_x);
  EXPECT_EQ(locked.right_y, still.right_y);
  EXPECT_EQ(locked.right_z, still.right_z);
  EXPECT_LT(locked.right_tool, 1e-9);
  EXPECT_GT(locked.left_tool, 0.5);
}

TEST(SersLanes, AFlexibleForearmVariantGivesTheSameBitsAloneAndInAnyLane) {
  // Three variants of the flexible-forearm machine (4 segments per forearm, SDIRK2): another hand mass,
  // another elbow gain, another forearm section; 0.6 s of the Cartesian move of both tools.
  std::vector<ArmModel> lanes;
  for (const char* set : {"", "hand", "gain"}) {
    YAML::Node doc = load_yaml_file(kSers);
    for (const char* f : {"left_forearm", "right_forearm"})
      for (YAML::Node b : doc["bodies"])
        if (b["name"].as<std::string>() == f) b["flexible"]["segments"] = 4;
    doc["simulation"]["duration"] = 0.6;
    doc["simulation"]["substeps"] = 2;
    if (std::string(set) == "hand")
      for (YAML::Node b : doc["bodies"])
        if (b["name"].as<std::string>() == "right_hand") b["mass"] = 14.0;
    if (std::string(set) == "gain") doc["joints"]["left_elbow"]["controller"]["kp"] = 9000.0;
    lanes.push_back(parse_arm(doc, kSers));
  }
  ASSERT_EQ(lanes[0].integrator, Integrator::kSdirk2);
  const ArmRun together = simulate_arms(lanes);
  for (std::size_t l = 0; l < lanes.size(); ++l) {
    ASSERT_EQ(together.status[l], LaneStatus::kOk);
    const ArmRun alone = simulate_arms(std::span<const ArmModel>(&lanes[l], 1));
    EXPECT_EQ(alone.traces[0].columns, together.traces[l].columns) << "lane " << l;
  }
  const std::vector<ArmModel> reversed(lanes.rbegin(), lanes.rend());
  const ArmRun back = simulate_arms(reversed);
  for (std::size_t l = 0; l < lanes.size(); ++l)
    EXPECT_EQ(back.traces[lanes.size() - 1 - l].columns, together.traces[l].columns) << "lane " << l;
}

}  // namespace
}  // namespace ff
