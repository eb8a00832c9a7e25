// Linearised modes of the arm about rest: the hub clamped, and the hub in the PID loop.
// x = [q; v], xdot = A x with A = [[0, I], [-M^-1 K, -M^-1 C]], M = M(0) from the composite-rigid-body
// algorithm (Featherstone 2008, Table 6.2). Each eigenvalue lambda gives omega_n = |lambda|,
// zeta = -Re(lambda) / |lambda|.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "kernel/model.hpp"

namespace ff {

struct Mode {
  double omega_n;     // natural frequency, rad/s; 0: a free motion (is_zero_eigenvalue)
  double zeta;        // damping ratio (1 for a real pole)
  bool oscillatory;   // a complex pair (reported once)
  double frequency_hz() const;
};

// The problem's stiffness scale, rad/s: sqrt of the infinity norm of M^-1 K (the block -M^-1 K of the
// state matrix, its sign aside), about its stiffest undamped mode's frequency.
double calc_stiffness_scale(const Eigen::Ref<const Eigen::MatrixXd>& minv_k);

// Whether an eigenvalue of magnitude `omega` (rad/s) is zero to the eigen-solve's resolution, relative to
// the problem's stiffness scale: a free motion (a joint with neither gain nor spring), not a slow or
// unstable mode. An undamped free motion is a double zero eigenvalue, a Jordan block, which round-off
// eps |M^-1 K| in A splits into +-sqrt(eps) x scale (a "grows e-fold in 237 s" pole); 100 times that is
// the threshold, 1.5e-6 x scale. (The largest |lambda| is no scale: the joint dampers' real poles reach
// 1e7 rad/s at N = 96, where 1.5e-6 of them would swallow the beam's first modes.)
bool is_zero_eigenvalue(double omega, double scale);

// Joint-space mass matrix M(q) (N x N), kg·m^2.
Eigen::MatrixXd calc_mass_matrix(const Model& m, const Eigen::VectorXd& q);

// Modes with the hub held still (joint 0 removed), ascending in omega_n.
std::vector<Mode> calc_clamped_modes(const Model& m);
// Modes of the continuous-time closed loop: PD(+I) on the hub angle, load-compensation feed-forward.
std::vector<Mode> calc_closed_loop_modes(const Model& m);
// The closed loop's resonances: its oscillatory modes with zeta < 0.3, ascending, rad/s.
// The robust notch filter places its zeros omega_z1, omega_z2 at the first two.
std::vector<double> calc_closed_loop_resonances(const Model& m);
std::vector<double> calc_resonances(const std::vector<Mode>& closed_loop);

// Fixed-step substeps per control period, from the modes of the clamped and the closed loop.
// RK4: h omega_n <= 1 for every oscillatory mode, h |lambda| <= 2.5 for every real pole (RK4 is
// stable to ~2.78). SDIRK2 (L-stable): accuracy only, h omega_n <= 0.5 for the lightly damped
// modes (zeta < 0.3); the stiff, heavily damped ones decay whatever h. Midpoint (A-stable only): the
// same for the lightly damped modes, and h |lambda| <= 4 for the others, whose numerical amplification
// (1 - z/2) / (1 + z/2), z = h |lambda|, tends to -1 for large z (at 4: -1/3).
int calc_auto_substeps(const Model& m);
int calc_auto_substeps(const std::vector<Mode>& modes, double control_period, Integrator integrator);

// The most fixed steps per controller sample a model may take, given or automatic (the rig's and the
// arm's `simulation.substeps`).
inline constexpr int kMaxSubsteps = 100000;
// Steps per controller sample for h rate <= 1: ceil(rate T), at least 1; kMaxSubsteps + 1 for anything
// beyond kMaxSubsteps (a NaN rate too), so that an absurd rate never overflows the int.
int calc_substeps_for_rate(double rate, double control_period);

}  // namespace ff
