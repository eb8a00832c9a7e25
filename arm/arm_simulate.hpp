// Closed-loop runs of arm models (arm_model.hpp) over lanes: W variants of one shape advanced together
// by the tree kernel (multibody/lanes.hpp, lane_integrators.hpp), every actuated joint's controller at
// its sample rate with the torque held between samples (arm_model.hpp gives the law).
#pragma once

#include <span>
#include <string>
#include <vector>

#include "arm/arm_model.hpp"
#include "kernel/batch.hpp"  // LaneStatus

namespace ff {

// One lane's signals at every controller sample (column 0 is the time `t`, s), sampled at the instant
// before that sample's torque is applied; the torque columns hold the torque applied from it on.
//   <joint>.ref, <joint>.q, <joint>.qd, <joint>.torque    per actuated joint (rad, rad/s, N·m; prismatic m, N)
//   tool.x, tool.y, tool.z, tool.ref_x, tool.ref_y, tool.ref_z   the tool point and where the rigid arm
//                                                        at the reference puts it, base frame, m
//   <link>.deflection_y, <link>.deflection_z             a flexible link's tip from the straight link's
//                                                        tip, in the link's root frame, m
//   <joint>.q_measured, <joint>.qd_measured              per actuated joint, what its controller measured
//                                                        at this sample (joints.NAME.sensors), rad, rad/s
//   <joint>.pressure_a, <joint>.pressure_b               per hydraulic joint, its chamber pressures, Pa
// A hydraulic joint's torque column is its actuator's torque D (p_a - p_b) at the sample (the joint's
// own torque, not the controller's demand, which is the valve loop's command).
struct ArmTrace {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;  // (names) x (samples)
  const std::vector<double>& column(const std::string& name) const;  // throws std::out_of_range
  const std::vector<double>& t() const { return columns.front(); }
};

struct ArmRun {
  std::vector<ArmTrace> traces;      // (W)
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
};

// Why arms a and b cannot share a batch ("" when they can): their trees differ in topology, or their
// actuated joints, rate, duration, substeps, integrator or notch sections differ.
std::string explain_arm_shape_mismatch(const ArmModel& a, const ArmModel& b);

// The trace's column names for an arm.
std::vector<std::string> arm_trace_names(const ArmModel& m);

// Runs every lane to its duration. Throws std::invalid_argument when the lanes' shapes differ.
// A lane whose state stops being finite is frozen with the status kNonfinite (its trace NaN from then).
// keep_q changes only what is kept, never the results (ArmRun::q is stored into memory reserved
// before the first step); `reference` replaces the reference (above).
ArmRun simulate_arms(std::span<const ArmModel> lanes, const ArmRunOptions& options = {});

// Writes a trace as CSV (a header of its names, one row per sample), atomically; reads it back.
void write_arm_trace_csv(const ArmTrace& trace, const std::string& path);
ArmTrace read_arm_trace_csv(const std::string& path);

}  // namespace ff
