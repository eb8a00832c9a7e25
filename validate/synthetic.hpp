// Measurement records made by the project itself: a truth model run in closed loop, its signals
// sampled, Gaussian noise added to every measured channel. With an effect hidden in the truth model,
// such records test whether diagnose finds it.
#pragma once

#include <cstdint>

#include "kernel/model.hpp"
#include "validate/record.hpp"

namespace ff {

// Columns t, ref, hub_torque, hub_angle, hub_rate, tip_deflection (and pressure_a, pressure_b with
// hydraulics; the output channels as their sensors measure them, kernel/sensors.hpp measure_output; the
// hub angle and rate as logged, log_loop_channel: by default what the controller read)
// at every `decimate`-th controller
// sample; each measured channel (all but t and ref) gets noise of standard deviation
// noise x (its standard deviation over the run), from the counter-based stream of (seed, channel).
Record make_synthetic_record(const Model& truth, double noise, std::uint64_t seed, int decimate = 1);

}  // namespace ff
