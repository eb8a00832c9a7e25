// kernel/sensors.cpp: quantised, noisy, delayed measurements of the hub angle and rate, and the
// recorded sensors (strain gauge, tip accelerometer, tip position) sampled and held at their own rate.
#include "kernel/sensors.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "common/errors.hpp"
#include "common/random.hpp"
#include "kernel/controller.hpp"
#include "kernel/dynamics.hpp"
#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

struct Rig {
  Model m;
  BatchModel bm;
  BatchState s;
  explicit Rig(const ModelSpec& spec) : m(make_model(spec)), bm(make_batch(std::span<const Model>(&m, 1))), s(make_state(bm)) {}
  // One sample: the true hub angle x at sample k; returns what the controller sees.
  double see(long k, double x) {
    s.sample = k;
    s.q[0] = x;
    double a = 0, r = 0;
    compute_measurements(bm, s, &a, &r);
    return a;
  }
};

TEST(Sensors, EncoderQuantisesTheHubAngle) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.resolution = 0.01;
  Rig rig(spec);
  EXPECT_DOUBLE_EQ(rig.see(0, 0.0149), 0.01);
  EXPECT_DOUBLE_EQ(rig.see(1, 0.0151), 0.02);
  EXPECT_DOUBLE_EQ(rig.see(2, -0.0049), 0.0);
  // And the PD acts on the quantised angle: kp (r - 0.01).
  rig.s.sample = 3;
  rig.s.q[0] = 0.0149;
  double r = 0.05, acc = 0.0, rf = 0.0;
  compute_control(rig.bm, rig.s, &r, &acc, &rf);
  EXPECT_NEAR(rig.s.tau[0], 1e5 * (0.05 - 0.01), 1e-9);
}

TEST(Sensors, NoiseHasItsStandardDeviationAndRepeats) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.noise = 1e-3;
  Rig a(spec), b(spec);
  spec.simulation.seed = 2;
  Rig c(spec);
  double sum = 0, sum2 = 0;
  const int n = 20000;
  bool all_equal = true, any_differs = false;
  for (int k = 0; k < n; ++k) {
    const double x = a.see(k, 0.3) - 0.3;
    sum += x;
    sum2 += x * x;
    all_equal &= b.see(k, 0.3) - 0.3 == x;
    any_differs |= c.see(k, 0.3) - 0.3 != x;
  }
  EXPECT_NEAR(sum / n, 0.0, 5.0 * 1e-3 / std::sqrt(n));  // 5 standard errors
  EXPECT_NEAR(std::sqrt(sum2 / n), 1e-3, 3e-5);
  EXPECT_TRUE(all_equal);    // same seed, same noise
  EXPECT_TRUE(any_differs);  // another seed, other noise
}

TEST(Sensors, DelayShiftsTheMeasurementByWholeSamples) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.delay = 3;
  Rig rig(spec);
  for (long k = 0; k < 10; ++k) {
    const double seen = rig.see(k, 0.1 * static_cast<double>(k));
    EXPECT_DOUBLE_EQ(seen, k >= 3 ? 0.1 * static_cast<double>(k - 3) : 0.0) << "sample " << k;
  }
}

TEST(Sensors, EncoderAtAQuarterOfTheControllerRateHoldsEachReadingFourSamples) {
  // 250 Hz on a 1 kHz controller, delay 2: at sample k the controller sees the reading of sample
  // 4 floor((k - 2) / 4), the same rule as the recorded sensors, or the first one while k < 2.
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.rate = 250.0;
  spec.sensors.hub_angle.delay = 2;
  Rig rig(spec);
  for (long k = 0; k < 20; ++k) {
    const long j = k >= 2 ? (k - 2) / 4 * 4 : 0;
    EXPECT_DOUBLE_EQ(rig.see(k, 0.1 * static_cast<double>(k)), 0.1 * static_cast<double>(j)) << "sample " << k;
  }
}

TEST(Sensors, PdActsOnHubAngleAndRateSampledEveryFourthControllerSample) {
  // Both controller channels at 250 Hz: the PD torque at sample k is kp (r_k - theta(t_j)) - kd omega(t_j)
  // with j = 4 floor(k / 4), the true hub angle and rate at those instants, so the measurement changes
  // only every 4th sample while the reference moves at every one.
  ModelSpec spec = test::rig_spec(0.5, 1.0);
  spec.sensors.hub_angle.rate = 250.0;
  spec.sensors.hub_rate.rate = 250.0;
  spec.hub_inertia = 500.0;  // the rate loop kd / J_hub stable at 250 Hz
  const auto tr = test::run_one(make_model(spec)).traces[0];
  const double kp = spec.controller.kp, kd = spec.controller.kd;
  int changes = 0;
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    const std::size_t j = k / 4 * 4;
    ASSERT_DOUBLE_EQ(tr.torque[k], kp * (tr.ref[k] - tr.hub_angle[j]) - kd * tr.hub_rate[j]) << "sample " << k;
    if (k > 0 && tr.hub_angle[k] != tr.hub_angle[k - 1] && k % 4 != 0)
      ++changes;  // the true angle moves in between samples the controller never sees
  }
  EXPECT_GT(changes, 1000);
}

TEST(Sensors, ClosedLoopWithCoarseEncoderStillTracks) {
  // A 1 mrad encoder on the hub: the arm still arrives, within about a quantum, at its target.
  ModelSpec spec = test::rig_spec(0.5, 20.0);
  spec.notch.enabled = true;
  spec.sensors.hub_angle.resolution = 1e-3;
  const auto tr = test::run_one(make_model(spec)).traces[0];
  EXPECT_NEAR(tr.hub_angle.back(), 0.5, 2e-3);
}

// ---- recorded sensors: strain gauge, tip accelerometer, tip position --------------------------

// One lane's recorded sensors called directly, on a state the test sets.
struct Recorder {
  Model m;
  BatchModel bm;
  BatchState s;
  Workspace ws;
  std::vector<double> out;
  explicit Recorder(const ModelSpec& spec)
      : m(make_model(spec)), bm(make_batch(std::span<const Model>(&m, 1))), s(make_state(bm)), ws(make_workspace(bm)),
        out(kRecordedColumns, 0.0) {}
  // The recorded value of `column` at sample k.
  double read(long k, RecordedColumn column) {
    s.sample = k;
    compute_recorded_sensors(bm, s, ws, out.data());
    return out[column];
  }
};

// The trace column `name` (an extra channel), or an empty list.
std::vector<double> column(const Trace& tr, const std::string& name) {
  for (const auto& [n, values] : tr.extra)
    if (n == name) return values;
  ADD_FAILURE() << "no column " << name;
  return {};
}

TEST(Sensors, RecordedSensorsAreOffByDefault) {
  const auto tr = test::run_one(make_model(test::rig_spec(0.5, 0.5))).traces[0];
  EXPECT_TRUE(tr.extra.empty());
}

TEST(Sensors, StrainGaugeReadsTheElasticMomentOfItsJoint) {
  // Bent statically at joint 3 (hardening joint): M = k_3 q_3 + k3_3 q_3^3; the damper's c_3 qd_3 is not strain.
  ModelSpec spec = test::rig_spec();
  spec.joints.cubic_stiffness = 2.0e6;
  spec.sensors.strain_gauge.enabled = true;
  spec.sensors.strain_gauge.joint = 3;
  Recorder rec(spec);
  const double q3 = 0.02, k = rec.m.joint_k[3], k3 = rec.m.joint_k3[3];
  rec.s.q[3] = q3;
  rec.s.q[1] = 0.01;   // other joints bent too: not this gauge's moment
  rec.s.v[3] = 0.5;    // moving: the damper moment c_3 * 0.5 is not read
  EXPECT_NEAR(rec.read(0, kStrainMoment), k * q3 + k3 * q3 * q3 * q3, 1e-9 * k * q3);
  EXPECT_GT(k3 * q3 * q3 * q3, 1e-3 * k * q3);  // the cubic term matters here
  // Quantised to its resolution.
  rec.bm.rec_resolution[kStrainGauge][0] = 100.0;
  EXPECT_DOUBLE_EQ(rec.read(1, kStrainMoment), 100.0 * std::nearbyint((k * q3 + k3 * q3 * q3 * q3) / 100.0));
}

TEST(Sensors, StrainGaugeEstimatesTheTipDeflectionUnderAStaticTipLoad) {
  // Tip load P, joints k = EI / l (kappa = 1): joint i at x_i = (i - 1/2) l carries M_i = P (L - x_i), so
  // q_i = M_i / k and the chain's tip deflection is sum q_i (L - x_i) = (P l / EI) l^2 sum_{m=1}^{N-1} (m - 1/2)^2
  // = P L^3 / (3 EI) (1 - 1/(4 (N-1)^2)): the continuous cantilever's, less the midpoint-rule error. The gauge's
  // estimate M_i L^3 / (3 EI (L - x_i)) is the continuous value, so estimate / truth - 1 = 1 / (4 (N-1)^2 - 1),
  // at any joint (small deflection: sin phi = phi to ~phi^2/6 ~ 1e-8 here).
  const double P = 1.0;  // N
  for (int n : {3, 6, 12}) {
    for (int joint : {1, n / 2, n - 1}) {
      ModelSpec spec = test::rig_spec();
      spec.segments = n;
      spec.joints.stiffness = spec.beam.youngs_modulus * calc_area_moment(spec.beam) / spec.joints.reference_cell;
      spec.sensors.strain_gauge.enabled = true;
      spec.sensors.strain_gauge.joint = joint;
      Recorder rec(spec);
      const double L = spec.beam.length, l = rec.m.cell;
      for (int i = 1; i < n; ++i) rec.s.q[i] = P * (L - (i - 0.5) * l) / rec.m.joint_k[i];
      const double truth = calc_tip(rec.bm, rec.s.q.data(), 0).deflection;
      const double estimate = rec.read(0, kStrainTipEstimate);
      const double M = n - 1;
      EXPECT_NEAR(estimate / truth - 1.0, 1.0 / (4.0 * M * M - 1.0), 1e-6) << "N " << n << " joint " << joint;
      EXPECT_NEAR(estimate, P * L * L * L / (3.0 * spec.beam.youngs_modulus * calc_area_moment(spec.beam)),
                  1e-12 * estimate);
    }
  }
}

TEST(Sensors, TipAccelerometerIsTheSecondDerivativeOfTheTipDeflection) {
  // The held torque steps at every sample and the acceleration with it. The accelerometer reads a-(t_k), under
  // the torque held before sample k; the central difference (y[k+1] - 2 y[k] + y[k-1]) / T^2 weighs y'' with a
  // hat over [t_{k-1}, t_{k+1}], i.e. (a-(t_k) + a+(t_k)) / 2 + O(T^2 y''''), a+ under the new torque (taken
  // here from the state `observe` sees). Checked during the move, where y'' is large.
  ModelSpec spec = test::rig_spec(0.5, 1.0);
  spec.sensors.tip_accelerometer.enabled = true;
  const Model m = make_model(spec);
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  Workspace ws = make_workspace(bm);
  std::vector<double> qdd(bm.nseg), after;
  const auto run = simulate(bm, [&](const BatchState& s) {
    double a = 0.0;
    compute_acceleration(bm, s.q.data(), s.v.data(), s.z.data(), s.tau.data(), qdd.data(), nullptr, ws);
    compute_tip_acceleration(bm, s.q.data(), s.v.data(), qdd.data(), &a);
    after.push_back(a);
  });
  const Trace& tr = run.traces[0];
  const auto before = column(tr, "tip_accel");
  ASSERT_EQ(before.size(), tr.t.size());
  ASSERT_EQ(after.size(), tr.t.size());
  const double T = m.control_period;
  double worst = 0.0, largest = 0.0, jump = 0.0;
  for (std::size_t k = 1; k + 1 < tr.t.size(); ++k) {
    if (tr.t[k] < 0.5 || tr.t[k] > 2.5) continue;
    const double fd = (tr.tip_deflection[k + 1] - 2.0 * tr.tip_deflection[k] + tr.tip_deflection[k - 1]) / (T * T);
    worst = std::max(worst, std::fabs(fd - 0.5 * (before[k] + after[k])));
    largest = std::max(largest, std::fabs(before[k]));
    jump = std::max(jump, std::fabs(after[k] - before[k]));
  }
  EXPECT_GT(largest, 0.5);  // m/s^2: the move bends the beam
  EXPECT_LT(worst, 1e-3 * largest) << "largest " << largest << " jump " << jump;  // ~2e-4 here
  EXPECT_GT(jump, 0.1 * largest);  // the ZOH step is no detail: the two limits differ (~0.36 of 1 m/s^2)
}

TEST(Sensors, TipPositionIsTheTipDeflectionDelayedByWholeSamples) {
  ModelSpec spec = test::rig_spec(0.5, 1.0);
  spec.sensors.tip_position.enabled = true;
  spec.sensors.tip_position.delay = 7;
  const auto tr = test::run_one(make_model(spec)).traces[0];
  const auto pos = column(tr, "tip_position");
  ASSERT_EQ(pos.size(), tr.t.size());
  for (std::size_t k = 0; k < pos.size(); ++k)
    ASSERT_EQ(pos[k], tr.tip_deflection[k >= 7 ? k - 7 : 0]) << "sample " << k;
}

TEST(Sensors, SampleAndHoldKeepsEachReadingForRateRatioSamples) {
  // 100 Hz on a 1 kHz controller: each reading held 10 samples; with delay 3 the reading of sample
  // 10 floor((k - 3) / 10) is recorded at k.
  ModelSpec spec = test::rig_spec(0.5, 1.0);
  spec.sensors.tip_position.enabled = true;
  spec.sensors.tip_position.rate = 100.0;
  spec.sensors.tip_position.delay = 3;
  const auto tr = test::run_one(make_model(spec)).traces[0];
  const auto pos = column(tr, "tip_position");
  for (std::size_t k = 0; k < pos.size(); ++k) {
    const std::size_t j = k >= 3 ? (k - 3) / 10 * 10 : 0;
    ASSERT_EQ(pos[k], tr.tip_deflection[j]) << "sample " << k;
  }
  EXPECT_NE(pos[13], pos[12]);  // a new reading every 10 samples
  EXPECT_EQ(pos[22], pos[13]);
}

TEST(Sensors, RecordedNoiseHasItsStandardDeviationAndRepeatsPerChannel) {
  // Straight arm at rest, no torque held: every truth is 0, every reading is noise. Mean ~ 0 (5 standard
  // errors), std ~ sigma, the same for the same seed, independent between channels and seeds.
  ModelSpec spec = test::rig_spec();
  spec.sensors.tip_position.enabled = true;
  spec.sensors.tip_position.noise = 1e-3;
  spec.sensors.strain_gauge.enabled = true;
  spec.sensors.strain_gauge.noise = 1e-3;
  spec.sensors.tip_accelerometer.enabled = true;
  spec.sensors.tip_accelerometer.noise = 0.2;
  Recorder a(spec), b(spec);
  spec.simulation.seed = 2;
  Recorder c(spec);
  const int n = 20000;
  double sum[3] = {}, sum2[3] = {};
  const RecordedColumn cols[3] = {kTipPosition, kStrainMoment, kTipAccel};
  const double sigma[3] = {1e-3, 1e-3, 0.2};
  bool repeats = true, channels_differ = false, seeds_differ = false;
  for (int k = 0; k < n; ++k) {
    double x[3];
    for (int j = 0; j < 3; ++j) {
      x[j] = a.read(k, cols[j]);
      sum[j] += x[j];
      sum2[j] += x[j] * x[j];
      repeats &= b.read(k, cols[j]) == x[j];
      seeds_differ |= c.read(k, cols[j]) != x[j];
    }
    channels_differ |= x[0] != x[1];  // same sigma, other stream
  }
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(sum[j] / n, 0.0, 5.0 * sigma[j] / std::sqrt(n)) << recorded_column_name(cols[j]);
    EXPECT_NEAR(std::sqrt(sum2[j] / n), sigma[j], 0.03 * sigma[j]) << recorded_column_name(cols[j]);
  }
  EXPECT_TRUE(repeats);
  EXPECT_TRUE(channels_differ);
  EXPECT_TRUE(seeds_differ);
}

TEST(Sensors, RecordedChannelsAreTraceColumnsInTheCsv) {
  ModelSpec spec = test::rig_spec(0.5, 0.2);
  spec.sensors.strain_gauge.enabled = true;
  spec.sensors.tip_accelerometer.enabled = true;
  spec.sensors.tip_position.enabled = true;
  const auto tr = test::run_one(make_model(spec)).traces[0];
  const std::string path = ::testing::TempDir() + "ff_sensors_trace.csv";
  write_trace_csv(tr, path);
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "t,ref,ref_filtered,hub_torque,hub_angle,hub_rate,tip_deflection,tip_angle,"
                    "strain_moment,strain_tip_estimate,tip_accel,tip_position");
  std::remove(path.c_str());
}

TEST(Sensors, LanesMustAgreeOnTheirRecordedSensors) {
  ModelSpec spec = test::rig_spec();
  const Model plain = make_model(spec);
  spec.sensors.tip_position.enabled = true;
  const Model gauged = make_model(spec);
  const Model both[2] = {plain, gauged};
  EXPECT_THROW(make_batch(std::span<const Model>(both, 2)), std::invalid_argument);
}

}  // namespace
}  // namespace ff

namespace ff {
namespace {

// The output channels (sensors.hub_torque ...): the sensor rule applied to a finished sequence.
TEST(OutputChannels, DelayAndHoldFollowTheSensorRule) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.tip_deflection.delay = 3;
  spec.sensors.tip_deflection.rate = 250.0;  // hold 4 controller samples at 1 kHz
  const Model m = make_model(spec);
  std::vector<double> x(40);
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = static_cast<double>(k);
  const auto y = measure_output(m, kOutTipDeflection, x, false);
  for (long k = 0; k < 40; ++k) {
    const long j = k >= 3 ? (k - 3) / 4 * 4 : 0;  // the reading of sample 4 floor((k - 3) / 4)
    EXPECT_EQ(y[k], static_cast<double>(j)) << k;
  }
  // Another channel keeps its own (none): unchanged.
  EXPECT_EQ(measure_output(m, kOutHubTorque, x, true), x);
}

TEST(OutputChannels, NoiseAndQuantumOnlyWhenMeasuredNotPredicted) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_torque.noise = 2.0;
  spec.sensors.hub_torque.resolution = 0.5;
  const Model m = make_model(spec);
  const std::vector<double> x(20000, 100.0);
  const auto y = measure_output(m, kOutHubTorque, x, true);
  double s1 = 0, s2 = 0;
  for (double v : y) {
    EXPECT_EQ(std::fmod(v, 0.5), 0.0);
    s1 += v - 100.0;
    s2 += (v - 100.0) * (v - 100.0);
  }
  EXPECT_NEAR(s1 / y.size(), 0.0, 0.05);
  EXPECT_NEAR(std::sqrt(s2 / y.size()), std::sqrt(4.0 + 0.25 / 12.0), 0.05);  // noise and the quantum's share
  EXPECT_EQ(measure_output(m, kOutHubTorque, x, true), y);                    // repeats (seed, channel)
  EXPECT_EQ(measure_output(m, kOutHubTorque, x, false), x);                   // a prediction: neither
}

// ---- what a record's column of an in-loop channel holds (sensors.hub_angle.logged) -----------------

// A real logger records what the controller read: the logged column (logged: read, the default) is the
// controller's input sample for sample, late, held, quantised and with the loop's own noise.
TEST(LoggedChannels, ReadIsTheControllersInputSampleForSample) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.delay = 2;
  spec.sensors.hub_angle.rate = 250.0;  // held 4 samples
  spec.sensors.hub_angle.resolution = 1e-3;
  spec.sensors.hub_angle.noise = 3e-4;
  Rig rig(spec);
  std::vector<double> x(200), seen(200);
  for (std::size_t k = 0; k < x.size(); ++k) {
    x[k] = 0.3 * std::sin(0.05 * static_cast<double>(k));
    seen[k] = rig.see(static_cast<long>(k), x[k]);
  }
  EXPECT_EQ(rig.m.spec.sensors.hub_angle.logged, "read");
  EXPECT_EQ(log_loop_channel(rig.m, kLoopHubAngle, x, true), seen);
  // A prediction: the expected reading E[Q(x_j + sigma n)], j = 4 floor((k - 2) / 4).
  const auto p = log_loop_channel(rig.m, kLoopHubAngle, x, false);
  for (std::size_t k = 0; k < x.size(); ++k) {
    const std::size_t j = k >= 2 ? (k - 2) / 4 * 4 : 0;
    ASSERT_EQ(p[k], calc_expected_reading(x[j], 3e-4, 1e-3)) << k;
  }
}

// E[Q(x + sigma n)] against its definition: the mean of 400 000 quantised noisy readings (within 5 standard
// errors), at random x and sigma / q from 0.01 to 3 (both of calc_expected_reading's branches); its limits:
// the staircase Q(x) at sigma = 0, x itself once sigma >> q, a level's midpoint kept by symmetry.
TEST(ExpectedReading, IsTheMeanOfManyQuantisedNoisyReadings) {
  CounterRng pick(77, 0);
  for (int c = 0; c < 24; ++c) {
    const double q = 1e-3 * std::pow(10.0, pick.uniform() - 0.5);
    const double s = 0.01 * std::pow(300.0, pick.uniform()), x = (pick.uniform() - 0.5) * 40 * q;
    const double sigma = s * q;
    CounterRng noise(1234, static_cast<std::uint64_t>(c));
    const int n = 400000;
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; ++i) {
      const double y = q * std::nearbyint((x + sigma * noise.normal()) / q);
      sum += y;
      sum2 += y * y;
    }
    const double mean = sum / n, se = std::sqrt(std::max(sum2 / n - mean * mean, 0.0) / n);
    EXPECT_NEAR(calc_expected_reading(x, sigma, q), mean, 5.0 * se + 1e-9 * q) << "x/q " << x / q << " sigma/q " << s;
  }
  EXPECT_EQ(calc_expected_reading(0.0149, 0.0, 0.01), 0.01);
  EXPECT_EQ(calc_expected_reading(0.0149, 1e-3, 0.0), 0.0149);
  EXPECT_NEAR(calc_expected_reading(0.0137, 0.05, 0.01), 0.0137, 1e-15);  // sigma = 5 q: smooth
  EXPECT_NEAR(calc_expected_reading(0.015, 0.002, 0.01), 0.015, 1e-15);
  // The two branches meet at sigma = q / 2.
  for (double u : {0.1, 0.3, 0.45})
    EXPECT_NEAR(calc_expected_reading(u, 0.4999999, 1.0), calc_expected_reading(u, 0.5000001, 1.0), 1e-6) << u;
}

// simulation.expected_readings: the controller is given E[Q(x + sigma n)], the same at every sample (no
// noise drawn), the recorded sensors likewise.
TEST(ExpectedReading, IsWhatTheControllerReadsInExpectedMode) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.resolution = 1e-3;
  spec.sensors.hub_angle.noise = 4e-4;
  spec.simulation.expected_readings = true;
  Rig rig(spec);
  for (long k = 0; k < 50; ++k) {
    const double x = 1e-4 * static_cast<double>(k);
    ASSERT_EQ(rig.see(k, x), calc_expected_reading(x, 4e-4, 1e-3)) << k;
  }
  EXPECT_NE(rig.see(60, 2.5e-4), 0.0);  // a quarter-quantum in: the staircase would read 0
}

// The same in a closed-loop run: the PD's torque is kp (r_k - y_k) - kd w_k with y and w the trace's true
// hub angle and rate as logged (read), so the logged columns are exactly what the controller acted on.
TEST(LoggedChannels, ThePdActsOnTheLoggedColumns) {
  ModelSpec spec = test::rig_spec(0.5, 1.0);
  spec.sensors.hub_angle.delay = 3;
  spec.sensors.hub_angle.resolution = 2.0 * M_PI / 65536.0;  // a 16-bit encoder
  spec.sensors.hub_angle.noise = 2e-5;
  spec.sensors.hub_rate.delay = 1;
  spec.sensors.hub_rate.noise = 1e-3;
  const Model m = make_model(spec);
  const auto tr = test::run_one(m).traces[0];
  const auto y = log_loop_channel(m, kLoopHubAngle, tr.hub_angle, true);
  const auto w = log_loop_channel(m, kLoopHubRate, tr.hub_rate, true);
  for (std::size_t k = 0; k < tr.t.size(); ++k)
    ASSERT_NEAR(tr.torque[k], spec.controller.kp * (tr.ref[k] - y[k]) - spec.controller.kd * w[k], 1e-9 * spec.controller.kp)
        << k;
}

// logged: true, an on-time measurement: the true angle plus the channel's noise (sd sigma, mean 0), no
// delay, hold or quantisation; a prediction is the true angle itself.
TEST(LoggedChannels, TrueIsTheOnTimeAngleWithNoiseOnly) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.delay = 5;
  spec.sensors.hub_angle.rate = 250.0;
  spec.sensors.hub_angle.resolution = 1e-2;
  spec.sensors.hub_angle.noise = 1e-4;
  spec.sensors.hub_angle.logged = "true";
  const Model m = make_model(spec);
  std::vector<double> x(20000);
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = 0.3 * std::sin(1e-3 * static_cast<double>(k));
  const auto y = log_loop_channel(m, kLoopHubAngle, x, true);
  double s1 = 0, s2 = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    s1 += y[k] - x[k];
    s2 += (y[k] - x[k]) * (y[k] - x[k]);
  }
  const double n = static_cast<double>(x.size());
  EXPECT_NEAR(s1 / n, 0.0, 5.0 * 1e-4 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(s2 / n), 1e-4, 3e-6);  // the noise's, not the 10 mrad quantum's (2.9 mrad RMS)
  EXPECT_EQ(log_loop_channel(m, kLoopHubAngle, x, false), x);
}

// A logger that stamps late (logged_delay L) shifts the column, either way it is logged; unlog_loop_channel
// brings a read column back on time (the loop's delay and L).
TEST(LoggedChannels, LoggerLatencyShiftsTheColumnAndUnlogUndoesIt) {
  ModelSpec spec = test::rig_spec();
  spec.sensors.hub_angle.delay = 2;
  spec.sensors.hub_angle.logged_delay = 5;
  std::vector<double> x(50);
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = static_cast<double>(k);
  for (const char* logged : {"read", "true"}) {
    spec.sensors.hub_angle.logged = logged;
    const Model m = make_model(spec);
    const auto y = log_loop_channel(m, kLoopHubAngle, x, false);
    const std::size_t d = std::string(logged) == "read" ? 7 : 5;
    for (std::size_t k = 0; k < x.size(); ++k) ASSERT_EQ(y[k], k >= d ? x[k - d] : 0.0) << logged << " " << k;
    const auto back = unlog_loop_channel(m, kLoopHubAngle, y);
    for (std::size_t k = 0; k + d < x.size(); ++k) ASSERT_EQ(back[k], x[k]) << logged << " " << k;
  }
  spec.sensors.hub_angle.logged = "late";
  EXPECT_THROW(make_model(spec), ConfigError);
}

TEST(OutputChannels, NamesAreTheRecordColumns) {
  for (int c = 0; c < kOutputChannels; ++c)
    EXPECT_EQ(find_output_channel(output_channel_name(OutputChannel(c))), OutputChannel(c));
  EXPECT_EQ(find_output_channel("hub_angle"), kOutputChannels);  // a controller channel, in the loop
}

}  // namespace
}  // namespace ff
