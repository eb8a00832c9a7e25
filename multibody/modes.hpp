// Linearised modes of a kinematic tree (multibody/tree.hpp) about a pose q0 at rest (qd = 0):
//   M x'' + C x' + K x = 0,  M = M(q0) (CRBA, armature included), K = dg/dq + diag(k) at q0
//   (calc_static_stiffness: the springs and the gravity stiffness), C = diag(c) (the joint dampers),
// each plus an optional caller-given matrix (a closed loop's PD gains on the actuated dofs). Locked
// dofs (clamped joints) are removed. Undamped (C = 0, no actuator states): the symmetric-definite
// problem K v = w^2 M v; damped: the eigenvalues lambda of A = [[0, I], [-M^-1 K, -M^-1 C]] (with
// actuator states: TreeModeOptions::actuator_*), omega_n = |lambda|,
// zeta = -Re(lambda) / |lambda|, as kernel/modes.hpp does for the reference rig.
//
// K is symmetric at an equilibrium; away from one (gravity not balanced at q0) dg/dq is not, and only
// its symmetric part enters the undamped problem (the damped one takes K as it is).
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "multibody/tree.hpp"

namespace ff {

struct TreeModeOptions {
  std::vector<int> locked_dofs;     // held still (removed from the problem)
  Eigen::MatrixXd extra_stiffness;  // (nv x nv) added to K, N·m/rad; empty = none
  Eigen::MatrixXd extra_damping;    // (nv x nv) added to C, N·m·s/rad; empty = none
  double fd_step = 1e-6;            // the gravity stiffness's central-difference step (calc_static_stiffness)
  // First-order states z coupled to the tree (actuators, linearised at q0; all four empty = none): the
  // generalised force per unit z, B = dtau/dz (nv x nz), and the states' rates
  // z' = Zq dq + Zv dqd + Zz dz (nz x nv, nz x nv, nz x nz). The problem is then x' = A x,
  // x = [q; qd; z], A = [[0, I, 0], [-M^-1 K, -M^-1 C, M^-1 B], [Zq, Zv, Zz]] (a locked dof's rows and
  // columns removed); a mode's shape is its q block.
  Eigen::MatrixXd actuator_force, actuator_q, actuator_qd, actuator_z;
};

struct TreeMode {
  double omega_n = 0.0;    // rad/s (for a real pole: |lambda|; for an unstable static mode: sqrt(-w^2)); 0: a
                           // free motion, zero to the solve's resolution (kernel/modes.hpp is_zero_eigenvalue)
  double zeta = 0.0;       // damping ratio; 1 for a stable real pole, -1 for an unstable one
  bool oscillatory = true; // a complex pair (reported once), or an undamped mode with w^2 > 0
  Eigen::VectorXd shape;   // (nv) joint coordinates, zero at the locked dofs, largest |entry| = 1 and positive
  bool moves = true;       // false: the eigenvector's q and qd blocks are below 1e-6 of it (an actuator state
                           // alone, as a valve-controlled actuator's mean chamber pressure)
  double frequency_hz() const;
};

// The modes, ascending in omega_n. Throws std::invalid_argument on q0 of the wrong size, a locked
// dof out of range or twice, extra matrices of the wrong size, and a non-finite M or K.
std::vector<TreeMode> calc_tree_modes(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q0,
                                      const TreeModeOptions& options = {});

}  // namespace ff
