#include "kernel/controller.hpp"

#include <algorithm>

#include "kernel/notch.hpp"
#include "kernel/sensors.hpp"

namespace ff {

void reset_controller(const BatchModel& bm, BatchState& s, const double* r0) {
  // A feedback-path notch rests at the hub angle measured at this sample (the measurement is a pure
  // function of the sample and the state, so compute_control sees the same value again).
  double angle[kMaxLanes] = {}, rate[kMaxLanes];
  bool feedback = false;
  for (int l = 0; l < bm.W; ++l) feedback |= bm.nsections > 0 && bm.notch_feedback[l];
  if (feedback) compute_measurements(bm, s, angle, rate);
  for (int l = 0; l < bm.W; ++l) {
    s.integral[l] = 0.0;
    if (bm.nsections > 0)
      reset_notch_state(bm.nsections, bm.W, l, bm.notch_coef.data(), bm.notch_feedback[l] ? angle[l] : r0[l],
                        s.notch_state.data());
  }
}

void compute_control(const BatchModel& bm, BatchState& s, const double* ref, const double* ref_ff,
                     double* ref_filtered) {
  const int W = bm.W;
  // What the controller sees of the hub angle and rate (kernel/sensors.hpp).
  double sensed_angle[kMaxLanes], sensed_rate[kMaxLanes];
  compute_measurements(bm, s, sensed_angle, sensed_rate);
  // Robust notch filter (seed eq. 6) on the reference, or on the measured hub angle (placement feedback).
  if (bm.nsections > 0) {
    double in[kMaxLanes], out[kMaxLanes];
    for (int l = 0; l < W; ++l) in[l] = bm.notch_feedback[l] ? sensed_angle[l] : ref[l];
    step_notch(bm.nsections, W, bm.notch_coef.data(), s.notch_state.data(), in, out);
    for (int l = 0; l < W; ++l) {
      ref_filtered[l] = bm.notch_feedback[l] ? ref[l] : out[l];
      sensed_angle[l] = bm.notch_feedback[l] ? out[l] : sensed_angle[l];  // e = r - F(theta_m)
    }
  } else {
    std::copy(ref, ref + W, ref_filtered);
  }

  const double T = bm.control_period;
  // Joint 1, the root of the beam: its moment on the hub. A rigid arm (N = 1) has none: its lanes read
  // zeros instead of one lane block past the joint arrays' end.
  static const double kNone[kMaxLanes] = {};
  const bool beam = bm.nseg > 1;
  const double* q1s = beam ? s.q.data() + W : kNone;
  const double* v1s = beam ? s.v.data() + W : kNone;
  const double* k1 = beam ? bm.joint_k.data() + W : kNone;
  const double* c1 = beam ? bm.joint_c.data() + W : kNone;
  const double* k31 = beam ? bm.joint_k3.data() + W : kNone;
  // The hydraulic load signal n D (p_a - p_b), N·m (seed: "hydraulic pressure instead of torque").
  double pressure_torque[kMaxLanes] = {};
  if (bm.layout.pressure >= 0)
    for (int l = 0; l < W; ++l) {
      const LaneDrive& d = bm.drive[l];
      const double dp = (s.z[bm.layout.pressure * W + l] - s.z[(bm.layout.pressure + 1) * W + l]) * kPressureUnit;
      pressure_torque[l] = d.n * d.D * dp;
    }
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    const double e = ref_filtered[l] - sensed_angle[l];
    const double q1 = q1s[l];
    const double root_moment = (k1[l] + k31[l] * q1 * q1) * q1 + c1[l] * v1s[l];  // beam on the hub, N·m
    const double load = bm.load_pressure[l] ? pressure_torque[l] : root_moment;
    const double raw = bm.kp[l] * e + bm.ki[l] * s.integral[l] - bm.kd[l] * sensed_rate[l] - bm.load_comp[l] * load +
                       bm.ff_gain[l] * ref_ff[l];
    const double lim = bm.torque_limit[l];
    const double tau = std::clamp(raw, -lim, lim);
    const bool winding = (raw != tau) && (e * raw > 0.0);
    s.integral[l] += winding ? 0.0 : e * T;
    s.tau[l] = tau;
  }
}

}  // namespace ff
