// The hub drive: what turns the controller's torque demand into torque on the hub, and the
// friction there. Each part is optional (a YAML block, off by default) and, when on, owns states
// in BatchState::z (rows given by DriveLayout, lane innermost like q and v):
//   - hydraulic rotary actuator: servo-valve spool x_v (normalised) and rate, chamber pressures
//     p_a, p_b (stored in MPa so that every state is of order one);
//   - drive train: actuator shaft angle theta_a and rate (gear, backlash, compliance to the hub);
//   - LuGre friction at the hub: bristle deflection z (rad).
// Without any of them the hub torque is the demand plus the static friction map, as before.
#pragma once

#include <cstddef>
#include <string>
#include <utility>

#include "kernel/model.hpp"

namespace ff {

struct BatchModel;

inline constexpr double kPressureUnit = 1.0e6;  // Pa per stored pressure unit (MPa)

// Rows of BatchState::z of each part; -1 when the part is off.
struct DriveLayout {
  int spool = -1;     // x_v, then dx_v/dt (1/s)
  int pressure = -1;  // p_a, then p_b (MPa)
  int shaft = -1;     // theta_a (rad), then omega_a (rad/s)
  int bristle = -1;   // LuGre z (rad)
  int nz = 0;         // rows in all
};

DriveLayout make_drive_layout(const ModelSpec& spec);

// Per-lane constants of the drive, derived once from the model (SI units).
struct LaneDrive {
  bool lugre = false;
  // hydraulics
  double D = 0, V0 = 0, beta = 0, ps = 0, pt = 0, pr = 0, kv = 0, dp_lam = 0, leak = 0, kr = 0;
  double wv = 0, zv = 0, gain = 0;
  // drive train
  double ja = 0, n = 1, eta = 1, k = 0, k3 = 0, c = 0, b = 0;
  bool closing = false;  // c only while the twist grows, e de/dt > 0 (DriveSpec::closing_damping)
  // LuGre (b, Fc, Fs, vs shared with the static map in BatchModel)
  double sigma0 = 0, sigma1 = 0;
};

LaneDrive make_lane_drive(const Model& m);

// The hydraulic constants of a LaneDrive from the actuator's spec alone (SI units; drive-train
// fields at their neutral defaults): what make_lane_drive takes for the rig's hub and what a tree
// joint's actuator uses (multibody/lanes.hpp).
LaneDrive make_hydraulic_drive(const HydraulicSpec& h);

// Rows of one hydraulic actuator's states: spool x_v, its rate (1/s), p_a, p_b (MPa, kPressureUnit).
inline constexpr int kHydraulicStates = 4;

// One hydraulic actuator (the rig's equations, one copy: the rig's hub and every tree joint call it).
// x[k * stride], k = 0..3: x_v, dx_v/dt, p_a, p_b (MPa); `demand` the torque loop's command (N·m at
// the pinion), theta and omega the pinion's angle (rad; the rack centred at 0) and rate. Returns the
// actuator's torque D (p_a - p_b), N·m; writes the states' rates to xdot[k * stride] when xdot is set:
//   u = sat(K (demand - D dp) / (D p_s), -1, 1),  x_v'' = w_v^2 (u - x_v) - 2 z_v w_v x_v'
//   p_a' = beta / V_a (Q_a - Q_leak + Q_relief,a - D omega),  V_a = max(V0 + D theta, V0 / 20)
//   p_b' = beta / V_b (Q_b + Q_leak + Q_relief,b + D omega),  V_b = max(V0 - D theta, V0 / 20)
// with the four lands' orifice flows k_v x root(dp), the leakage a -> b and relief / anti-cavitation.
double eval_hydraulic_actuator(const LaneDrive& p, double demand, double theta, double omega, const double* x,
                               std::size_t stride, double* xdot);

// An implicit stage of one actuator with its pinion held at (theta, omega): solves
// X = xpre + gh f(X) (4 states, contiguous) by simplified Newton (Jacobian by forward differences at
// xpre, four iterations), as the rig solves its hub drive's stages (kernel/fixed_step.cpp).
void solve_hydraulic_stage(const LaneDrive& p, double demand, double theta, double omega, const double* xpre,
                           double gh, double* X);

// The Jacobian df/dx of one actuator's rates with the pinion held (4 x 4 row-major), by forward
// differences at x (contiguous), and the rates f0 there.
void calc_hydraulic_jacobian(const LaneDrive& p, double demand, double theta, double omega, const double* x,
                             double* f0, double* jac);

// Solves A x = b in place (b becomes x) for a small dense n x n A (row-major), Gaussian elimination
// with partial pivoting.
void solve_small_system(int n, double* A, double* b);

// The fastest rate (1/s) of one hydraulic actuator a fixed step must resolve (h rate <= 1): the spool,
// the torque loop, the relief valves and the oil spring sqrt(2 beta D^2 / (V0 J)) on the inertia J
// (kg·m^2) the pinion moves.
double calc_hydraulic_rate(const LaneDrive& p, double inertia);

// The hydraulic block's values checked (the rig's make_model and the arm reader): the first fault as
// {key within the block, message}, or two empty strings.
std::pair<std::string, std::string> explain_hydraulic_fault(const HydraulicSpec& h);

// The drive at rest with the hub at angle zero: spool centred, both chambers at the mean of
// supply and tank pressure, shaft aligned with the hub, bristles relaxed. Writes z (nz x W).
void init_drive_state(const BatchModel& bm, double* z);

// For every lane: the torque on the hub joint, friction included (W), and the drive's state
// rates zdot (nz x W), from the chain state (q, v), the drive state z and the held demand tau_cmd (W).
void compute_hub_drive(const BatchModel& bm, const double* q, const double* v, const double* z, const double* tau_cmd,
                       double* tau_hub, double* zdot);

// The torque the actuator puts on the hub now, as a measurement would see it (W): D (p_a - p_b)
// (times n, through the gear) or the drive train's transmitted torque; the demand without either.
void compute_actuator_torque(const BatchModel& bm, const double* q, const double* v, const double* z,
                             const double* tau_cmd, double* tau_act);

// Signed orifice root with a laminar core: dp / (dp^2 + dp_lam^2)^(1/4), Pa^(1/2). Odd, smooth,
// sqrt|dp| sign(dp) for |dp| >> dp_lam and linear through zero.
double calc_orifice_root(double dp, double dp_lam);

// The valve coefficient k_v of Q = k_v x root(dp) (x the normalised spool travel), m^3/(s Pa^1/2):
// C_d w x_max sqrt(2 / rho) when the physical form is given, else rated_flow / root(rated_drop).
// The one place k_v comes from (the lanes' flows, the modes' loop damping).
double calc_valve_coefficient(const HydraulicSpec& h);

// The flow through one land at full opening and the rated drop, m^3/s, which sizes the relief
// valves: rated_flow, or k_v root(rated_drop) in the physical form (where a file keeps rated_drop
// at its default, 3.5 MPa).
double calc_rated_flow(const HydraulicSpec& h);

// The actuator's displacement D, m^3/rad: piston_area x pinion_radius when given, else displacement.
// The one place D comes from (the lanes, the modes, the oil-spring frequency).
double calc_displacement(const HydraulicSpec& h);

// Transmitted torque of the drive train at output twist d (rad) and twist rate dd (rad/s), N·m.
double calc_transmission_torque(const LaneDrive& p, double d, double dd);

// Its tangent there: dT/dd (N·m/rad) and dT/d(dd) (N·m·s/rad); both 0 inside the free play and
// where the teeth would pull (the torque clipped at 0). What a linearly implicit stage takes.
struct TransmissionTangent {
  double stiffness = 0.0, damping = 0.0;
};
TransmissionTangent calc_transmission_tangent(const LaneDrive& p, double d, double dd);

// The factor on the transmitted torque the driving side feels with efficiency eta, given the power
// P (W) the drive passes to the load: s / eta + (1 - s) eta, s = (1 + tanh(P / 1 W)) / 2 (1 driving,
// 0 driven, 1/2 at rest; docs/formats.md, drive.efficiency).
double calc_efficiency_factor(double eta, double power);

// The fastest rate (1/s) of the drive's dynamics a fixed step must resolve (h rate <= 1): the
// spool, the torque loop, relief valves, the oil spring and drive train on the hub's own inertia,
// the static friction map's slope at rest, the LuGre bristles. Used to choose substeps; 0 without
// drive parts or friction.
double calc_drive_rate(const Model& m);

// The damping the hydraulic torque loop adds at the hub below its bandwidth: the flow D w the hub
// draws needs a spool opening D w / K_q, which the loop buys with a torque error D^2 p_s w / (K K_q);
// K_q = kv sqrt(p_s / 2) is the flow gain at half supply drop per land. N·m·s/rad.
double calc_hydraulic_damping(const HydraulicSpec& h);

// The hydraulic natural frequency sqrt(4 beta D^2 / (V_t J)) with V_t = 2 V0 and J the inertia
// on the pinion (kg·m^2), rad/s (Merritt, Hydraulic Control Systems, 1967, eq. 5-82).
double calc_hydraulic_frequency(const HydraulicSpec& h, double inertia);

}  // namespace ff
