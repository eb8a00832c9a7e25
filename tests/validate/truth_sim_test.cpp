// The independent truth simulator (tests/validate/truth/): it matches the independent reference trace,
// conserves energy, and each hidden effect obeys an analytic fact.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "tests/validate/truth/truth_sim.hpp"
#include "validate/record.hpp"

namespace ff::truth {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;

// The rig of tests/data/reference-traces/README.md: PD 0 -> 0.5 rad in 3 s, then held, 20 s.
TruthRig reference_rig() {
  TruthRig r;
  r.trajectory.moves = {{0.5, 17.0}};
  r.duration = 20.0;
  return r;
}

// No control, no move: the chain on its own from an initial bend.
TruthRig free_rig(double joint_angle, double duration) {
  TruthRig r;
  r.controller.kp = r.controller.kd = 0.0;
  r.trajectory.moves.clear();
  r.initial.joint_angle = joint_angle;
  r.duration = duration;
  return r;
}

double rms(const std::vector<double>& x) {
  double s = 0.0;
  for (double v : x) s += v * v;
  return std::sqrt(s / x.size());
}

// Clamped-hub natural frequencies of the chain linearised at phi = 0, Hz, ascending.
std::vector<double> clamped_frequencies(const TruthRig& rig) {
  const TruthChain ch = make_truth_chain(rig);
  const int n = ch.n;
  const Eigen::MatrixXd M = calc_truth_mass_matrix(ch, Eigen::VectorXd::Zero(n));
  // Joint i: k_i (phi_i - phi_{i-1})^2 / 2 in the absolute angles.
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
  for (int i = 1; i < n; ++i) {
    K(i, i) += ch.k[i];
    K(i - 1, i - 1) += ch.k[i];
    K(i, i - 1) -= ch.k[i];
    K(i - 1, i) -= ch.k[i];
  }
  // Hub clamped: phi_0 = 0, drop its row and column.
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(K.bottomRightCorner(n - 1, n - 1),
                                                                M.bottomRightCorner(n - 1, n - 1));
  std::vector<double> f;
  for (int i = 0; i < n - 1; ++i) f.push_back(std::sqrt(es.eigenvalues()[i]) / kTwoPi);
  return f;
}

TEST(TruthSim, MassMatrixGivesTheRigsClampedModes) {
  // reference-rig.md: hub clamped, N = 6 gives 0.300 and 2.300 Hz, N = 48 gives 0.2985 and 2.275 Hz.
  TruthRig r;
  auto f = clamped_frequencies(r);
  EXPECT_NEAR(f[0], 0.300, 5e-4);
  EXPECT_NEAR(f[1], 2.300, 5e-4);
  r.segments = 48;
  f = clamped_frequencies(r);
  EXPECT_NEAR(f[0], 0.2985, 5e-5);
  EXPECT_NEAR(f[1], 2.275, 5e-4);
  // The straight arm's inertia about the hub axis: the hub, the beam (rho h t L^3/3 + its thickness
  // term) and the payload (m L^2 + J), with M_00 + 2 sum_j M_0j + ... = 1' M 1.
  TruthRig base;
  const TruthChain ch = make_truth_chain(base);
  const Eigen::MatrixXd M = calc_truth_mass_matrix(ch, Eigen::VectorXd::Zero(ch.n));
  const double L = base.beam.length, mb = base.beam.density * base.beam.height * base.beam.thickness * L;
  double beam = 0.0;  // sum of segments about the hub axis: m_i (L_i^2 + t^2)/12 + m_i x_i^2
  double x = 0.0;
  for (int i = 0; i < ch.n; ++i) {
    const double mi = mb * ch.length[i] / L, xi = x + 0.5 * ch.length[i];
    beam += mi * (ch.length[i] * ch.length[i] + base.beam.thickness * base.beam.thickness) / 12.0 + mi * xi * xi;
    x += ch.length[i];
  }
  const double rigid = base.hub_inertia + beam + base.payload.mass * L * L + base.payload.inertia;
  EXPECT_NEAR(M.sum(), rigid, 1e-9 * rigid);
  EXPECT_NEAR(beam, mb * L * L / 3.0 + mb * base.beam.thickness * base.beam.thickness / 12.0, 1e-9 * beam);
}

TEST(TruthSim, MatchesTheIndependentReferenceTrace) {
  const Record ref = read_record_csv(FLEXFARM_SOURCE_DIR "/tests/data/reference-traces/fbtb_n6_pd_0p5rad.csv",
                                     {"ref", "hub_torque", "hub_angle", "tip_deflection"});
  const TruthRun run = run_truth(reference_rig());
  const Record& rec = run.record;
  ASSERT_EQ(ref.size(), 20000u);  // t = 0 ... 19.999 s
  ASSERT_GE(rec.size(), ref.size());
  std::vector<double> dtip, dangle, dtorque;
  for (std::size_t k = 0; k < ref.size(); ++k) {
    ASSERT_NEAR(rec.t[k], ref.t[k], 1e-12);
    ASSERT_NEAR(rec.at("ref")[k], ref.at("ref")[k], 1e-9);
    dtip.push_back(rec.at("tip_deflection")[k] - ref.at("tip_deflection")[k]);
    dangle.push_back(rec.at("hub_angle")[k] - ref.at("hub_angle")[k]);
    dtorque.push_back(rec.at("hub_torque")[k] - ref.at("hub_torque")[k]);
  }
  // The reference is RK4 at 0.1 ms of another formulation; its tip deflection is 290 mm RMS.
  const double tip_rms = rms(ref.at("tip_deflection"));
  EXPECT_NEAR(tip_rms, 0.29, 0.01);
  EXPECT_LT(rms(dtip), 0.5e-6);                    // m: half a micrometre RMS
  double worst_tip = 0.0, worst_angle = 0.0, worst_torque = 0.0;
  for (std::size_t k = 0; k < dtip.size(); ++k) {
    worst_tip = std::max(worst_tip, std::fabs(dtip[k]));
    worst_angle = std::max(worst_angle, std::fabs(dangle[k]));
    worst_torque = std::max(worst_torque, std::fabs(dtorque[k]));
  }
  EXPECT_LT(worst_tip, 1e-6);                      // m
  EXPECT_LT(worst_angle, 1e-7);                    // rad
  EXPECT_LT(worst_torque, 0.01);                   // N m, of peaks ~ 1e4 N m
  std::printf("reference trace: tip RMS diff %.3g m (max %.3g), hub angle max diff %.3g rad, torque max diff %.3g N m\n",
              rms(dtip), worst_tip, worst_angle, worst_torque);
}

// Energy drift max |E(t) - E(0)| / E(0) of a 5 s free vibration from a 0.01 rad bend.
double energy_drift(bool drive, double rtol) {
  TruthRig r = free_rig(0.01, 5.0);
  r.joint.damping = 0.0;
  r.joint.stiffening = 0.3;
  r.drive.enabled = drive;
  r.drive.damping = 0.0;
  r.drive.cubic_stiffness = 1e9;  // a hardening mesh: its energy k d^2/2 + k3 d^4/4 too
  r.solver.rtol = rtol;
  const TruthTrace tr = run_truth(r).trace;
  const double e0 = tr.energy.front();
  // The bend stores k q^2/2 + k3 q^4/4 in each of the 5 joints (k = 39.5 kN m/rad at N = 6).
  const double k = r.joint.stiffness, k3 = 0.3 * k / (0.01 * 0.01), q = 0.01;
  EXPECT_NEAR(e0, 5.0 * (0.5 * k * q * q + 0.25 * k3 * q * q * q * q), 1e-9 * e0);
  // It moved: the bend relaxed into vibration (the energy changes form).
  EXPECT_GT(*std::max_element(tr.hub_rate.begin(), tr.hub_rate.end()), 1e-3);
  double drift = 0.0;
  for (double e : tr.energy) drift = std::max(drift, std::fabs(e - e0) / e0);
  std::printf("drive %d, rtol %g: energy drift %.3g\n", drive, rtol, drift);
  return drift;
}

TEST(TruthSim, ConservesEnergyWithoutControlAndDamping) {
  // The chain alone, and with the stiff drive mesh (a 300 Hz mode on the shaft), at the default rtol 1e-9;
  // a tighter rtol shrinks the drift: it is the integrator's error, not the model's.
  const double chain = energy_drift(false, 1e-9), geared = energy_drift(true, 1e-9);
  EXPECT_LT(chain, 2e-8);
  EXPECT_LT(geared, 5e-7);
  EXPECT_LT(energy_drift(true, 1e-11), 0.1 * geared);
}

}  // namespace
}  // namespace ff::truth
