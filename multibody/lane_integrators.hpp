// Fixed-step integrators over the lanes of multibody/lanes.hpp, with a generalised force held over
// the step (the controller's zero-order hold): the same three methods as the planar kernel
// (kernel/fixed_step.hpp), so a tree gets what the reference rig gets:
//   RK4       classical, explicit: four ABA passes a step; stable to h omega <= 2.8.
//   midpoint  implicit midpoint, linearly implicit in the joint springs and dampers (their
//             tau = -k (q - q0) - c qd enters the stage solve as armature h/2 c + (h/2)^2 k), M and
//             the velocity terms at a predictor: one ABA pass a step; A-stable.
//   SDIRK2    Alexander's (1977) two-stage L-stable SDIRK, gamma = 1 - 1/sqrt(2), the springs and
//             dampers implicit in the same way (armature gamma h c + (gamma h)^2 k): two passes a step.
// Joint friction (TreeLanes::friction, kernel/friction.hpp) acts at every stage of all three, at the
// stage's rate: explicitly in RK4 (its substeps must resolve the map's slope: h D / J <= 2.8), and in
// the implicit pair linearly implicit like the dampers, its slope D(w) = -d tau_f / dw at the stage's
// spring-state rate on the diagonal (armature gh D; the midpoint rule takes the Coulomb and Stribeck
// part's h D_c, backward Euler), as the reference rig takes its hub friction (kernel/fixed_step.cpp):
// viscous friction is then exactly a damper, and a Coulomb joint holds still without chattering at
// any smoothing.
// The springs of a finely lumped flexible link are what make the tree stiff (in 3-D its torsion
// above all: omega ~ sqrt(G / rho) / l, 5.8e4 rad/s for aluminium cells of 8 cm), and its
// stiffness-proportional dampers too (a real pole at beta omega^2); the implicit pair steps at the
// accuracy the slow modes need, not at the stability limit of the fast ones. The velocity terms
// (Coriolis, gyroscopic) stay explicit at the predictor: the midpoint rule, which does not damp the
// unresolved modes, can go unstable when they are strongly excited (a twist put into the link as an
// initial condition), SDIRK2 damps them and does not.
// Hydraulic actuators (TreeLanes::hydraulic_dofs; their states TreeLanesState::z) join every stage as
// the reference rig's hub drive does (kernel/fixed_step.cpp): in RK4 as four more rates of its
// tableau; in the implicit pair each actuator's stage Z = zpre + gh f(Z) is solved per lane by
// simplified Newton with its joint held at the stage's kinematic predictor (qk, vk; the rig holds its
// hub at the spring state, whose velocity is the step's start: on an undamped oil spring that gained
// 19 % of amplitude in 9 periods at h omega = 0.014; with the predictor the amplitude stays within
// 5e-5 over 27 periods, tests/arm/arm_hydraulics_test.cpp), and its torque
// D (p_a - p_b) from Z then acts in the stage's dynamics (SDIRK2's second stage from
// zpre = z + (1 - g) h F1; the midpoint rule's z_new = 2 Z - z). The substeps must resolve the
// actuators' rates (calc_hydraulic_rate) for accuracy.
// LuGre bristles (TreeLanes::lugre_dofs, one state z each after the actuators') are solved per stage
// as the rig's (kernel/friction.hpp, solve_lugre_stage: exact for the implicit stage at the joint's
// stage rate), their torque sigma0 z + sigma1 zdot acting in that stage's dynamics; in RK4 they are
// one more rate of the tableau. A nonlinear drive train (TreeLanes::transmissions: free play, cubic
// stiffness, efficiency) acts at its twist at every stage, its tangent (kernel/drive.hpp,
// calc_transmission_tangent) on the implicit pair's diagonal as a spring and damper's gh c + (gh)^2 k.
#pragma once

#include <vector>

#include "multibody/lanes.hpp"

namespace ff {

// What changes during a run, (nv x W) each.
struct TreeLanesState {
  std::vector<double> q, qd;  // joint coordinates (rad or m) and rates
  std::vector<double> a_prev; // the last step's accelerations: the implicit pair's velocity predictor
                              // (zero before the first step)
  std::vector<double> z;      // (nz x W) the hydraulic actuators' states (TreeLanes::hydraulic_dofs)
};
TreeLanesState make_tree_lanes_state(const TreeLanes& tl);  // q = qd = 0, z = 0 (the caller sets the pressures)

// Scratch sized once for a batch.
struct TreeStepWorkspace {
  TreeStepWorkspace() = default;
  explicit TreeStepWorkspace(const TreeLanes& tl);
  TreeLanesWorkspace aba;
  std::vector<double> q1, qd1, kq[4], kv[4], tau, armature;  // (nv x W)
  std::vector<double> tau_act;                               // (nv x W) with hydraulic actuators only
  std::vector<double> z1, kz[4];                             // (nz x W) their stage states and rates
  double armature_gh = -1.0;  // the stage coefficient `armature` was made for, s
};

// One step h (s) of every lane with the generalised force tau_applied (nv x W) held; the joints'
// springs and dampers (TreeLanes stiffness, damping) and friction (TreeLanes::friction) act as well.
void step_tree_rk4(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, TreeStepWorkspace& ws, double h);
void step_tree_midpoint(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, TreeStepWorkspace& ws,
                        double h);
void step_tree_sdirk2(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, TreeStepWorkspace& ws,
                      double h);

}  // namespace ff
