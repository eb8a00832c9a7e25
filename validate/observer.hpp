// An observer on the model: it runs along a measurement record and estimates the model's plant state
// x = [q; v; z] (kernel/batch.hpp: joint angles, rates, hub-drive states; nx = 2N + nz) at every
// controller sample, and k-step predictions restart from that estimate (replay.hpp, compare.hpp).
//
// Method: a steady-state (constant-gain) Kalman filter applied to the nonlinear model, an extended
// observer in predictor-corrector form (Anderson & Moore, "Optimal Filtering", 1979, ch. 4 and 8):
//   predict  x(k|k-1) = f(x(k-1|k-1), u)       the model itself over one controller sample: in closed
//                                               loop the record's ref drives the model's controller
//                                               (closed on the estimate), in open loop the record's
//                                               hub torque drives the plant;
//   correct  x(k|k)   = x(k|k-1) + L (y_k - h(x(k|k-1)))        at every sample with a measurement,
//   L = P C^T (C P C^T + R)^-1,  P = A P A^T - A P C^T (C P C^T + R)^-1 C P A^T + Q  (the filter DARE),
// A = df/dx and C = dh/dx by central differences of the batch kernel at the model's initial state
// (the arm at rest at the record's start); the DARE is solved by the structure-preserving doubling
// algorithm (Chu, Fan, Lin & Wang, Int. J. Control 77, 2004; convergence: Lin & Xu, SIAM J. Matrix
// Anal. Appl. 28, 2006). Why this method rather than an EKF or a UKF:
//   - the arm turns in a horizontal plane, so its dynamics do not depend on the hub angle, and the
//     beam's joint angles stay at milliradians: the model linearised at rest holds along the whole
//     record, and a time-varying Kalman gain would settle to this constant one anyway;
//   - it is the predictor system-identification tools use: MATLAB's predict/compare and SIPPY run the
//     model's steady-state Kalman predictor (the innovations form with a constant gain K);
//   - the observer is the model, one more lane of the batch kernel with a correction at each sample:
//     about the cost of one replay, deterministic; an EKF or UKF would need 2 nx + 1 lanes and a
//     covariance update at every sample.
// Limits: the gain is designed on the model's smooth part (static Coulomb and Stribeck friction,
// backlash, sensor quantisation, noise and delays left out of the linearisation; the controller's own
// states held); the correction acts on the full nonlinear model.
//
// Measurements y: hub_angle always; hub_rate and tip_deflection when the record has them; hub_torque
// only in closed loop and only when the model's actuator torque is a function of its drive states
// (hydraulics: n D (p_a - p_b); a drive train: its transmitted torque). Without a drive the recorded
// torque is the controller's output, computed from the hub angle and rate already measured through
// the model's own control law: using it would count that information twice and let an error in the
// control law bias the state. In open loop the record's torque is the input, not a measurement.
//
// Noise: R = diag(var(second differences of the channel) / 6) per channel (white noise e of variance
// s^2 gives var(e_{k+1} - 2 e_k + e_{k-1}) = 6 s^2; a signal smooth at the record's rate adds
// almost nothing). Q: white acceleration on every joint coordinate, piecewise constant over a
// controller sample (Bar-Shalom, Li & Kirubarajan, "Estimation with Applications to Tracking and
// Navigation", 2001, sec. 6.3.3): per joint [[T^4/4, T^3/2], [T^3/2, T^2]] sigma_a^2; the drive states
// get none of their own. A record sampled every m controller samples is corrected every m samples,
// with A^m and Q_m = sum_{j<m} A^j Q A^jT in the DARE.
#pragma once

#include <Eigen/Dense>
#include <span>
#include <string>
#include <vector>

#include "kernel/batch.hpp"
#include "kernel/model.hpp"
#include "kernel/simulate.hpp"
#include "validate/record.hpp"
#include "validate/replay.hpp"

namespace ff {

// sigma_a of the process noise, rad/s^2 (hub and beam joints alike): the model's one-sample
// acceleration error the observer allows for (`flexfarm compare --process-noise`).
inline constexpr double kDefaultProcessNoise = 0.005;

struct ObserverOptions {
  double process_noise = kDefaultProcessNoise;  // sigma_a, rad/s^2 (> 0)
  std::vector<double> initial_state;            // x(0|-1), nx values; empty: the model's own initial state
};

// The record channels the observer measures for `mode` (closed or open loop), in this order:
// hub_angle, hub_rate, tip_deflection, hub_torque (those that apply, see above).
std::vector<std::string> observer_channels(const Model& m, const Record& r, ReplayMode mode);

// var(y_{k+1} - 2 y_k + y_{k-1}) / 6 (mean square of the second differences over 6): the variance of
// white noise on a smooth signal, in y's unit squared. 0 with fewer than 3 samples.
double calc_white_noise_variance(const std::vector<double>& y);

// The stabilising solution of the filter DARE above, by doubling: with A_0 = A^T, G_0 = C^T R^-1 C,
// H_0 = Q, W = I + G_i H_i:
//   A_{i+1} = A_i W^-1 A_i,  G_{i+1} = G_i + A_i W^-1 G_i A_i^T,  H_{i+1} = H_i + A_i^T H_i W^-1 A_i,
// H_i -> P quadratically. `ok` is false when it does not converge or P does not solve the DARE to
// 1e-8 (relative, Frobenius); R must be positive definite.
struct RiccatiSolution {
  bool ok = false;
  Eigen::MatrixXd P;
  int iterations = 0;
  double residual = 0.0;  // |P - DARE(P)| / |P|
};
RiccatiSolution solve_filter_dare(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, const Eigen::MatrixXd& Q,
                                  const Eigen::MatrixXd& R);

// The observer of one model on one record: its linearisation, noise and gain.
struct ObserverDesign {
  bool ok = false;
  std::string message;                // why not, when !ok
  std::vector<std::string> channels;  // measured, the rows of C and the columns of L
  std::vector<double> noise_std;      // sqrt(R_ii), channel units
  double process_noise = 0.0;         // sigma_a, rad/s^2
  int period = 1;                     // controller samples between measurements
  Eigen::MatrixXd A, C;               // over one period (A^m); C (ny x nx)
  Eigen::MatrixXd Q, R, P, L;         // per period; P: prior covariance; L (nx x ny)
  double pole_radius = 0.0;           // spectral radius of (I - L C) A: the linearised estimation error
                                      // shrinks by at least about this factor per period
  int doublings = 0;                  // steps of the DARE's doubling algorithm
};

// Pieces of the design, shared with the arm's observer (validate/arm_observer.hpp):
// the record sample measured at each of n controller samples k (the first within T/4 of t0 + k T), or -1;
int calc_measurement_period(const std::vector<long>& at);  // the median spacing of those, at least 1
std::vector<long> find_measured_samples(const Record& r, double T, long n);
// Q over one controller sample T for x = [q (joints); v (joints); the rest] with white acceleration of
// std sigma_a on every joint (above), nx x nx; `continuous`: the acceleration white in continuous time
// with the same rate variance per sample (Bar-Shalom et al. 2001, sec. 6.2.2): [[T^4/3, T^3/2],
// [T^3/2, T^2]] sigma_a^2, full rank, the angle keeping sigma_a^2 T^4 / 12 of its own;
Eigen::MatrixXd calc_process_noise(int joints, int nx, double T, double sigma_a, bool continuous = false);
// d.R and d.noise_std for the record's columns d.channels (above);
void set_measurement_noise(const Record& r, ObserverDesign& d);
// the central-difference steps delta_i = 1e-6 max(1, |x0_i|) (state units), and the derivative from
// values at x0 +- delta_i e_i (columns 2i and 2i + 1 of f): (f_2i - f_2i+1) / (2 delta_i);
Eigen::VectorXd make_difference_steps(const Eigen::VectorXd& x0);
Eigen::MatrixXd calc_central_differences(const Eigen::MatrixXd& f, const Eigen::VectorXd& delta);
// the gain from the linearisation over one controller sample (A1, C; process noise Q1 a sample) and
// d.R, corrected every d.period samples: sets d.A (A1^m), d.C, d.Q (Q_m), d.P, d.L, d.doublings,
// d.pole_radius, d.ok and d.message.
void design_steady_gain(const Eigen::MatrixXd& A1, const Eigen::MatrixXd& C, const Eigen::MatrixXd& Q1, ObserverDesign& d);

// Designs the observer of model m (any span: it is set for the record) for the record in `mode`
// (closed or open loop; std::invalid_argument for inverse dynamics). A numerical failure is a result
// (ok = false, message).
ObserverDesign design_observer(const Model& m, const Record& r, ReplayMode mode, const ObserverOptions& options = {});

// The observer's run on each model (lanes of one batch, like replay()), and, with k_ahead > 0, the
// k-step prediction: every k_ahead controller samples (k = 0, K, 2K ...) a prediction lane takes the
// observer's state x(k|k-1) (the estimate from the measurements before sample k: all plant states,
// and the model's controller, notch and sensor states as the observer's model had them) and runs
// k_ahead samples without correction (in closed loop the model's controller closed on the model's own
// simulated measurements), so each predicted sample is 1 to k_ahead samples ahead of the last
// measurement used.
struct ObserverRun {
  int nx = 0;                                 // 2N + nz
  std::vector<ObserverDesign> design;         // per model
  std::vector<Trace> estimate;                // per model: the channels of x(k|k) at every controller sample
  std::vector<Trace> k_step;                  // per model (k_ahead > 0): the k-step predictions
  std::vector<LaneStatus> estimate_status, k_step_status;
  std::vector<std::vector<double>> state;     // per model: x(k|k), state[l][k * nx + i]
  bool ok(std::size_t l) const { return design[l].ok && estimate_status[l] == LaneStatus::kOk; }
  bool k_step_ok(std::size_t l) const { return ok(l) && l < k_step_status.size() && k_step_status[l] == LaneStatus::kOk; }
};
ObserverRun run_observer(std::span<const Model> models, const Record& r, ReplayMode mode, int k_ahead = 0,
                         const ObserverOptions& options = {});

}  // namespace ff
