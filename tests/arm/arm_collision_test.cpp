// Tests of arm/arm_collision: an arm's capsules against the world and between arms, as results. Closed
// forms: a link that just touches a floor at the angle trigonometry gives, the clearance of two mirrored
// arms; invariants: the same clearance bits in any lane of a batch, stored and online metrics alike.
#include "arm/arm_collision.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "arm/arm_metrics.hpp"
#include "arm/arm_online_metrics.hpp"
#include "arm/arm_simulate.hpp"
#include "arm/arm_yaml.hpp"
#include "common/yaml_reader.hpp"
#include "multibody/algorithms.hpp"
#include "tests/arm/test_support.hpp"

namespace ff {
namespace {

using test::arm_error;
using test::arm_from;
using test::pendulum_arm;

const std::string kConfigs = std::string(FLEXFARM_SOURCE_DIR) + "/configs/";

// The pendulum (a 1 m capsule of radius 0.05 from the hinge, turning about y: +q tips its end down)
// above a floor 0.8 m below the hinge, moving to `q_end` in 1 s; `more` obstacles after the floor.
std::string pendulum_over_floor(double q_end, const std::string& more = "") {
  return test::tracking_pendulum(
      q_end, "", "world:\n  floor: {type: plane, position: [0, 0, -0.8]}\n" + more + "collision:\n  arm: {radius: 0.05}\n");
}

// The clearances at pose q.
std::vector<double> clearances_at(const ArmModel& m, const Eigen::VectorXd& q, ArmClearanceWitness* w = nullptr) {
  std::vector<Pose> poses(static_cast<std::size_t>(m.tree.num_bodies()));
  calc_body_poses(m.tree, q, poses);
  std::vector<double> out(m.collision.columns());
  calc_arm_clearances(m.collision, poses, out.data(), w);
  return out;
}

TEST(ArmCollision, ALinkJustTouchesTheFloorAtTheAngleWhoseSineIsTheGapOverItsLength) {
  const ArmModel m = arm_from(pendulum_over_floor(1.0));
  ASSERT_EQ(m.collision.capsules.size(), 1u);  // from the hinge to twice the centre of mass
  EXPECT_EQ(m.collision.capsules[0].b, Vec3(1, 0, 0));
  ASSERT_EQ(m.collision.columns(), 3u);         // clearance, arm.clearance, floor.clearance
  // sin(q) * 1 m + 0.05 m = 0.8 m.
  const double touch = std::asin(0.75);
  Eigen::VectorXd q(1);
  for (double dq : {-0.1, -1e-3, 0.0, 1e-3, 0.1}) {
    q[0] = touch + dq;
    ArmClearanceWitness w;
    const std::vector<double> c = clearances_at(m, q, &w);
    const double expected = 0.8 - std::sin(q[0]) - 0.05;
    EXPECT_NEAR(c[0], expected, 1e-14) << dq;
    EXPECT_EQ(c[1], c[0]);
    EXPECT_EQ(c[2], c[0]);
    EXPECT_EQ(w.distance, c[0]);
    EXPECT_EQ(w.obstacle, 0);
    EXPECT_NEAR(w.on_arm.x(), std::cos(q[0]), 1e-14);  // the link's end
    EXPECT_NEAR(w.on_other.z(), -0.8, 1e-14);
  }
  q[0] = touch;
  EXPECT_NEAR(clearances_at(m, q)[0], 0.0, 1e-15);
}

TEST(ArmCollision, ARunThroughTheFloorFirstTouchesWhereTheLinksAngleCrossesTheTouchingOne) {
  const ArmModel m = arm_from(pendulum_over_floor(1.2));
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1));
  ASSERT_EQ(run.status[0], LaneStatus::kOk);
  const ArmTrace& tr = run.traces[0];
  const std::vector<double>&t = tr.t(), &q = tr.column("arm.q"), &c = tr.column("clearance");
  // The trace's clearance is the geometry's of the trace's angle at every sample.
  double q_max = -1;
  for (std::size_t k = 0; k < t.size(); ++k) {
    ASSERT_NEAR(c[k], 0.75 - std::sin(q[k]), 1e-14) << k;
    q_max = std::max(q_max, q[k]);
  }
  const std::vector<std::string> cols = arm_metric_columns(m);
  const std::vector<double> v = calc_arm_metrics(m, tr, run.status[0]);
  auto metric = [&](const std::string& name) { return v[static_cast<std::size_t>(std::find(cols.begin(), cols.end(), name) - cols.begin())]; };
  // The least clearance is at the largest angle; the contact begins between the samples where q crosses
  // asin(0.75), at the linear interpolation of the clearance.
  EXPECT_NEAR(metric("min_clearance_m"), 0.75 - std::sin(q_max), 1e-14);
  EXPECT_EQ(metric("arm_clearance_m"), metric("min_clearance_m"));
  EXPECT_EQ(metric("floor_clearance_m"), metric("min_clearance_m"));
  const double touch = std::asin(0.75);
  std::size_t k = 0;
  while (q[k] < touch) ++k;
  EXPECT_GE(metric("first_contact_s"), t[k - 1]);
  EXPECT_LE(metric("first_contact_s"), t[k]);
  EXPECT_NEAR(metric("first_contact_s"), t[k - 1] + (t[k] - t[k - 1]) * c[k - 1] / (c[k - 1] - c[k]), 1e-15);
  EXPECT_EQ(metric("contacts"), 1.0);  // it stays down there
  EXPECT_EQ(metric("contact"), 1.0);
  EXPECT_GT(metric("min_clearance_time_s"), 0.9);
  // Short of the floor: never a contact.
  const ArmModel short_of_it = arm_from(pendulum_over_floor(0.7));
  const ArmRun r2 = simulate_arms(std::span<const ArmModel>(&short_of_it, 1));
  const std::vector<double> v2 = calc_arm_metrics(short_of_it, r2.traces[0], r2.status[0]);
  const std::size_t first = static_cast<std::size_t>(std::find(cols.begin(), cols.end(), "first_contact_s") - cols.begin());
  EXPECT_TRUE(std::isnan(v2[first]));
  EXPECT_EQ(v2[first + 1], 0.0);  // contacts
  EXPECT_EQ(v2[first + 2], 0.0);  // contact
  EXPECT_GT(v2[first - 2], 0.1);
}

// Several obstacles of every analytic kind and a mesh-free world; random-ish positions per lane.
std::string pendulum_in_a_room(double dx, double dz) {
  return pendulum_over_floor(1.2, "  post: {type: cylinder, radius: 0.1, length: 2.0, position: [" +
                                      std::to_string(0.9 + dx) + ", 0.3, 0]}\n"
                                      "  crate: {type: box, size: [0.3, 0.3, 0.3], position: [0.6, -0.2, " +
                                      std::to_string(-0.5 + dz) + "], rpy: [0.1, 0.2, 0.3]}\n"
                                      "  lamp: {type: sphere, radius: 0.1, position: [0.2, 0, 0.4]}\n"
                                      "  rail: {type: capsule, radius: 0.03, length: 1.0, axis: [1, 0, 0], position: [0.5, 0.2, -0.3]}\n"
                                      "  shaft: {type: bore, radius: 1.5, length: 3.0}\n");
}

TEST(ArmCollision, EveryLaneOfABatchGivesTheClearancesItGivesAloneAndOnlineMetricsTheStoredOnesBits) {
  std::vector<ArmModel> lanes;
  for (int l = 0; l < 4; ++l) lanes.push_back(arm_from(pendulum_in_a_room(0.05 * l, -0.04 * l)));
  ASSERT_EQ(lanes[0].collision.columns(), 1u + 1u + 6u);
  std::vector<OnlineArmRun> online;
  for (const ArmModel& m : lanes) online.emplace_back(m);
  const ArmRun batch = simulate_arms(lanes);
  const ArmRun batch_online = simulate_arms(lanes, {.online = &online});
  for (std::size_t l = 0; l < lanes.size(); ++l) {
    const ArmRun alone = simulate_arms(std::span<const ArmModel>(&lanes[l], 1));
    for (const std::string& name : alone.traces[0].names)
      if (name.ends_with("clearance"))
        test::expect_same_bits(alone.traces[0].column(name), batch.traces[l].column(name), name + " lane " + std::to_string(l));
    test::expect_same_bits(calc_arm_metrics(lanes[l], batch.traces[l], batch.status[l]), online[l].result(batch_online.status[l]),
                           "metrics lane " + std::to_string(l));
  }
  // The lanes differ (the post and the crate move), so their clearances do.
  EXPECT_NE(calc_arm_metrics(lanes[0], batch.traces[0], batch.status[0]),
            calc_arm_metrics(lanes[3], batch.traces[3], batch.status[3]));
}

TEST(ArmCollision, TwoMirroredArmsAtRestAreTheirShouldersSpacingLessTheirThickestCapsulesApart) {
  // configs/sers.yaml: two arms 0.6 m apart (y = +-0.3), each in its own plane at q = 0, mirror images:
  // the least clearance is between a capsule and its mirror image, 0.6 m less twice the thickest radius.
  YAML::Node doc = load_yaml_file(kConfigs + "sers.yaml");
  doc["world"]["floor"]["type"] = "plane";
  const ArmModel m = parse_arm(doc, kConfigs + "sers.yaml");
  ASSERT_FALSE(m.collision.arm_pairs.empty());
  double r_max = 0;
  for (const auto& [u, v] : m.collision.arm_pairs) {
    const int bu = m.collision.capsules[static_cast<std::size_t>(u)].body, bv = m.collision.capsules[static_cast<std::size_t>(v)].body;
    // Never a body and its ancestor (a chain's own links).
    for (int i = bv; i >= 0; i = m.tree.body(i).parent) ASSERT_NE(i, bu);
    for (int i = bu; i >= 0; i = m.tree.body(i).parent) ASSERT_NE(i, bv);
    r_max = std::max({r_max, m.collision.capsules[static_cast<std::size_t>(u)].radius,
                      m.collision.capsules[static_cast<std::size_t>(v)].radius});
  }
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(m.tree.nv());
  ArmClearanceWitness w;
  const std::vector<double> c = clearances_at(m, q, &w);
  // The floor (z = 0) is touched by the platform's capsule; the arms' least is between each other.
  double arms = std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < m.collision.parts.size(); ++p)
    if (m.collision.parts[p].starts_with("left_")) arms = std::min(arms, c[1 + p]);
  EXPECT_NEAR(arms, 0.6 - 2 * r_max, 1e-12);
}

TEST(ArmCollision, TheWorldAndCollisionBlocksNameTheKeyOfEachMistake) {
  const auto with = [](const std::string& world) {
    return arm_error(pendulum_arm("joints: {arm: {controller: {kp: 10}}}\ntrajectory: {waypoints: [{time: 1, joints: {arm: 0.1}}]}\n" + world));
  };
  EXPECT_NE(with("world:\n  w: {type: slab}\n").find("world.w.type: unknown obstacle type 'slab'"), std::string::npos)
      << with("world:\n  w: {type: slab}\n");
  EXPECT_NE(with("world:\n  w: {type: box, radius: 1, size: [1, 1, 1]}\n").find("world.w.radius: is not a key of a box"),
            std::string::npos);
  EXPECT_NE(with("world:\n  w: {type: cylinder, radius: 1}\n").find("world.w.length: missing: a cylinder needs it"),
            std::string::npos);
  EXPECT_NE(with("world:\n  w: {type: box, size: [1, 0, 1]}\n").find("world.w.size: every edge of a box must be > 0"),
            std::string::npos);
  EXPECT_NE(with("world:\n  w: {type: sphere, radius: -1}\n").find("world.w.radius: must be > 0"), std::string::npos);
  EXPECT_NE(with("world:\n  w: {type: bore, radius: 1, length: 1, axis: [1, 0, 0], rpy: [0, 0, 1]}\n")
                .find("world.w.axis: give the orientation either as rpy or as axis"),
            std::string::npos);
  EXPECT_NE(with("world:\n  w: {type: mesh, file: nowhere.stl}\n").find("world.w.file: "), std::string::npos);
  EXPECT_NE(with("world:\n  arm: {type: plane}\n").find("world.arm: an obstacle's name must differ"), std::string::npos);
  EXPECT_NE(with("world:\n  a.b: {type: plane}\n").find("no dots"), std::string::npos);
  EXPECT_NE(with("collision:\n  elbow: {radius: 1}\n").find("collision.elbow: no part of that name"), std::string::npos);
  EXPECT_NE(with("collision:\n  arm: {thickness: 1}\n").find("collision.arm.thickness"), std::string::npos);
  // The line of the obstacle is named.
  EXPECT_NE(with("world:\n  w: {type: slab}\n").find("arm.yaml:12:"), std::string::npos) << with("world:\n  w: {type: slab}\n");
}

TEST(ArmCollision, APartLeftOutOrAnArmWithoutAWorldMeasuresNothing) {
  const ArmModel none = arm_from(pendulum_arm("joints: {arm: {controller: {kp: 10}}}\n"));
  EXPECT_FALSE(none.collision.active());
  EXPECT_EQ(none.collision.columns(), 0u);
  const std::vector<std::string> cols = arm_metric_columns(none);
  EXPECT_EQ(std::find(cols.begin(), cols.end(), "min_clearance_m"), cols.end());
  std::string text = pendulum_over_floor(1.0);
  text.replace(text.find("arm: {radius: 0.05}"), 19, "arm: {enabled: false}");
  const ArmModel off = arm_from(text);
  EXPECT_TRUE(off.collision.capsules.empty());
  EXPECT_FALSE(off.collision.active());
}

}  // namespace
}  // namespace ff

namespace ff {
namespace {

TEST(ArmCollision, TheTankRisersMastClearsTheRiserAndTheDomesHoleByTheBoreLessItsOwnRadius) {
  // configs/tank_riser.yaml hanging straight down with the mast 0.6 m deployed: the mast (a 425 kg tube
  // with I_zz 7.5 kg m^2 about its axis: radius sqrt(7.5 / 425)) runs up the 0.3 m bore's axis, and the
  // boom (radius sqrt((I_y + I_z) / A) of its section) hangs down it and through the dome mesh's hole,
  // whose flats are at 0.3 m.
  const ArmModel m = parse_arm(load_yaml_file(kConfigs + "tank_riser.yaml"), kConfigs + "tank_riser.yaml");
  Eigen::VectorXd q = Eigen::VectorXd::Zero(m.tree.nv());
  for (const auto& [joint, value] : std::vector<std::pair<std::string, double>>{{"deploy", 0.6}, {"shoulder", M_PI / 2}})
    q[m.spec.tree.dof_index.at(joint)] = value;
  const std::vector<double> c = clearances_at(m, q);
  const auto column = [&](const std::string& name) {
    const auto& parts = m.collision.parts;
    const auto p = std::find(parts.begin(), parts.end(), name);
    if (p != parts.end()) return c[1 + static_cast<std::size_t>(p - parts.begin())];
    const auto& obs = m.collision.world.obstacles;
    const auto o = std::find_if(obs.begin(), obs.end(), [&](const Obstacle& x) { return x.name == name; });
    return c[1 + parts.size() + static_cast<std::size_t>(o - obs.begin())];
  };
  const double mast = 0.3 - std::sqrt(7.5 / 425.0), boom = 0.3 - std::sqrt(2 * 7.30e-6 / 2.752e-3);
  EXPECT_NEAR(column("mast"), mast, 1e-12);   // the bore: closed form
  EXPECT_NEAR(column("riser"), mast, 1e-12);
  EXPECT_NEAR(column("boom"), boom, 1e-6);    // the least of the bore and the hole
  EXPECT_NEAR(column("dome"), boom, 1e-6);    // the hole: FCL's distance to the mesh
  EXPECT_EQ(std::find(m.collision.parts.begin(), m.collision.parts.end(), "turret"), m.collision.parts.end());
}

}  // namespace
}  // namespace ff
