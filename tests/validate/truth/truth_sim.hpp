// An independent truth simulator of the reference rig (docs/reference-rig.md) for testing flexfarm's
// validation tools on records flexfarm did not make. It shares no dynamics code with kernel/: its own
// formulation (absolute segment angles, the dense mass matrix of the Lagrangian, Eigen LDLT), its own
// integrator (SUNDIALS CVODE, BDF, dense direct solver, re-initialised at every controller sample),
// its own regularisations (atan friction, a hyperbolic dead zone) and its own parameterisation of
// the hidden effects. Equations and the mapping to flexfarm's model paths: README.md next to this file.
#pragma once

#include <Eigen/Dense>

#include <cstdint>
#include <string>
#include <vector>

#include "validate/record.hpp"

namespace ff::truth {

// One cubic move r = r0 + (r1 - r0)(3u^2 - 2u^3), u = (t - t_start)/move_time, then a hold.
struct TruthMove {
  double target = 0.0;  // r1, rad
  double hold = 0.0;    // s, after the move ends
};

// A sensor channel: Gaussian noise (1 sigma, the channel's unit) and a delay in controller samples.
struct TruthChannel {
  double noise = 0.0;
  int delay = 0;
};

// The rig in physical terms, SI units. Defaults: the reference rig (reference-rig.md) with no hidden
// effect, moving 0 -> 0.5 rad -> 0 as configs/fbtb.yaml.
struct TruthRig {
  struct Beam {
    double length = 4.1656;         // L, m
    double height = 0.3048;         // h (vertical), m
    double thickness = 0.01905;     // t (bends in the horizontal plane), m
    double density = 7750.0;        // rho, kg/m^3
    double youngs_modulus = 207e9;  // E, Pa (only the README's k = kappa EI / l note uses it)
  } beam;
  // N rigid segments: l/2, (N - 2) x l, l/2 with l = L/(N - 1) (N = 1: one rigid arm of length L).
  int segments = 6;
  struct Joint {
    double stiffness = 39.5e3;      // k at the reference cell, N m/rad; k_N = k (reference_cell / l)
    double damping = 90.4;          // c at the reference cell, N m s/rad; scales as k
    double reference_cell = 0.83312;  // m (L/5, the seed's N = 6 cell)
    // Hardening joints, moment k q + k3 q^3: the secant stiffness M/q rises by the fraction
    // `stiffening` at |q| = `stiffening_angle`, i.e. k3 = stiffening k / stiffening_angle^2 (per joint).
    double stiffening = 0.0;        // fraction (0.2 = 20 % stiffer at the angle below); 0 = linear
    double stiffening_angle = 0.01; // rad
  } joint;
  // Hub (actuator, pinion, base frame) rigidly on segment 1, kg m^2. With a drive train: the hub alone,
  // the actuator's own inertia is drive.inertia.
  double hub_inertia = 50.0;
  struct Payload {
    double mass = 328.7;            // kg, point mass at the tip point
    double inertia = 118.6;         // kg m^2 about its own centre of mass (the tip point)
  } payload;
  // PID on the measured hub angle, derivative on the measured rate, zero-order hold:
  //   tau = sat(kp (r - theta_m) + ki I - kd omega_m),  I += (r - theta_m) T unless saturated that way.
  // Feed-forward with the controller's own (nominal) model: + f (J_nom r'' + kd r'), J_nom the straight
  // arm's inertia about the hub (1' M(0) 1) with the nominal hub and payload below (the drive's shaft not
  // included), so a plant whose payload differs is not tracked exactly (README.md, "Controller").
  struct Controller {
    double rate = 1000.0;           // Hz
    double kp = 1.0e5;              // N m/rad
    double kd = 3.0e4;              // N m s/rad
    double ki = 0.0;                // N m/(rad s)
    double torque_limit = 0.0;      // |tau| bound, N m; 0 = none
    double feedforward = 0.0;       // gain f; 0 = no feed-forward
    double nominal_hub_inertia = -1.0;      // kg m^2 in J_nom; < 0 = the plant's hub_inertia
    double nominal_payload_mass = -1.0;     // kg; < 0 = the plant's payload.mass
    double nominal_payload_inertia = -1.0;  // kg m^2; < 0 = the plant's payload.inertia
  } controller;
  struct Trajectory {
    double move_time = 3.0;         // s, every move
    std::vector<TruthMove> moves = {{0.5, 7.0}, {0.0, 45.0}};  // from r = 0 at t = 0
  } trajectory;
  // Hub friction. The Stribeck curve g(w, theta) = P(theta) (Fc + (Fs - Fc) exp(-|w/vs|^delta)), with the
  // worn-gear factor P(theta) = 1 + a cos(p theta + phase). Static law (bristle_stiffness 0):
  //   tau_f = -(b w + g(w, theta) (2/pi) atan(w/eps));
  // LuGre (Canudas de Wit et al. 1995, bristle_stiffness sigma0 > 0), bristle deflection z (rad):
  //   z' = w - sigma0 |w| z / g(w, theta),   tau_f = -(sigma0 z + sigma1 z' + b w).
  struct Friction {
    double viscous = 0.0;           // b, N m s/rad
    double coulomb = 0.0;           // Fc, N m
    double stiction = 0.0;          // Fs >= Fc, the breakaway (Stribeck peak), N m; 0 = Fc (no peak)
    double stribeck_velocity = 0.01;  // vs, rad/s
    double stribeck_exponent = 2.0; // delta of exp(-|w/vs|^delta)
    double smoothing = 1e-4;        // eps of the atan regularisation, rad/s (static law only)
    double bristle_stiffness = 0.0; // sigma0, N m/rad; > 0 = LuGre
    double bristle_damping = 0.0;   // sigma1, N m s/rad (LuGre)
    double position_amplitude = 0.0;  // a in P(theta), in [0, 1)
    double position_waves = 1.0;    // p: waves of P per hub revolution
    double position_phase = 0.0;    // rad
  } friction;
  // A constant signed load on the hub, N m: the hub gets tau_actuator + tau_f - torque_offset.
  double torque_offset = 0.0;
  // Drive train between actuator and hub (off: the controller's torque acts on the hub). The motor
  // torque tau/n acts on the actuator shaft (angle theta_a, inertia J_a); the mesh torque on the hub:
  //   d = theta_a/n - theta_h,  e = g(d) (the dead zone),  tau_s = s(e) + k3 e^3 + c de/dt,
  //   J_a theta_a'' = (tau - tau_s)/n,  the hub gets tau_s; with backlash the teeth never pull.
  // s(e) is the multi-slope mesh: slope k up to |e| = knee_1, stiffness_2 up to knee_2, stiffness_3
  // beyond (odd, continuous); knee_1 = 0: s = k e. one_sided_damping: c acts only while |e| grows.
  struct Drive {
    bool enabled = false;
    double inertia = 5.0;           // J_a on the shaft, kg m^2
    double ratio = 1.0;             // n = shaft angle / hub angle
    double stiffness = 2.0e7;       // k, N m/rad (at the hub)
    double cubic_stiffness = 0.0;   // k3, N m/rad^3
    double damping = 2.0e3;         // c, N m s/rad
    double backlash = 0.0;          // total gap 2b, rad (at the hub)
    // delta of the dead zone g(d) = s(d - b) - s(-d - b), s(x) = (x + sqrt(x^2 + delta^2))/2, rad
    double backlash_smoothing = 1e-6;
    double knee_1 = 0.0;            // rad; 0 = linear mesh
    double stiffness_2 = 0.0;       // N m/rad, slope beyond knee_1
    double knee_2 = 0.0;            // rad (> knee_1); 0 = two slopes
    double stiffness_3 = 0.0;       // N m/rad, slope beyond knee_2
    bool one_sided_damping = false; // the mesh damps only while the teeth close (e de/dt > 0)
  } drive;
  // Hydraulic rotary actuator (rack and pinion) behind a servo valve, off by default; its pinion is on
  // the hub (or on the drive's shaft). Torque on the pinion D (p_a - p_b), D = piston_area x pinion_radius.
  // The amplifier closes a torque loop: spool command u = sat(K (tau/n - D dp) / (D p_s), -1, 1);
  // spool x'' = wv^2 (u - x) - 2 zv wv x'. Critically lapped four-land valve, x > 0 opening supply -> a:
  //   Q_a = kv (x+ R(p_s - p_a) - x- R(p_a - p_t)),  Q_b = kv (x- R(p_s - p_b) - x+ R(p_b - p_t)),
  //   R(dp) = dp / sqrt(|dp| + dp_l) (sqrt with a laminar core), kv = rated_flow / sqrt(rated_drop);
  // chambers V_a,b = V0 +- D theta_p: p_a' = beta/V_a (Q_a - Q_l - D w_p), p_b' = beta/V_b (Q_b + Q_l + D w_p),
  // Q_l = leakage (p_a - p_b). No relief or anti-cavitation valves. Both chambers start at (p_s + p_t)/2.
  struct Hydraulics {
    bool enabled = false;
    double piston_area = 1.25e-2;   // A, m^2
    double pinion_radius = 0.2;     // r, m (D = A r = 2.5e-3 m^3/rad)
    double chamber_volume = 4.5e-3; // V0 per chamber, rack centred, lines included, m^3
    double bulk_modulus = 1.4e9;    // beta, Pa
    double supply_pressure = 21e6;  // p_s, Pa
    double tank_pressure = 0.2e6;   // p_t, Pa
    double rated_flow = 1.6e-3;     // one land, full opening, at rated_drop, m^3/s
    double rated_drop = 3.5e6;      // Pa
    double laminar_drop = 0.1e6;    // dp_l, Pa
    double leakage = 1e-12;         // cross-port a -> b, m^3/(s Pa)
    double valve_frequency = 200.0; // Hz
    double valve_damping = 0.7;
    double pressure_gain = 5.0;     // K; 0 = valve held closed
  } hydraulics;
  // Sensors. The controller reads the hub-angle encoder and the tachometer `delay` samples late; the
  // record's hub_angle and hub_rate are the readings time-stamped when taken (record.as_seen: as the
  // controller saw them). hub_torque and tip_deflection are recorded only: their delay shifts the column.
  struct Sensors {
    struct Angle : TruthChannel {
      bool quantize = false;        // encoder: reading = q round((theta + noise)/q), q = 2 pi / 2^bits
      int encoder_bits = 16;
    } hub_angle;                    // rad
    struct Rate : TruthChannel {
      bool recorded = true;         // write the hub_rate column (the loop always uses the tachometer)
    } hub_rate;                     // rad/s: true rate + noise
    TruthChannel hub_torque;        // N m: the actuator's torque on the hub (the mesh torque with a drive)
    TruthChannel tip_deflection;    // m
    TruthChannel pressure;          // Pa, each chamber (recorded with hydraulics: pressure_a, pressure_b)
  } sensors;
  struct RecordSpec {
    int decimate = 1;               // a record row every `decimate` controller samples (from t = 0)
    bool as_seen = false;           // hub_angle, hub_rate columns = what the controller used (delayed)
  } record;
  std::uint64_t seed = 1;           // noise: std::mt19937_64 per channel, seeded by (seed, channel)
  double duration = 0.0;            // s; 0 = the end of the last hold
  struct Initial {
    double joint_angle = 0.0;       // every beam joint starts bent by this, at rest, hub at 0, rad
    double hub_rate = 0.0;          // the hub and arm start turning rigidly at this rate (the drive's shaft at rest), rad/s
  } initial;
  struct Solver {
    double rtol = 1e-9;             // CVODE relative tolerance
    double atol = 1e-12;            // CVODE absolute tolerance (rad, rad/s)
    long max_steps = 50000;         // per controller period
  } solver;
};

// The chain's constants derived from a rig: segment lengths, joint laws, and the coefficients a_jk of
// the mass matrix M_jk(phi) = a_jk cos(phi_j - phi_k) (README.md).
struct TruthChain {
  int n = 0;                        // N segments
  std::vector<double> length;       // L_i, m
  std::vector<double> k, c, k3;     // joint i between segments i-1 and i (entry 0 unused = 0)
  Eigen::MatrixXd a;                // kg m^2, symmetric
};
TruthChain make_truth_chain(const TruthRig& rig);
Eigen::MatrixXd calc_truth_mass_matrix(const TruthChain& chain, const Eigen::VectorXd& phi);
// The straight arm's inertia about the hub, 1' M(0) 1, kg m^2; `nominal`: with the controller's nominal
// hub and payload (what its feed-forward uses).
double calc_truth_rigid_inertia(const TruthRig& rig, bool nominal = false);

// The true signals at every controller sample (before that sample's torque acts), for tests.
struct TruthTrace {
  std::vector<double> t;              // s
  std::vector<double> ref;            // rad
  std::vector<double> demand;         // the controller's torque, N m
  std::vector<double> hub_torque;     // the actuator's torque on the hub, N m
  std::vector<double> hub_angle;      // theta_h, rad
  std::vector<double> hub_rate;       // rad/s
  std::vector<double> tip_deflection; // sum L_i sin(phi_i - theta_h), m
  std::vector<double> root_joint;     // q_1 = phi_1 - phi_0, rad (0 when N = 1)
  std::vector<double> twist;          // drive twist d = theta_a/n - theta_h, rad (0 without a drive)
  std::vector<double> twist_rate;     // its rate, rad/s
  std::vector<double> energy;         // kinetic + elastic (joints, drive mesh), J
  std::vector<double> friction;       // the friction torque on the hub, N m
  std::vector<double> bristle;        // LuGre's z, rad (0 without)
  std::vector<double> seen_angle;     // what the controller used, rad
  std::vector<double> seen_rate;      // rad/s
  std::vector<double> pressure_a, pressure_b;  // chamber pressures, Pa (empty without hydraulics)
};

// What CVODE did over the run.
struct TruthSolverStats {
  long steps = 0, rhs_evals = 0, jacobian_evals = 0, restarts = 0;
};

struct TruthRun {
  Record record;                      // the measurement record (truth_record_columns order)
  TruthTrace trace;
  TruthSolverStats stats;
};

// Runs the rig for rig.duration (0 = to the end of the last hold). Throws std::invalid_argument on a
// non-physical rig (naming the field) and std::runtime_error when CVODE fails.
TruthRun run_truth(const TruthRig& rig);
// The record alone: t, ref, hub_torque, hub_angle, hub_rate (when recorded), tip_deflection, and with
// hydraulics pressure_a, pressure_b.
Record simulate_truth(const TruthRig& rig);
Record simulate_truth(const TruthRig& rig, double duration);
// The record's columns after t, in file order (write_record_csv's `order`).
std::vector<std::string> truth_record_columns(const TruthRig& rig);

// The field table: every TruthRig field by its dotted name ("drive.backlash", "sensors.tip_deflection.delay",
// "trajectory.moves" as "target:hold,target:hold"). Throws std::invalid_argument for an unknown key
// ("unknown key 'x'") or a value that does not parse.
void set_truth_field(TruthRig& rig, const std::string& key, const std::string& value);
struct TruthFieldInfo {
  std::string name, unit, value;      // value: as in `rig`
};
std::vector<TruthFieldInfo> list_truth_fields(const TruthRig& rig);

}  // namespace ff::truth
