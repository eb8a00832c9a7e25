// W kinematic trees of equal topology in lock-step: the articulated-body algorithm of
// multibody/algorithms.hpp over lanes (variants), structure-of-arrays with the lane innermost, so
// every loop over lanes vectorises and a lane's numbers never depend on its neighbours (the same bits
// in any lane, at any W). The scalar functions of multibody/algorithms.hpp are the oracle.
//
// Layout: component k of body i (or dof j) in lane l at [(i * K + k) * W + l], K the components
// of the quantity (written next to each array); joint coordinates q, qd, qdd, tau at [j * W + l].
// Spatial conventions as multibody/spatial.hpp: motion [omega; v], force [n; f], B X_A = (E, r).
#pragma once

#include <cstddef>
#include <new>
#include <span>
#include <vector>

#include "kernel/drive.hpp"
#include "kernel/friction.hpp"
#include "multibody/tree.hpp"

namespace ff {

// Storage on 64-byte (cache-line) boundaries for the ABA's lane arrays: at W = 8 a component's lanes are
// then one cache line. On malloc's 16-byte boundaries three 8-lane loads in four crossed two lines: the
// ABA was 11 % slower at W = 8, ~20 % at W = 16 and on the flexible arm.
template <class T>
struct CacheLineAllocator {
  using value_type = T;
  static constexpr std::align_val_t kAlign{64};
  CacheLineAllocator() = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kAlign)); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, kAlign); }
  template <class U>
  bool operator==(const CacheLineAllocator<U>&) const { return true; }
};
using LaneArray = std::vector<double, CacheLineAllocator<double>>;

// The immutable parameters of W trees: the topology once, everything else per lane.
struct TreeLanes {
  int W = 0;                    // lanes
  int nb = 0;                   // bodies
  int nv = 0;                   // joint coordinates
  std::vector<Tree> trees;      // (W) the source trees (kinematics for output, the scalar oracle)
  std::vector<int> parent;      // (nb) parent body, -1 = the base
  std::vector<int> dof;         // (nb) the body's joint coordinate, -1 when fixed
  std::vector<JointType> joint; // (nb)
  // The ABA works in each body's joint frame: the body's coordinates turned (per lane) so that its joint
  // axis is z (multibody/lanes.cpp, joint_frame); X_tree and inertia are in those frames.
  LaneArray X_tree;             // K = 12: joint frame X parent's joint frame: E row-major (9), then r (3), m
  LaneArray inertia;            // K = 10: mass (kg), h = m c (3, kg·m), I about the body origin
                                //   (xx, xy, xz, yy, yz, zz, kg·m²): the spatial inertia's blocks
  std::vector<double> armature, stiffness, damping, spring_reference;  // (nv x W), Body's units
  std::vector<double> gravity;  // K = 3 per lane: [k * W + l], m/s²
  // Joint friction (kernel/friction.hpp; none from make_tree_lanes, set_tree_lanes_friction adds it):
  // the dofs some lane has friction on, ascending, and per such dof f and lane l its map at [f * W + l]
  // (a lane without friction there holds the zero map). compute_tree_passive_forces adds it.
  std::vector<int> friction_dofs;
  std::vector<FrictionMap> friction;
  // Hydraulic actuators (kernel/drive.hpp, eval_hydraulic_actuator; none from make_tree_lanes,
  // add_tree_lanes_hydraulics adds them), on the same dofs in every lane: the dofs driven by one, in the
  // order added, and per actuator a and lane l its constants and the constant load on its joint (N·m or
  // N: a torque offset) at [a * W + l]. At such a dof the integrators read tau_applied as the actuator's
  // torque command (its valve loop's); the joint gets D (p_a - p_b) - load instead
  // (compute_tree_actuator_forces). Their states are TreeLanesState::z, rows 4 a .. 4 a + 3: spool, its
  // rate, p_a, p_b (MPa).
  std::vector<int> hydraulic_dofs;
  std::vector<LaneDrive> hydraulics;
  std::vector<double> hydraulic_load;
  // LuGre friction (kernel/friction.hpp, calc_lugre_bristle_rate; none from make_tree_lanes,
  // add_tree_lanes_lugre adds it) in place of the static map at its dofs: the dofs, in the order added,
  // and per dof b and lane l its map (b, Fc, Fs - Fc, vs) and bristle stiffness and damping at
  // [b * W + l]. Each has one state, its bristle deflection z (rad or m), row bristle_row(b) of
  // TreeLanesState::z, after the hydraulic actuators'. compute_tree_actuator_forces adds its torque.
  std::vector<int> lugre_dofs;
  std::vector<FrictionMap> lugre;
  std::vector<double> bristle_stiffness, bristle_damping;
  // Drive trains with a nonlinear law (kernel/drive.hpp, calc_transmission_torque: free play, cubic
  // stiffness; calc_efficiency_factor: efficiency; none from make_tree_lanes, add_tree_lanes_transmission
  // adds them) on a joint's twist (description/tree_description.hpp, insert_drive_train): per drive d the
  // twist's dof, the rotor's (the joint's) dof, and per lane l its law at [d * W + l] (k, k3, c, b, eta
  // in output units, n = 1). At such a twist the law replaces the linear spring and damper; the body
  // gets T(-q_t, -qd_t), the rotor T (1 - factor) (compute_tree_passive_forces).
  std::vector<int> transmission_dofs, transmission_rotor_dofs;
  std::vector<LaneDrive> transmissions;
  int hydraulic_states() const { return kHydraulicStates * static_cast<int>(hydraulic_dofs.size()); }
  int bristle_row(std::size_t b) const { return hydraulic_states() + static_cast<int>(b); }
  int nz() const { return hydraulic_states() + static_cast<int>(lugre_dofs.size()); }
};

// Gathers trees of one topology (the same number of bodies, parents and joint types) into lanes.
// Throws std::invalid_argument naming the lane and body where the topology differs, or on no trees
// or more than kMaxTreeLanes.
inline constexpr int kMaxTreeLanes = 256;
TreeLanes make_tree_lanes(std::span<const Tree> trees);

// Lane l of tl alone (W = 1): its tree, parameters and every law TreeLanes holds for it (friction,
// hydraulic actuators, LuGre, drive trains), as tl has them. For per-lane solvers (multibody/tree_cvode.hpp).
TreeLanes extract_tree_lane(const TreeLanes& tl, int l);

// Puts friction on joint coordinate `dof` of every lane: per_lane[l] is lane l's (W of them). A dof
// given again is replaced; one whose maps are all zero is dropped. Throws std::invalid_argument on a dof
// out of range, a count other than W, or a map that is not physical (negative b, Fc or stiction,
// stiction below Fc unless 0, non-positive stribeck_velocity or smoothing).
void set_tree_lanes_friction(TreeLanes& tl, int dof, std::span<const FrictionSpec> per_lane);

// Puts a hydraulic actuator on joint coordinate `dof` of every lane: per_lane[l] its constants
// (make_hydraulic_drive), load[l] the constant load on the joint (W of each). Throws
// std::invalid_argument on a dof out of range or driven already, or counts other than W.
void add_tree_lanes_hydraulics(TreeLanes& tl, int dof, std::span<const LaneDrive> per_lane,
                               std::span<const double> load);

// Puts LuGre friction on joint coordinate `dof` of every lane (per_lane[l]: its FrictionSpec, model
// "lugre", W of them), in place of any static map there. Throws std::invalid_argument on a dof out of
// range or with LuGre already, a count other than W, or a map that is not physical (as
// set_tree_lanes_friction, and Fc > 0, sigma0 > 0, sigma1 >= 0).
void add_tree_lanes_lugre(TreeLanes& tl, int dof, std::span<const FrictionSpec> per_lane);

// Puts a nonlinear drive-train law on the twist dof `twist` whose rotor turns at dof `rotor`, in every
// lane (per_lane[l]: k, k3, c, b, eta of LaneDrive; n unused), zeroing the twist's linear spring and
// damper in the lanes. Throws std::invalid_argument on a dof out of range, a twist given twice, a count
// other than W, or a law that is not physical (k > 0, c, b, k3 >= 0, eta in (0, 1]).
void add_tree_lanes_transmission(TreeLanes& tl, int twist, int rotor, std::span<const LaneDrive> per_lane);

// The generalised force the states z give (nv x W): tau_applied (null: none), at each hydraulic dof
// replaced by D (p_a - p_b) - load from the actuator's states z (nz x W), its command tau_applied there,
// and at each LuGre dof the bristles' friction added; the states' rates into zdot (nz x W) when it is
// not null. Nothing allocated.
void compute_tree_actuator_forces(const TreeLanes& tl, const double* q, const double* qd, const double* z,
                                  const double* tau_applied, double* tau_act, double* zdot);

// Scratch of the recursions for every body and lane, sized once: nothing is allocated per call.
struct TreeLanesWorkspace {
  TreeLanesWorkspace() = default;
  explicit TreeLanesWorkspace(const TreeLanes& tl);
  int W = 0, nb = 0, nv = 0;
  // All in the bodies' joint frames (TreeLanes).
  LaneArray Xup;                // K = 12: i X_parent(i) = X_J(q_i) X_tree,i
  LaneArray v, a;               // K = 6: velocity, acceleration
  LaneArray c;                  // K = 4: velocity-product acceleration v × S qd, x and y of [w; v] (z is 0)
  LaneArray IA;                 // K = 21: articulated inertia [A B; B^T C]: A (sym 6), B (9), C (sym 6)
  LaneArray pA;                 // K = 6: articulated bias force
  LaneArray d, u;               // K = 1: S^T I^A S + armature, tau - S^T p^A
  std::vector<double> zeros;    // (nv x W) the extra armature when none is given
};

// qdd = M(q)^-1 (tau - C(q, qd) - g(q)) in every lane (ABA, RBDA Table 7.1), the trees' armature
// and `extra_armature` (nv x W, may be null: an implicit integrator's h gamma c + (h gamma)^2 k) on
// M's diagonal. q, qd, tau, qdd: (nv x W). tau is the total generalised force, as in
// calc_forward_dynamics (springs included: compute_tree_passive_forces).
void compute_tree_forward_dynamics(const TreeLanes& tl, const double* q, const double* qd, const double* tau,
                                   const double* extra_armature, double* qdd, TreeLanesWorkspace& ws);

// tau = tau_applied - k (q - q0) - c qd + tau_f(qd) in every lane and dof (calc_passive_forces plus a
// given force, plus the joint friction of TreeLanes::friction at the rate qd, plus the nonlinear drive
// trains of TreeLanes::transmissions; tau_applied may be null for none). (nv x W) each.
void compute_tree_passive_forces(const TreeLanes& tl, const double* q, const double* qd, const double* tau_applied,
                                 double* tau);

}  // namespace ff
