// Lanes: W variants of equal shape advanced in lock-step. Every per-lane array is
// structure-of-arrays with the lane innermost, x[j*W + lane], so loops over lanes vectorise.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "kernel/drive.hpp"
#include "kernel/friction.hpp"
#include "kernel/model.hpp"
#include "kernel/notch.hpp"

namespace ff {

// Outcome of one lane (variant). Numerical failure is recorded here, never thrown.
enum class LaneStatus : std::uint8_t { kOk = 0, kNonfinite, kSolverFail };
const char* lane_status_name(LaneStatus s);

// The most lanes one batch may hold.
inline constexpr int kMaxLanes = 256;

// Recorded sensors (kernel/sensors.hpp), in trace order; their noise streams are channels 2, 3, 4
// (0 and 1 are the hub angle and rate).
enum RecordedChannel { kStrainGauge = 0, kTipAccelerometer, kTipPositionSensor, kRecordedChannels };

// The parameters of W models of equal shape, gathered lane-innermost. Immutable once made: nothing
// a run changes lives here (the tip body a payload event changes is BatchState::tip).
struct BatchModel {
  int W = 0;                        // lanes
  int nseg = 0;                     // N, bodies and joints
  int nsections = 0;                // notch biquads per lane (0 = no notch)
  int substeps = 1;                 // fixed-step substeps per control period
  double control_period = 0.0;      // s
  double duration = 0.0;            // s
  std::vector<Model> models;        // the W source models (trajectory, metrics, reporting)
  std::vector<double> body_mass;    // (N x W), kg
  std::vector<double> body_first;   // mass times centre-of-mass offset (N x W), kg·m
  std::vector<double> body_inertia; // about the joint axis (N x W), kg·m^2
                                    // (row N-1, the tip body with its payload, as made: where a run's
                                    // BatchState::tip starts)
  std::vector<double> seg_length;   // (N x W), m
  std::vector<double> joint_k;      // (N x W), N·m/rad, row 0 = 0
  std::vector<double> joint_c;      // (N x W), N·m·s/rad, row 0 = 0
  std::vector<double> joint_k3;     // (N x W), cubic stiffening, N·m/rad^3, row 0 = 0
  std::vector<double> kp, ki, kd;   // (W) PID gains
  std::vector<double> torque_limit; // (W), N·m, +inf when unlimited
  std::vector<double> load_comp;    // (W) load-compensation gain
  std::vector<char> load_pressure;  // (W) 1: load signal n D (p_a - p_b) from the pressures, 0: root bending moment
  std::vector<double> ff_gain;      // (W) gain of the model-based feed-forward
  std::vector<double> notch_coef;   // (5 * nsections x W) biquad coefficients
  std::vector<char> notch_feedback; // (W) 1: the notch filters the measured hub angle, 0: the reference
  std::vector<FrictionMap> friction;  // (W) the hub's friction map (kernel/friction.hpp)
  std::vector<double> hub_offset;   // (W) constant load torque on the hub (hub.torque_offset), N·m
  // Sensors, per channel (0 hub angle, 1 hub rate) and lane: quantum, noise std, delay (samples),
  // hold (controller samples per sensor sample), noise key.
  std::vector<double> sensor_resolution[2], sensor_noise[2];  // (W)
  std::vector<int> sensor_delay[2], sensor_hold[2];           // (W)
  std::vector<std::uint64_t> sensor_key[2];                   // (W)
  int sensor_history = 1;           // ring length: the largest delay + hold
  std::vector<char> expected_readings;  // (W) 1: every sensor gives its expected reading (simulation.expected_readings)
  // Recorded sensors: which ones the lanes have (the same in every lane), then per channel and lane:
  // quantum, noise std, delay (samples), hold (controller samples per sensor sample), noise key.
  bool rec_enabled[kRecordedChannels] = {};
  std::vector<double> rec_resolution[kRecordedChannels], rec_noise[kRecordedChannels];  // (W)
  std::vector<int> rec_delay[kRecordedChannels], rec_hold[kRecordedChannels];           // (W)
  std::vector<std::uint64_t> rec_key[kRecordedChannels];                                // (W)
  int rec_history = 1;              // ring length: the largest delay + hold
  std::vector<int> strain_joint;    // (W) the strain gauge's joint, 1..N-1
  std::vector<double> strain_gain;  // (W) tip deflection per gauge moment, m/(N·m) (calc_strain_tip_gain)
  DriveLayout layout;               // rows of the hub drive's states in BatchState::z
  std::vector<LaneDrive> drive;     // (W) the hub drive's constants (kernel/drive.hpp)
};

// Everything the lanes of one batch must share: what sizes the state and the step loop.
struct BatchShape {
  int nseg = 0;
  int notch_sections = 0;     // 2 order + 1 when the notch is on, else 0
  int substeps = 0;
  double control_period = 0;  // s
  double duration = 0;        // s
  Integrator integrator = Integrator::kRk4;
  int drive_parts = 0;        // bits: hydraulic actuator 1, drive train 2, LuGre friction 4
  int recorded = 0;           // bits: strain gauge 1, tip accelerometer 2, tip position 4
  auto operator<=>(const BatchShape&) const = default;
};
BatchShape batch_shape_of(const Model& m);

// Gathers models of one BatchShape into lanes. Throws std::invalid_argument when shapes differ.
BatchModel make_batch(std::span<const Model> models);

// Controller samples per sample of a sensor channel: controller.rate / rate (1 when rate = 0).
int calc_sensor_hold(const ChannelSpec& ch, double controller_rate);

// The continuous notch filter (seed eq. 6) a model asks for, with its zeros in place.
NotchDesign make_notch_design(const Model& m);

// The tip body's inertial parameters (body N-1: the last segment with its payload, and the hub when
// N = 1), W each, lane innermost: the part of the body table a run changes (payload events pick and
// release at their samples). make_state starts it from the model's row N-1.
struct TipLoad {
  std::vector<double> mass;         // (W), kg
  std::vector<double> first;        // (W) mass times centre-of-mass offset, kg·m
  std::vector<double> inertia;      // (W) about the joint axis, kg·m^2
};

// One body row of the dynamics' inputs: mass, first moment, inertia about the joint axis (W each).
struct BodyRow {
  const double* mass;
  const double* first;
  const double* inertia;
};

// The bodies the dynamics read (a view, nothing owned): bodies 0..N-2 from the model's tables
// (BatchModel::body_*, N x W), the tip body N-1 from a run's TipLoad (or the model's own row N-1).
struct BodyTable {
  int W = 0, nseg = 0;
  const double* mass = nullptr;     // (N x W), rows 0..N-2 read
  const double* first = nullptr;
  const double* inertia = nullptr;
  BodyRow tip{};                    // (W) body N-1
  BodyRow row(int i) const {
    if (i == nseg - 1) return tip;
    const std::size_t o = static_cast<std::size_t>(i) * W;
    return {mass + o, first + o, inertia + o};
  }
};

// The model's bodies with `tip` as the tip body.
BodyTable make_body_table(const BatchModel& bm, const TipLoad& tip);
// The model's bodies as made (its own tip row): for callers without a run's state.
BodyTable make_body_table(const BatchModel& bm);

// Everything that changes during a run, and nothing else: a copy of it is a checkpoint the same
// model resumes from bit for bit (the fixed-step integrators; CVODE restarts at every sample anyway).
// The payload events already applied follow from `sample` (kernel/simulate.cpp), so they need no
// counter of their own.
struct BatchState {
  double t = 0.0;                   // s
  long sample = 0;                  // controller samples taken
  std::vector<double> q;            // (N x W) q0 hub angle, qi relative joint angles, rad
  std::vector<double> v;            // (N x W) rates, rad/s
  std::vector<double> z;            // (nz x W) hub drive states (kernel/drive.hpp)
  std::vector<double> tau;          // (W) torque demand held until the next sample, N·m
  std::vector<double> integral;     // (W) integral of the tracking error, rad·s
  std::vector<double> notch_state;  // (2 * nsections x W)
  std::vector<double> measured[2];  // (sensor_history x W) ring of past measurements per channel
  std::vector<double> recorded[kRecordedChannels];  // (rec_history x W) rings of the enabled recorded sensors
  std::vector<double> a_prev;       // (N x W) the last step's accelerations, rad/s^2: SDIRK2's and the
                                    // midpoint rule's velocity predictor (zero before the first step)
  TipLoad tip;                      // the tip body now (payload events change it), W each
  std::vector<LaneStatus> status;   // (W)
};

BatchState make_state(const BatchModel& bm);

// Copies everything of lane `from` that changes during a run (plant q, v, drive z, held torque,
// integral, notch, sensor rings, the integrators' predictor, the tip load, status) into lane `to`:
// lane `to` then continues bit for bit as lane `from` would (the fixed-step integrators; CVODE keeps
// its own history; payload events still to come are lane `to`'s model's). Allocates nothing.
void copy_lane(const BatchModel& bm, BatchState& s, int from, int to);

// Scratch for the articulated-body algorithm and the integrators, sized once: nothing is
// allocated while stepping.
struct Workspace {
  // articulated-body algorithm, per body (N x W)
  std::vector<double> cq, sq;                         // cos, sin of the joint angle
  std::vector<double> vw, vx, vy;                     // body spatial velocity
  std::vector<double> cy, cz;                         // velocity-product acceleration (0, cy, cz)
  std::vector<double> i00, i01, i02, i11, i12, i22;   // articulated inertia (symmetric 3x3)
  std::vector<double> p0, p1, p2;                     // articulated bias force
  std::vector<double> d, u;                           // joint-space inertia and force
  std::vector<double> a0, a1, a2;                     // body spatial acceleration
  std::vector<double> armature;                       // extra joint-space inertia (N x W)
  double armature_gh = 0.0;                           // the h gamma `armature` was made for, s
  // fixed-step integrator stages, (N x W) each
  std::vector<double> q1, v1, kq[4], kv[4];
  std::vector<double> tau_joint;                      // (N x W) joint torques
  std::vector<double> tau_hub;                        // (W) hub drive torque, friction included
  // hub drive states in the integrators, (nz x W) each
  std::vector<double> z1, kz[4], zdot, zpert, znew;
  std::vector<double> zjac;                           // (W x nz x nz) Newton matrices of the drive's implicit stages
};

Workspace make_workspace(const BatchModel& bm);

}  // namespace ff
