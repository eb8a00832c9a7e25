// Exact nonlinear dynamics of the planar chain: hub + N rigid segments on torsional springs,
// horizontal plane (no gravity). Free functions over all lanes of a batch.
#pragma once

#include "kernel/batch.hpp"

namespace ff {

// Joint torques tau (N x W): tau_0 = the hub drive's torque (friction included, W),
// tau_i = -k_i q_i - k3_i q_i^3 - c_i v_i (i >= 1).
void compute_joint_torques(const BatchModel& bm, const double* q, const double* v, const double* tau_hub,
                           double* tau);

// Hub friction torque at hub angle q and rate w of lane l (FrictionSpec), N·m; never adds energy: tau_f w <= 0.
double calc_hub_friction(const BatchModel& bm, int lane, double q, double w);

// The friction map's damping at hub rate w, -d calc_hub_friction / dw, N·m·s/rad, not below 0 (the
// Stribeck drop's negative slope is left out): b + g'(w) tanh(w/eps) + g(w) sech^2(w/eps) / eps.
double calc_hub_friction_damping(const BatchModel& bm, int lane, double q, double w);

// Forward dynamics qdd = M(q)^-1 (tau - C(q, v) v) by the articulated-body algorithm
// (Featherstone, Rigid Body Dynamics Algorithms, 2008, Table 7.1, planar form), O(N) per lane.
// The bodies' inertial parameters are `body` (make_body_table: the model's, with a run's tip load);
// the model gives the rest (segment lengths). q, v, tau (joint torques), armature (extra joint-space
// inertia on M's diagonal) and qdd are (N x W); ws is scratch.
void compute_forward_dynamics(const BatchModel& bm, const BodyTable& body, const double* q, const double* v,
                              const double* tau, const double* armature, double* qdd, Workspace& ws);
// The same on the model's bodies as made (its own tip body, before any payload event).
void compute_forward_dynamics(const BatchModel& bm, const double* q, const double* v, const double* tau,
                              const double* armature, double* qdd, Workspace& ws);

// Everything at once: the hub drive (torque on the hub and its state rates zdot, nz x W) from the
// held demand tau_cmd (W), the joint torques, then qdd on the bodies `body`. zdot may be null when
// there are no drive states.
void compute_acceleration(const BatchModel& bm, const BodyTable& body, const double* q, const double* v,
                          const double* z, const double* tau_cmd, double* qdd, double* zdot, Workspace& ws);
// The same on the model's bodies as made.
void compute_acceleration(const BatchModel& bm, const double* q, const double* v, const double* z,
                          const double* tau_cmd, double* qdd, double* zdot, Workspace& ws);

// Tip deflection (m) and tip angle (rad) of one lane (reference-rig.md, "Signals").
struct TipKinematics {
  double deflection;  // sum L_i sin(theta_i - theta_h), m
  double along;       // sum L_i cos(theta_i - theta_h), m
  double angle;       // theta_h + atan2(deflection, along), rad
};
TipKinematics calc_tip(const BatchModel& bm, const double* q, int lane);
// Tip deflection (m) and tip angle (rad) of every lane at once (W each); uses ws.a0..a2, cq, sq as scratch.
void compute_tip(const BatchModel& bm, const double* q, double* deflection, double* angle, Workspace& ws);
// Lateral tip acceleration in the frame turning with the hub: the second time derivative of the tip
// deflection y = sum L_i sin phi_i, phi_i = q_1 + ... + q_i (relative to that frame: no centripetal,
// Coriolis or hub-angular terms), from the rates v and accelerations qdd (N x W each), m/s^2 (W):
//   y'' = sum L_i (cos phi_i phi_i'' - sin phi_i phi_i'^2).
void compute_tip_acceleration(const BatchModel& bm, const double* q, const double* v, const double* qdd,
                              double* accel);

// Kinetic energy 1/2 v^T M(q) v (of the bodies `body`, or the model's as made) and spring energy
// sum (k_i q_i^2 / 2 + k3_i q_i^4 / 4) of one lane, J.
double calc_kinetic_energy(const BatchModel& bm, const BodyTable& body, const double* q, const double* v, int lane);
double calc_kinetic_energy(const BatchModel& bm, const double* q, const double* v, int lane);
double calc_spring_energy(const BatchModel& bm, const double* q, int lane);

}  // namespace ff
