// The digital controller, sampled with zero-order hold: reference -> robust notch (seed eq. 6; or on
// the measured hub angle) -> PID on the hub angle with derivative on the measured rate,
// load-compensation feed-forward, torque limit with anti-windup.
#pragma once

#include "kernel/batch.hpp"

namespace ff {

// Puts every lane's notch filter at rest at input r0 (before the first sample), or, with the notch on the
// feedback path, at the hub angle measured at sample s.sample.
void reset_controller(const BatchModel& bm, BatchState& s, const double* r0);

// One controller sample for all lanes at s.t. ref (W): commanded hub angle; ref_ff (W): the
// model-based feed-forward torque at unit gain, J_rigid r'' + kd r' (N·m): the rigid arm's inverse
// dynamics plus what the derivative on the measured rate takes away when the arm tracks exactly.
// Writes ref_filtered (W) and the held torque s.tau (W):
//   e = F(r) - theta_h (notch on the reference) or e = r - F(theta_h) (on the feedback path; ref_filtered = r),
//   theta_h and omega_h as measured (kernel/sensors.hpp), omega_h never filtered,
//   tau = sat(kp e + ki integral - kd omega_h - g (k_1 q_1 + k3_1 q_1^3 + c_1 qd_1) + f ref_ff).
// The integral is advanced by forward Euler and frozen while the torque saturates in the
// direction of the error (clamping anti-windup).
void compute_control(const BatchModel& bm, BatchState& s, const double* ref, const double* ref_ff,
                     double* ref_filtered);

}  // namespace ff
