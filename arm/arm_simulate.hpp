// Closed-loop runs of arm models (arm_model.hpp) over lanes: W variants of one shape advanced together
// by the tree kernel (multibody/lanes.hpp, lane_integrators.hpp), every actuated joint's controller at
// its sample rate with the torque held between samples (arm_model.hpp gives the law).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "arm/arm_model.hpp"
#include "kernel/batch.hpp"  // LaneStatus
#include "multibody/lane_integrators.hpp"
#include "multibody/tree_cvode.hpp"

namespace ff {

class OnlineArmRun;  // arm_online_metrics.hpp

// One lane's signals at every controller sample (column 0 is the time `t`, s), sampled at the instant
// before that sample's torque is applied; the torque columns hold the torque applied from it on.
//   <joint>.ref, <joint>.q, <joint>.qd, <joint>.torque    per actuated joint (rad, rad/s, N·m; prismatic m, N)
//   tool.x, tool.y, tool.z, tool.ref_x, tool.ref_y, tool.ref_z   the tool point and where the rigid arm
//                                                        at the reference puts it, base frame, m; per
//                                                        tool, named as it is ("tool" for `tool:`)
//   <link>.deflection_y, <link>.deflection_z             a flexible link's tip from the straight link's
//                                                        tip, in the link's root frame, m
//   <joint>.q_measured, <joint>.qd_measured              per actuated joint, what its controller measured
//                                                        at this sample (joints.NAME.sensors), rad, rad/s
//   <joint>.pressure_a, <joint>.pressure_b               per hydraulic joint, its chamber pressures, Pa
//   <monitor>.tripped                                    per safety monitor (`monitors:`), 0 before its
//                                                        trip, 1 from the sample it tripped at on
// A hydraulic joint's torque column is its actuator's torque D (p_a - p_b) at the sample (the joint's
// own torque, not the controller's demand, which is the valve loop's command).
struct ArmTrace {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;  // (names) x (samples)
  const std::vector<double>& column(const std::string& name) const;  // throws std::out_of_range
  const std::vector<double>& t() const { return columns.front(); }
};

struct ArmRun {
  std::vector<ArmTrace> traces;      // (W); empty with ArmRunOptions::online
  std::vector<LaneStatus> status;    // (W)
  // With ArmRunOptions::keep_q, each lane's full joint state at every sample: q[l] is nv x samples,
  // column k the coordinates (tree dof order: actuated, passive and elastic) at the trace's sample k
  // (the same instant as its row k), NaN from the sample a failed lane went non-finite. Empty without.
  std::vector<Eigen::MatrixXd> q;    // (W) or empty
};

struct ArmRunOptions {
  bool keep_q = false;               // fill ArmRun::q (for drawing the arm: plotting/animate3d.hpp)
  // Replay of a measurement record (validate/arm_record.hpp). When set, the reference of actuated joint j
  // (m.actuated's order) at controller sample k (t = k T) is (*reference)[j][k], the last value held past
  // the end, in every lane, in place of the trajectory and its shapers; the feed-forward's r' and r'' are
  // its central differences (r[k+1] - r[k-1]) / 2T and (r[k+1] - 2 r[k] + r[k-1]) / T^2, indices clamped
  // to the samples (at rest before the first and after the last). Its size must be the actuated joints',
  // each non-empty (std::invalid_argument otherwise). Unlike keep_q, it changes the results.
  const std::vector<std::vector<double>>* reference = nullptr;
  // The lanes' metrics accumulated while they run (one OnlineArmRun per lane, made from its model; the
  // caller takes result(status) after): each lane's row is fed at every sample instead of stored, and
  // ArmRun::traces stays empty. Its size must be the lanes' (std::invalid_argument otherwise).
  std::vector<OnlineArmRun>* online = nullptr;
};

// Why arms a and b cannot share a batch ("" when they can): their trees differ in topology, or their
// actuated joints, rate, duration, substeps, integrator or notch sections differ.
std::string explain_arm_shape_mismatch(const ArmModel& a, const ArmModel& b);

// The trace's column names for an arm.
std::vector<std::string> arm_trace_names(const ArmModel& m);

// Runs every lane to its duration. Throws std::invalid_argument when the lanes' shapes differ.
// A lane whose state stops being finite is frozen with the status kNonfinite (its trace NaN from then).
// keep_q and online change only what is kept, never the results (ArmRun::q is stored into memory
// reserved before the first step); `reference` replaces the reference (above).
ArmRun simulate_arms(std::span<const ArmModel> lanes, const ArmRunOptions& options = {});

// The sample loop of simulate_arms one controller sample at a time, for callers that act between
// samples (the observer of validate/arm_observer.hpp reads the outputs, corrects the plant state and
// copies lanes). simulate_arms is, per sample k: step_arm_controllers(k), the trace's row k from `row`,
// then step_arm_plant(k) (none after the last sample). Made once by make_arm_lanes (the same checks and
// initial state as simulate_arms); stepping allocates nothing.
struct ArmLanes {
  std::span<const ArmModel> models;  // (W) the caller's: they must outlive this
  const std::vector<std::vector<double>>* reference = nullptr;  // ArmRunOptions::reference
  int W = 0, na = 0, nv = 0, nh = 0;
  long samples = 0;                  // controller samples of the models' duration
  double T = 0.0;                    // s, the controller's sample time
  TreeLanes tl;
  TreeLanesState s;                  // the plant: q, qd, a_prev (nv x W), z (nz x W)
  std::vector<LaneStatus> status;    // (W)
  std::vector<std::string> names;    // the trace's columns (arm_trace_names)
  std::vector<double> row;           // (names x W) the outputs at the last sample stepped, [c * W + l]
  // The rest is the loop's own: the controllers' states (joint j, lane l at [j * W + l]), the sensors'
  // rings of past readings (H x W per joint), scratch.
  std::vector<int> hyd_joints;       // actuated joint index of hydraulic actuator a
  std::vector<double> z0;            // the actuators' initial states (a failed lane's reset)
  TreeStepWorkspace ws;
  std::unique_ptr<TreeCvode> cvode;  // with a CVODE integrator
  std::vector<char> cvode_ok;
  std::vector<double> integral, tau_held;
  std::vector<std::vector<double>> notch_coef, notch_state;  // per joint (lanes innermost)
  std::vector<double> notch_in, notch_out;                   // (W)
  int H = 1;
  std::vector<double> q_meas, qd_meas;
  std::vector<std::vector<double>> ring_q, ring_qd;
  std::vector<double> r, rd, rdd, scratch, tau_id, tau_g, e, tau_applied, kin;
  std::vector<ArmFeedforward> ff;
  std::vector<Pose> poses;
  Eigen::VectorXd q_lane, q_ref;
  // The safety monitors (ArmModel::monitors; monitor i, lane l at [i * W + l]): evaluated at every sample
  // from the outputs row before the control law. The first monitor to trip whose action is not `record`
  // acts, from act_sample on (its trip sample plus its delay).
  int nmon = 0;
  std::vector<double> tripped;       // (nmon x W) 0, then 1 from the trip on
  std::vector<double> tool_prev;     // (3 x tools x W) each tool point at the previous sample (tool_speed)
  std::vector<int> act_monitor;      // (W) the acting monitor, -1 none
  std::vector<long> act_sample;      // (W) the sample its action starts at
  std::vector<double> act_r0, act_v0;  // (na x W) each joint's reference and its rate there
};

// The lanes at their initial state, sample 0 next. Throws std::invalid_argument as simulate_arms does.
ArmLanes make_arm_lanes(std::span<const ArmModel> lanes, const ArmRunOptions& options = {});
// Controller samples of an arm's run: floor(duration / T) + 1.
long calc_arm_samples(const ArmModel& m);
// Sample k (t = k T) of the controllers: the sensors read the plant, calc_arm_outputs puts the plant's
// columns in `row`, the safety monitors trip from them (a hold or stop then replaces the reference, a
// brake the control law), the reference, notch and control law give the torque held until the next
// sample; `row` then holds every trace column at sample k.
void step_arm_controllers(ArmLanes& a, long k);
// The columns of `row` that are functions of the plant state alone (every <joint>.q and .qd, a
// hydraulic joint's .torque and pressures, tool.x/y/z, the deflections, the clearances), from the state
// now; NaN kinematics in a failed lane. step_arm_controllers calls it first.
void calc_arm_outputs(ArmLanes& a);
// The plant from sample k to k + 1 with the held torques; a lane gone non-finite (or whose solver
// failed) is frozen at rest with its status set.
void step_arm_plant(ArmLanes& a, long k);
// The plant state x = [q; qd; z] of lane l (nv, nv, nz rows): 2 nv + nz values.
int calc_arm_state_size(const ArmLanes& a);
void get_arm_state(const ArmLanes& a, int l, double* x);
void set_arm_state(ArmLanes& a, int l, const double* x);
// Lane `from` of a into lane `to` of b (lanes of one shape: the same tree, joints and sensor rings;
// std::invalid_argument otherwise): the plant state, the integrator's predictor, the controllers'
// integral, held torque, notch states and sensor rings, the status. Lane `to` then continues as
// lane `from` would with b's model (CVODE starts its history anew). Allocates nothing.
void copy_arm_lane(const ArmLanes& a, int from, ArmLanes& b, int to);

// A trace of the lanes' columns and samples (zeros); lane l's `row` stored as its sample k; after a run,
// a failed lane's trace made NaN from the sample it failed at (simulate_arms's traces are these).
ArmTrace make_arm_trace(const ArmLanes& a);
void store_arm_row(const ArmLanes& a, int l, long k, ArmTrace& tr);
void mark_arm_trace_failure(const ArmLanes& a, ArmTrace& tr);

// Writes a trace as CSV (a header of its names, one row per sample), atomically; reads it back.
void write_arm_trace_csv(const ArmTrace& trace, const std::string& path);
ArmTrace read_arm_trace_csv(const std::string& path);

}  // namespace ff
