// The immutable model of one flexible arm: a hub and a beam of N rigid segments joined by
// torsional springs, its controller and its commanded motion (reference-rig.md).
// Built and validated once by make_model(); never written afterwards.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kernel/shaper.hpp"

namespace ff {

// Beam geometry and material (reference-rig.md, "Beam").
struct BeamSpec {
  double length = 4.1656;         // L, m
  double height = 0.3048;         // h (vertical), m
  double thickness = 0.01905;     // t (bends in the horizontal plane), m
  double density = 7750.0;        // rho, kg/m^3
  double youngs_modulus = 207e9;  // E, Pa
};

// Torsional spring-dampers between segments; k and c scale as reference_cell / l.
struct JointSpec {
  double stiffness = 39.5e3;      // k at the reference cell length, N·m/rad
  double damping = 90.4;          // c at the reference cell length, N·m·s/rad
  double reference_cell = 0.83312;  // cell length the two values above belong to, m
  double cubic_stiffness = 0.0;   // k3 of the hardening term k3 q^3 at the reference cell, N·m/rad^3; 0 = linear
};

// PID on the hub angle, sampled with zero-order hold (reference-rig.md, "Controller").
struct ControllerSpec {
  double rate = 1000.0;           // sample rate, Hz
  double kp = 1.0e5;              // N·m/rad
  double ki = 0.0;                // N·m/(rad·s)
  double kd = 3.0e4;              // N·m·s/rad, acts on the measured hub rate
  double torque_limit = 0.0;      // |tau| bound, N·m; 0 = unlimited
  double load_compensation = 0.0; // gain on the root bending moment fed forward (seed, "load compensation"): the model's
                                  // true k1 q1 + k3_1 q1^3 + c1 q1', not a sensor reading (or the pressure signal)
  double feedforward = 0.0;       // gain f on the model-based feed-forward f (J_rigid r'' + kd r') (1 = full)
  std::string load_signal = "moment";  // load compensation from the root bending "moment" or the hydraulic "pressure" (n D dp)
  // The controller's internal model (feed-forward inertia, notch zeros, shaper design): "nominal", the model
  // file with its --set overrides, which a study's variables and runs, diagnose's candidates and calibrate's
  // fits do not change (sweep/paths.hpp, Assignment::plant_only); or "plant", the varied model itself.
  std::string model = "nominal";
};

// Robust notch filter of seed eq. 6 acting on the reference, or on the measured hub angle.
struct NotchSpec {
  bool enabled = false;
  // "reference": F acts on r, e = F(r) - theta_m. "feedback": F acts on the measured hub angle, e = r - F(theta_m);
  // the derivative path keeps the measured rate unfiltered.
  std::string placement = "reference";
  int order = 1;                  // n
  double alpha[2] = {1.6, 1.6};   // omega_pi = alpha_i * omega_zi
  double zeta[2] = {1.0, 1.0};    // zeta_pi
  double omega_z[2] = {0.0, 0.0}; // rad/s; 0 = place at the computed closed-loop resonances
};

// One measured channel: sampled and held at `rate`, quantised to `resolution`, with Gaussian noise
// and a delay in controller samples (kernel/sensors.hpp).
struct ChannelSpec {
  double resolution = 0.0;        // quantum, in the channel's unit; 0 = none
  double noise = 0.0;             // standard deviation, in the channel's unit; 0 = none
  int delay = 0;                  // controller samples
  double rate = 0.0;              // sample rate, Hz; must divide controller.rate; 0 = controller.rate
};

// A channel the controller reads (sensors.hub_angle, .hub_rate; an arm joint's sensors.angle, .rate) and what a
// record's column of it holds (docs/formats.md, "Logged columns"): "read", what the controller read (late,
// held, quantised and noisy as the loop saw it: what real loggers record, the default), or "true", an
// on-time measurement of the true signal (its noise only), kernel/sensors.hpp log_loop_channel.
struct LoopChannelSpec : ChannelSpec {
  std::string logged = "read";    // read, true
  int logged_delay = 0;           // the logged column's own latency (a logger that stamps late), controller samples
};
// Whether `name` is a value of `logged` (read, true); a logged: true channel's column is on time.
inline bool is_logged_name(const std::string& name) { return name == "read" || name == "true"; }
inline bool is_logged_on_time(const LoopChannelSpec& ch) { return ch.logged == "true"; }

// A recorded channel (off by default): written to the trace at every controller sample, not fed back.
struct RecordedChannelSpec : ChannelSpec {
  bool enabled = false;
};

// Strain gauge at a beam joint: the elastic bending moment k_i q_i + k3_i q_i^3 (N·m) and the tip
// deflection a static cantilever with a tip load would have under it (calc_strain_tip_gain), m.
struct StrainGaugeSpec : RecordedChannelSpec {
  int joint = 1;                  // beam joint 1..N-1 (1 = the root)
};

// What the controller measures (reference-rig.md: the PD uses the hub angle and the hub rate),
// the recorded sensors, and the output channels: how a record's columns of signals the trace has as
// truths (hub_torque, tip_deflection, pressure_a, pressure_b) were measured (kernel/sensors.hpp,
// measure_output). Their delay shifts the recorded signal only; no controller reads them.
struct SensorSpec {
  LoopChannelSpec hub_angle;      // encoder, rad
  LoopChannelSpec hub_rate;       // tachometer, rad/s
  StrainGaugeSpec strain_gauge;   // N·m (and m)
  RecordedChannelSpec tip_accelerometer;  // lateral tip acceleration in the hub frame, m/s^2
  RecordedChannelSpec tip_position;       // tip deflection (camera, laser tracker), m
  ChannelSpec hub_torque;         // the record's hub torque, N·m
  ChannelSpec tip_deflection;     // the record's tip deflection, m
  ChannelSpec pressure_a, pressure_b;  // the record's chamber pressures, Pa
};

// Friction at the hub (off by default): viscous, Coulomb and Stribeck, regularised at zero velocity:
// tau_f = -(b w + (Fc + (Fs - Fc) exp(-(w/vs)^2)) tanh(w/eps)) (Armstrong-Helouvry 1994; tanh smoothing).
struct FrictionSpec {
  double viscous = 0.0;           // b, N·m·s/rad
  double coulomb = 0.0;           // Fc, N·m
  double stiction = 0.0;          // Fs >= Fc: breakaway torque of the Stribeck peak, N·m; 0 = Fc
  double stribeck_velocity = 0.01;  // vs, rad/s
  double smoothing = 1e-3;        // eps, rad/s: the tanh regularisation (small = sharper, stiffer)
  // "static": the map above. "lugre": the LuGre bristle model (Canudas de Wit et al. 1995) with a state z:
  //   dz/dt = w - sigma0 |w| z / g(w),  g(w) = Fc + (Fs - Fc) exp(-(w/vs)^2),  tau_f = -(sigma0 z + sigma1 dz/dt + b w).
  std::string model = "static";
  double bristle_stiffness = 1.0e5;  // sigma0, N·m/rad
  double bristle_damping = 300.0;    // sigma1, N·m·s/rad
  // A worn or eccentric gear: the levels Fc and Fs times 1 + a cos(p q) + b sin(p q) at joint angle q,
  // p = position_waves a revolution (0: none), a = position_cos, b = position_sin (a^2 + b^2 < 1).
  double position_waves = 0.0;
  double position_cos = 0.0;
  double position_sin = 0.0;
};

// Hydraulic rotary actuator (rack and pinion) behind a servo valve; off by default, when the
// controller's torque acts on the hub directly. The valve amplifier closes a torque loop on the
// chamber pressures: spool command u = sat(K (tau_cmd - D (p_a - p_b)) / (D p_s), -1, 1).
struct HydraulicSpec {
  bool enabled = false;
  double displacement = 2.5e-3;   // D = piston area x pinion radius, m^3/rad (torque D dp, flow D w)
  // D in physical terms (both or neither; 0 = not given): D = A r (calc_displacement).
  double piston_area = 0.0;       // A, m^2
  double pinion_radius = 0.0;     // r, m
  double chamber_volume = 4.5e-3; // V0, each chamber with the rack centred (lines included), m^3
  double bulk_modulus = 1.4e9;    // beta, Pa
  double supply_pressure = 21e6;  // p_s, Pa
  double tank_pressure = 0.2e6;   // p_t, Pa
  double relief_pressure = 0.0;   // p_r, Pa: relief valves open above it; 0 = 1.1 p_s
  double rated_flow = 1.6e-3;     // Q_r through one land at full opening and the rated drop, m^3/s
  double rated_drop = 3.5e6;      // that drop, Pa
  // The valve coefficient in physical terms (all four or none; 0 = not given), from the orifice
  // flow Q = C_d w x sqrt(2 dp / rho): k_v = C_d w x_max sqrt(2 / rho) (calc_valve_coefficient).
  double discharge_coefficient = 0.0;  // C_d
  double port_width = 0.0;        // w, orifice area per metre of spool travel, m
  double spool_stroke = 0.0;      // x_max, spool travel at full opening, m
  double oil_density = 0.0;       // rho, kg/m^3
  double laminar_drop = 0.1e6;    // below this drop the orifice flow turns linear (smooth zero crossing), Pa
  double leakage = 1.0e-12;       // cross-port leakage a -> b, m^3/(s·Pa)
  double valve_frequency = 200.0; // spool natural frequency, Hz
  double valve_damping = 0.7;     // spool damping ratio
  double pressure_gain = 5.0;     // K of the torque loop; 0 = valve held closed
};

// Drive train between the actuator and the hub; off by default (actuator rigidly on the hub).
// Actuator shaft angle theta_a, output twist d = theta_a / n - theta_h, free play +-b:
//   tau_s = k e + k3 e^3 + c dd/dt in contact (e = d -+ b beyond the play, 0 inside), never pulling.
// The hub gets tau_s; the shaft feels tau_s / (n eta) when driving the load, tau_s eta / n when driven.
struct DriveSpec {
  bool enabled = false;
  double inertia = 5.0;           // J_a, actuator-side inertia (rotor, pinion, gears) on the shaft, kg·m^2
  double ratio = 1.0;             // n = shaft angle / output angle
  double efficiency = 1.0;        // eta in (0, 1]
  double stiffness = 2.0e7;       // k, output side, N·m/rad
  double cubic_stiffness = 0.0;   // k3, hardening, N·m/rad^3
  double damping = 2.0e3;         // c, N·m·s/rad
  double backlash = 0.0;          // total free play 2b at the output, rad
  // true: c acts only while the teeth close (e de/dt > 0): impact losses, no drag as they part
  bool closing_damping = false;
};

// Input shaper on the reference (kernel/shaper.hpp), off by default.
struct ShaperSpec {
  std::string type = "none";      // none, zv, zvd, ei
  double frequency = 0.0;         // design frequency, rad/s; 0 = the first closed-loop resonance
  double damping = -1.0;          // design damping ratio; < 0 = that resonance's damping
  double vtol = 0.05;             // EI: residual vibration allowed at the design frequency
};

// The payload changes at a controller sample (pick or release), joint rates continuous.
struct PayloadEvent {
  double time = 0.0;              // s: applied at the first controller sample at or after it
  double mass = 0.0;              // kg, the new payload mass
  double inertia = 0.0;           // kg·m^2, the new payload inertia about its centre of mass
};

// One move of the cubic trajectory r = r0 + (r1 - r0)(3u^2 - 2u^3), u = t/T_m, then a hold.
struct MoveSpec {
  double target = 0.0;            // rad
  double hold = 0.0;              // s, after the move ends
};

struct TrajectorySpec {
  double move_time = 3.0;         // T_m, s
  std::vector<MoveSpec> moves;    // executed in order from r = 0 at t = 0
};

// rk4: classical Runge-Kutta (explicit; fine for small N). sdirk2: L-stable two-stage SDIRK with the
// joint springs and dampers implicit (any N). cvode_*: BDF reference with a dense or KLU solver.
// midpoint: linearly implicit midpoint rule, joints implicit as in sdirk2, one articulated-body pass
// per step (A-stable, not L-stable: short chains such as N = 6 at one step per sample).
// cvode_gmres (arm models only): matrix-free CVODE, preconditioned by the joint springs
// (multibody/tree_cvode.hpp).
enum class Integrator { kRk4, kSdirk2, kCvodeDense, kCvodeKlu, kMidpoint, kCvodeGmres };

struct SimulationSpec {
  double duration = 0.0;          // s; 0 = end of the last hold
  Integrator integrator = Integrator::kRk4;
  int substeps = 0;               // fixed-step substeps per control period; 0 = chosen from the fastest mode
  double rtol = 1e-8;             // CVODE relative tolerance
  double atol = 1e-10;            // CVODE absolute tolerance
  std::uint64_t seed = 1;         // sensor noise; a study gives each variant its own
  // true: every sensor gives the expectation of its reading, E[Q(x + sigma n)] (calc_expected_reading),
  // instead of drawing its noise: a prediction of what a noisy, quantised sensor reads on average.
  bool expected_readings = false;
};

// Everything a user writes in a model YAML file.
struct ModelSpec {
  BeamSpec beam;
  int segments = 6;               // N >= 2
  bool units_check = true;        // `units_check`: targets beyond a turn, implausible E or density refused
  JointSpec joints;
  double hub_inertia = 50.0;      // kg·m^2, actuator + pinion + base frame
  // A constant load torque on the hub, signed (the drive must supply it to hold still): cable drag, an
  // unbalanced axis, amplifier bias; N·m. The hub gets tau_drive + tau_friction - hub_torque_offset.
  double hub_torque_offset = 0.0;
  double payload_mass = 328.7;    // kg, at the tip point
  double payload_inertia = 118.6; // kg·m^2 about its own centre of mass
  std::vector<PayloadEvent> payload_events;  // in time order
  ControllerSpec controller;
  NotchSpec notch;
  ShaperSpec shaper;
  SensorSpec sensors;
  FrictionSpec friction;
  HydraulicSpec hydraulics;
  DriveSpec drive;
  TrajectorySpec trajectory;
  SimulationSpec simulation;
};

// A planar rigid body in its own joint frame: spatial inertia [[J, 0, h], [0, m, 0], [h, 0, m]].
struct BodyInertia {
  double mass;    // m, kg
  double first;   // h = m * x_com, kg·m
  double inertia; // J about the joint axis, kg·m^2
};

// The derived, immutable model. Body 0 is the hub with the first segment; joint 0 is the hub
// axis, joint i >= 1 the spring between segments i-1 and i. Generalised coordinates:
// q0 = hub angle (absolute), qi = relative joint angle.
struct Model {
  ModelSpec spec;
  int nseg = 0;                          // N
  std::vector<double> seg_length;        // L_i (N), m
  std::vector<double> seg_mass;          // m_i (N), kg
  std::vector<double> seg_inertia;       // m_i (L_i^2 + t^2)/12 about the centre (N), kg·m^2
  std::vector<BodyInertia> body;         // per body, payload and hub included (N)
  std::vector<double> joint_k;           // spring of joint i (N, entry 0 unused = 0), N·m/rad
  std::vector<double> joint_c;           // damper of joint i (N, entry 0 unused = 0), N·m·s/rad
  std::vector<double> joint_k3;          // cubic stiffening of joint i (N, entry 0 unused = 0), N·m/rad^3
  double cell = 0.0;                     // l = L/(N-1), m
  double control_period = 0.0;           // 1/rate, s
  double duration = 0.0;                 // s
  double omega_z[2] = {0.0, 0.0};        // notch zeros in use, rad/s (placed when enabled)
  int substeps = 1;                      // fixed-step substeps per control period
  std::vector<double> resonances;        // closed-loop resonances (oscillatory, zeta < 0.3), ascending, rad/s
  std::vector<Impulse> shaper;           // input-shaper impulses; one of amplitude 1 at 0 when off
  double rigid_inertia = 0.0;            // the straight arm's inertia about the hub axis, M_00(q = 0), kg·m^2
  // The controller's model's rigid_inertia, for the feed-forward: the nominal model's (make_model's
  // `controller`), else this model's, kg·m^2. omega_z and shaper above are the controller's too.
  double control_inertia = 0.0;
};

// The tip body (last segment with a payload of `mass`, `inertia`; with the hub when N = 1) in its joint frame.
BodyInertia make_tip_body(const Model& m, double mass, double inertia);

// Derives and validates the model. Throws ConfigError (naming `source`) on non-physical values.
// `controller`: the controller's internal model (the nominal one, sweep/paths.hpp), whose rigid inertia,
// notch zeros and shaper the controller then uses instead of this model's; nullptr = this model's own.
Model make_model(const ModelSpec& spec, const std::string& source = "<model>", const Model* controller = nullptr);

// Beam mass rho h t L, kg.
double calc_beam_mass(const BeamSpec& beam);
// Area moment h t^3 / 12, m^4.
double calc_area_moment(const BeamSpec& beam);
// Equivalent cantilever torsional stiffness 3EI/L of a beam of length `length` (seed eq. 5), N·m/rad.
double calc_cantilever_stiffness(const BeamSpec& beam, double length);
// Tip deflection per bending moment at beam joint `joint` (1..N-1, at x_i = (i - 1/2) l from the hub) of a
// continuous clamped cantilever with a tip load P (Euler-Bernoulli, EI from `beam`): M(x) = P (L - x),
// delta = P L^3 / (3 EI), so delta / M_i = L^3 / (3 EI (L - x_i)), m/(N·m). The segmented chain with
// k = EI / l deflects (1 - 1/(4 (N-1)^2)) times this (midpoint sum of (L - x_i)^2), EI / (k l) times
// more for other k (1.105 on the reference rig).
double calc_strain_tip_gain(const BeamSpec& beam, int segments, int joint);

}  // namespace ff
