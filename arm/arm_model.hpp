// The immutable model of a manipulator of any shape: a kinematic tree (multibody/tree.hpp, read from
// tree YAML or URDF by description/), its actuated joints each with its own controller, a commanded
// motion and how to simulate it. Built and validated once by make_arm(); never written afterwards.
//
// The control law of actuated joint j, sampled at `rate` with zero-order hold (docs/formats.md, "Arm
// models"), the reference rig's law (kernel/controller.hpp) per joint:
//   e_j   = F_j(r_j) - q_j                        (notch on the reference; on the feedback: r_j - F_j(q_j))
//   tau_j = sat(kp e_j + ki int e_j - kd qd_j + f_i (ID(r, r', r'') - G(r) + kd r'_j) + f_g G(r)_j)
// with q_j and qd_j as the joint's sensors give them (quantised, noisy, held, delayed: sensors.angle,
// sensors.rate; exact by default), the joint getting tau_j - torque_offset_j and its friction, and r
// the shaped joint reference, ID the rigid arm's inverse dynamics (RNEA, flexible links held
// straight, the joint's own passive spring and damper added) and G(r) its gravity torques, f_i and f_g the feed-forward gains, the integral frozen
// while the torque saturates in the direction of the error (clamping anti-windup).
// A joint with a hydraulic actuator (`hydraulics:`) gets D (p_a - p_b) - torque_offset and its
// friction instead, tau_j being the actuator's valve-loop command (kernel/drive.hpp).
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "arm/arm_collision.hpp"
#include "description/tree_description.hpp"
#include "kernel/model.hpp"  // NotchSpec, ShaperSpec, FrictionSpec, ChannelSpec, Integrator
#include "kernel/notch.hpp"
#include "kernel/shaper.hpp"
#include "multibody/algorithms.hpp"
#include "multibody/joint_trajectory.hpp"
#include "multibody/modes.hpp"
#include "multibody/statics.hpp"
#include "multibody/tree.hpp"

namespace ff {

// The control of one actuated joint, as the user writes it.
struct JointControlSpec {
  std::string joint;           // the moving joint's name in the tree
  double kp = 0.0;             // N·m/rad (prismatic: N/m)
  double ki = 0.0;             // N·m/(rad·s)
  double kd = 0.0;             // N·m·s/rad, on the measured joint rate
  double torque_limit = 0.0;   // |tau| bound, N·m (N); 0 = the joint's effort limit, or unlimited
  double feedforward = 0.0;    // f_i: gain on the rigid arm's inverse dynamics less gravity (1 = full)
  double gravity_compensation = 0.0;  // f_g: gain on the rigid arm's gravity torques at the reference
  NotchSpec notch;             // on this joint's reference or feedback; omega_z 0 = this joint's resonances
  ShaperSpec shaper;           // on this joint's reference; frequency 0 = the arm's first resonance
  // The joint's plant and sensors (the reference rig's hub blocks, per joint):
  FrictionSpec friction;       // the static map or LuGre's bristles (kernel/friction.hpp) on this joint, in
                               // the plant, at every integrator stage (multibody/lane_integrators.hpp); off
                               // by default
  double torque_offset = 0.0;  // a constant load torque the drive must supply, N·m (N): the joint gets
                               // tau - torque_offset (the rig's hub_torque_offset)
  LoopChannelSpec angle_sensor;  // what the controller measures of q (sensors.angle), rad (m); its `logged`:
                                 // what a record's <joint>.angle holds (validate/arm_record.hpp)
  // A slipped encoder (sensors.angle.fault_time, fault_offset): from the first controller sample at or
  // after fault_time the measured angle is off by fault_offset (added to what the channel gives).
  double angle_fault_time = std::numeric_limits<double>::infinity();  // s; infinity = never
  double angle_fault_offset = 0.0;                                    // rad (m)
  LoopChannelSpec rate_sensor;   // and of qd (sensors.rate), rad/s (m/s); `logged`: what <joint>.rate holds
  bool drive = false;          // a compliant drive train (`drive:`): the tree holds the joint's rotor and
                               // its twist "<joint>.twist" (insert_drive_train); the joint is the rotor's
  DriveTrain train;            // with `drive:`, its values; the lanes apply its nonlinear law at the twist
  // A hydraulic rotary actuator behind a servo valve (`hydraulics:`, the rig's, kernel/drive.hpp;
  // enabled by the block's presence): the joint then gets D (p_a - p_b) from the actuator's states,
  // the controller's torque is the valve loop's command, the chamber flows take the joint's rate, the
  // rack centred at q = 0. Not with `drive:`.
  HydraulicSpec hydraulics;
};

// Where a waypoint goes: joint values by name (the others keep the previous waypoint's), or a tool
// position reached by inverse kinematics at plan time, or several tools' positions at once (`tools`,
// with `joints` fixing some actuated joints first; the IK moves the others).
struct ArmWaypoint {
  double time = 0.0;                 // arrival, s from the start
  std::vector<std::pair<std::string, double>> joints;  // joint name -> rad (m)
  bool cartesian = false;            // `tool` set: solve for the actuated joints
  Vec3 tool = Vec3::Zero();          // the tool point's target in the base frame, m
  std::vector<std::pair<std::string, Vec3>> tools;  // `tools`: tool name -> its target, base frame, m
  int line = 0;                      // where it is written, for errors
};

// One named tool point (`tools: {NAME: {body, point}}`; the `tool:` block is the one tool named "tool").
struct ToolSpec {
  std::string name;
  std::string body;                  // "" = the last body; a flexible link's name means its tip
  Vec3 point = Vec3::Zero();         // in that body's frame (a flexible link: from its tip point), m
  int line = 0;                      // where it is written, for errors
};

// One safety monitor as the user writes it (`monitors: {NAME: {type, ...}}`, docs/formats.md, "Safety
// monitors"): what it watches, its limit, and what the arm does when it trips.
struct MonitorSpec {
  std::string name;                  // heads its trace column NAME.tripped and metric NAME_trip_s
  std::string type;                  // joint_torque, joint_speed, deflection, tool_speed, workspace, clearance, command
  std::string joint;                 // joint_torque, joint_speed: an actuated joint
  std::string link;                  // deflection: a flexible link
  std::string tool;                  // tool_speed, workspace: "" = the first tool
  double limit = 0.0;                // N·m (N), rad/s (m/s), m, m/s or m by type
  Vec3 lower = Vec3::Zero(), upper = Vec3::Zero();  // workspace: the box, base frame, m
  double time = 0.0;                 // command: when the operator's stop comes, s
  std::string action = "record";     // record, hold, stop, brake
  double deceleration = 0.0;         // stop: rad/s² (m/s²)
  double delay = 0.0;                // s from the trip to the action (whole controller samples, rounded up)
  double brake_torque = 0.0;         // brake: N·m (N); 0 = each joint's torque limit
  int line = 0;                      // where it is written, for errors
};

struct ArmSpec {
  std::string source;                // the file, for errors
  std::string description;
  bool units_check = true;           // `units_check`: revolute angles beyond a turn refused (degrees?)
  TreeDescription tree;
  std::string tool_body;             // the end effector's body ("" = the last body; a flexible link's tip)
  Vec3 tool_point = Vec3::Zero();    // in that body's frame (a flexible link: from its tip point), m
  bool tool_point_given = false;
  std::vector<ToolSpec> tools;       // `tools:` in file order; empty: the one tool of `tool:` (named "tool")
  double rate = 1000.0;              // controller sample rate, Hz
  // The controller's internal model (`controller.model`): "nominal", the model file with its --set
  // overrides, which a study's variables and runs, diagnose's candidates and calibrate's fits do not
  // change (sweep/paths.hpp, Assignment::plant_only); or "plant", the varied model itself.
  std::string controller_model = "nominal";
  std::vector<JointControlSpec> joints;  // the actuated joints, in file order
  TrajectoryShape shape = TrajectoryShape::kQuintic;
  std::vector<std::pair<std::string, double>> start;  // joint values at t = 0 (others 0), rad (m)
  int start_line = 0;
  std::vector<ArmWaypoint> waypoints;
  double duration = 0.0;             // s; 0 = the last waypoint's time plus `settle`
  double settle = 5.0;               // s after the last waypoint when duration is 0
  Integrator integrator = Integrator::kRk4;
  bool integrator_given = false;     // default: sdirk2 with a flexible link, rk4 without
  int substeps = 0;                  // per control period; 0 = from the modes (CVODE: 1)
  double rtol = 1e-8, atol = 1e-10;  // CVODE's tolerances
  double band = 0.02;                // settling band, fraction of each move's amplitude
  double tool_band = 0.0;            // the tool's settling band, m; 0 = band x the tool's largest move
  std::uint64_t seed = 1;            // sensor noise (simulation.seed); a study gives each variant its own
  bool expected_readings = false;    // simulation.expected_readings (kernel/model.hpp SimulationSpec)
  World world;                       // `world:` (world/world_yaml.hpp): the obstacles
  std::vector<CollisionPartSpec> collision;  // `collision:`: the parts' overrides
  std::vector<MonitorSpec> monitors; // `monitors:` in file order
};

// A flexible link's tip, for its deflection.
struct LinkTip {
  std::string name;
  int root_body = -1;                // the root segment (its frame is the undeformed link's)
  int tip_body = -1;
  Vec3 tip_point = Vec3::Zero();     // in the tip body's frame, m
  Vec3 rigid_tip = Vec3::Zero();     // where the straight link's tip sits in the root body's frame, m
  std::vector<int> elastic_dofs;
};

// One actuated joint, derived.
struct ActuatedJoint {
  std::string name;
  int dof = -1;
  int body = -1;                     // the body its joint moves
  JointControlSpec control;
  double torque_limit = 0.0;         // in use (0 = unlimited)
  std::vector<Biquad> notch;         // sections; empty when off
  bool notch_on_feedback = false;
  std::vector<Impulse> shaper;       // one of amplitude 1 at 0 when off
  // The sensors (kernel/sensors.hpp, sample_channel): controller samples per sensor sample, and the
  // noise streams calc_variant_seed(seed, 2 i) (angle) and (seed, 2 i + 1) (rate), i the joint's index
  // in ArmModel::actuated.
  int angle_hold = 1, rate_hold = 1;
  std::uint64_t angle_key = 0, rate_key = 0;
  // With hydraulics: the torque the actuator holds at the start, the joint's static load at q0
  // (gravity, its own spring, torque_offset), N·m (N). The chambers start at (p_s + p_t)/2 +- hold / (2 D),
  // the spool centred (calc_initial_pressures).
  double hold_torque = 0.0;
};

// A tool point, derived: trace columns <name>.x/.y/.z and .ref_x/.ref_y/.ref_z, metrics <name>_settling_s, ...
struct ArmTool {
  std::string name;                  // "tool" for the `tool:` block (or none given)
  int body = -1;
  Vec3 point = Vec3::Zero();         // in body's frame, m
};

// A safety monitor, derived (arm_simulate.hpp evaluates it at every controller sample from the
// outputs row, before the control law).
inline constexpr const char* kMonitorTypes =
    "joint_torque, joint_speed, deflection, tool_speed, workspace, clearance, command";
enum class MonitorType { kJointTorque, kJointSpeed, kDeflection, kToolSpeed, kWorkspace, kClearance, kCommand };
enum class MonitorAction { kRecord, kHold, kStop, kBrake };
// A type's or action's name (as `monitors:` writes it) to its value; false when unknown.
bool parse_monitor_type(const std::string& name, MonitorType& out);
bool parse_monitor_action(const std::string& name, MonitorAction& out);

struct ArmMonitor {
  std::string name;
  MonitorType type = MonitorType::kCommand;
  MonitorAction action = MonitorAction::kRecord;
  int joint = -1;                    // index in ArmModel::actuated (joint_torque, joint_speed)
  int link = -1;                     // index in ArmModel::links (deflection)
  int tool = 0;                      // index in ArmModel::tools (tool_speed, workspace)
  double limit = 0.0;
  Vec3 lower = Vec3::Zero(), upper = Vec3::Zero();
  long command_sample = 0;           // command: the first sample at or after its time
  long delay_samples = 0;            // ceil(delay / T)
  double deceleration = 0.0;         // stop
  double brake_torque = 0.0;         // brake: 0 = each joint's torque limit
};

struct ArmModel {
  ArmSpec spec;
  Tree tree;
  std::vector<ActuatedJoint> actuated;  // in dof order
  std::vector<int> passive_dofs;     // every other moving joint (cells, unactuated joints)
  std::vector<int> compliant_dofs;   // the flexible links' cells and the drive trains' twists: what sags
  std::vector<ArmTool> tools;        // at least one: `tool:`'s as "tool", or `tools:`'s in file order
  int tool_body = -1;                // the first tool's body and point
  Vec3 tool_point = Vec3::Zero();    // in tool_body's frame, m
  std::vector<LinkTip> links;        // the flexible links
  JointTrajectory trajectory;        // of the actuated joints (their order), start = the initial pose
  Eigen::VectorXd q0;                // the initial state: actuated joints at the start, elastic dofs at
                                     // the static sag under gravity with the actuated joints held
  Eigen::VectorXd qd0;               // the initial joint rates: zero (a caller may set them, e.g. a coasting test)
  double control_period = 0.0;       // s
  double duration = 0.0;             // s
  int substeps = 1;
  Integrator integrator = Integrator::kRk4;
  std::vector<double> resonances;    // closed-loop resonances at q0 (zeta < 0.3), ascending, rad/s
  double move_end = 0.0;             // the last waypoint's time, s
  ArmCollision collision;            // the capsules, obstacles and pairs between arms (arm_collision.hpp)
  std::vector<ArmMonitor> monitors;  // `monitors:` in file order
  // A brake's rate gain per actuated joint, k_b = M_jj(q0) / T: the joint's own inertia at the start over
  // the sample time (in its linear zone a sampled brake kills the joint's rate in about one sample).
  // N·m·s/rad (N·s/m); empty without a brake monitor.
  std::vector<double> brake_gain;
  // The controller's internal model (make_arm's `controller`: the nominal arm): its rigid tree gives the
  // feed-forward and gravity compensation; the notches, shapers, trajectory and brake gains above are its
  // designs. Null: this model is its own.
  std::shared_ptr<const ArmModel> control;
};

// The model the arm's controller holds of it: m.control, or m itself.
inline const ArmModel& arm_controller_model(const ArmModel& m) { return m.control ? *m.control : m; }

// Derives and validates the model. Throws ConfigError naming spec.source and the key: an unknown or
// passive joint given a controller, a joint controlled twice, a waypoint naming an unknown joint or
// out of time order, an unreachable tool target (the IK's failure), a notch or shaper it cannot design.
// `controller`: the controller's internal model (the nominal arm, sweep/paths.hpp), whose designs the
// controller uses instead of this model's (ArmModel::control); nullptr = this model's own.
ArmModel make_arm(const ArmSpec& spec, std::shared_ptr<const ArmModel> controller = nullptr);

// The static equilibrium of the compliant dofs (flexible links, drive twists) under gravity at `pose`
// (nv), every other joint held
// there (statics.hpp with the non-elastic dofs locked). When it does not converge (a link buckling),
// q is `pose` and the result says why.
StaticEquilibriumResult calc_arm_sag(const ArmModel& m, const Eigen::VectorXd& pose);

// The closed loop linearised at rest at q (nv): each electric joint's kp and kd added to K and C, each
// hydraulic joint's actuator as its four states (TreeModeOptions::actuator_*: spool, torque loop, orifice
// flows, oil spring, linearised by central differences with the chambers holding the joint's static load
// at q), the PD commanding its valve loop. make_arm's notches, shapers and substeps and `flexfarm modes`
// take these.
TreeModeOptions make_arm_loop_options(const ArmModel& m, const Eigen::VectorXd& q);
std::vector<TreeMode> calc_arm_closed_loop_modes(const ArmModel& m, const Eigen::VectorXd& q);

// A hydraulic joint's chamber pressures at the start (Pa): p_a, p_b = (p_s + p_t)/2 +- hold_torque / (2 D).
std::pair<double, double> calc_initial_pressures(const ActuatedJoint& a);

// The joint reference of the actuated joints at t (their order), shaped by each joint's shaper:
// r_j(t) = sum_i A_i s_j(t - t_i), and its first two derivatives. `scratch` holds 3 x (actuated
// joints) doubles. Allocation-free.
void eval_arm_reference(const ArmModel& m, double t, double* r, double* rd, double* rdd, double* scratch);

// The rigid arm's gravity torques G(q) and inverse dynamics ID(q, qd, qdd) at the actuated joints
// (the flexible links held straight: their dofs 0), scratch in `ws` (built on m's tree). The simulation
// passes the controller's model (arm_controller_model).
struct ArmFeedforward {
  explicit ArmFeedforward(const Tree& tree);
  TreeWorkspace ws;
  Eigen::VectorXd q, qd, qdd, tau, zero;
};
void calc_arm_feedforward(const ArmModel& m, const double* r, const double* rd, const double* rdd, double* tau_id,
                          double* tau_g, ArmFeedforward& ff);

}  // namespace ff
