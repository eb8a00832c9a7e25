// multibody/inverse_kinematics: a planar 2R arm against its closed-form solution (both elbow
// branches), the UR-like 6-DOF arm of tests/data/urdf/arm6.yaml reaching poses made by forward
// kinematics, the closest point to a target beyond reach, free dofs (a flexible link held rigid),
// joint limits, and bad arguments.
#include "multibody/inverse_kinematics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "multibody/algorithms.hpp"
#include "multibody/flexible_link.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

using Eigen::VectorXd;
constexpr double kPi = std::numbers::pi;

// Angle difference wrapped to (-pi, pi].
double angle_diff(double a, double b) { return std::remainder(a - b, 2 * kPi); }

BodySpec link_body(int parent, const Vec3& position, double length, double mass) {
  BodySpec b;
  b.parent = parent;
  b.axis = Vec3::UnitZ();
  b.position = position;
  b.mass = mass;
  b.com = {length / 2, 0.0, 0.0};
  b.inertia = test::box_inertia(mass, length, 0.04, 0.04);
  return b;
}

// Planar 2R arm in the base's x-y plane: shoulder at the origin, elbow at l1 along link 1's x, the
// tip at l2 along link 2's x; both joints about z.
constexpr double kL1 = 0.5, kL2 = 0.4;  // m
Tree two_link_arm() {
  TreeSpec s;
  s.bodies.push_back(link_body(-1, Vec3::Zero(), kL1, 2.0));
  s.bodies.push_back(link_body(0, {kL1, 0.0, 0.0}, kL2, 1.0));
  return make_tree(s);
}
const Vec3 kTip2R{kL2, 0.0, 0.0};

// Closed-form 2R inverse kinematics (Spong, Hutchinson and Vidyasagar, Robot Modeling and Control,
// 2006, sec. 3.3): cos q2 = (x² + y² - l1² - l2²) / (2 l1 l2), q2 = ±acos, q1 = atan2(y, x) -
// atan2(l2 sin q2, l1 + l2 cos q2). elbow = +1 or -1 picks the branch.
VectorXd closed_form_2r(double l1, double l2, double x, double y, double elbow) {
  const double c2 = (x * x + y * y - l1 * l1 - l2 * l2) / (2 * l1 * l2);
  const double q2 = elbow * std::acos(c2);
  VectorXd q(2);
  q << std::atan2(y, x) - std::atan2(l2 * std::sin(q2), l1 + l2 * std::cos(q2)), q2;
  return q;
}

// The arm of tests/data/urdf/arm6.yaml (UR5-like): joint positions and rpy (URDF's fixed-axis
// R = Rz(yaw) Ry(pitch) Rx(roll)), axes, masses, centres of mass, principal moments; tool0 fixed.
Mat3 rpy(double r, double p, double y) { return rotz(y) * roty(p) * rotx(r); }
Tree arm6() {
  struct L {
    Vec3 position, rpy, axis;
    double mass;
    Vec3 com, moments;
    bool fixed;
  };
  const double h = kPi / 2;
  const L links[] = {
      {{0, 0, 0.089159}, {0, 0, 0}, Vec3::UnitZ(), 3.7, {0, 0.00193, -0.02561}, {0.0102675, 0.0102675, 0.00666}, false},
      {{0, 0.13585, 0}, {0, h, 0}, Vec3::UnitY(), 8.393, {0, 0, 0.28}, {0.22689, 0.22689, 0.0151074}, false},
      {{0, -0.1197, 0.425}, {0, 0, 0}, Vec3::UnitY(), 2.275, {0, 0, 0.196125}, {0.0312168, 0.0312168, 0.004095}, false},
      {{0, 0, 0.39225}, {0, h, 0}, Vec3::UnitY(), 1.219, {0, 0.093, 0}, {0.0025, 0.0030, 0.0040}, false},
      {{0, 0.093, 0}, {0.1, -0.2, 0.3}, Vec3::UnitZ(), 1.219, {0, 0, 0.09465}, {0.0025, 0.0025, 0.0021942}, false},
      {{0, 0, 0.09465}, {-h, 0, 0}, Vec3::UnitY(), 0.1879, {0, 0.065, 0}, {0.000133, 0.000179, 0.000133}, false},
      {{0, 0.0823, 0}, {-h, 0, 0}, Vec3::UnitZ(), 0.35, {0, 0, 0.04}, {0.0004, 0.0004, 0.0002}, true},
  };
  TreeSpec s;
  for (int i = 0; i < 7; ++i) {
    BodySpec b;
    b.parent = i - 1;
    b.joint = links[i].fixed ? JointType::kFixed : JointType::kRevolute;
    b.axis = links[i].axis;
    b.position = links[i].position;
    b.rotation = rpy(links[i].rpy.x(), links[i].rpy.y(), links[i].rpy.z());
    b.mass = links[i].mass;
    b.com = links[i].com;
    b.inertia = links[i].moments.asDiagonal();
    s.bodies.push_back(b);
  }
  return make_tree(s);
}
constexpr int kTool = 6;               // tool0
const Vec3 kToolPoint{0.0, 0.0, 0.05};  // 5 cm out along the tool's z, m

TEST(InverseKinematics, TwoLinkArmReachesTheClosedFormSolutionOnTheElbowBranchOfItsStart) {
  // Targets at 0.2..0.85 m (reach 0.9 m, inner 0.1 m) around the circle; from a start with the elbow
  // bent one way the solver lands on that branch of the closed form, to 1e-9 rad.
  const Tree tree = two_link_arm();
  test::Rng rng(7);
  for (int k = 0; k < 20; ++k) {
    const double d = rng.uniform(0.2, 0.85), phi = rng.uniform(-kPi, kPi);
    const Vec3 p{d * std::cos(phi), d * std::sin(phi), 0.0};
    for (double elbow : {1.0, -1.0}) {
      VectorXd q0(2);
      q0 << phi, elbow * 1.0;
      const IkResult r = solve_inverse_kinematics(tree, q0, {.body = 1, .point = kTip2R, .position = p});
      ASSERT_TRUE(r.converged) << r.why;
      EXPECT_TRUE(r.why.empty());
      EXPECT_LE(r.position_error, 1e-9);
      EXPECT_EQ(r.orientation_error, 0.0);
      const VectorXd qc = closed_form_2r(kL1, kL2, p.x(), p.y(), elbow);
      EXPECT_NEAR(angle_diff(r.q[0], qc[0]), 0.0, 1e-8) << "target " << k << " elbow " << elbow;
      EXPECT_NEAR(angle_diff(r.q[1], qc[1]), 0.0, 1e-8) << "target " << k << " elbow " << elbow;
      EXPECT_LE((calc_point_position(tree, r.q, 1, kTip2R) - p).norm(), 1e-9);
    }
  }
}

TEST(InverseKinematics, TargetBeyondReachStopsAtTheStretchedArmPointingAtIt) {
  // A target 1.25 m away, reach l1 + l2 = 0.9 m: no solution; the closest point is the straight arm
  // aimed at the target, 0.35 m short, reported with converged = false and a reason.
  const Tree tree = two_link_arm();
  const double phi = 0.7;
  const Vec3 p = 1.25 * Vec3{std::cos(phi), std::sin(phi), 0.0};
  VectorXd q0(2);
  q0 << -0.4, 1.2;
  const IkResult r = solve_inverse_kinematics(tree, q0, {.body = 1, .point = kTip2R, .position = p});
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.why.rfind("target 0.35 m beyond reach (the point stays within 0.9 m of body 0's joint)", 0), 0u)
      << r.why;
  EXPECT_NEAR(r.position_error, 1.25 - (kL1 + kL2), 1e-12);
  EXPECT_NEAR(angle_diff(r.q[0], phi), 0.0, 1e-8);
  EXPECT_NEAR(angle_diff(r.q[1], 0.0), 0.0, 1e-8);
  RecordProperty("why", r.why);
  RecordProperty("iterations", r.iterations);
}

TEST(InverseKinematics, SixDofArmReachesRandomPosesMadeByForwardKinematics) {
  // 50 poses of the tool point and tool orientation from random q in [-pi, pi]^6 (reachable by
  // construction); the solver starts from q plus up to ±0.6 rad on every joint (a nearby seed, as a
  // controller tracking a path would) and must reach both to 1e-9 m and 1e-9 rad.
  const Tree tree = arm6();
  ASSERT_EQ(tree.nv(), 6);
  test::Rng rng(20260611);
  int worst_iterations = 0, total = 0;
  for (int k = 0; k < 50; ++k) {
    const VectorXd q = test::random_q(rng, tree);
    const Pose pose = calc_body_pose(tree, q, kTool);
    const IkTarget target{.body = kTool, .point = kToolPoint, .position = pose.point(kToolPoint), .orient = true,
                          .rotation = pose.rotation};
    const VectorXd q0 = q + test::random_vector(rng, 6, -0.6, 0.6);
    const IkResult r = solve_inverse_kinematics(tree, q0, target);
    ASSERT_TRUE(r.converged) << "pose " << k << ": " << r.why;
    EXPECT_LE(r.position_error, 1e-9);
    EXPECT_LE(r.orientation_error, 1e-9);
    const Pose got = calc_body_pose(tree, r.q, kTool);
    EXPECT_LE((got.point(kToolPoint) - target.position).norm(), 1e-9);
    EXPECT_LE((got.rotation - pose.rotation).cwiseAbs().maxCoeff(), 2e-9);
    worst_iterations = std::max(worst_iterations, r.iterations);
    total += r.iterations;
  }
  RecordProperty("worst_iterations", worst_iterations);
  RecordProperty("mean_iterations", test::sci(total / 50.0));
}

TEST(InverseKinematics, SixDofArmFromHomeReachesThePoseOrReportsWhereItStopped) {
  // Full poses from the home pose q = 0, far from most solutions: damped least squares is a local
  // method, so some runs end in a local minimum; each is then a result with its reason and residual.
  const Tree tree = arm6();
  test::Rng rng(20260611);
  int converged = 0;
  for (int k = 0; k < 50; ++k) {
    const VectorXd q = test::random_q(rng, tree);
    const Pose pose = calc_body_pose(tree, q, kTool);
    const IkTarget target{.body = kTool, .point = kToolPoint, .position = pose.point(kToolPoint), .orient = true,
                          .rotation = pose.rotation};
    const IkResult r = solve_inverse_kinematics(tree, VectorXd::Zero(6), target);
    if (r.converged) {
      ++converged;
      EXPECT_LE(r.position_error, 1e-9);
      EXPECT_LE(r.orientation_error, 1e-9);
    } else {
      EXPECT_EQ(r.why.rfind("stationary ", 0), 0u) << r.why;
      EXPECT_GT(std::max(r.position_error, r.orientation_error), 1e-6) << r.why;
      const Pose got = calc_body_pose(tree, r.q, kTool);
      EXPECT_NEAR(r.position_error, (got.point(kToolPoint) - target.position).norm(), 1e-15);
    }
  }
  EXPECT_GE(converged, 20);
  RecordProperty("converged_of_50", converged);
  // Far outside the arm: beyond reach, whatever the start.
  const IkResult far = solve_inverse_kinematics(tree, VectorXd::Zero(6),
                                                {.body = kTool, .point = kToolPoint, .position = {3.0, 0.0, 0.5}});
  EXPECT_FALSE(far.converged);
  EXPECT_NE(far.why.find(" beyond reach (the point stays within "), std::string::npos) << far.why;
  RecordProperty("far_why", far.why);
}

TEST(InverseKinematics, SixDofArmReachesRandomPositionsFromHome) {
  // Position only (3 equations, 6 dofs: redundant), 50 targets from random q, every one from the
  // home pose q = 0: to 1e-9 m.
  const Tree tree = arm6();
  test::Rng rng(99);
  int worst_iterations = 0;
  for (int k = 0; k < 50; ++k) {
    const VectorXd q = test::random_q(rng, tree);
    const IkTarget target{.body = kTool, .point = kToolPoint, .position = calc_point_position(tree, q, kTool, kToolPoint)};
    const IkResult r = solve_inverse_kinematics(tree, VectorXd::Zero(6), target);
    ASSERT_TRUE(r.converged) << "target " << k << ": " << r.why;
    EXPECT_LE((calc_point_position(tree, r.q, kTool, kToolPoint) - target.position).norm(), 1e-9);
    worst_iterations = std::max(worst_iterations, r.iterations);
  }
  RecordProperty("worst_iterations", worst_iterations);
}

// A shoulder, a planar flexible link of 0.8 m (5 segments, 4 cell joints), an elbow at its tip and a
// rigid 0.5 m forearm: with the cell joints at 0 it is the 2R arm l1 = 0.8 m, l2 = 0.5 m.
struct FlexArm {
  Tree tree;
  int shoulder = -1, elbow = -1, forearm = -1;
  std::vector<int> cells;
};
FlexArm flexible_two_link_arm() {
  TreeSpec s;
  s.bodies.push_back(link_body(-1, Vec3::Zero(), 0.05, 1.0));
  FlexibleLinkSpec link;
  link.name = "upper";
  link.length = 0.8;
  link.section = {.youngs_modulus = 70e9, .shear_modulus = 26e9, .density = 2700, .area = 2e-4,
                  .second_moment_y = 1e-9, .second_moment_z = 2e-9, .torsion_constant = 1e-9};
  link.segments = 5;
  link.planar = true;
  const int tip = append_flexible_link(s, 0, Vec3::Zero(), Mat3::Identity(), link);
  s.bodies.push_back(link_body(tip, flexible_link_tip_point(link), 0.5, 1.0));
  FlexArm a{make_tree(s), -1, -1, -1, {}};
  a.forearm = a.tree.num_bodies() - 1;
  a.shoulder = a.tree.body(0).dof;
  a.elbow = a.tree.body(a.forearm).dof;
  for (const Body& b : a.tree.bodies())
    if (b.dof >= 0 && b.dof != a.shoulder && b.dof != a.elbow) a.cells.push_back(b.dof);
  return a;
}

TEST(InverseKinematics, FreeDofsAloneMoveAndTheFlexibleLinksCellJointsStayBitForBit) {
  const FlexArm a = flexible_two_link_arm();
  ASSERT_EQ(a.cells.size(), 4u);
  const int nv = a.tree.nv();
  const Vec3 tip{0.5, 0.0, 0.0};
  const Vec3 p{0.6, 0.7, 0.0};
  IkOptions opt;
  opt.free_dofs = {a.elbow, a.shoulder};
  // The rigid model (cells at 0): the 2R closed form with l1 = 0.8 m, l2 = 0.5 m.
  VectorXd q0 = VectorXd::Zero(nv);
  q0[a.elbow] = 0.8;
  IkResult r = solve_inverse_kinematics(a.tree, q0, {.body = a.forearm, .point = tip, .position = p}, opt);
  ASSERT_TRUE(r.converged) << r.why;
  const VectorXd qc = closed_form_2r(0.8, 0.5, p.x(), p.y(), 1.0);
  EXPECT_NEAR(angle_diff(r.q[a.shoulder], qc[0]), 0.0, 1e-8);
  EXPECT_NEAR(angle_diff(r.q[a.elbow], qc[1]), 0.0, 1e-8);
  for (int d : a.cells) EXPECT_EQ(r.q[d], 0.0);
  // A bent link (cells at 0.03..0.06 rad): the cells keep their values bit for bit, the target is
  // still reached by the shoulder and elbow alone.
  for (std::size_t i = 0; i < a.cells.size(); ++i) q0[a.cells[i]] = 0.03 * (1.0 + i / 3.0);
  r = solve_inverse_kinematics(a.tree, q0, {.body = a.forearm, .point = tip, .position = p}, opt);
  ASSERT_TRUE(r.converged) << r.why;
  EXPECT_LE((calc_point_position(a.tree, r.q, a.forearm, tip) - p).norm(), 1e-9);
  for (int d : a.cells) EXPECT_EQ(r.q[d], q0[d]) << "dof " << d;
  // The elbow alone cannot reach it: a circle of radius 0.5 m about the elbow; stationary, closest.
  opt.free_dofs = {a.elbow};
  r = solve_inverse_kinematics(a.tree, q0, {.body = a.forearm, .point = tip, .position = p}, opt);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.q[a.shoulder], q0[a.shoulder]);
  for (int d : a.cells) EXPECT_EQ(r.q[d], q0[d]);
  const Vec3 elbow = calc_body_pose(a.tree, q0, a.forearm).position;
  EXPECT_NEAR(r.position_error, std::abs((p - elbow).norm() - 0.5), 1e-9) << r.why;
  EXPECT_EQ(r.why.rfind("stationary ", 0), 0u) << r.why;
  EXPECT_NE(r.why.find("the free dofs cannot reach"), std::string::npos) << r.why;
}

TEST(InverseKinematics, JointLimitsAreHonouredAndPickTheAllowedBranch) {
  const Tree tree = two_link_arm();
  const Vec3 p{0.3, 0.6, 0.0};
  // The elbow limited to [0.1, 2.5] rad (bent one way only): from an elbow-down start (clamped to
  // 0.1 first) the solver reaches the elbow-up branch.
  IkOptions opt;
  opt.lower = {-kPi, 0.1};
  opt.upper = {kPi, 2.5};
  VectorXd q0(2);
  q0 << 1.5, -1.0;
  IkResult r = solve_inverse_kinematics(tree, q0, {.body = 1, .point = kTip2R, .position = p}, opt);
  ASSERT_TRUE(r.converged) << r.why;
  const VectorXd qc = closed_form_2r(kL1, kL2, p.x(), p.y(), 1.0);
  EXPECT_NEAR(r.q[0], qc[0], 1e-8);
  EXPECT_NEAR(r.q[1], qc[1], 1e-8);
  // Without limits the same start keeps the elbow-down branch.
  opt.respect_limits = false;
  r = solve_inverse_kinematics(tree, q0, {.body = 1, .point = kTip2R, .position = p}, opt);
  ASSERT_TRUE(r.converged) << r.why;
  EXPECT_LT(r.q[1], 0.0);
  // The shoulder capped at 0.5 rad, a target needing more on both branches: not reached, the
  // shoulder exactly at its limit, everything within the limits, the reason names the dof.
  opt.respect_limits = true;
  opt.lower = {-0.5, -2.5};
  opt.upper = {0.5, 2.5};
  const Vec3 far{-0.2, 0.7, 0.0};
  q0 << 0.0, 0.5;
  r = solve_inverse_kinematics(tree, q0, {.body = 1, .point = kTip2R, .position = far}, opt);
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.why.find("joint limits"), std::string::npos) << r.why;
  EXPECT_NE(r.why.find("dof 0"), std::string::npos) << r.why;
  EXPECT_EQ(r.q[0], 0.5);
  EXPECT_GE(r.q[1], -2.5);
  EXPECT_LE(r.q[1], 2.5);
  EXPECT_GT(r.position_error, 0.01);
  RecordProperty("why", r.why);
}

TEST(InverseKinematics, SixDofArmStaysWithinTightLimits) {
  // Limits of ±1.2 rad on every joint, targets from random q inside ±1 rad: all reached, and the
  // solution within the limits.
  const Tree tree = arm6();
  test::Rng rng(5);
  IkOptions opt;
  opt.lower.assign(6, -1.2);
  opt.upper.assign(6, 1.2);
  for (int k = 0; k < 20; ++k) {
    const VectorXd q = test::random_vector(rng, 6, -1.0, 1.0);
    const Pose pose = calc_body_pose(tree, q, kTool);
    const IkTarget target{.body = kTool, .point = kToolPoint, .position = pose.point(kToolPoint), .orient = true,
                          .rotation = pose.rotation};
    const IkResult r = solve_inverse_kinematics(tree, VectorXd::Zero(6), target, opt);
    EXPECT_TRUE(r.converged) << "pose " << k << ": " << r.why;
    for (int j = 0; j < 6; ++j) {
      EXPECT_GE(r.q[j], -1.2);
      EXPECT_LE(r.q[j], 1.2);
    }
  }
}

TEST(InverseKinematics, IterationLimitIsReportedWithTheResidual) {
  const Tree tree = two_link_arm();
  VectorXd q0(2);
  q0 << 0.0, 0.3;
  IkOptions opt;
  opt.max_iterations = 2;
  const IkResult r = solve_inverse_kinematics(tree, q0, {.body = 1, .point = kTip2R, .position = {-0.3, 0.5, 0.0}}, opt);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.iterations, 2);
  EXPECT_EQ(r.why.rfind("did not converge in 2 iterations; residual ", 0), 0u) << r.why;
  EXPECT_NEAR(r.position_error, (calc_point_position(tree, r.q, 1, kTip2R) - Vec3{-0.3, 0.5, 0.0}).norm(), 1e-15);
  // Already there: no iteration.
  const Vec3 here = calc_point_position(tree, q0, 1, kTip2R);
  const IkResult s = solve_inverse_kinematics(tree, q0, {.body = 1, .point = kTip2R, .position = here});
  EXPECT_TRUE(s.converged);
  EXPECT_EQ(s.iterations, 0);
  EXPECT_EQ(s.q, q0);
}

void expect_rejected(const Tree& tree, const VectorXd& q0, const IkTarget& t, const IkOptions& o,
                     const std::string& words) {
  try {
    solve_inverse_kinematics(tree, q0, t, o);
    ADD_FAILURE() << "accepted; expected an error with \"" << words << "\"";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(InverseKinematics, BadArgumentsThrowButFailuresToReachDoNot) {
  const Tree tree = two_link_arm();
  const VectorXd q0 = VectorXd::Zero(2);
  const IkTarget t{.body = 1, .point = kTip2R, .position = {0.3, 0.3, 0.0}};
  const IkOptions o;
  expect_rejected(tree, q0, {.body = 2}, o, "no body 2");
  expect_rejected(tree, q0, {.body = -1}, o, "no body -1");
  expect_rejected(tree, VectorXd::Zero(3), t, o, "q0 has 3 entries");
  expect_rejected(tree, VectorXd::Constant(2, std::nan("")), t, o, "q0 is not finite");
  expect_rejected(tree, q0, {.body = 1, .position = {0, std::nan(""), 0}}, o, "not finite");
  expect_rejected(tree, q0, {.body = 1, .orient = true, .rotation = 2 * Mat3::Identity()}, o, "proper rotation");
  expect_rejected(tree, q0, {.body = 1, .orient = true, .rotation = -Mat3::Identity()}, o, "proper rotation");
  IkOptions b;
  b.free_dofs = {0, 2};
  expect_rejected(tree, q0, t, b, "free dof 2 is out of range");
  b.free_dofs = {1, 1};
  expect_rejected(tree, q0, t, b, "free dof 1 is listed twice");
  b = {};
  b.lower = {0.0};
  expect_rejected(tree, q0, t, b, "lower limits have 1 entries");
  b = {};
  b.lower = {0.0, 1.0};
  b.upper = {1.0, 0.5};
  expect_rejected(tree, q0, t, b, "dof 1: lower limit 1 is above the upper 0.5");
  b = {};
  b.upper = {std::nan(""), 1.0};
  expect_rejected(tree, q0, t, b, "upper limit of dof 0 is NaN");
  b = {};
  b.damping = 0.0;
  expect_rejected(tree, q0, t, b, "damping");
  b = {};
  b.max_iterations = -1;
  expect_rejected(tree, q0, t, b, "max_iterations");
  b = {};
  b.tolerance = 0.0;
  expect_rejected(tree, q0, t, b, "tolerance");
  // Infinite limits are unbounded, not errors; an unreachable target is a result.
  b = {};
  b.lower = {-std::numeric_limits<double>::infinity(), 0.0};
  EXPECT_NO_THROW(solve_inverse_kinematics(tree, q0, t, b));
  EXPECT_NO_THROW(solve_inverse_kinematics(tree, q0, {.body = 1, .point = kTip2R, .position = {5.0, 0.0, 0.0}}));
}

TEST(InverseKinematics, APointNoJointMovesIsReachedOnlyWhereItIs) {
  // A tree of one fixed body (nv = 0): the point 0.2 m from the origin, targets there and 0.5 m away.
  TreeSpec s;
  s.bodies.push_back(link_body(-1, {0.1, 0.0, 0.0}, 0.2, 1.0));
  s.bodies[0].joint = JointType::kFixed;
  const Tree tree = make_tree(s);
  ASSERT_EQ(tree.nv(), 0);
  const IkResult here = solve_inverse_kinematics(tree, VectorXd(0), {.body = 0, .point = {0.1, 0, 0}, .position = {0.2, 0, 0}});
  EXPECT_TRUE(here.converged);
  const IkResult away = solve_inverse_kinematics(tree, VectorXd(0), {.body = 0, .point = {0.1, 0, 0}, .position = {0.2, 0.5, 0}});
  EXPECT_FALSE(away.converged);
  EXPECT_EQ(away.why, "target beyond reach: 0.5 m from the point, which no joint moves");
  EXPECT_DOUBLE_EQ(away.position_error, 0.5);
}

}  // namespace
}  // namespace ff
