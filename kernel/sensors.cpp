#include "kernel/sensors.hpp"

#include <algorithm>
#include <cmath>

#include "kernel/dynamics.hpp"
#include "common/random.hpp"

namespace ff {

double calc_expected_reading(double x, double sigma, double q) {
  if (!(q > 0.0)) return x;
  if (!(sigma > 0.0)) return q * std::nearbyint(x / q);
  const double u = x / q, s = sigma / q;
  if (s > 0.5) {  // the damped Fourier series: exp(-2 pi^2 m^2 s^2) < 1e-8 from m = 3
    double saw = 0.0;
    for (int m = 1; m <= 3; ++m)
      saw += (m % 2 ? 1.0 : -1.0) / m * std::sin(2.0 * M_PI * m * u) * std::exp(-2.0 * M_PI * M_PI * m * m * s * s);
    return x - q / M_PI * saw;
  }
  if (!(std::abs(u) < 1e15)) return x;  // a quantum below the angle's own precision
  // E[round(u + s n)] = a + sum_{k = a..b} P(u + s n >= k + 1/2), P = Phi((u - k - 1/2) / s): the thresholds
  // k + 1/2 within 9 s of u (those below are crossed for certain, counted in a; those above never).
  const auto a = static_cast<long long>(std::ceil(u - 9.0 * s - 0.5)), b = static_cast<long long>(std::floor(u + 9.0 * s - 0.5));
  double e = static_cast<double>(a);
  for (long long k = a; k <= b; ++k) e += 0.5 * std::erfc((static_cast<double>(k) + 0.5 - u) / (s * M_SQRT2));
  return q * e;
}

double sample_channel(double x, double sigma, bool expected, std::uint64_t key, double quantum, long d, long n, long k,
                      int H, int W, int l, double* ring) {
  double y = x;
  if (expected) {
    y = calc_expected_reading(x, sigma, quantum);
  } else {
    if (sigma > 0.0) y += sigma * CounterRng(key, k).normal();
    if (quantum > 0.0) y = quantum * std::nearbyint(y / quantum);
  }
  ring[(k % H) * W + l] = y;
  const long j = k >= d ? (k - d) / n * n : 0;
  return ring[(j % H) * W + l];
}

void compute_measurements(const BatchModel& bm, BatchState& s, double* hub_angle, double* hub_rate) {
  const int W = bm.W, H = bm.sensor_history;
  const long k = s.sample;
  const double* truth[2] = {s.q.data(), s.v.data()};  // row 0: the hub
  double* out[2] = {hub_angle, hub_rate};
  for (int c = 0; c < 2; ++c)
    for (int l = 0; l < W; ++l)
      out[c][l] = sample_channel(truth[c][l], bm.sensor_noise[c][l], bm.expected_readings[l], bm.sensor_key[c][l],
                                 bm.sensor_resolution[c][l],
                                 bm.sensor_delay[c][l], bm.sensor_hold[c][l], k, H, W, l, s.measured[c].data());
}

const char* loop_channel_name(LoopChannel c) { return c == kLoopHubAngle ? "hub_angle" : "hub_rate"; }

const LoopChannelSpec& loop_channel_spec(const SensorSpec& s, LoopChannel c) {
  return c == kLoopHubAngle ? s.hub_angle : s.hub_rate;
}

std::vector<double> log_channel(const LoopChannelSpec& ch, double controller_rate, std::uint64_t key,
                                const std::vector<double>& x, bool noisy) {
  const bool read = !is_logged_on_time(ch);
  const long n = read ? calc_sensor_hold(ch, controller_rate) : 1, d = read ? ch.delay : 0;
  std::vector<double> y(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    const long kk = static_cast<long>(k);
    const std::size_t j = std::min(static_cast<std::size_t>(kk >= d ? (kk - d) / n * n : 0), x.size() - 1);
    double v = x[j];
    if (!noisy) {
      if (read) v = calc_expected_reading(v, ch.noise, ch.resolution);
    } else {
      if (ch.noise > 0.0) v += ch.noise * CounterRng(key, j).normal();
      if (read && ch.resolution > 0.0) v = ch.resolution * std::nearbyint(v / ch.resolution);  // as sample_channel
    }
    y[k] = v;
  }
  // The logger's own latency L: the column holds at k what was logged at max(k - L, 0).
  if (const std::size_t L = static_cast<std::size_t>(ch.logged_delay); L > 0)
    for (std::size_t k = y.size(); k-- > 0;) y[k] = y[k >= L ? k - L : 0];
  return y;
}

std::vector<double> log_loop_channel(const Model& m, LoopChannel c, const std::vector<double>& x, bool noisy) {
  return log_channel(loop_channel_spec(m.spec.sensors, c), m.spec.controller.rate,
                     calc_variant_seed(m.spec.simulation.seed, static_cast<std::uint64_t>(c)), x, noisy);
}

std::vector<double> unlog_channel(const LoopChannelSpec& ch, const std::vector<double>& y) {
  const std::size_t d = static_cast<std::size_t>((is_logged_on_time(ch) ? 0 : ch.delay) + ch.logged_delay);
  std::vector<double> x(y.size());
  for (std::size_t k = 0; k < y.size(); ++k) x[k] = y[std::min(k + d, y.size() - 1)];
  return x;
}

std::vector<double> unlog_loop_channel(const Model& m, LoopChannel c, const std::vector<double>& y) {
  return unlog_channel(loop_channel_spec(m.spec.sensors, c), y);
}

const char* recorded_column_name(RecordedColumn c) {
  switch (c) {
    case kStrainMoment: return "strain_moment";
    case kStrainTipEstimate: return "strain_tip_estimate";
    case kTipAccel: return "tip_accel";
    case kTipPosition: return "tip_position";
    case kRecordedColumns: break;
  }
  return "?";
}

void compute_recorded_sensors(const BatchModel& bm, BatchState& s, Workspace& ws, double* out) {
  const int W = bm.W, H = bm.rec_history;
  const long k = s.sample;
  const double* q = s.q.data();
  double truth[kMaxLanes], angle[kMaxLanes];
  for (int c = 0; c < kRecordedChannels; ++c) {
    if (!bm.rec_enabled[c]) continue;
    // The sensor's (first) column.
    double* y_out = out + (c == kStrainGauge ? kStrainMoment : c == kTipAccelerometer ? kTipAccel : kTipPosition) * W;
    if (c == kStrainGauge) {
      for (int l = 0; l < W; ++l) {  // elastic moment of the gauge's joint, N·m
        const int o = bm.strain_joint[l] * W + l;
        truth[l] = (bm.joint_k[o] + bm.joint_k3[o] * q[o] * q[o]) * q[o];
      }
    } else if (c == kTipAccelerometer) {
      double* qdd = ws.q1.data();
      double* zdot = bm.layout.nz > 0 ? ws.zdot.data() : nullptr;
      compute_acceleration(bm, make_body_table(bm, s.tip), q, s.v.data(), s.z.data(), s.tau.data(), qdd, zdot, ws);
      compute_tip_acceleration(bm, q, s.v.data(), qdd, truth);
    } else {
      compute_tip(bm, q, truth, angle, ws);
    }
    for (int l = 0; l < W; ++l)
      y_out[l] = sample_channel(truth[l], bm.rec_noise[c][l], bm.expected_readings[l], bm.rec_key[c][l], bm.rec_resolution[c][l],
                                bm.rec_delay[c][l], bm.rec_hold[c][l], k, H, W, l, s.recorded[c].data());
  }
  if (bm.rec_enabled[kStrainGauge])
    for (int l = 0; l < W; ++l) out[kStrainTipEstimate * W + l] = bm.strain_gain[l] * out[kStrainMoment * W + l];
}

const char* output_channel_name(OutputChannel c) {
  switch (c) {
    case kOutHubTorque: return "hub_torque";
    case kOutTipDeflection: return "tip_deflection";
    case kOutPressureA: return "pressure_a";
    case kOutPressureB: return "pressure_b";
    case kOutputChannels: break;
  }
  return "?";
}

const ChannelSpec& output_channel_spec(const SensorSpec& s, OutputChannel c) {
  const ChannelSpec* ch[kOutputChannels] = {&s.hub_torque, &s.tip_deflection, &s.pressure_a, &s.pressure_b};
  return *ch[c];
}

OutputChannel find_output_channel(const std::string& name) {
  for (int c = 0; c < kOutputChannels; ++c)
    if (name == output_channel_name(OutputChannel(c))) return OutputChannel(c);
  return kOutputChannels;
}

std::vector<double> measure_output(const Model& m, OutputChannel c, const std::vector<double>& x, bool noisy) {
  const ChannelSpec& ch = output_channel_spec(m.spec.sensors, c);
  const long n = calc_sensor_hold(ch, m.spec.controller.rate), d = ch.delay;
  const std::uint64_t key = calc_variant_seed(m.spec.simulation.seed, static_cast<std::uint64_t>(5 + c));
  std::vector<double> y(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    const long kk = static_cast<long>(k);
    const std::size_t j = static_cast<std::size_t>(kk >= d ? (kk - d) / n * n : 0);
    double v = x[std::min(j, x.size() - 1)];
    if (noisy && ch.noise > 0.0) v += ch.noise * CounterRng(key, j).normal();
    if (noisy && ch.resolution > 0.0) v = ch.resolution * std::nearbyint(v / ch.resolution);
    y[k] = v;
  }
  return y;
}

}  // namespace ff
