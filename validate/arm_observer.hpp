// An observer on an arm model (arm/arm_model.hpp): it runs along an arm measurement record
// (arm_record.hpp) and estimates the arm's plant state x = [q; qd; z] at every controller sample (q,
// qd: every dof of the tree, nv each: the actuated joints, passive joints, flexible-link cells, drive
// twists; z: TreeLanesState::z, the actuators' states, taken as opaque rows), and k-step predictions
// restart from that estimate (arm_compare.hpp), as the reference rig's observer does (observer.hpp).
// The controllers' states (integral, held torque, notch, sensor rings) are not estimated: the observer
// lane's controllers run on the corrected state, and a prediction takes them as that lane has them.
//
// Method: an extended Kalman filter in predictor-corrector form whose gain is the steady-state gain of
// the model linearised at the current estimate, re-designed every `relinearise` seconds (a piecewise
// constant gain; Anderson & Moore, "Optimal Filtering", 1979, ch. 4 and 8; Simon, "Optimal State
// Estimation", 2006, sec. 13.2):
//   predict  x(k|k-1) = f(x(k-1|k-1), r_k-1)   the model over one controller sample, its controllers
//                                               following the record's references (closed loop);
//   correct  x(k|k)   = x(k|k-1) + L_k (y_k - h(x(k|k-1)))    at every sample with a measurement;
//   every n samples (n T = relinearise, and at k = 0): A = df/dx and C = dh/dx at x(k|k-1) by central
//   differences, each perturbed state one lane of the tree kernel (multibody/lanes.hpp: 2 nx lanes
//   stepped one controller sample from copies of the observer's lane, its controllers' states
//   included), and L = P C^T (C P C^T + R)^-1 from the filter DARE of (A, C, Q, R) solved by doubling
//   (solve_filter_dare, observer.hpp); L held until the next linearisation.
// Why this method:
//   - a 3-D arm under gravity moves through poses: its inertia, gravity stiffness and above all the
//     map from the joints and cells to the tool point and the links' deflections in the base frame
//     (tool.x/y/z rotate with the shoulder) change along the record, so the rig's one gain at the start
//     pose is wrong once the arm has turned; re-linearising at the estimate follows them;
//   - a full EKF would propagate P through a Jacobian at every sample (2 nx lanes and an nx^3 update
//     per sample); the steady-state gain of the local linearisation is the limit that recursion
//     reaches while the pose changes slowly against the observer's time constant (tens of samples),
//     at 2 nx lanes for one sample and one DARE per re-linearisation;
//   - it is the rig's observer (and the innovations-form predictor of system-identification tools)
//     when the pose does not change: the same noise model and Riccati solver;
//   - deterministic: the lanes are independent, so a model's estimate has the same bits whatever the
//     other models and lanes run beside it.
// Limits: the gain is designed on the model's smooth part (static Coulomb friction and stiction and
// the sensors' quantisation left out of the linearisation; the controllers' own states held over the
// sample); between re-linearisations the gain is the last pose's; the time-varying error system is not
// proven stable (each frozen one is: pole_radius < 1). A linearisation that fails keeps the last gain
// (counted, `failed`); the observer corrects from the first gain on. With a CVODE model the central
// differences see the integrator's tolerances.
//
// Measurements y (those the record has, none constant over it): every actuated joint's .angle always;
// its .rate; its .torque only for a hydraulic joint (the actuator's D (p_a - p_b), a function of z: an
// electric joint's recorded torque is its controller's output, computed from the angles and rates
// already measured through the model's own control law, which would count them twice and let an
// error in the control law bias the state, as the rig's rule); tool.x/y/z and the links' deflections.
// Noise: R per channel as observer.hpp's (the variance of its second differences / 6), at least
// (1e-8 unit)^2 (below any real sensor; a noise-free record's smooth channels would give 1e-22).
// Q: white acceleration sigma_a on every tree dof, none of its own on z, but white in continuous time
// (Bar-Shalom, Li & Kirubarajan 2001, sec. 6.2.2: per dof [[T^4/3, T^3/2], [T^3/2, T^2]] sigma_a^2)
// where the rig's is piecewise constant over the sample (rank one per dof): an arm record measures
// rates and angles both, and under a rank-one Q a rate measured almost exactly tells the filter the
// angle as well, so an angle error (a wrong start) decayed at the pole 0.999 (arm6 at 1 kHz, noise-free
// record); the continuous model leaves the angle sigma_a^2 T^4 / 12 of its own and the same error is
// gone within 20 ms. The DARE is solved on the problem balanced by sqrt(Q_ii) and sqrt(R_cc) (angles,
// rates and metres differ by ten orders of magnitude in their noise, and the doubling's tolerances are
// relative to |P|). A record sampled every m controller samples is corrected every m samples.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "arm/arm_model.hpp"
#include "arm/arm_simulate.hpp"
#include "validate/observer.hpp"
#include "validate/record.hpp"

namespace ff {

// Seconds between the arm observer's linearisations (`flexfarm compare --relinearise`).
inline constexpr double kDefaultRelinearise = 0.1;
// sigma_a of the arm observer's process noise, rad/s^2 (`flexfarm compare --process-noise` on an arm):
// larger than the rig's (kDefaultProcessNoise) because an arm model's errors in acceleration are: a
// hidden Coulomb torque of 0.15 N m at the two-link arm's elbow (0.09 kg m^2) is 1.7 rad/s^2. At the
// rig's 0.005 the observer on that record corrected so little that its one-step prediction fitted the
// elbow angle to 95.9 % (the free run 95.3 %); at 1, to 99.87 % (tests/validate/arm_observer_test.cpp).
inline constexpr double kDefaultArmProcessNoise = 1.0;

struct ArmObserverOptions {
  double process_noise = kDefaultArmProcessNoise;  // sigma_a, rad/s^2 (prismatic m/s^2) on every tree dof (> 0)
  double relinearise = kDefaultRelinearise;     // s between linearisations (> 0; at least every sample)
  std::vector<double> initial_state;            // x(0|-1), nx values; empty: the replay's start state
};

// The record channels the observer measures for arm m (above), in this order: per actuated joint
// .angle, .rate, .torque (hydraulic), then tool.x/y/z, then the links' deflections.
std::vector<std::string> arm_observer_channels(const ArmModel& m, const Record& r);

// The observer of one model on one record.
struct ArmObserverDesign {
  bool ok = false;                    // the gain at the record's start was designed
  std::string message;                // why not, or which later linearisations failed
  std::vector<std::string> channels;  // measured: the rows of C, the columns of L
  std::vector<double> noise_std;      // sqrt(R_ii), channel units
  double process_noise = 0.0;         // sigma_a
  int period = 1;                     // controller samples between measurements
  int relinearise = 1;                // controller samples between linearisations
  int gains = 0;                      // gains designed
  int failed = 0;                     // linearisations that failed (the last gain kept)
  double pole_radius = 0.0;           // the largest spectral radius of (I - L C) A over the gains
  int doublings = 0;                  // the most DARE doublings any gain took
};

// The observer on each model (lanes of one run, the models of one shape, explain_arm_shape_mismatch)
// and, with k_ahead > 0, the k-step prediction: every k_ahead controller samples (k = 0, K, 2K ...) a
// prediction lane takes the observer's lane before its correction at k (x(k|k-1) and its controllers'
// states) and runs k_ahead samples uncorrected, so each predicted sample is 1 to k_ahead samples ahead
// of the last measurement used. Throws std::invalid_argument on k_ahead < 0, bad options or shapes.
struct ArmObserverRun {
  int nx = 0;                                 // 2 nv + nz
  bool resampled = false;                     // the record is not on the controller grid (replay_arm_record)
  std::vector<ArmObserverDesign> design;      // per model
  std::vector<ArmTrace> estimate;             // per model: its trace at x(k|k), controller grid
  std::vector<ArmTrace> k_step;               // per model (k_ahead > 0): the k-step predictions
  std::vector<LaneStatus> estimate_status, k_step_status;
  std::vector<std::vector<double>> state;     // per model: x(k|k), state[l][k * nx + i]
  bool ok(std::size_t l) const { return design[l].ok && estimate_status[l] == LaneStatus::kOk; }
  bool k_step_ok(std::size_t l) const { return ok(l) && l < k_step_status.size() && k_step_status[l] == LaneStatus::kOk; }
};
ArmObserverRun run_arm_observer(std::span<const ArmModel> models, const Record& r, int k_ahead = 0,
                                const ArmObserverOptions& options = {});

}  // namespace ff
