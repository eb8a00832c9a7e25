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
// multi_slope: the mesh with three slopes (knees at 5 and 15 urad, the twist reaching ~20 urad).
double energy_drift(bool drive, double rtol, bool multi_slope = false) {
  TruthRig r = free_rig(0.01, 5.0);
  r.joint.damping = 0.0;
  r.joint.stiffening = 0.3;
  r.drive.enabled = drive;
  r.drive.damping = 0.0;
  r.drive.cubic_stiffness = 1e9;  // a hardening mesh: its energy k d^2/2 + k3 d^4/4 too
  if (multi_slope) {
    r.drive.knee_1 = 5e-6;
    r.drive.stiffness_2 = 4e7;
    r.drive.knee_2 = 1.5e-5;
    r.drive.stiffness_3 = 8e7;
  }
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
  // The multi-slope mesh's piecewise-quadratic potential balances its piecewise-linear torque.
  EXPECT_LT(energy_drift(true, 1e-9, true), 2e-6);
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

// ---------------------------------------------------------------------------------------------
// Effects in forms flexfarm does not share (issue 33): LuGre, exponential Stribeck, a worn gear's
// position-dependent friction, a multi-slope mesh, one-sided mesh damping, a late logger, a nominal
// feed-forward.

// The hub alone (no beam, no payload: J = 50 kg m^2), no control, a constant torque `load` on it
// (torque_offset = -load), for `duration` s.
TruthRig hub_rig(double load, double duration) {
  TruthRig r = free_rig(0.0, duration);
  r.segments = 1;
  r.beam.density = 0.0;
  r.payload.mass = r.payload.inertia = 0.0;
  r.torque_offset = -load;
  return r;
}

TEST(TruthSim, LuGreBristlesHoldTheHubOnTheirPresliding) {
  // Below breakaway LuGre's bristles hold the hub: moving one way, dz/dtheta = 1 - sigma0 z / Fc, so
  // z = (Fc/sigma0)(1 - exp(-sigma0 theta / Fc)); at rest sigma0 z = load, the hub at
  //   theta = -(Fc/sigma0) ln(1 - load/Fc)   (Canudas de Wit et al. 1995; overdamped by sigma1).
  TruthRig r = hub_rig(300.0, 3.0);
  r.friction.coulomb = 500.0;
  r.friction.bristle_stiffness = 1e5;
  r.friction.bristle_damping = 1e4;
  const TruthTrace tr = run_truth(r).trace;
  const double theta = -(500.0 / 1e5) * std::log(1.0 - 300.0 / 500.0);  // 4.58 mrad (a linear spring: 3 mrad)
  EXPECT_NEAR(tr.hub_angle.back(), theta, 1e-3 * theta);
  EXPECT_NEAR(tr.bristle.back(), 300.0 / 1e5, 1e-6 * 3e-3);
  EXPECT_NEAR(tr.friction.back(), -300.0, 1e-3);
  EXPECT_LT(std::fabs(tr.hub_rate.back()), 1e-6);
  // Monotone (overdamped): it never went past the rest point.
  for (double x : tr.hub_angle) ASSERT_LE(x, theta * (1 + 1e-6));
}

// The hub rate w solving load = g(w) s(w) + b w, g = Fc + (Fs - Fc) exp(-|w/vs|^delta), s = 1 (LuGre) or
// the static law's (2/pi) atan(w/eps) (eps > 0); g s + b w rises in w here (b exceeds g's steepest fall).
double steady_slip(double load, double fc, double fs, double vs, double delta, double b, double eps) {
  double lo = 0.0, hi = load / b;
  for (int i = 0; i < 200; ++i) {
    const double w = 0.5 * (lo + hi);
    const double s = eps > 0 ? M_2_PI * std::atan(w / eps) : 1.0;
    ((fc + (fs - fc) * std::exp(-std::pow(w / vs, delta))) * s + b * w < load ? lo : hi) = w;
  }
  return 0.5 * (lo + hi);
}

TEST(TruthSim, LuGreAndStaticFrictionSlideAtTheStribeckCurvesSteadyState) {
  // Driven by 600 N m against Fc = 300, Fs = 500 N m, vs = 0.2 rad/s, b = 1500 N m s/rad: the hub slides at
  // the w where load = g(w) + b w. LuGre's steady state is exactly that (z' = 0: sigma0 z = g); the static
  // law's is g (2/pi) atan(w/eps) + b w. The exponent delta changes w: 1 (exponential) against 3.
  auto slide = [](double delta, double sigma0) {
    TruthRig r = hub_rig(600.0, 1.5);
    r.friction.coulomb = 300.0;
    r.friction.stiction = 500.0;
    r.friction.stribeck_velocity = 0.2;
    r.friction.stribeck_exponent = delta;
    r.friction.viscous = 1500.0;
    r.friction.bristle_stiffness = sigma0;
    r.friction.bristle_damping = sigma0 > 0 ? 300.0 : 0.0;
    return run_truth(r).trace;
  };
  const double eps = TruthRig{}.friction.smoothing;
  const double w1 = steady_slip(600.0, 300.0, 500.0, 0.2, 1.0, 1500.0, 0.0);
  const double w1s = steady_slip(600.0, 300.0, 500.0, 0.2, 1.0, 1500.0, eps);
  const double w3s = steady_slip(600.0, 300.0, 500.0, 0.2, 3.0, 1500.0, eps);
  std::printf("steady slip: delta 1 %.6f rad/s (static law %.6f), delta 3 %.6f rad/s\n", w1, w1s, w3s);
  ASSERT_GT(std::fabs(w1s - w3s), 0.02 * w1);  // the exponent matters here
  const TruthTrace lugre = slide(1.0, 1e5), exp1 = slide(1.0, 0.0), exp3 = slide(3.0, 0.0);
  EXPECT_NEAR(lugre.hub_rate.back(), w1, 1e-5 * w1);
  EXPECT_NEAR(lugre.friction.back(), -600.0, 1e-3);
  EXPECT_NEAR(exp1.hub_rate.back(), w1s, 1e-5 * w1s);
  EXPECT_NEAR(exp3.hub_rate.back(), w3s, 1e-5 * w3s);
}

TEST(TruthSim, WornGearFrictionFollowsTheHubAngle) {
  // Heavy viscous damping (J/b = 0.5 ms): the hub slides quasi-statically at
  //   w(theta) = (load - Fc (1 + a cos(p theta + phase))) / b,
  // so the rate traces the gear's wear pattern: 4 waves per revolution, a = 0.5.
  TruthRig r = hub_rig(52000.0, 6.0);
  r.friction.viscous = 1e5;
  r.friction.coulomb = 2000.0;
  r.friction.position_amplitude = 0.5;
  r.friction.position_waves = 4.0;
  r.friction.position_phase = 0.3;
  const TruthTrace tr = run_truth(r).trace;
  double worst = 0.0, lo = INFINITY, hi = -INFINITY;
  for (std::size_t k = 500; k < tr.t.size(); ++k) {
    const double w = (52000.0 - 2000.0 * (1.0 + 0.5 * std::cos(4.0 * tr.hub_angle[k] + 0.3))) / 1e5;
    worst = std::max(worst, std::fabs(tr.hub_rate[k] - w));
    lo = std::min(lo, tr.hub_rate[k]);
    hi = std::max(hi, tr.hub_rate[k]);
  }
  EXPECT_GT(tr.hub_angle.back(), 2.0 * M_PI / 4.0);  // more than one wave
  EXPECT_LT(worst, 0.01 * (0.5 * 2000.0 / 1e5));     // 1 % of the swing a Fc / b
  EXPECT_NEAR(hi - lo, 2.0 * 0.5 * 2000.0 / 1e5, 0.03 * (hi - lo));
}

// The rig with the default drive, moving 0.5 rad, for 1 s.
TruthRig geared_rig() {
  TruthRig r;
  r.trajectory.moves = {{0.5, 7.0}};
  r.duration = 1.0;
  r.drive.enabled = true;
  return r;
}

TEST(TruthSim, MultiSlopeMeshWithEqualSlopesIsTheLinearMesh) {
  TruthRig r = geared_rig();
  const TruthTrace linear = run_truth(r).trace;
  r.drive.knee_1 = 1e-5;
  r.drive.knee_2 = 3e-5;
  r.drive.stiffness_2 = r.drive.stiffness_3 = r.drive.stiffness;
  const TruthTrace same = run_truth(r).trace;
  double peak = 0.0, worst = 0.0, twist = 0.0;
  for (std::size_t k = 0; k < linear.t.size(); ++k) {
    peak = std::max(peak, std::fabs(linear.hub_torque[k]));
    twist = std::max(twist, std::fabs(linear.twist[k]));
    worst = std::max(worst, std::fabs(same.hub_torque[k] - linear.hub_torque[k]));
  }
  EXPECT_GT(twist, 3e-5);  // the move's twist reaches past both knees
  EXPECT_LT(worst, 1e-6 * peak);
  // Stiffer slopes beyond the knees change the motion.
  r.drive.stiffness_2 = r.drive.stiffness_3 = 3.0 * r.drive.stiffness;
  const TruthTrace stiff = run_truth(r).trace;
  double differ = 0.0;
  for (std::size_t k = 0; k < linear.t.size(); ++k) differ = std::max(differ, std::fabs(stiff.twist[k] - linear.twist[k]));
  EXPECT_GT(differ, 0.1 * twist);
}

TEST(TruthSim, MultiSlopeMeshHoldsALoadAtItsPiecewiseTwist) {
  // PD holding r = 0 against 5000 N m on the hub: at rest the mesh carries the load, s(e) = 5000 N m, so
  // e = knee_1 + (5000 - k knee_1)/k2 with two slopes, knee_2 + (5000 - s(knee_2))/k3 with three.
  auto twist = [](double knee_2) {
    TruthRig r = hub_rig(-5000.0, 4.0);  // the hub gets -5000 N m
    r.controller = TruthRig{}.controller;
    r.drive.enabled = true;
    r.drive.knee_1 = 1e-4;  // s(knee_1) = 2000 N m
    r.drive.stiffness_2 = 6e7;
    r.drive.knee_2 = knee_2;
    r.drive.stiffness_3 = 1.5e8;
    const TruthTrace tr = run_truth(r).trace;
    EXPECT_NEAR(tr.hub_torque.back(), 5000.0, 0.05);
    return tr.twist.back();
  };
  EXPECT_NEAR(twist(0.0), 1e-4 + 3000.0 / 6e7, 1e-5 * 1.5e-4);                    // 0.150 mrad
  EXPECT_NEAR(twist(1.2e-4), 1.2e-4 + (5000.0 - 3200.0) / 1.5e8, 1e-5 * 1.3e-4);  // 0.132 mrad
}

// Energy lost over each sample interval of a free hub hitting the drive's shaft through a 1 mrad gap,
// split by whether either end of the interval had the teeth in contact and closing (|d| > b, d d' > 0).
std::pair<double, double> mesh_losses(bool one_sided) {
  TruthRig r = hub_rig(0.0, 0.05);
  r.controller.rate = 20000.0;  // a fine trace: the collisions last about 1.5 ms
  r.initial.hub_rate = 0.5;
  r.drive.enabled = true;
  r.drive.backlash = 1e-3;
  r.drive.damping = 1e3;  // zeta 0.05 in contact
  r.drive.one_sided_damping = one_sided;
  const TruthTrace tr = run_truth(r).trace;
  const double b = 0.5e-3;
  auto closing = [&](std::size_t k) { return std::fabs(tr.twist[k]) > b && tr.twist[k] * tr.twist_rate[k] > 0; };
  double in_closing = 0.0, elsewhere = 0.0;
  int contacts = 0;
  for (std::size_t k = 0; k + 1 < tr.t.size(); ++k) {
    const double loss = tr.energy[k] - tr.energy[k + 1];
    (closing(k) || closing(k + 1) ? in_closing : elsewhere) += loss;
    contacts += std::fabs(tr.twist[k]) <= b && std::fabs(tr.twist[k + 1]) > b;
  }
  EXPECT_GE(contacts, 4);
  std::printf("mesh damping %s: %d contacts, lost %.4g J closing, %.4g J otherwise, of %.4g J\n",
              one_sided ? "one-sided" : "two-sided", contacts, in_closing, elsewhere, tr.energy.front());
  return {in_closing, elsewhere};
}

TEST(TruthSim, OneSidedMeshDampingDissipatesOnlyWhileTheTeethClose) {
  const auto [closing, elsewhere] = mesh_losses(true);
  const auto [closing2, elsewhere2] = mesh_losses(false);
  const double e0 = 0.5 * 50.0 * 0.5 * 0.5;         // J, the hub's kinetic energy at the start
  EXPECT_GT(closing, 0.01 * e0);                    // the impacts dissipate
  EXPECT_LT(std::fabs(elsewhere), 1e-3 * closing);  // nothing while the gap is open or the teeth part
  EXPECT_GT(elsewhere2, 0.2 * closing2);            // the two-sided mesh also damps as the teeth part
}

TEST(TruthSim, LoggerRecordsTheLateQuantisedReadingTheControllerUsed) {
  // record.as_seen: the hub angle and rate columns are what the controller read, 5 and 2 samples late,
  // the angle quantised by the in-loop 16-bit encoder; without it, the same readings on time.
  TruthRig r = reference_rig();
  r.duration = 2.0;
  r.sensors.hub_angle.delay = 5;
  r.sensors.hub_angle.quantize = true;
  r.sensors.hub_angle.noise = 2e-5;
  r.sensors.hub_rate.delay = 2;  // 3 ms makes the rate loop ring near Nyquist (kd / J_hub = 500 /s)
  r.sensors.hub_rate.noise = 1e-3;
  r.record.as_seen = true;
  const TruthRun seen = run_truth(r);
  r.record.as_seen = false;
  const Record on_time = simulate_truth(r);
  const double q = kTwoPi / 65536.0;
  const auto &a = seen.record.at("hub_angle"), &w = seen.record.at("hub_rate");
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k], seen.trace.seen_angle[k]) << k;
    ASSERT_EQ(w[k], seen.trace.seen_rate[k]) << k;
    ASSERT_EQ(a[k], on_time.at("hub_angle")[k >= 5 ? k - 5 : 0]) << k;
    ASSERT_EQ(w[k], on_time.at("hub_rate")[k >= 2 ? k - 2 : 0]) << k;
    ASSERT_NEAR(a[k] / q, std::nearbyint(a[k] / q), 1e-9) << k;
  }
}

TEST(TruthSim, NominalFeedForwardLeavesThePayloadMismatchAsTrackingError) {
  // A rigid arm under PD + f (J_nom r'' + kd r'). With J_nom the plant's inertia the error obeys
  // J e'' + kd e' + kp e = 0 from rest: it tracks but for the zero-order hold. With a nominal payload of
  // 250 kg (plant 328.7 kg) it obeys J e'' + kd e' + kp e = dJ r'', dJ = 78.7 kg L^2; on the cubic
  // (fourth derivative 0) the forced error is e = (dJ/kp)(r'' - (kd/kp) r''').
  TruthRig r;
  r.segments = 1;
  r.trajectory.moves = {{0.5, 0.0}};
  r.duration = 2.5;
  auto worst_error = [](const TruthTrace& tr) {
    double e = 0.0;
    for (std::size_t k = 0; k < tr.t.size(); ++k) e = std::max(e, std::fabs(tr.ref[k] - tr.hub_angle[k]));
    return e;
  };
  const double pd = worst_error(run_truth(r).trace);
  r.controller.feedforward = 1.0;
  const double matched = worst_error(run_truth(r).trace);
  EXPECT_LT(matched, 0.01 * pd) << "PD alone " << pd;
  r.controller.nominal_payload_mass = 250.0;
  const double dj = calc_truth_rigid_inertia(r) - calc_truth_rigid_inertia(r, true);
  EXPECT_NEAR(dj, 78.7 * r.beam.length * r.beam.length, 1e-9 * dj);
  const TruthTrace tr = run_truth(r).trace;
  const double T = 3.0, u = 2.5 / T, kp = r.controller.kp, kd = r.controller.kd;
  const double acc = 0.5 * 6.0 * (1.0 - 2.0 * u) / (T * T), jerk = -0.5 * 12.0 / (T * T * T);
  const double forced = dj / kp * (acc - kd / kp * jerk);  // -2.1 mrad
  std::printf("feed-forward: PD alone %.3g rad, matched %.3g rad, forced %.4g rad, got %.4g rad\n", pd, matched,
              forced, tr.ref.back() - tr.hub_angle.back());
  EXPECT_NEAR(tr.ref.back() - tr.hub_angle.back(), forced, 0.03 * std::fabs(forced));
  EXPECT_GT(std::fabs(forced), 20.0 * matched);
}

TEST(TruthSim, NewEffectFieldsAreCheckedByName) {
  TruthRig r = reference_rig();
  r.duration = 0.01;
  auto message = [](const TruthRig& x) {
    try {
      run_truth(x);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("ran");
  };
  TruthRig a = r;
  a.friction.position_amplitude = 1.0;
  EXPECT_EQ(message(a).rfind("friction.position_amplitude: must be in [0, 1)", 0), 0u) << message(a);
  TruthRig b = r;
  b.drive.knee_1 = 2e-4;
  b.drive.stiffness_2 = 1e7;
  b.drive.knee_2 = 1e-4;
  b.drive.stiffness_3 = 1e7;
  EXPECT_EQ(message(b).rfind("drive.knee_2: must be", 0), 0u) << message(b);
  TruthRig c = r;
  c.friction.stribeck_exponent = 0.0;
  EXPECT_EQ(message(c).rfind("friction.stribeck_exponent: must be > 0", 0), 0u) << message(c);
  set_truth_field(r, "friction.bristle_stiffness", "1e5");
  set_truth_field(r, "controller.nominal_payload_mass", "250");
  set_truth_field(r, "drive.one_sided_damping", "true");
  EXPECT_EQ(r.friction.bristle_stiffness, 1e5);
  EXPECT_EQ(r.controller.nominal_payload_mass, 250.0);
  EXPECT_TRUE(r.drive.one_sided_damping);
}

}  // namespace
}  // namespace ff::truth
