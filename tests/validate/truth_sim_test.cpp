// The independent truth simulator (tests/validate/truth/): it matches the independent reference trace,
// conserves energy, and each hidden effect obeys an analytic fact.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <tuple>
#include <unistd.h>

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

// Mean period of x from its upward zero crossings (linear interpolation), s.
double mean_period(const std::vector<double>& t, const std::vector<double>& x) {
  std::vector<double> up;
  for (std::size_t k = 1; k < x.size(); ++k)
    if (x[k - 1] < 0.0 && x[k] >= 0.0) up.push_back(t[k - 1] + (t[k] - t[k - 1]) * x[k - 1] / (x[k - 1] - x[k]));
  if (up.size() < 2) return NAN;
  return (up.back() - up.front()) / (up.size() - 1);
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


TEST(TruthSim, CoulombFrictionHoldsTheHubBelowBreakaway) {
  // No control; a constant load on the hub against Coulomb friction Fc = 500 N m. Below breakaway the hub
  // creeps at the regularisation's speed, (2/pi) atan(w/eps) Fc = load, w = eps tan(pi load / (2 Fc));
  // above it, it accelerates.
  auto run = [](double load, double stiction) {
    TruthRig r = free_rig(0.0, 2.0);
    r.friction.coulomb = 500.0;
    r.friction.stiction = stiction;
    r.torque_offset = load;
    return run_truth(r).trace;
  };
  const double eps = TruthRig{}.friction.smoothing;
  const TruthTrace held = run(250.0, 0.0);
  const double creep = eps * std::tan(M_PI * 250.0 / (2.0 * 500.0));  // = eps
  EXPECT_NEAR(held.hub_rate.back(), -creep, 0.05 * creep);           // the load turns it clockwise
  EXPECT_LT(std::fabs(held.hub_angle.back()), 2.0 * 1.1 * creep);    // rad after 2 s: at most the creep
  // Between Fc and the Stribeck peak Fs = 700 N m: still held.
  const TruthTrace peak = run(600.0, 700.0);
  EXPECT_LT(std::fabs(peak.hub_angle.back()), 1e-3);
  // Above breakaway (1.5 Fc) the net 250 N m turns the arm: hundreds of times the creep.
  const TruthTrace slips = run(750.0, 0.0);
  EXPECT_LT(slips.hub_angle.back(), -100.0 * std::fabs(held.hub_angle.back()));
  EXPECT_LT(slips.hub_angle.back(), -0.01);
}

TEST(TruthSim, OutputDelayShiftsTheColumnExactly) {
  TruthRig r = reference_rig();
  r.duration = 3.0;
  r.sensors.hub_angle.noise = 1e-5;
  r.sensors.hub_torque.noise = 2.0;
  r.sensors.tip_deflection.noise = 1e-4;
  r.seed = 3;
  const Record base = simulate_truth(r);
  r.sensors.tip_deflection.delay = 30;
  r.sensors.hub_torque.delay = 7;
  const Record late = simulate_truth(r);
  ASSERT_EQ(late.size(), base.size());
  for (std::size_t k = 0; k < base.size(); ++k) {
    ASSERT_EQ(late.at("tip_deflection")[k], base.at("tip_deflection")[k >= 30 ? k - 30 : 0]) << k;
    ASSERT_EQ(late.at("hub_torque")[k], base.at("hub_torque")[k >= 7 ? k - 7 : 0]) << k;
    ASSERT_EQ(late.at("hub_angle")[k], base.at("hub_angle")[k]) << k;  // the loop did not notice
    ASSERT_EQ(late.at("hub_rate")[k], base.at("hub_rate")[k]) << k;
  }
}

TEST(TruthSim, InLoopHubAngleDelayChangesTheResponse) {
  TruthRig r = reference_rig();
  r.duration = 4.0;
  const TruthRun base = run_truth(r);
  r.sensors.hub_angle.delay = 20;
  const TruthRun late = run_truth(r);
  // The controller saw the angle 20 samples late ...
  for (std::size_t k = 0; k < late.trace.t.size(); ++k)
    ASSERT_EQ(late.trace.seen_angle[k], late.trace.hub_angle[k >= 20 ? k - 20 : 0]);
  // ... which changed the motion (20 ms of lag in a loop with a 3.6 s slow mode: millimetres at the tip);
  // the recorded hub angle is the reading stamped when taken.
  double dtip = 0.0, dangle = 0.0;
  for (std::size_t k = 0; k < base.record.size(); ++k) {
    dtip = std::max(dtip, std::fabs(late.record.at("tip_deflection")[k] - base.record.at("tip_deflection")[k]));
    dangle = std::max(dangle, std::fabs(late.record.at("hub_angle")[k] - base.record.at("hub_angle")[k]));
    ASSERT_EQ(late.record.at("hub_angle")[k], late.trace.hub_angle[k]);
  }
  EXPECT_GT(dtip, 1e-3);
  EXPECT_GT(dangle, 1e-4);
  // record.as_seen: the column is what the controller used.
  r.record.as_seen = true;
  const Record seen = simulate_truth(r);
  for (std::size_t k = 0; k < seen.size(); ++k) ASSERT_EQ(seen.at("hub_angle")[k], late.trace.seen_angle[k]);
}

TEST(TruthSim, BacklashTransmitsNoTorqueWhileTheActuatorCrossesTheGap) {
  // A drive with a 4 mrad gap (b = 2 mrad), starting centred: the actuator crosses b before the teeth
  // meet; then the sampled PD rattles it from flank to flank (as flexfarm's model of the same rig does).
  TruthRig r;
  r.trajectory.moves = {{0.5, 7.0}};
  r.duration = 1.0;
  r.drive.enabled = true;
  r.drive.backlash = 0.004;
  const TruthTrace tr = run_truth(r).trace;
  const double b = 0.002, delta = r.drive.backlash_smoothing, k = r.drive.stiffness, c = r.drive.damping;
  int inside = 0, deep = 0;
  double peak = 0.0, worst_deep = 0.0;
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    peak = std::max(peak, std::fabs(tr.hub_torque[i]));
    const double x = b - std::fabs(tr.twist[i]);  // distance to the nearer flank, rad
    if (x <= 0.0) continue;
    ++inside;
    // Inside the gap the smooth dead zone leaves e <= delta^2/(4x) per flank and de/dt <= delta^2/(4x^2) |dd/dt|:
    // the torque is the regularisation's, k delta^2/(2x) + c delta^2/(2x^2) |dd/dt| at most.
    const double bound = k * delta * delta / (2.0 * x) + c * delta * delta / (2.0 * x * x) * std::fabs(tr.twist_rate[i]);
    EXPECT_LE(std::fabs(tr.hub_torque[i]), bound * (1 + 1e-9) + 1e-9) << "t = " << tr.t[i];
    if (x > 0.1 * b) {  // well inside: no torque to speak of
      ++deep;
      worst_deep = std::max(worst_deep, std::fabs(tr.hub_torque[i]));
    }
  }
  std::printf("backlash: %d samples inside the gap, %d well inside, largest torque there %.3g N m of %.3g\n", inside,
              deep, worst_deep, peak);
  EXPECT_GT(deep, 20);
  EXPECT_GT(peak, 1e3);
  EXPECT_LT(worst_deep, 1e-5 * peak);
  // Both flanks were used: the twist reached beyond +b and beyond -b.
  EXPECT_GT(*std::max_element(tr.twist.begin(), tr.twist.end()), b);
  EXPECT_LT(*std::min_element(tr.twist.begin(), tr.twist.end()), -b);
  // The first crossing: the hub waits until the teeth meet (but for the regularisation's push), while
  // without the gap it would have started to turn.
  std::size_t meet = 0;
  while (meet < tr.t.size() && tr.twist[meet] < b - 20.0 * delta) ++meet;
  EXPECT_GT(meet, 10u);
  r.drive.backlash = 0.0;
  r.duration = tr.t[meet];
  const TruthTrace tight = run_truth(r).trace;
  std::printf("backlash: teeth meet at %.3f s, hub then %.3g rad (%.3g rad without the gap)\n", tr.t[meet],
              tr.hub_angle[meet - 1], tight.hub_angle[meet - 1]);
  for (std::size_t i = 1; i < meet; ++i)
    EXPECT_LE(std::fabs(tr.hub_angle[i]), 1e-3 * tight.hub_angle[i]) << "t = " << tr.t[i];
}

TEST(TruthSim, EncoderQuantisesTheHubAngle) {
  TruthRig r = reference_rig();
  r.duration = 4.0;
  r.sensors.hub_angle.quantize = true;  // 16 bits over 2 pi
  const TruthRun run = run_truth(r);
  const double q = kTwoPi / 65536.0;
  const auto& angle = run.record.at("hub_angle");
  std::size_t levels = 0;
  for (std::size_t k = 0; k < angle.size(); ++k) {
    const double n = angle[k] / q;
    ASSERT_NEAR(n, std::nearbyint(n), 1e-9) << k;
    EXPECT_LE(std::fabs(angle[k] - run.trace.hub_angle[k]), 0.5 * q * (1 + 1e-12));
    levels += k > 0 && angle[k] != angle[k - 1];
  }
  EXPECT_GT(levels, 1000u);  // 0.5 rad is 5215 quanta
  // The controller sees the same quantised reading.
  EXPECT_EQ(run.trace.seen_angle[500], angle[500]);
}

TEST(TruthSim, HardeningJointsRaiseTheFirstModeWithAmplitude) {
  // Free vibration of the uncontrolled chain from a uniform bend (mostly its first flexible mode):
  // with joint.stiffening = 0.5 at 0.01 rad, the period shortens with amplitude; linear joints keep it.
  auto frequency = [](double bend, double stiffening) {
    TruthRig r = free_rig(bend, 12.0);
    r.joint.damping = 0.0;
    r.joint.stiffening = stiffening;
    const TruthTrace tr = run_truth(r).trace;
    return 1.0 / mean_period(tr.t, tr.tip_deflection);
  };
  const double linear_small = frequency(1e-5, 0.0), linear_large = frequency(0.01, 0.0);
  const double hard_small = frequency(1e-5, 0.5), hard_large = frequency(0.01, 0.5);
  std::printf("first mode: linear %.5f / %.5f Hz, hardening %.5f / %.5f Hz (small / large bend)\n", linear_small,
              linear_large, hard_small, hard_large);
  EXPECT_NEAR(linear_large / linear_small, 1.0, 2e-3);
  EXPECT_NEAR(hard_small / linear_small, 1.0, 1e-4);
  // Duffing: w/w0 = 1 + (3/8) s (A/q_ref)^2 for one joint at amplitude A, 1.19 at A = q_ref.
  EXPECT_GT(hard_large / hard_small, 1.1);
  EXPECT_LT(hard_large / hard_small, 1.3);
}

TEST(TruthSim, DecimationGivesTheSampleTimes) {
  TruthRig r = reference_rig();
  r.duration = 2.0;
  r.sensors.tip_deflection.noise = 1e-4;
  const Record full = simulate_truth(r);
  r.record.decimate = 10;
  const Record tenth = simulate_truth(r);
  ASSERT_EQ(full.size(), 2001u);
  ASSERT_EQ(tenth.size(), 201u);
  for (std::size_t j = 0; j < tenth.size(); ++j) {
    EXPECT_NEAR(tenth.t[j], 0.01 * j, 1e-12);
    EXPECT_EQ(tenth.at("tip_deflection")[j], full.at("tip_deflection")[10 * j]);
    EXPECT_EQ(tenth.at("hub_torque")[j], full.at("hub_torque")[10 * j]);
  }
}

TEST(TruthSim, FieldTableNamesEveryField) {
  TruthRig r;
  set_truth_field(r, "drive.backlash", "0.002");
  set_truth_field(r, "sensors.tip_deflection.delay", "30");
  set_truth_field(r, "seed", "7");
  set_truth_field(r, "drive.enabled", "true");
  set_truth_field(r, "trajectory.moves", "1:2,0:3.5");
  EXPECT_EQ(r.drive.backlash, 0.002);
  EXPECT_EQ(r.sensors.tip_deflection.delay, 30);
  EXPECT_EQ(r.seed, 7u);
  EXPECT_TRUE(r.drive.enabled);
  ASSERT_EQ(r.trajectory.moves.size(), 2u);
  EXPECT_EQ(r.trajectory.moves[1].hold, 3.5);
  try {
    set_truth_field(r, "drive.backlsh", "1");
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "unknown key 'drive.backlsh'");
  }
  EXPECT_THROW(set_truth_field(r, "segments", "6.5"), std::invalid_argument);
  EXPECT_THROW(set_truth_field(r, "drive.enabled", "yes please"), std::invalid_argument);
  // Every listed field reads back what it lists.
  TruthRig copy;
  for (const auto& f : list_truth_fields(r)) set_truth_field(copy, f.name, f.value);
  const auto a = list_truth_fields(r), b = list_truth_fields(copy);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].value, b[i].value) << a[i].name;
}

TEST(TruthSim, SolverFailureIsAClearError) {
  TruthRig r = reference_rig();
  r.duration = 0.1;
  r.solver.max_steps = 1;
  try {
    run_truth(r);
    ADD_FAILURE() << "ran";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("CVODE failed"), std::string::npos) << e.what();
  }
  r.solver.max_steps = 50000;
  r.drive.inertia = 0.0;
  EXPECT_THROW(run_truth(r), std::invalid_argument);
}

// truth_record ARGS, its exit code and output.
std::pair<int, std::string> run_tool(const std::string& args) {
  const std::string cmd = "'" TRUTH_RECORD_BINARY "' " + args + " 2>&1";
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(TruthSim, RecordToolWritesARecordAndRefusesUnknownKeys) {
  const auto path = std::filesystem::temp_directory_path() / ("truth_record_" + std::to_string(::getpid()) + ".csv");
  auto [code, out] = run_tool("duration=1 record.decimate=2 sensors.hub_rate.recorded=false --out '" + path.string() + "'");
  ASSERT_EQ(code, 0) << out;
  const Record r = read_record_csv(path.string(), {"ref", "hub_torque", "hub_angle", "tip_deflection"});
  EXPECT_EQ(r.size(), 501u);
  EXPECT_FALSE(r.has("hub_rate"));
  EXPECT_NEAR(r.t[1], 0.002, 1e-12);
  std::filesystem::remove(path);
  std::tie(code, out) = run_tool("drive.backlsh=0.002 --out x.csv");
  EXPECT_EQ(code, 2);
  EXPECT_EQ(out, "truth_record: unknown key 'drive.backlsh' (--help lists the keys)\n");
  std::tie(code, out) = run_tool("duration=1");
  EXPECT_EQ(code, 2);
}

TEST(TruthSim, HydraulicOilSpringRingsAtItsFrequency) {
  // A rigid arm (N = 1) on the actuator with the valve held closed and no leakage, under a constant load:
  // the oil is a spring K = 2 beta D^2 / V0 about the centred rack (dp = -2 beta D theta / V0), so the arm
  // rings at sqrt(K / J) about theta = -load / K, and D (p_a - p_b) carries the load on average.
  TruthRig r = free_rig(0.0, 3.0);
  r.segments = 1;
  r.hydraulics.enabled = true;
  r.hydraulics.pressure_gain = 0.0;
  r.hydraulics.leakage = 0.0;
  r.torque_offset = 1000.0;
  const TruthRun run = run_truth(r);
  const TruthTrace& tr = run.trace;
  const auto& h = r.hydraulics;
  const double D = h.piston_area * h.pinion_radius, K = 2.0 * h.bulk_modulus * D * D / h.chamber_volume;
  const double J = make_truth_chain(r).a(0, 0);
  const double f = std::sqrt(K / J) / kTwoPi;  // 3.76 Hz (configs/fbtb_hydraulic.yaml)
  EXPECT_NEAR(f, 3.76, 0.01);
  const double eq = -r.torque_offset / K;
  std::vector<double> swing;
  double torque = 0.0;
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    swing.push_back(tr.hub_angle[k] - eq);
    torque += tr.hub_torque[k] / tr.t.size();
  }
  EXPECT_NEAR(1.0 / mean_period(tr.t, swing), f, 2e-3 * f);
  EXPECT_NEAR(*std::min_element(tr.hub_angle.begin(), tr.hub_angle.end()), 2.0 * eq, 1e-3 * std::fabs(eq));
  EXPECT_NEAR(torque, r.torque_offset, 0.03 * r.torque_offset);  // on average the oil holds the load
  // The record carries both chamber pressures, starting at (p_s + p_t)/2.
  ASSERT_TRUE(run.record.has("pressure_a") && run.record.has("pressure_b"));
  EXPECT_EQ(run.record.at("pressure_a")[0], 0.5 * (h.supply_pressure + h.tank_pressure));
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    ASSERT_EQ(run.record.at("pressure_a")[k], tr.pressure_a[k]);
    ASSERT_NEAR(tr.hub_torque[k], D * (tr.pressure_a[k] - tr.pressure_b[k]), 1e-9 * K);
  }
}

TEST(TruthSim, HydraulicTorqueLoopDeliversTheDemandAtRest) {
  // A rigid arm (N = 1, a well damped PD loop: zeta 0.38 at 0.6 Hz) holding a constant load. At rest the
  // spool is centred (no flow but the leakage's), so the torque loop u = K (tau - D dp)/(D p_s) ~ 0 holds
  // D dp at the demand, and the demand at the load.
  TruthRig r = free_rig(0.0, 10.0);
  r.segments = 1;
  r.controller = TruthRig{}.controller;
  r.controller.kd = 2.0e4;  // configs/fbtb_hydraulic.yaml
  r.hydraulics.enabled = true;
  r.torque_offset = 800.0;
  const TruthTrace tr = run_truth(r).trace;
  const double demand = tr.demand.back(), delivered = tr.hub_torque.back();
  // The hub at rest: the actuator carries the load exactly, and the PD's error gives the demand.
  EXPECT_NEAR(delivered, 800.0, 1e-3);
  EXPECT_NEAR(tr.hub_angle.back(), -demand / r.controller.kp, 1e-9);
  // The spool's steady opening x feeds the leakage Q_l = l dp through both lands, k_v x R(p_s - p_a) = Q_l
  // with p_a = (p_s + p_t)/2 + dp/2; the loop needs the torque error D p_s x / K for it.
  const auto& h = r.hydraulics;
  const double D = h.piston_area * h.pinion_radius, dp = 800.0 / D, kv = h.rated_flow / std::sqrt(h.rated_drop);
  const double drop = 0.5 * (h.supply_pressure - h.tank_pressure) - 0.5 * dp;
  const double x = h.leakage * dp / (kv * drop / std::sqrt(drop + h.laminar_drop));
  EXPECT_NEAR(demand - delivered, D * h.supply_pressure * x / h.pressure_gain, 0.01 * (demand - delivered));
  EXPECT_GT(demand - delivered, 1.0);  // N m
  EXPECT_NEAR(tr.pressure_a.back() - tr.pressure_b.back(), dp, 1e-6 * dp);
}

}  // namespace
}  // namespace ff::truth
