// The truth arm (tests/validate/truth_arm/): energy is conserved, one link swings at the pendulum's
// period, the two-link arm with rigid drives agrees with flexfarm's arm model (another formulation),
// gravity's static equilibrium holds, and the hidden effects obey analytic facts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "sweep/paths.hpp"
#include "tests/validate/truth_arm/truth_arm.hpp"
#include "validate/arm_record.hpp"

namespace ff::truth {
namespace {

std::string data(const std::string& file) { return std::string(FLEXFARM_SOURCE_DIR) + "/tests/data/truth_arm/" + file; }

// The arm with no control at all: the plant alone.
TruthArm free_arm(int joints, double duration) {
  TruthArm a = make_suite_arm(joints);
  for (auto& j : a.joint) {
    j.controller.kp = j.controller.kd = 0.0;
    j.controller.gravity_compensation = 0.0;
  }
  a.trajectory.waypoints.clear();
  a.duration = duration;
  a.solver.rtol = 1e-11;  // the drift below is CVODE's error (1e-9: 1.2e-6 of the swing)
  a.solver.atol = 1e-13;
  return a;
}

double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k) m = std::max(m, std::abs(a[k] - b[k]));
  return m;
}

// The free arm falls from its start and swings: kinetic + potential is constant (no friction, no damping).
TEST(TruthArm, EnergyIsConservedWithoutDampingOrControl) {
  TruthArm a = free_arm(3, 1.5);
  const TruthArmRun run = run_truth_arm(a);
  const auto [lo, hi] = std::minmax_element(run.trace.energy.begin(), run.trace.energy.end());
  const double swing = std::abs(calc_truth_arm_potential(a, run.trace.q.front()) - calc_truth_arm_potential(a, run.trace.q.back()));
  EXPECT_GT(swing, 1.0);                          // the arm really moved (J)
  EXPECT_LT(*hi - *lo, 1e-6 * std::max(swing, 1.0));

  // Compliant, undamped drives, the motors free: the meshes' springs and the rotors join the sum.
  for (int i = 0; i < 3; ++i) {
    a.joint[static_cast<std::size_t>(i)].drive.compliant = true;
    a.joint[static_cast<std::size_t>(i)].drive.damping = 0.0;
    a.joint[static_cast<std::size_t>(i)].drive.stiffness = 3e3;
  }
  a.joint[0].drive.knee = 2e-3;       // and a second slope
  a.joint[0].drive.stiffness2 = 9e3;
  a.duration = 0.5;
  const TruthArmRun c = run_truth_arm(a);
  const auto [clo, chi] = std::minmax_element(c.trace.energy.begin(), c.trace.energy.end());
  EXPECT_LT(*chi - *clo, 1e-6 * std::abs(c.trace.energy.front()) + 1e-6);
  EXPECT_GT(max_abs_diff({c.trace.motor.back()[0]}, {c.trace.q.back()[0]}), 1e-4);  // the drive twisted

  // Free play 4 mrad at every joint: impacts without damping keep the sum; the one-sided damper (only
  // while the teeth close) only ever takes energy out.
  for (int i = 0; i < 3; ++i) a.joint[static_cast<std::size_t>(i)].drive.backlash = 4e-3;
  const TruthArmRun play = run_truth_arm(a);
  const auto [plo, phi] = std::minmax_element(play.trace.energy.begin(), play.trace.energy.end());
  EXPECT_LT(*phi - *plo, 1e-6 * std::abs(play.trace.energy.front()) + 1e-6);
  for (int i = 0; i < 3; ++i) a.joint[static_cast<std::size_t>(i)].drive.damping = 5.0;
  const TruthArmRun damped = run_truth_arm(a);
  for (std::size_t k = 1; k < damped.trace.energy.size(); ++k)
    EXPECT_LE(damped.trace.energy[k], damped.trace.energy[k - 1] + 1e-7) << "sample " << k;
  EXPECT_LT(damped.trace.energy.back(), damped.trace.energy.front() - 1e-3);
}

// One uniform bar (L = 1 m, 1 kg) hanging, released 0.01 rad from the bottom: period 2 pi sqrt(I_o/(m g c)),
// I_o = m L^2/3, c = L/2 (the amplitude's correction, theta0^2/16, is 6e-6).
TEST(TruthArm, OneLinkSwingsAtThePendulumPeriod) {
  TruthArm a;
  a.joints = 1;
  a.payload = {0.0, 0.0};
  auto& j = a.joint[0];
  j.link = {1.0, 1.0, 0.5, 1.0 / 12.0};
  j.drive.motor_inertia = 0.0;
  j.controller.kp = j.controller.kd = j.controller.gravity_compensation = 0.0;
  a.trajectory.start = {-M_PI / 2 + 0.01};
  a.controller.rate = 2000.0;
  a.duration = 6.0;
  const TruthArmRun run = run_truth_arm(a);
  // Upward zero crossings of q + pi/2, linearly interpolated.
  std::vector<double> up;
  for (std::size_t k = 1; k < run.trace.t.size(); ++k) {
    const double x0 = run.trace.q[k - 1][0] + M_PI / 2, x1 = run.trace.q[k][0] + M_PI / 2;
    if (x0 < 0 && x1 >= 0) up.push_back(run.trace.t[k - 1] + (run.trace.t[k] - run.trace.t[k - 1]) * (-x0) / (x1 - x0));
  }
  ASSERT_GE(up.size(), 3u);
  const double period = (up.back() - up.front()) / static_cast<double>(up.size() - 1);
  const double analytic = 2.0 * M_PI * std::sqrt((1.0 / 3.0) / (9.81 * 0.5));
  EXPECT_NEAR(period / analytic, 1.0, 2e-5);
}

// The two-link suite arm with rigid drives, noise-free, against flexfarm's arm model of the same arm
// (tests/data/truth_arm/arm2.yaml: recursive Newton-Euler, its own integrator): the same move, the same
// sampled references (measured: 4e-8 rad at worst; asserted 1e-6).
TEST(TruthArm, TwoLinkArmAgreesWithFlexfarmsArmModel) {
  const TruthArm a = make_suite_arm(2);
  const TruthArmRun truth = run_truth_arm(a);
  const ArmModel m = load_arm_with(data("arm2.yaml"), {"simulation.rtol=1e-10"});
  const Record ff = make_arm_record(m, {}, 1);
  ASSERT_EQ(ff.t.size(), truth.record.t.size());
  for (const char* joint : {"j1", "j2"}) {
    const std::string j = joint;
    EXPECT_LT(max_abs_diff(ff.at(j + ".ref"), truth.record.at(j + ".ref")), 1e-12) << j;
    // Measured: 4e-8 rad, 4e-7 rad/s, 3e-6 N m at worst.
    EXPECT_LT(max_abs_diff(ff.at(j + ".angle"), truth.record.at(j + ".angle")), 1e-6) << j;
    EXPECT_LT(max_abs_diff(ff.at(j + ".rate"), truth.record.at(j + ".rate")), 1e-5) << j;
    EXPECT_LT(max_abs_diff(ff.at(j + ".torque"), truth.record.at(j + ".torque")), 1e-4) << j;
  }
  // The move is real: tracking errors of several mrad, which both models agree on.
  double lag = 0.0;
  for (std::size_t k = 0; k < truth.record.t.size(); ++k)
    lag = std::max(lag, std::abs(truth.record.at("j1.ref")[k] - truth.record.at("j1.angle")[k]));
  EXPECT_GT(lag, 1e-3);
}

// A compliant elbow drive (the motor's own state and a spring-damper mesh) against flexfarm's `drive:`
// (a rotor body and a passive twist joint): the motor-side angles and the torques agree, and the link lags.
TEST(TruthArm, CompliantDriveAgreesWithFlexfarmsDriveTrain) {
  TruthArm a = make_suite_arm(2);
  a.duration = 2.0;
  auto& d = a.joint[1].drive;
  d.compliant = true;
  d.stiffness = 3000.0;
  d.damping = 3.0;
  const TruthArmRun truth = run_truth_arm(a);
  const ArmModel m = load_arm_with(data("arm2.yaml"), {"simulation.duration=2.0", "simulation.rtol=1e-10",
                                                       "bodies[link2].joint.armature=0", "joints.j2.drive.stiffness=3000",
                                                       "joints.j2.drive.damping=3", "joints.j2.drive.rotor_inertia=1e-5",
                                                       "joints.j2.drive.ratio=100"});
  const Record ff = make_arm_record(m, {}, 1);
  for (const char* joint : {"j1", "j2"}) {
    const std::string j = joint;
    // Measured: 5e-8 rad, 1e-5 N m at worst.
    EXPECT_LT(max_abs_diff(ff.at(j + ".angle"), truth.record.at(j + ".angle")), 1e-6) << j;
    EXPECT_LT(max_abs_diff(ff.at(j + ".torque"), truth.record.at(j + ".torque")), 1e-4) << j;
  }
  double twist = 0.0;
  for (std::size_t k = 0; k < truth.trace.t.size(); ++k) twist = std::max(twist, std::abs(truth.trace.motor[k][1] - truth.trace.q[k][1]));
  EXPECT_GT(twist, 1e-3);  // rad (3.3e-3): the mesh carries the elbow's gravity torque and the move's
}

// The 3- and 6-joint suite arms agree with their nominal models too (the mapping of README.md; 3e-8 rad).
TEST(TruthArm, SuiteArmsAgreeWithTheirNominalModels) {
  for (int n : {3, 6}) {
    TruthArm a = make_suite_arm(n);
    a.duration = 1.5;
    const TruthArmRun truth = run_truth_arm(a);
    const Record ff = make_arm_record(load_arm_with(data("arm" + std::to_string(n) + ".yaml"), {"simulation.duration=1.5"}), {}, 1);
    for (int i = 0; i < n; ++i) {
      const std::string j = truth_arm_joint_name(i);
      EXPECT_LT(max_abs_diff(ff.at(j + ".angle"), truth.record.at(j + ".angle")), 1e-6) << n << " joints, " << j;
    }
  }
}

// Gravity's torques are the potential's gradient; the arm held by exactly them stays put; and a PD whose
// gravity model has the nominal payload settles where kp (r - q) + G_nominal(r) = G_true(q).
TEST(TruthArm, StaticEquilibriumUnderGravity) {
  TruthArm a = make_suite_arm(3);
  const Eigen::Vector3d q(-0.4, 0.7, 0.3);
  const Eigen::VectorXd g = calc_truth_arm_gravity(a, q, a.payload.mass);
  for (int i = 0; i < 3; ++i) {
    Eigen::VectorXd dq = Eigen::VectorXd::Zero(3);
    dq[i] = 1e-6;
    const double fd = (calc_truth_arm_potential(a, q + dq) - calc_truth_arm_potential(a, q - dq)) / 2e-6;
    EXPECT_NEAR(g[i], fd, 1e-6 * std::abs(g[0]));
  }
  // Held by G alone (no PD): no motion.
  TruthArm held = a;
  for (auto& j : held.joint) j.controller.kp = j.controller.kd = 0.0;
  held.trajectory.start = {q[0], q[1], q[2]};
  held.trajectory.waypoints.clear();
  held.duration = 1.0;
  const TruthArmRun still = run_truth_arm(held);
  EXPECT_LT((still.trace.q.back() - q).cwiseAbs().maxCoeff(), 1e-8);

  // The true payload 0.5 kg heavier than the controller's: Newton's iteration on the static balance.
  TruthArm heavy = held;
  for (int i = 0; i < 3; ++i) heavy.joint[static_cast<std::size_t>(i)].controller = a.joint[static_cast<std::size_t>(i)].controller;
  heavy.controller.payload_mass = a.payload.mass;
  heavy.payload.mass = a.payload.mass + 0.5;
  heavy.duration = 4.0;
  const TruthArmRun sag = run_truth_arm(heavy);
  const Eigen::VectorXd g_nom = calc_truth_arm_gravity(heavy, q, a.payload.mass);
  Eigen::VectorXd kp(3), x = q;
  for (int i = 0; i < 3; ++i) kp[i] = heavy.joint[static_cast<std::size_t>(i)].controller.kp;
  for (int it = 0; it < 30; ++it) {
    const Eigen::VectorXd f = kp.cwiseProduct(q - x) + g_nom - calc_truth_arm_gravity(heavy, x, heavy.payload.mass);
    Eigen::Matrix3d J;
    for (int c = 0; c < 3; ++c) {
      Eigen::VectorXd d = Eigen::VectorXd::Zero(3);
      d[c] = 1e-7;
      J.col(c) = (kp.cwiseProduct(q - x - d) + g_nom - calc_truth_arm_gravity(heavy, x + d, heavy.payload.mass) - f) / 1e-7;
    }
    x -= J.lu().solve(f);
  }
  EXPECT_GT((x - q).cwiseAbs().maxCoeff(), 3e-3);  // a visible sag
  EXPECT_LT((sag.trace.q.back() - x).cwiseAbs().maxCoeff(), 1e-6);
}

// A compliant drive starts with its motor at the reference and its link sagged by G/k (past the gap);
// the record logs what the controller read: an encoder's quanta, a late angle.
TEST(TruthArm, HiddenEffectsObeyTheirAnalyticFacts) {
  TruthArm a = make_suite_arm(2);
  a.duration = 0.2;
  a.joint[1].drive.compliant = true;
  a.joint[1].drive.backlash = 4e-3;
  const TruthArmRun c = run_truth_arm(a);
  const Eigen::VectorXd g = calc_truth_arm_gravity(a, c.trace.q.front(), a.payload.mass);
  EXPECT_NEAR(c.trace.motor.front()[1] - c.trace.q.front()[1], std::copysign(2e-3, g[1]) + g[1] / a.joint[1].drive.stiffness, 1e-9);

  TruthArm e = make_suite_arm(2);
  e.duration = 1.0;
  e.joint[0].sensors.angle.encoder_bits = 12;
  e.joint[1].sensors.angle.delay = 7;
  const TruthArmRun r = run_truth_arm(e);
  const double quantum = 2.0 * M_PI / 4096.0;
  for (double x : r.record.at("j1.angle")) EXPECT_NEAR(x / quantum, std::nearbyint(x / quantum), 1e-6);
  for (std::size_t k = 7; k < r.record.t.size(); ++k) EXPECT_DOUBLE_EQ(r.record.at("j2.angle")[k], r.trace.q[k - 7][1]);
}

// One link in a horizontal plane driven by a constant torque tau0 against its friction runs up to the
// speed where tau0 = b v + g(v) (2/pi) atan(v/eps) (static law), or tau0 = b v + g(v) (LuGre's steady
// state: z = g(v)/sigma0), g(v) = Fc + (Fs - Fc) exp(-|v/vs|^delta): the exponent is the truth's own.
TEST(TruthArm, FrictionLawsReachTheirSteadySlidingSpeed) {
  for (const bool lugre : {false, true}) {
    TruthArm a;
    a.joints = 1;
    a.gravity = 0.0;
    a.payload = {0.0, 0.0};
    auto& j = a.joint[0];
    j.link = {1.0, 1.0, 0.5, 1.0 / 12.0};
    j.controller.kp = j.controller.kd = j.controller.gravity_compensation = 0.0;
    j.torque_offset = -3.0;  // the joint gets tau - offset = +3 N m
    auto& f = j.friction;
    f.viscous = 2.0;
    f.coulomb = 1.0;
    f.stiction = 2.0;
    f.stribeck_velocity = 0.8;
    f.stribeck_exponent = 1.0;
    f.lugre = lugre;
    a.trajectory.start = {0.0};
    a.duration = 5.0;
    const TruthArmRun run = run_truth_arm(a);
    auto residual = [&](double v) {
      const double g = f.coulomb + (f.stiction - f.coulomb) * std::exp(-std::pow(v / f.stribeck_velocity, f.stribeck_exponent));
      return 3.0 - f.viscous * v - g * (lugre ? 1.0 : (2.0 / M_PI) * std::atan(v / f.smoothing));
    };
    double lo = 0.01, hi = 10.0;
    for (int i = 0; i < 200; ++i) (residual(0.5 * (lo + hi)) > 0 ? lo : hi) = 0.5 * (lo + hi);
    EXPECT_NEAR(run.trace.qd.back()[0], 0.5 * (lo + hi), 1e-6) << (lugre ? "LuGre" : "static");
    EXPECT_GT(0.5 * (lo + hi), 0.5);  // where the Stribeck term still counts (exp(-v/vs) > 0.2)
  }
}

TEST(TruthArm, FieldsAreNamedAndCheckedByKey) {
  TruthArm a;
  set_truth_arm_field(a, "j3.friction.coulomb", "2.5");
  EXPECT_EQ(a.joint[2].friction.coulomb, 2.5);
  set_truth_arm_field(a, "trajectory.waypoints", "1.5:0.1/0.2,2:0/0");
  ASSERT_EQ(a.trajectory.waypoints.size(), 2u);
  EXPECT_EQ(a.trajectory.waypoints[1].time, 2.0);
  EXPECT_THROW(set_truth_arm_field(a, "j7.link.mass", "1"), std::invalid_argument);
  try {
    set_truth_arm_field(a, "j1.friction.lugre", "maybe");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("j1.friction.lugre"), std::string::npos);
  }
  a.joint[1].friction.coulomb = 2.0;  // a breakaway below the Coulomb level
  a.joint[1].friction.stiction = 1.0;
  try {
    run_truth_arm(a);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("j2.friction.stiction"), std::string::npos);
  }
}

}  // namespace
}  // namespace ff::truth
