#include "kernel/simulate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "kernel/controller.hpp"
#include "kernel/cvode.hpp"
#include "kernel/drive.hpp"
#include "kernel/dynamics.hpp"
#include "common/files.hpp"
#include "kernel/fixed_step.hpp"
#include "kernel/sensors.hpp"
#include "kernel/trajectory.hpp"

namespace ff {

namespace {

// Lanes whose state stopped being finite are marked; they keep running harmlessly in lock-step.
void mark_nonfinite(const BatchModel& bm, BatchState& s) {
  for (int l = 0; l < bm.W; ++l) {
    if (s.status[l] != LaneStatus::kOk) continue;
    for (int i = 0; i < bm.nseg; ++i)
      if (!std::isfinite(s.q[i * bm.W + l]) || !std::isfinite(s.v[i * bm.W + l])) {
        s.status[l] = LaneStatus::kNonfinite;
        break;
      }
  }
}

// The extra channels a batch's traces carry, in order.
std::vector<std::string> extra_channels(const BatchModel& bm) {
  std::vector<std::string> names;
  if (bm.layout.pressure >= 0 || bm.layout.shaft >= 0) names.push_back("torque_demand");
  if (bm.layout.pressure >= 0) {
    names.push_back("pressure_a");
    names.push_back("pressure_b");
  }
  // Recorded sensors (kernel/sensors.hpp): the strain gauge gives two columns.
  if (bm.rec_enabled[kStrainGauge]) {
    names.push_back(recorded_column_name(kStrainMoment));
    names.push_back(recorded_column_name(kStrainTipEstimate));
  }
  if (bm.rec_enabled[kTipAccelerometer]) names.push_back(recorded_column_name(kTipAccel));
  if (bm.rec_enabled[kTipPositionSensor]) names.push_back(recorded_column_name(kTipPosition));
  return names;
}

// The tip deflection (m) and angle (rad) and the actuator's hub torque (N·m, returned: ws.tau_hub) of
// every lane at this sample.
const double* compute_tip_and_torque(const BatchModel& bm, const BatchState& s, double* defl, double* tip_angle,
                                     Workspace& ws) {
  compute_tip(bm, s.q.data(), defl, tip_angle, ws);
  double* torque = ws.tau_hub.data();
  compute_actuator_torque(bm, s.q.data(), s.v.data(), s.z.data(), s.tau.data(), torque);
  return torque;
}

// rec (kRecordedColumns x W): the recorded sensors' output at this sample.
void record(const BatchModel& bm, const BatchState& s, const double* ref, const double* ref_f, double* defl,
            double* tip_angle, const double* rec, Workspace& ws, std::vector<Trace>& out) {
  const double* torque = compute_tip_and_torque(bm, s, defl, tip_angle, ws);
  const int W = bm.W, pr = bm.layout.pressure;
  for (int l = 0; l < W; ++l) {
    Trace& tr = out[l];
    tr.t.push_back(s.t);
    tr.ref.push_back(ref[l]);
    tr.ref_filtered.push_back(ref_f[l]);
    tr.torque.push_back(torque[l]);
    std::size_t c = 0;
    if (pr >= 0 || bm.layout.shaft >= 0) tr.extra[c++].second.push_back(s.tau[l]);
    if (pr >= 0) {
      tr.extra[c++].second.push_back(s.z[pr * W + l] * kPressureUnit);
      tr.extra[c++].second.push_back(s.z[(pr + 1) * W + l] * kPressureUnit);
    }
    for (int col = 0; col < kRecordedColumns; ++col)
      if (bm.rec_enabled[recorded_channel(RecordedColumn(col))]) tr.extra[c++].second.push_back(rec[col * W + l]);
    tr.hub_angle.push_back(s.q[l]);
    tr.hub_rate.push_back(s.v[l]);
    tr.tip_deflection.push_back(defl[l]);
    tr.tip_angle.push_back(tip_angle[l]);
  }
}

// The same signals into each lane's online metrics instead of a trace.
void accumulate(const BatchModel& bm, const BatchState& s, double* defl, double* tip_angle, Workspace& ws,
                std::vector<OnlineRun>& out) {
  const double* torque = compute_tip_and_torque(bm, s, defl, tip_angle, ws);
  for (int l = 0; l < bm.W; ++l) out[l].add(s.t, tip_angle[l], s.q[l], defl[l], torque[l]);
}

}  // namespace

namespace {
// Payload events (pick, release) due at controller sample k = s.sample set their lane's tip load
// s.tip: those at or before t_k (1e-12 s of slack) and not already due at t_(k-1), in order. Which
// events are done follows from the sample alone, so the state needs no event counter.
void apply_payload_events(const BatchModel& bm, BatchState& s) {
  const double T = bm.control_period;
  const double t = s.sample * T + 1e-12, t_prev = (s.sample - 1) * T + 1e-12;
  for (int l = 0; l < bm.W; ++l) {
    const Model& m = bm.models[l];
    for (const PayloadEvent& e : m.spec.payload_events) {
      if (e.time > t) break;  // in time order (make_model)
      if (s.sample > 0 && e.time <= t_prev) continue;
      const BodyInertia b = make_tip_body(m, e.mass, e.inertia);
      s.tip.mass[l] = b.mass;
      s.tip.first[l] = b.first;
      s.tip.inertia[l] = b.inertia;
    }
  }
}
}  // namespace

namespace {
double at_sample(const std::vector<double>& x, long k) { return x[std::min<std::size_t>(k, x.size() - 1)]; }

// A record's signals at sample k: the reference and the feed-forward from its rate and acceleration (as
// the trajectory's, with the controller's model's inertia), then the caller's hook on the state.
void apply_inputs(const BatchModel& bm, const SampleInputs& in, long k, BatchState& s, double* ref, double* ref_ff) {
  const bool ff = !in.ref_rate.empty() && !in.ref_accel.empty();
  if (!in.ref.empty())
    for (int l = 0; l < bm.W; ++l) {
      ref[l] = at_sample(in.ref, k);
      ref_ff[l] = ff && bm.ff_gain[l] != 0.0
                      ? bm.models[l].control_inertia * at_sample(in.ref_accel, k) + bm.kd[l] * at_sample(in.ref_rate, k)
                      : 0.0;
    }
  if (in.at_sample) in.at_sample(s);
}
}  // namespace

BatchRun simulate(const BatchModel& bm, const std::function<void(const BatchState&)>& observe,
                  const SampleInputs* inputs, std::vector<OnlineRun>* metrics) {
  if (metrics && metrics->size() != static_cast<std::size_t>(bm.W))
    throw std::invalid_argument("simulate: one OnlineRun per lane expected");
  // The model stays as it is; payload events change the state's tip load (BatchState::tip).
  bool events = false;
  for (const auto& m : bm.models) events |= !m.spec.payload_events.empty();
  const int W = bm.W;
  const double T = bm.control_period;
  const long nsamples = std::lround(bm.duration / T) + 1;
  const Integrator kind = bm.models[0].spec.simulation.integrator;

  BatchState s = make_state(bm);
  Workspace ws = make_workspace(bm);
  std::unique_ptr<CvodeBatch> cvode;
  if (kind == Integrator::kCvodeDense || kind == Integrator::kCvodeKlu) cvode = std::make_unique<CvodeBatch>(bm, kind);

  BatchRun run;
  if (!metrics) run.traces.resize(W);
  const auto extra = extra_channels(bm);
  for (auto& tr : run.traces) {
    for (auto* x : {&tr.t, &tr.ref, &tr.ref_filtered, &tr.torque, &tr.hub_angle, &tr.hub_rate, &tr.tip_deflection,
                    &tr.tip_angle})
      x->reserve(nsamples);
    for (const auto& name : extra) {
      tr.extra.emplace_back(name, std::vector<double>());
      tr.extra.back().second.reserve(nsamples);
    }
  }

  std::vector<double> ref(W), ref_ff(W), ref_f(W), defl(W), tip_angle(W), rec(kRecordedColumns * W);
  const bool recording = std::any_of(bm.rec_enabled, bm.rec_enabled + kRecordedChannels, [](bool b) { return b; });
  Workspace sensor_ws = recording ? make_workspace(bm) : Workspace{};  // the recorded sensors' own scratch
  const double h = T / bm.substeps;
  for (long k = 0; k < nsamples; ++k) {
    s.t = k * T;
    s.sample = k;
    if (events) apply_payload_events(bm, s);
    // Controller sample: reference, filter, PID; then record the signals of this instant.
    for (int l = 0; l < W; ++l) {
      ref[l] = calc_shaped_reference(bm.models[l].spec.trajectory, bm.models[l].shaper, s.t);
      // Feed-forward torque per unit gain: J_rigid r'' + kd r' (what the PD takes away from exact tracking),
      // J_rigid the controller's model's (Model::control_inertia: the nominal model's).
      const auto& mdl = bm.models[l];
      ref_ff[l] = bm.ff_gain[l] != 0.0
                      ? mdl.control_inertia * calc_shaped_reference_accel(mdl.spec.trajectory, mdl.shaper, s.t) +
                            bm.kd[l] * calc_shaped_reference_rate(mdl.spec.trajectory, mdl.shaper, s.t)
                      : 0.0;
    }
    if (inputs) apply_inputs(bm, *inputs, k, s, ref.data(), ref_ff.data());
    // The recorded sensors read the plant before this sample's torque is applied.
    if (recording) compute_recorded_sensors(bm, s, sensor_ws, rec.data());
    if (k == 0) reset_controller(bm, s, ref.data());
    compute_control(bm, s, ref.data(), ref_ff.data(), ref_f.data());
    if (inputs && !inputs->torque.empty()) std::fill(s.tau.begin(), s.tau.end(), at_sample(inputs->torque, k));
    if (metrics) accumulate(bm, s, defl.data(), tip_angle.data(), ws, *metrics);
    else record(bm, s, ref.data(), ref_f.data(), defl.data(), tip_angle.data(), rec.data(), ws, run.traces);
    if (observe) observe(s);
    if (k + 1 == nsamples) break;
    // Plant: integrate to the next sample with the torque held.
    if (cvode) {
      cvode->advance(s, T);
    } else if (kind == Integrator::kSdirk2) {
      for (int j = 0; j < bm.substeps; ++j) step_sdirk2(bm, s, ws, h);
    } else if (kind == Integrator::kMidpoint) {
      for (int j = 0; j < bm.substeps; ++j) step_midpoint(bm, s, ws, h);
    } else {
      for (int j = 0; j < bm.substeps; ++j) step_rk4(bm, s, ws, h);
    }
    mark_nonfinite(bm, s);
  }
  run.status = s.status;
  return run;
}

void write_trace_csv(const Trace& tr, const std::string& path) {
  std::string text = "t,ref,ref_filtered,hub_torque,hub_angle,hub_rate,tip_deflection,tip_angle";
  for (const auto& [name, values] : tr.extra) text += "," + name;
  text += "\n";
  char buf[512];
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    std::snprintf(buf, sizeof buf, "%.6f,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g", tr.t[k], tr.ref[k],
                  tr.ref_filtered[k], tr.torque[k], tr.hub_angle[k], tr.hub_rate[k], tr.tip_deflection[k],
                  tr.tip_angle[k]);
    text += buf;
    for (const auto& [name, values] : tr.extra) {
      std::snprintf(buf, sizeof buf, ",%.10g", values[k]);
      text += buf;
    }
    text += "\n";
  }
  write_file_atomic(path, text);
}

Trace read_trace_csv(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error(path + ": cannot open");
  Trace tr;
  char line[1024];
  int line_no = 0;
  while (std::fgets(line, sizeof line, f)) {
    if (++line_no == 1) continue;  // header
    double x[8];
    if (std::sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &x[0], &x[1], &x[2], &x[3], &x[4], &x[5], &x[6], &x[7]) != 8) {
      std::fclose(f);
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": expected 8 numbers");
    }
    std::vector<double>* cols[8] = {&tr.t, &tr.ref, &tr.ref_filtered, &tr.torque, &tr.hub_angle, &tr.hub_rate,
                                    &tr.tip_deflection, &tr.tip_angle};
    for (int c = 0; c < 8; ++c) cols[c]->push_back(x[c]);
  }
  std::fclose(f);
  return tr;
}

}  // namespace ff
