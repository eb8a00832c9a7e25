// An independent truth simulator of planar serial arms (N = 1..6 revolute joints) in a vertical plane
// under gravity (or a horizontal one), for testing flexfarm's arm diagnosis on records flexfarm did not
// make. It shares no dynamics code with arm/, multibody/ or kernel/: its own formulation (absolute link
// angles, the Lagrangian's dense mass matrix from the link geometry, Eigen LDLT), its own integrator
// (SUNDIALS CVODE, BDF, dense direct solver, re-initialised at every controller sample), and hidden
// effects in forms flexfarm does not share (LuGre and exponential-Stribeck friction, position-dependent
// friction, multi-slope mesh stiffness, one-sided damped backlash, a logger recording the late value,
// an encoder quantised in the loop, a controller whose gravity model keeps the nominal payload).
// Equations, fields and the mapping to flexfarm's arm models: README.md next to this file.
#pragma once

#include <Eigen/Dense>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "validate/record.hpp"

namespace ff::truth {

constexpr int kMaxTruthArmJoints = 6;

// One joint and the link it moves (joint i sits at the far end of link i-1; joint 1 on the base).
struct TruthArmJoint {
  struct Link {
    double length = 0.4;      // L, m: joint to the next joint (or to the payload)
    double mass = 2.0;        // m, kg
    double com = 0.2;         // c, m: the centre of mass along the link from its joint
    double inertia = 0.03;    // I, kg m^2: about the centre of mass, in the plane
  } link;
  // The actuator: a motor (rotor inertia J on the motor shaft) behind a gear of ratio n. Rigid drive: the
  // rotor's kinetic energy 1/2 J n^2 qdot^2 (its joint's armature). Compliant: the motor's own angle
  // theta (joint units) and a mesh torque tau_s(d, d') with the twist d = theta - q (README.md).
  struct Drive {
    double motor_inertia = 2e-5;  // J, kg m^2 on the motor shaft
    double ratio = 100.0;         // n = motor angle / joint angle
    bool compliant = false;
    double stiffness = 2e4;       // k1, N m/rad at the joint: the first slope
    double knee = 0.0;            // e1, rad: where the second slope starts (0 = one slope)
    double stiffness2 = 0.0;      // k2, N m/rad
    double knee2 = 0.0;           // e2 > e1, rad: where the third slope starts (0 = two slopes)
    double stiffness3 = 0.0;      // k3, N m/rad
    double damping = 20.0;        // c, N m s/rad (with backlash: only in contact, only while the teeth close)
    double backlash = 0.0;        // total gap 2b, rad at the joint
  } drive;
  // PD(+I) on the sensed angle (the motor side, in joint units; `link_side`: the joint's own angle) and
  // the sensed rate, plus the gravity torque of the controller's (nominal) model at the reference.
  struct Controller {
    double kp = 400.0;            // N m/rad
    double kd = 40.0;             // N m s/rad
    double ki = 0.0;              // N m/(rad s)
    double torque_limit = 0.0;    // |tau| bound, N m; 0 = none
    double gravity_compensation = 1.0;  // f_g
    bool link_side = false;
  } controller;
  // Friction on the motor side (the joint with a rigid drive), in joint units:
  //   static: F = b v + p(x) (Fc + (Fs - Fc) exp(-|v/vs|^delta)) (2/pi) atan(v/eps)
  //   lugre:  z' = v - sigma0 |v| z / g(v), g = p(x) (Fc + (Fs - Fc) exp(-|v/vs|^delta)),
  //           F = sigma0 z + sigma1 z' + b v
  //   p(x) = 1 + a sin(2 pi x / P + psi): position-dependent (x the angle the friction acts at).
  struct Friction {
    double viscous = 0.0;         // b, N m s/rad
    double coulomb = 0.0;         // Fc, N m
    double stiction = 0.0;        // Fs >= Fc, N m; 0 = Fc (no peak)
    double stribeck_velocity = 0.02;  // vs, rad/s
    double stribeck_exponent = 1.0;   // delta, > 0 (1: exponential)
    double smoothing = 1e-4;      // eps of the atan, rad/s
    bool lugre = false;
    double bristle_stiffness = 1e4;   // sigma0, N m/rad
    double bristle_damping = 30.0;    // sigma1, N m s/rad
    double position_amplitude = 0.0;  // a, fraction
    double position_period = 0.5;     // P, rad
    double position_phase = 0.0;      // psi, rad
  } friction;
  double torque_offset = 0.0;     // N m: a constant load; the motor side gets tau - offset
  // Sensors: the controller reads the angle and the rate `delay` samples late; the logger records what
  // the controller read (late, quantised, noisy). The torque column is the held torque command + noise.
  struct Sensors {
    struct Angle {
      double noise = 0.0;         // rad, 1 sigma
      int delay = 0;              // samples
      int encoder_bits = 0;       // quantum 2 pi / 2^bits of the reading (noise first); 0 = none
    } angle;
    struct Rate {
      double noise = 0.0;         // rad/s
      int delay = 0;              // samples
    } rate;
    double torque_noise = 0.0;    // N m
  } sensors;
};

struct TruthArm {
  int joints = 2;                 // N, 1..6
  double gravity = 9.81;          // m/s^2 along -y in the plane of motion; 0: a horizontal plane
  struct Payload {
    double mass = 1.0;            // kg, a point mass at the last link's end
    double inertia = 1e-3;        // kg m^2 about itself, in the plane
  } payload;
  std::array<TruthArmJoint, kMaxTruthArmJoints> joint;  // j1 ... j6 (the first `joints` are used)
  struct Controller {
    double rate = 500.0;          // Hz, zero-order hold
    double payload_mass = -1.0;   // the payload mass of the controller's gravity model, kg; < 0 = the true
  } controller;
  // Quintic rest-to-rest moves through waypoints of every joint, as flexfarm's trajectory.
  struct Trajectory {
    std::vector<double> start;    // rad per joint at t = 0 ("a/b/c"); missing joints 0
    struct Waypoint {
      double time = 1.0;          // s, after the waypoint before
      std::vector<double> q;      // rad per joint
    };
    std::vector<Waypoint> waypoints;  // "T:a/b,T:a/b"
    double settle = 1.0;          // s after the last waypoint (when duration is 0)
  } trajectory;
  double duration = 0.0;          // s; 0 = the last waypoint + settle
  std::uint64_t seed = 1;         // noise: std::mt19937_64 per channel, seeded by (seed, channel)
  struct Solver {
    double rtol = 1e-9;
    double atol = 1e-11;
    long max_steps = 100000;      // per controller period
  } solver;
};

// The arms of the acceptance suite (2, 3 or 6 joints): the values of tests/data/truth_arm/arm<n>.yaml.
TruthArm make_suite_arm(int joints);

// The joint's name in the record and in the nominal models: "j1" ... "j6".
std::string truth_arm_joint_name(int i);

// The Lagrangian's pieces at the absolute link angles phi (README.md): M(phi) with every rigid drive's
// rotor, the gravity torques at the joints (relative coordinates; the torque each joint must supply to
// hold the arm at q) with payload mass `payload_mass`, and the potential energy.
Eigen::MatrixXd calc_truth_arm_mass_matrix(const TruthArm& arm, const Eigen::VectorXd& phi);
Eigen::VectorXd calc_truth_arm_gravity(const TruthArm& arm, const Eigen::VectorXd& q, double payload_mass);
double calc_truth_arm_potential(const TruthArm& arm, const Eigen::VectorXd& q);

struct TruthArmTrace {
  std::vector<double> t;                  // s, every controller sample (before its torque acts)
  std::vector<Eigen::VectorXd> q, qd;     // the joints' true angles (link side), rad, rad/s
  std::vector<Eigen::VectorXd> motor;     // the motor angles in joint units (= q with a rigid drive), rad
  std::vector<Eigen::VectorXd> tau;       // the held torque command, N m
  std::vector<double> energy;             // kinetic + potential + elastic (meshes), J
};

struct TruthArmRun {
  Record record;                          // t, then per joint <j>.ref, .angle, .rate, .torque
  TruthArmTrace trace;
  long steps = 0;                         // CVODE's steps
};

// Runs the arm. Throws std::invalid_argument naming the field for a non-physical arm and
// std::runtime_error when CVODE fails.
TruthArmRun run_truth_arm(const TruthArm& arm);
// The record's columns after t, in file order.
std::vector<std::string> truth_arm_record_columns(const TruthArm& arm);

// The field table: "joints", "gravity", "payload.mass", "j2.friction.coulomb", "trajectory.waypoints"
// ("T:a/b,T:a/b"), ... Unknown key: std::invalid_argument("unknown key 'x'"); a bad value names the key.
void set_truth_arm_field(TruthArm& arm, const std::string& key, const std::string& value);
struct TruthArmField {
  std::string name, unit, value;
};
std::vector<TruthArmField> list_truth_arm_fields(const TruthArm& arm);

}  // namespace ff::truth
