// SUNDIALS CVODE (BDF, Newton iteration) over the lanes of multibody/lanes.hpp: the variable-step
// reference integrator for kinematic trees, with the calling pattern of the fixed-step ones
// (multibody/lane_integrators.hpp): every lane advanced over one interval with the generalised force
// held (the controller's zero-order hold), the joints' springs and dampers acting as well.
//
// Each lane is an independent ODE y = [q; qd] (2 nv), ydot = [qd; qdd] with
// qdd = calc_forward_dynamics(tree_l, q, qd, tau) with tau the lane's own compute_tree_actuator_forces
// and compute_tree_passive_forces (multibody/lanes.hpp, on extract_tree_lane's one-lane copy: springs,
// dampers, joint friction, nonlinear drive trains): the scalar ABA of multibody/algorithms.hpp on the
// lane's own tree. With actuator states (TreeLanes::nz: hydraulic actuators, 4 each, then LuGre
// bristles, 1 each) they follow: y = [q; qd; z], their rates from kernel/drive.hpp's
// eval_hydraulic_actuator and kernel/friction.hpp's calc_lugre_bristle_rate, their torque at their
// dofs (a hydraulic dof's held force is its command). Each lane owns its SUNContext, vector,
// matrix, linear solver, CVODE memory, tree copy and workspace, so a lane's result depends on its own
// inputs and history only: the same bits alone or in a batch, in any position.
//
// Restarts (as the planar kernel, kernel/cvode.cpp, but only when needed): CVodeReInit at the start of
// an advance unless the lane continues exactly where its last successful advance ended -- the same t,
// the state in `s` bit-for-bit the one CVODE returned, and the same held force. A held force that
// jumps, a state the caller changed, or a failed advance restarts the BDF history; a constant force
// over many intervals keeps it (the stop time still pins each interval's end exactly).
//
// Linear solvers and Jacobians:
//   kDense  SUNDenseMatrix + SUNLinSol_Dense, CVODE's internal difference-quotient Jacobian
//           (2 nv right-hand sides per Jacobian).
//   kKlu    SUNSparseMatrix (CSC) + SUNLinSol_KLU with our own forward-difference Jacobian on the
//           pattern [[0, I], [dqdd/dq, dqdd/dqd]] (the zero diagonal of the top-left block stored so
//           that CVODE forms I - gamma J in place): 2 nv (nv + 1) stored entries, 2 nv right-hand sides
//           per Jacobian, as dense. Actuator states add their rows below qd's to every column and their
//           own columns (rows nv .. 2 nv + nz - 1).
//   kGmres  matrix-free: SUNLinSol_SPGMR (left preconditioning, Krylov dimension 5), J v by CVODE's
//           difference quotient (one right-hand side per iteration), preconditioned by the stiff part
//           of the Jacobian, the joint springs K and dampers C: P = I - gamma [[0, I], [-M^-1 K, -M^-1 C]],
//           solved exactly in O(nv) by one ABA pass with gamma C + gamma^2 K as extra armature (the
//           fixed-step implicit pair's trick, multibody/lane_integrators.hpp; the joint friction's
//           slope at the current rate added to C), gravity and qd off. No
//           Jacobian evaluations, no factorisation. Actuator states: block Jacobi, each actuator's
//           I - gamma dz'/dz (4 x 4, forward differences at the preconditioner's setup; a bristle 1 x 1).
//           A nonlinear drive's tangent joins K and C.
// Honest note on KLU: the reduced (joint-space) ODE has no sparse Jacobian -- M(q)^-1 couples every
// joint of a chain, so dqdd/dq and dqdd/dqd are full nv x nv blocks whatever the topology -- and KLU
// cannot gain from sparsity in the usual sense. What it gains is the ordering: eliminating the
// identity-structured q block first (AMD does) leaves the dense nv x nv Schur complement
// I - gamma dqdd/dqd - gamma^2 dqdd/dq, a quarter of the dense 2 nv x 2 nv matrix and an eighth of
// its LU flops, and KLU refactors with the first factorisation's pivot order. That is where KLU wins
// over dense, at every size measured. The better formulation is kGmres: the stiffness sits in the
// diagonal K and C, whose Newton system the ABA solves in O(nv), so no nv x nv matrix is ever formed.
// CPU seconds per second of simulated time, one 3-D flexible link of N segments on a revolute hub
// (nv = 3 (N - 1) + 1), from the straight link at rest under gravity, 1 ms samples, the default
// tolerances (rtol 1e-8, atol 1e-10); g++ -O2, one core of a shared machine, one run each
// (bench/tree_bench.cpp BM_TreeCvode):
//                 torque jumping every sample (restarts)      torque constant (one BDF history)
//    N   nv      dense    KLU  GMRES  dense/KLU  steps/s      dense    KLU  GMRES  dense/KLU  steps/s
//    2    4      0.16   0.16     -       1.0     3.8e4          -       -      -       -          -
//    8   22      3.5    2.2    3.1       1.6     1.0e5        0.70   0.41   0.54     1.7      1.9e4
//   24   70     41     17      8.8       2.4     1.0e5        7.5    2.9    1.5      2.6      1.8e4
//   48  142    231     68     16         3.4     9.9e4       44     13      2.9      3.3      1.7e4
// So: dense never wins; KLU is the fastest on short links (N = 8, nv = 22), preconditioned GMRES from
// N = 24 on (2x KLU at N = 24, 4x at N = 48, the gap growing with nv: no O(nv^2) Jacobian, no O(nv^3)
// factorisation). The step counts are nearly the same for all three (the same BDF error control;
// GMRES's Newton solves are accurate enough), so the ratios are the linear algebra.
// Dense against KLU: the Jacobian (2 nv forward-dynamics passes, O(nv^2)) costs the same in both; the
// dense 2 nv LU grows as 8 nv^3 against KLU's ~nv^3 and dominates dense from N = 8 on. In KLU's own
// profile at N = 48 the refactorisation is a third, the forward-dynamics passes (the Jacobian's 2 nv
// columns, then the Newton iterations) another third, CVODE's sparse copy / zero / I - gamma J a
// tenth. Not sparsity: along a chain even M(q) is full in joint coordinates, so the descriptor form
// M(q) qdd = f is no sparser; a truly sparse Jacobian needs body coordinates with joint constraints
// (a DAE for IDA).
// GMRES's preconditioner leaves out gravity, the velocity terms and dM/dq; where they are stiff
// rather than the joint springs and dampers (not in these links), GMRES needs more iterations.
// Restarting at every sample costs about 5.5 times the steps of one history (BDF restarts at order 1
// with a small step; handing it the last step size instead of CVODE's estimate was tried and was
// slower). The joint springs and dampers are the stiffness (the cell torsion's real poles at
// beta omega^2); the lightly damped bending modes at rtol 1e-8 set the step.
#pragma once

#include <memory>
#include <vector>

#include "multibody/lanes.hpp"
#include "multibody/lane_integrators.hpp"

namespace ff {

enum class TreeCvodeSolver { kDense, kKlu, kGmres };

struct TreeCvodeOptions {
  TreeCvodeSolver solver = TreeCvodeSolver::kDense;  // kGmres is the fastest on long links (above)
  double rtol = 1e-8;       // relative tolerance, > 0
  double atol = 1e-10;      // absolute tolerance (rad, m and their rates alike), > 0
  int max_steps = 100000;   // CVODE's internal steps per lane and advance, > 0
};

class TreeCvode {
 public:
  // One CVODE instance per lane of `tl` (each with a copy of the lane's tree). Throws
  // std::invalid_argument on non-positive or non-finite tolerances or max_steps, and
  // std::runtime_error when SUNDIALS cannot allocate a solver.
  TreeCvode(const TreeLanes& tl, const TreeCvodeOptions& opt);
  ~TreeCvode();
  TreeCvode(const TreeCvode&) = delete;
  TreeCvode& operator=(const TreeCvode&) = delete;

  // Advances every lane from its state in s (q, qd) over [t, t + dt] with tau_applied (nv x W; null
  // for none) held; the joint springs and dampers act as in the fixed-step integrators. ok (resized to
  // W) is per lane 1 on success; a lane CVODE fails on (too many steps, a non-finite right-hand side,
  // the error test failing at the minimum step, ...) keeps its state from the start of the interval
  // and reports 0: a numerical failure is a result, never thrown. On success s.a_prev is set to the
  // lane's accelerations at its new state (the implicit pair's predictor, should a fixed-step method
  // take over). dt = 0 leaves everything as it is (ok all 1). Throws std::invalid_argument when tl's
  // W or nv are not those the integrator was made for, or on a negative or non-finite t or dt, or
  // state vectors of the wrong size.
  void advance(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, double t, double dt,
               std::vector<char>& ok);

  long steps(int lane) const;      // CVODE's internal steps so far, over all advances
  long rhs_evals(int lane) const;  // right-hand-side evaluations so far (CVODE's and our Jacobian's)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ff
