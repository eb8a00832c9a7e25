// The sensors: each channel is the true value plus Gaussian noise, quantised, sampled and held at its
// own rate and delayed by whole controller samples. Noise is a pure function of (the model's seed,
// channel, sample): runs repeat bit for bit on any machine. The controller's sensors (hub angle and
// rate) feed the controller; the recorded sensors (strain gauge, tip accelerometer, tip position)
// go to the trace only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kernel/batch.hpp"

namespace ff {

// The expected reading of a quantised, noisy sensor, E[Q(x + sigma n)], n ~ N(0, 1), Q rounding to the
// nearest multiple of q: the staircase Q(x) smoothed by the noise (dither). With u = x / q, s = sigma / q:
//   s <= 0.5:  q (a + sum_{k = a..b} Phi((u - k - 1/2) / s)), the thresholds k + 1/2 within 9 s of u;
//   s >  0.5:  x - (q / pi) sum_m (-1)^(m+1) / m sin(2 pi m u) exp(-2 pi^2 m^2 s^2), the sawtooth's
//              Fourier series with each harmonic damped by the Gaussian's characteristic function.
// q = 0 gives x; sigma = 0 gives Q(x).
double calc_expected_reading(double x, double sigma, double q);

// One channel of lane l at controller sample k: the reading y = Q(x + sigma n), n ~ N(0, 1) from the
// counter-based stream `key` at sample k (common/random.hpp; Q rounds to the nearest multiple of
// `quantum`, none when 0), or its expectation calc_expected_reading(x, sigma, quantum) when `expected`
// (simulation.expected_readings), goes into the ring (H x W, H >= d + n); returned is what the channel
// gives now, the reading of the last sensor sample j = n floor((k - d) / n) <= k - d (delay d, hold n),
// or the first reading while k < d. With sigma = quantum = d = 0 and n = 1 it returns x.
double sample_channel(double x, double sigma, bool expected, std::uint64_t key, double quantum, long d, long n, long k,
                      int H, int W, int l, double* ring);

// Takes this sample's measurement of every lane (s.sample, s.q, s.v), stores it in the ring
// s.measured, and writes what the controller sees now (W each): the measurement of sample
// n floor((k - d) / n) (d = delay, n = hold = controller rate / sensor rate), or the first one while
// the run is younger than the delay; as the recorded sensors below.
void compute_measurements(const BatchModel& bm, BatchState& s, double* hub_angle, double* hub_rate);

// The channels the controller reads (sensors.hub_angle, .hub_rate; noise streams 0 and 1, as
// compute_measurements') and what a record's column of each holds (LoopChannelSpec::logged).
enum LoopChannel { kLoopHubAngle = 0, kLoopHubRate, kLoopChannels };
// The record column (and model path sensors.<name>) of a channel.
const char* loop_channel_name(LoopChannel c);
const LoopChannelSpec& loop_channel_spec(const SensorSpec& s, LoopChannel c);

// The logged column of an in-loop channel from its truth x at every controller sample (x_k at t = k T):
//   logged: read  y_k = Q(x_j + sigma n_j), j = n floor((k - d) / n) for k >= d, else j = 0 (delay d, hold n):
//                 what the controller read at sample k, bit for bit compute_measurements' (the same
//                 stream (seed, c) at sample j); noisy = false (a prediction) gives the expected reading
//                 calc_expected_reading(x_j, sigma, Q's quantum): the staircase smoothed by the noise.
//   logged: true  y_k = x_k + sigma n_k: an on-time measurement, noise only (the channel's stream at
//                 sample k; no delay, hold or quantisation); noisy = false gives x.
// Either then shifted by the logger's own latency L = logged_delay: the column at k holds y_max(k - L, 0).
std::vector<double> log_loop_channel(const Model& m, LoopChannel c, const std::vector<double>& x, bool noisy);
// The same rule for any in-loop channel `ch` (an arm joint's too) sampled by a controller at `controller_rate`
// (Hz), its noise stream `key`.
std::vector<double> log_channel(const LoopChannelSpec& ch, double controller_rate, std::uint64_t key,
                                const std::vector<double>& x, bool noisy);
// The channel's truth at controller sample k from its logged column y (a record's): y_(k + d + L) (d the
// loop's delay when logged as read, else 0; L = logged_delay; the hold's staircase kept), the last value
// beyond the end.
std::vector<double> unlog_loop_channel(const Model& m, LoopChannel c, const std::vector<double>& y);
std::vector<double> unlog_channel(const LoopChannelSpec& ch, const std::vector<double>& y);

// Trace columns of the recorded sensors (rows of compute_recorded_sensors' output), in order.
enum RecordedColumn { kStrainMoment = 0, kStrainTipEstimate, kTipAccel, kTipPosition, kRecordedColumns };
// Their names in Trace::extra and the trace CSV.
const char* recorded_column_name(RecordedColumn c);
// The sensor a column belongs to.
inline RecordedChannel recorded_channel(RecordedColumn c) {
  return c <= kStrainTipEstimate ? kStrainGauge : c == kTipAccel ? kTipAccelerometer : kTipPositionSensor;
}

// Takes this sample's reading of every enabled recorded sensor (BatchModel::rec_enabled) of every lane
// and writes what is recorded now, out[column * W + lane] (kRecordedColumns x W; rows of disabled sensors
// untouched). Each channel: y = Q(x + sigma n) with n from the stream (seed, channel) at sample k, stored
// in the ring s.recorded; the recorded value at sample k is the reading of sample n floor((k - d) / n)
// (d = delay, n = hold = controller rate / sensor rate), or the first reading while k < d. The truths x:
//   strain gauge: M = k_i q_i + k3_i q_i^3 at its joint (the elastic moment: a gauge reads strain, so the
//     damper c_i qd_i is not seen), N·m; its tip estimate is strain_gain times the recorded M, m;
//   tip accelerometer: compute_tip_acceleration with qdd = compute_acceleration (the tip body s.tip)
//     under the held torque s.tau (called before compute_control: the previous sample's torque, the acceleration just before
//     this sample, as a sensor read before the new torque acts), m/s^2;
//   tip position: the tip deflection (compute_tip), m.
// ws is scratch of its own, not the integrators' (SDIRK2 leaves joint armature in theirs): its q1 and zdot
// receive qdd and the drive rates. Allocates nothing.
void compute_recorded_sensors(const BatchModel& bm, BatchState& s, Workspace& ws, double* out);

// The output channels: how a record's columns of signals the trace carries as truths were measured
// (sensors.hub_torque, .tip_deflection, .pressure_a, .pressure_b). Nothing in the loop reads them, so
// they are applied to a finished trace; their noise streams are channels 5, 6, 7, 8.
enum OutputChannel { kOutHubTorque = 0, kOutTipDeflection, kOutPressureA, kOutPressureB, kOutputChannels };
// The record column (and model path sensors.<name>) of a channel.
const char* output_channel_name(OutputChannel c);
const ChannelSpec& output_channel_spec(const SensorSpec& s, OutputChannel c);
// The channel whose column is `name`, or kOutputChannels when none is.
OutputChannel find_output_channel(const std::string& name);

// The measured sequence of a truth x sampled at every controller sample (the sensor rule above):
// y_k = Q(x_j + sigma n_j), j = n floor((k - d) / n) for k >= d, else j = 0 (d = delay, n = hold),
// n_j from the stream (seed, 5 + c) at sample j. noisy = false (a prediction) leaves out the noise and
// the quantisation.
std::vector<double> measure_output(const Model& m, OutputChannel c, const std::vector<double>& x, bool noisy);

}  // namespace ff
