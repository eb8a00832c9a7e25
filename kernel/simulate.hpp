// One closed-loop run of a batch: the controller at its sample rate, the plant integrated
// between samples with the torque held (fixed-step RK4 or CVODE).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "kernel/batch.hpp"
#include "kernel/online_metrics.hpp"

namespace ff {

// One lane's signals at every controller sample, taken at the sample instant before that
// sample's torque is applied (as in the reference traces).
struct Trace {
  std::vector<double> t;               // s
  std::vector<double> ref;             // commanded hub angle r, rad
  std::vector<double> ref_filtered;    // r after the notch filter, rad
  std::vector<double> torque;          // the actuator's torque on the hub (the demand, with an ideal actuator), N·m
  std::vector<double> hub_angle;       // rad
  std::vector<double> hub_rate;        // rad/s
  std::vector<double> tip_deflection;  // m
  std::vector<double> tip_angle;       // rad
  // Further channels the model has, by name (SI units): torque_demand, pressure_a, pressure_b (Pa) ...
  std::vector<std::pair<std::string, std::vector<double>>> extra;
};

struct BatchRun {
  std::vector<Trace> traces;           // (W); empty when simulate fed online metrics instead
  std::vector<LaneStatus> status;      // (W)
};

// Signals from outside that replace the model's own, one value per controller sample k (the last
// value holds beyond the end), the same for every lane: replaying a measurement record.
struct SampleInputs {
  std::vector<double> ref;        // the reference r_k (rad) instead of the trajectory
  // Its rate and acceleration (rad/s, rad/s^2) at the samples, for the controller's feed-forward
  // f (J_rigid r'' + kd r'); empty: no feed-forward.
  std::vector<double> ref_rate, ref_accel;
  std::vector<double> torque;     // the hub torque demand (N·m) instead of the controller's: open loop
  // Called at every controller sample with the state at that instant (s.t, s.sample set), after the
  // reference is taken and before the sensors read the plant and the controller acts: it may change
  // any lane's state (validate/observer.cpp corrects an observer's lanes by its measurements and
  // restarts k-step predictions from them). It runs inside the step loop: it must be deterministic
  // and should allocate nothing.
  std::function<void(BatchState&)> at_sample;
};

// Runs every lane of the batch to bm.duration with the integrator the models ask for.
// `observe`, when given, sees the state at every controller sample (after the controller acted).
// `metrics`, when given (one per lane, from make_online_run), takes each lane's tip angle, hub angle,
// tip deflection and hub torque at every sample instead of a trace: no per-sample storage, and
// BatchRun::traces stays empty.
BatchRun simulate(const BatchModel& bm, const std::function<void(const BatchState&)>& observe = nullptr,
                  const SampleInputs* inputs = nullptr, std::vector<OnlineRun>* metrics = nullptr);

// Writes one trace as CSV (columns t, ref, ref_filtered, hub_torque, hub_angle, hub_rate,
// tip_deflection, tip_angle, then the extra channels), atomically.
void write_trace_csv(const Trace& tr, const std::string& path);
// Reads a trace written by write_trace_csv. Throws std::runtime_error naming the path and line.
Trace read_trace_csv(const std::string& path);

}  // namespace ff
