// Replaying a measurement record on models: what each model predicts for the record's channels.
// Closed loop: the record's reference drives the model's own controller. Open loop: the record's
// hub torque drives the plant. Inverse dynamics: the hub torque the model needs to move as measured.
// Candidate models run together as lanes of one batch (they must share a shape).
#pragma once

#include <map>
#include <span>
#include <string>
#include <vector>

#include "kernel/model.hpp"
#include "validate/record.hpp"

namespace ff {

enum class ReplayMode { kClosedLoop, kOpenLoop, kInverseDynamics };
const char* replay_mode_name(ReplayMode m);
ReplayMode parse_replay_mode(const std::string& name);  // throws std::invalid_argument

// The record columns a mode needs besides t.
std::vector<std::string> replay_inputs(ReplayMode mode);

// A model's predictions at the record's sample times, by channel name (hub_angle, tip_deflection,
// hub_rate, hub_torque; inverse dynamics: hub_torque only). `ok` is false when the lane failed.
struct Prediction {
  bool ok = true;
  std::map<std::string, std::vector<double>> channels;
};

// The channels a mode predicts that the record also measured: what compare and diagnose score.
std::vector<std::string> scored_channels(ReplayMode mode, const Record& r);

struct ObserverOptions;  // validate/observer.hpp

// Replays the record on each model (one lane each). k_ahead > 0 (closed and open loop): the k-step
// prediction from the observer's estimate (validate/observer.hpp, run_observer): every k_ahead
// controller samples each model restarts from its observer's state estimate from the measurements
// before that sample (all plant states), so each predicted sample is 1 to k_ahead samples ahead.
// Inverse dynamics follows the measured hub in any case: k_ahead is ignored.
std::vector<Prediction> replay(std::span<const Model> models, const Record& r, ReplayMode mode, int k_ahead = 0);
std::vector<Prediction> replay(std::span<const Model> models, const Record& r, ReplayMode mode, int k_ahead,
                               const ObserverOptions& observer);

// Fit % = 100 (1 - |y - yhat| / |y - mean(y)|) (normalised RMSE, as MATLAB's compare) and RMSE.
struct Fit {
  double percent = 0.0;
  double rmse = 0.0;
};
Fit calc_fit(const std::vector<double>& measured, const std::vector<double>& predicted);

// What drives a model on a record at n controller samples of period T (t = t0 + k T): closed loop, its
// reference, with the reference's rate and acceleration (central differences on the record's own times,
// then interpolated) for the controller's feed-forward, as a trajectory's would drive it; open loop, its
// hub torque.
struct SampleInputs;
SampleInputs make_record_inputs(const Record& r, bool closed_loop, double T, long n);

// A model with its simulated span and rate set for the record: duration = the record's length.
Model make_replay_model(const Model& m, const Record& r);

}  // namespace ff
