#include "kernel/sensors.hpp"

#include <cmath>

#include "kernel/dynamics.hpp"
#include "kernel/random.hpp"

namespace ff {

void compute_measurements(const BatchModel& bm, BatchState& s, double* hub_angle, double* hub_rate) {
  const int W = bm.W, H = bm.sensor_history;
  const long k = s.sample;
  const double* truth[2] = {s.q.data(), s.v.data()};  // row 0: the hub
  double* out[2] = {hub_angle, hub_rate};
  for (int c = 0; c < 2; ++c) {
    double* ring = s.measured[c].data();
    for (int l = 0; l < W; ++l) {
      // y = Q(x + sigma n), n ~ N(0, 1) from the counter-based stream (seed, channel) at sample k.
      double y = truth[c][l];
      if (bm.sensor_noise[c][l] > 0.0) y += bm.sensor_noise[c][l] * CounterRng(bm.sensor_key[c][l], k).normal();
      const double q = bm.sensor_resolution[c][l];
      if (q > 0.0) y = q * std::nearbyint(y / q);
      ring[(k % H) * W + l] = y;
      const int d = bm.sensor_delay[c][l];
      out[c][l] = ring[(k >= d ? (k - d) % H : 0) * W + l];
    }
  }
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
      compute_acceleration(bm, q, s.v.data(), s.z.data(), s.tau.data(), qdd, zdot, ws);
      compute_tip_acceleration(bm, q, s.v.data(), qdd, truth);
    } else {
      compute_tip(bm, q, truth, angle, ws);
    }
    double* ring = s.recorded[c].data();
    for (int l = 0; l < W; ++l) {
      // y = Q(x + sigma n), n ~ N(0, 1) from the counter-based stream (seed, 2 + c) at sample k.
      double y = truth[l];
      if (bm.rec_noise[c][l] > 0.0) y += bm.rec_noise[c][l] * CounterRng(bm.rec_key[c][l], k).normal();
      const double res = bm.rec_resolution[c][l];
      if (res > 0.0) y = res * std::nearbyint(y / res);
      ring[(k % H) * W + l] = y;
      // Delay d, then hold: the reading of the last sensor sample j = n floor((k - d) / n) <= k - d.
      const long d = bm.rec_delay[c][l], n = bm.rec_hold[c][l];
      const long j = k >= d ? (k - d) / n * n : 0;
      y_out[l] = ring[(j % H) * W + l];
    }
  }
  if (bm.rec_enabled[kStrainGauge])
    for (int l = 0; l < W; ++l) out[kStrainTipEstimate * W + l] = bm.strain_gain[l] * out[kStrainMoment * W + l];
}

}  // namespace ff
