// kernel/dynamics.cpp: the articulated-body algorithm against the mass matrix, energy, kinematics.
#include "kernel/dynamics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "kernel/fixed_step.hpp"
#include "kernel/modes.hpp"
#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

// Kinetic plus spring energy of lane 0, J.
double total_energy(const BatchModel& bm, const BatchState& s) {
  return calc_kinetic_energy(bm, s.q.data(), s.v.data(), 0) + calc_spring_energy(bm, s.q.data(), 0);
}

// qdd of one lane from the ABA for given q, v, hub torque.
Eigen::VectorXd aba(const Model& m, const Eigen::VectorXd& q, const Eigen::VectorXd& v, double tau) {
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  Workspace ws = make_workspace(bm);
  Eigen::VectorXd qdd(m.nseg);
  compute_acceleration(bm, q.data(), v.data(), nullptr, &tau, qdd.data(), nullptr, ws);
  return qdd;
}

TEST(Dynamics, AbaInvertsTheCompositeRigidBodyMassMatrix) {
  // At rest (no velocity terms) M(q) qdd = tau must hold for any configuration.
  ModelSpec spec = test::rig_spec();
  spec.segments = 9;
  const Model m = make_model(spec);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-0.6, 0.6);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd q(m.nseg);
    for (auto& x : q) x = angle(rng);
    const Eigen::VectorXd qdd = aba(m, q, Eigen::VectorXd::Zero(m.nseg), 1234.5);
    Eigen::VectorXd tau(m.nseg);
    for (int i = 0; i < m.nseg; ++i) tau[i] = i == 0 ? 1234.5 : -m.joint_k[i] * q[i];
    const Eigen::VectorXd residual = calc_mass_matrix(m, q) * qdd - tau;
    EXPECT_LT(residual.norm(), 1e-9 * tau.norm());
  }
}

TEST(Dynamics, MassMatrixIsSymmetricPositiveDefinite) {
  const Model m = make_model(test::rig_spec());
  Eigen::VectorXd q(m.nseg);
  q << 0.3, -0.2, 0.1, 0.4, -0.5, 0.2;
  const Eigen::MatrixXd M = calc_mass_matrix(m, q);
  EXPECT_LT((M - M.transpose()).norm(), 1e-12 * M.norm());
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M).eigenvalues().minCoeff(), 0.0);
}

TEST(Dynamics, UndeflectedArmRotatesAboutHubWithTotalInertia) {
  // M00 at q = 0 is the whole arm's inertia about the hub axis: hub + segments (parallel axis) + payload.
  const Model m = make_model(test::rig_spec());
  double j = m.spec.hub_inertia, x = 0.0;
  for (int i = 0; i < m.nseg; ++i) {
    const double xc = x + 0.5 * m.seg_length[i];
    j += m.seg_inertia[i] + m.seg_mass[i] * xc * xc;
    x += m.seg_length[i];
  }
  j += m.spec.payload_inertia + m.spec.payload_mass * x * x;
  EXPECT_NEAR(calc_mass_matrix(m, Eigen::VectorXd::Zero(m.nseg))(0, 0), j, 1e-9 * j);
  EXPECT_NEAR(x, m.spec.beam.length, 1e-12);
}

TEST(Dynamics, EnergyIsConservedWithoutDampingOrControl) {
  ModelSpec spec = test::rig_spec();
  spec.joints.damping = 0.0;
  const Model m = make_model(spec);
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  BatchState s = make_state(bm);
  Workspace ws = make_workspace(bm);
  s.q[1] = 0.05;  // bent at the root joint, hub free
  s.v[0] = 0.8;   // and spinning: centrifugal and Coriolis terms matter
  const double e0 = total_energy(bm, s);
  double worst = 0.0;
  for (int k = 0; k < 4000; ++k) {  // 4 s at h = 0.1 ms
    step_rk4(bm, s, ws, 1e-4);
    const double e = total_energy(bm, s);
    worst = std::max(worst, std::fabs(e - e0) / e0);
  }
  EXPECT_LT(worst, 1e-9);
}

TEST(Dynamics, EnergyIsConservedWithCubicStiffening) {
  // Hardening joints store k q^2/2 + k3 q^4/4; without damping the total stays constant.
  ModelSpec spec = test::rig_spec();
  spec.joints.damping = 0.0;
  spec.joints.cubic_stiffness = 4.0e6;  // at 0.1 rad: k3 q^2 = 4e4, about k
  const Model m = make_model(spec);
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  BatchState s = make_state(bm);
  Workspace ws = make_workspace(bm);
  s.q[1] = 0.1;
  s.v[0] = 0.5;
  const double e0 = total_energy(bm, s);
  EXPECT_NEAR(calc_spring_energy(bm, s.q.data(), 0), 0.5 * 39.5e3 * 0.01 + 0.25 * 4.0e6 * 1e-4, 1e-9);
  double worst = 0.0;
  for (int k = 0; k < 20000; ++k) {  // 2 s at h = 0.1 ms
    step_rk4(bm, s, ws, 1e-4);
    const double e = total_energy(bm, s);
    worst = std::max(worst, std::fabs(e - e0) / e0);
  }
  EXPECT_LT(worst, 1e-8);
}

TEST(Dynamics, HardeningJointsVibrateFasterAtLargerAmplitude) {
  // Backbone of a hardening (Duffing) spring: the period shortens as the amplitude grows; with
  // k3 = 0 it does not depend on the amplitude.
  auto period = [](double k3, double amplitude) {
    ModelSpec spec = test::rig_spec();
    spec.segments = 2;  // one joint, hub free, no angular momentum: a single vibration mode
    spec.joints.damping = 0.0;
    spec.joints.cubic_stiffness = k3;
    const Model m = make_model(spec);
    const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
    BatchState s = make_state(bm);
    Workspace ws = make_workspace(bm);
    s.q[m.nseg - 1] = amplitude;
    // Time between the first two downward zero crossings of the tip joint angle.
    double prev = s.q[m.nseg - 1], t = 0.0;
    std::vector<double> crossings;
    while (crossings.size() < 3 && t < 10.0) {
      step_rk4(bm, s, ws, 1e-4);
      t += 1e-4;
      const double x = s.q[m.nseg - 1];
      if (prev > 0.0 && x <= 0.0) crossings.push_back(t - 1e-4 * x / (x - prev));
      prev = x;
    }
    return crossings.size() < 3 ? 0.0 : crossings[2] - crossings[1];
  };
  EXPECT_NEAR(period(0.0, 0.001), period(0.0, 0.01), 1e-3 * period(0.0, 0.001));  // linear joints: isochronous
  EXPECT_LT(period(5.0e6, 0.2), 0.9 * period(5.0e6, 0.001));
}

TEST(Dynamics, JointDampingDissipatesEnergyMonotonically) {
  const Model m = make_model(test::rig_spec());
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  BatchState s = make_state(bm);
  Workspace ws = make_workspace(bm);
  s.q[2] = 0.05;
  double e_prev = total_energy(bm, s);
  const double e0 = e_prev;
  for (int k = 0; k < 3000; ++k) {
    step_rk4(bm, s, ws, 1e-3);
    const double e = total_energy(bm, s);
    ASSERT_LE(e, e_prev * (1 + 1e-12)) << "step " << k;
    e_prev = e;
  }
  EXPECT_LT(e_prev, 0.5 * e0);
}

TEST(Dynamics, AngularMomentumIsConservedWithoutHubTorque) {
  // No torque at the hub axis: the total angular momentum about it, (M v)_0, stays constant.
  ModelSpec spec = test::rig_spec();
  const Model m = make_model(spec);
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  BatchState s = make_state(bm);
  Workspace ws = make_workspace(bm);
  s.q[3] = 0.08;
  s.v[0] = 0.5;
  auto momentum = [&] {
    const Eigen::Map<const Eigen::VectorXd> q(s.q.data(), m.nseg), v(s.v.data(), m.nseg);
    return (calc_mass_matrix(m, q) * v)[0];
  };
  const double h0 = momentum();
  for (int k = 0; k < 4000; ++k) step_rk4(bm, s, ws, 5e-4);  // 2 s
  EXPECT_NEAR(momentum(), h0, 1e-9 * std::fabs(h0));
}

TEST(Dynamics, TipKinematicsOfABentBeam) {
  // Only the last joint bent by phi: deflection = L_N sin(phi), tip angle = hub + atan2(defl, along).
  const Model m = make_model(test::rig_spec());
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  std::vector<double> q(m.nseg, 0.0);
  q[0] = 0.2;
  q[m.nseg - 1] = 0.1;
  const TipKinematics tip = calc_tip(bm, q.data(), 0);
  const double ln = m.seg_length.back(), rest = m.spec.beam.length - ln;
  EXPECT_NEAR(tip.deflection, ln * std::sin(0.1), 1e-15);
  EXPECT_NEAR(tip.along, rest + ln * std::cos(0.1), 1e-14);
  EXPECT_NEAR(tip.angle, 0.2 + std::atan2(ln * std::sin(0.1), rest + ln * std::cos(0.1)), 1e-15);
}

}  // namespace
}  // namespace ff
