// Measurement records of arm models (docs/formats.md, "Measurement record", the arm form): a column per
// actuated joint and per sensor, named by joint or link, read by read_record_csv (record.hpp) like the
// rig's and checked against the model here; made from a model (`flexfarm record ARM.yaml`) and replayed
// on one (`flexfarm compare`, arm_compare.hpp).
//
//   t                                     s, strictly increasing
//   <joint>.ref                           the commanded reference, rad (prismatic m)            required
//   <joint>.angle                         the measured joint coordinate, rad (m)                required
//   <joint>.torque                        the drive's torque on the joint, N·m (N)              optional
//   <joint>.rate                          the measured joint rate, rad/s (m/s)                  optional
//   tool.x, tool.y, tool.z                the tool point in the base frame, m                   optional
//   <link>.deflection_y, .deflection_z    a flexible link's tip from the straight link's tip,   optional
//                                         in the link's root frame, m
// Signs: a joint's angle, rate and torque are positive about (along) its own axis, right-handed, as
// the arm's trace (arm_simulate.hpp) has them.
#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "arm/arm_model.hpp"
#include "arm/arm_simulate.hpp"
#include "validate/record.hpp"

namespace ff {

// Whether a record is in the arm form: a column named `<name>.ref` or `<name>.angle`. The rig's form
// (t, ref, hub_angle, ...) has no such column.
bool is_arm_record(const Record& r);

// An arm record's columns for `m` (after t), in the order `record` writes them: per actuated joint
// .ref, .angle, .rate, .torque; per tool <tool>.x, .y, .z (tool.x, ... for `tool:`); per flexible link
// with elastic dofs (not a one-segment, rigid one) .deflection_y, .deflection_z.
std::vector<std::string> arm_record_columns(const ArmModel& m);

// Whether a column is a tool point's coordinate (<tool>.x, .y or .z of one of m's tools).
bool is_arm_tool_column(const ArmModel& m, const std::string& column);

// The columns compare and diagnose score, in order: every actuated joint's .angle, every one's .torque,
// each tool's .x/.y/.z, the links' deflections; each with its joint ("" for the tools and the links).
std::vector<std::pair<std::string, std::string>> arm_scored_columns(const ArmModel& m);

// A joint's states from the record, what residuals are binned against, appended to `states`:
// `<joint>.velocity` (its .rate, else central differences of its .angle), `<joint>.angle` and, with
// `torque`, `<joint>.torque` when recorded.
void add_arm_joint_states(const Record& r, const std::string& joint, bool torque,
                          std::vector<std::pair<std::string, std::vector<double>>>& states);

// Whether a column holds one value throughout (nothing to fit).
bool is_constant_column(const std::vector<double>& x);

// The unit of an arm record's column ("rad", "m", "N m", ...; "" for an unknown column).
std::string arm_record_unit(const ArmModel& m, const std::string& column);

// Checks a record (read by read_record_csv) against the model: every actuated joint's .ref and .angle
// present; a column `<name>.ref|angle|rate|torque` naming no actuated joint, or
// `<name>.deflection_y|z` naming no flexible link, refused; tool.* other than x, y, z refused. Throws
// ConfigError(record file, line 1, column, message); other columns are read and ignored.
void check_arm_record(const Record& r, const ArmModel& m);

// Standard deviations of the noise `make_arm_record` adds (0: none).
struct ArmRecordNoise {
  double angle = 0.0;     // rad (prismatic m), on every <joint>.angle
  double rate = 0.0;      // rad/s (m/s), on every <joint>.rate
  double torque = 0.0;    // N·m (N), on every <joint>.torque
  double position = 0.0;  // m, on tool.x/y/z and the deflections
};

// The model's samples of its reference trajectory (shapers included) at every controller sample of its
// run, per actuated joint: what a controller following it sees, the input of `record`.
std::vector<std::vector<double>> sample_arm_reference(const ArmModel& m);

// A record made from a model: its closed-loop run, driven as a replay is (the reference sampled at the
// controller rate through ArmRunOptions::reference, so the model replayed on its own noise-free record
// reproduces it exactly), every column of arm_record_columns at every controller sample, each measured
// column (all but .ref) with Gaussian noise of its ArmRecordNoise deviation from the counter-based
// stream of (seed, column index) (kernel/random.hpp; index 1 = the first column after t). Throws
// std::runtime_error when the run fails numerically.
Record make_arm_record(const ArmModel& m, const ArmRecordNoise& noise, std::uint64_t seed);

// The model following a record's references (free run).
struct ArmReplay {
  bool ok = true;               // the run's lane status was ok
  bool resampled = false;       // the record's times are not the controller's samples: see replay_arm_record
  double control_period = 0.0;  // s
  ArmTrace trace;               // the model's run on its controller grid (t from 0)
  // The model's value of every arm_record_columns column at the record's times, by that name.
  std::map<std::string, std::vector<double>> at_record;
};

// A record column's name in an arm trace (arm_simulate.hpp): <joint>.angle is <joint>.q, .rate is .qd,
// the others their own.
std::string arm_trace_name(const std::string& column);

// What a replay of a checked record runs (replay_arm_record's rules below): the time base, each
// actuated joint's reference at every controller sample (ArmRunOptions::reference), and the models
// lasting the record's span and starting at its first references.
struct ArmReplaySetup {
  bool resampled = false;
  std::vector<std::vector<double>> ref;  // (actuated joints) x (controller samples)
  std::vector<ArmModel> lanes;           // one per model
};
ArmReplaySetup prepare_arm_replay(std::span<const ArmModel> models, const Record& r);
// A run's trace on the controller grid as the record's columns (arm_record_columns) at the record's
// times: the trace's samples, or linearly interpolated when `resampled`.
std::map<std::string, std::vector<double>> sample_arm_trace_at_record(const ArmTrace& tr, const ArmModel& m,
                                                                      const Record& r, bool resampled);

// Replays a checked record on a model: the run starts at rest at the model's initial state (when the
// record's first references differ from the model's start, at those references, the flexible links at
// their static sag there), lasts the record's span, and the actuated joints follow the record's .ref
// columns through ArmRunOptions::reference. Time base: when every record time t_k is t_0 + k T to
// within T/1000 (T the model's controller period) sample k is controller sample k; otherwise the
// references are linearly interpolated at t_0 + k T and the model's outputs linearly interpolated back
// at the record's times (`resampled`).
ArmReplay replay_arm_record(const ArmModel& m, const Record& r);
// The same for arms of one shape (explain_arm_shape_mismatch) as lanes of one run: one replay each.
// Throws std::invalid_argument when their shapes differ.
std::vector<ArmReplay> replay_arm_records(std::span<const ArmModel> models, const Record& r);

}  // namespace ff
