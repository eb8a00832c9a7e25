#include "kernel/sensors.hpp"

#include <cmath>

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

}  // namespace ff
