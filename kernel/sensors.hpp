// The controller's sensors: each measured channel (hub angle, hub rate) is the true value plus
// Gaussian noise, quantised, and delayed by whole controller samples. Noise is a pure function of
// (the model's seed, channel, sample): runs repeat bit for bit on any machine.
#pragma once

#include "kernel/batch.hpp"

namespace ff {

// Takes this sample's measurement of every lane (s.sample, s.q, s.v), stores it in the ring
// s.measured, and writes what the controller sees now (W each): the measurement `delay` samples
// old, or the first one while the run is younger than the delay.
void compute_measurements(const BatchModel& bm, BatchState& s, double* hub_angle, double* hub_rate);

}  // namespace ff
