// Dynamics and kinematics of a kinematic tree (multibody/tree.hpp) in spatial vectors, after
// Featherstone, Rigid Body Dynamics Algorithms (RBDA), 2008:
//   inverse dynamics   tau = M(q) qdd + C(q, qd) + g(q)    recursive Newton–Euler, RBDA Table 5.1
//   mass matrix        M(q)                                composite-rigid-body, RBDA Table 6.2
//   bias forces        C(q, qd) + g(q)                     the RNEA with qdd = 0
//   forward dynamics   qdd = M^-1 (tau - C - g)            articulated-body, RBDA Table 7.1
//   passive forces     -k (q - q0) - c qd                  each joint's spring-damper (BodySpec)
// M includes each joint's armature on its diagonal (a rotor inertia acting on that coordinate
// alone); the RNEA adds armature_i qdd_i to tau_i and the ABA adds it to D_i = S_i^T I^A_i S_i.
// The joint springs and dampers are NOT inside the dynamics functions: tau there is the total
// generalised force, so a caller with springs passes tau = tau_applied + calc_passive_forces(...)
// to calc_forward_dynamics (and reads tau_applied = RNEA - passive from calc_inverse_dynamics).
// q, qd, qdd, tau: joint coordinates in the tree's dof order (rad or m, and their rates; N·m or N).
// Every function takes its inputs as arguments and writes caller-owned outputs; `ws` is scratch,
// sized once for the tree (TreeWorkspace(tree)), so nothing is allocated per call. Sizes are
// checked: a vector of the wrong length or a workspace of another tree throws std::invalid_argument.
#pragma once

#include <Eigen/Dense>
#include <span>
#include <vector>

#include "multibody/spatial.hpp"
#include "multibody/tree.hpp"

namespace ff {

// Per-body scratch of the recursions, in body coordinates.
struct TreeWorkspace {
  TreeWorkspace() = default;
  explicit TreeWorkspace(const Tree& tree);
  std::vector<Transform> Xup;          // i X_parent(i) = X_J(q_i) X_tree,i
  std::vector<Transform> X0;           // i X_0, base to body (potential energy)
  std::vector<SpatialMotion> v, a, c;  // velocity, acceleration, velocity-product acceleration v × (S qd)
  std::vector<SpatialForce> f;         // RNEA: body force; ABA: articulated bias force p^A
  std::vector<SpatialMatrix> I;        // CRBA: composite inertia I^c; ABA: articulated inertia I^A
  std::vector<SpatialForce> U;         // ABA: I^A S
  std::vector<double> d, u;            // ABA: S^T I^A S + armature, tau - S^T p^A
};

// tau = M(q) qdd + C(q, qd) + g(q) (RNEA, RBDA Table 5.1), gravity as the base acceleration -a_g.
void calc_inverse_dynamics(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& qdd,
                           Eigen::Ref<Eigen::VectorXd> tau, TreeWorkspace& ws);

// The bias forces C(q, qd) + g(q): the generalised forces that hold qdd = 0 (RNEA with qdd = 0).
void calc_bias_forces(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& qd, Eigen::Ref<Eigen::VectorXd> bias,
                      TreeWorkspace& ws);

// The joint-space mass matrix M(q) (nv x nv, symmetric positive definite), armature on the diagonal
// (CRBA, RBDA Table 6.2).
void calc_mass_matrix(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Ref<Eigen::MatrixXd> M,
                      TreeWorkspace& ws);

// qdd = M(q)^-1 (tau - C(q, qd) - g(q)) (ABA, RBDA Table 7.1), O(N).
void calc_forward_dynamics(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& tau,
                           Eigen::Ref<Eigen::VectorXd> qdd, TreeWorkspace& ws);

// Kinetic energy 1/2 qd^T M(q) qd = sum_i 1/2 v_i^T I_i v_i + sum_j 1/2 armature_j qd_j², J.
double calc_kinetic_energy(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& qd, TreeWorkspace& ws);

// Gravitational potential energy -sum_i m_i gravity . c_i (c_i: body i's centre of mass in the base
// frame), J; zero with every centre of mass at the base origin.
double calc_potential_energy(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, TreeWorkspace& ws);

// The joints' passive spring-damper forces tau_i = -k_i (q_i - q0_i) - c_i qd_i (N·m or N) for every
// moving joint (all nv entries written; k, c, q0: BodySpec stiffness, damping, spring_reference).
// Add them to the applied tau before calc_forward_dynamics.
void calc_passive_forces(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                         const Eigen::Ref<const Eigen::VectorXd>& qd, Eigen::Ref<Eigen::VectorXd> tau);

// The joint springs' potential energy 1/2 sum_i k_i (q_i - q0_i)², J. With the kinetic and the
// gravitational energy it is conserved when nothing else acts and the dampers are zero.
double calc_spring_energy(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q);

// A body frame in the base frame.
struct Pose {
  Mat3 rotation = Mat3::Identity();  // the body's axes in base coordinates (active rotation)
  Vec3 position = Vec3::Zero();      // the body's origin in base coordinates, m
  // A point given in body coordinates, in base coordinates, m.
  Vec3 point(const Vec3& p) const { return position + rotation * p; }
};

// Forward kinematics of every body (poses.size() == tree.num_bodies()), O(N).
void calc_body_poses(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, std::span<Pose> poses);
// One body's pose, by its chain of ancestors (O(depth), allocates nothing).
Pose calc_body_pose(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, int body);
// A point fixed in a body (body coordinates, m) in base coordinates, m.
Vec3 calc_point_position(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, int body, const Vec3& point);

// The Jacobian of a point fixed in a body (body coordinates, m), in base coordinates: J (6 x nv) maps
// qd to [omega; v], the body's angular velocity (rad/s) and the point's velocity (m/s). Column j, for
// a joint on the chain from the body to the base with unit axis a_j (base coordinates) through its
// body's origin o_j: revolute [a_j; a_j × (p - o_j)], prismatic [0; a_j]; zero off the chain.
void calc_point_jacobian(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, int body, const Vec3& point,
                         Eigen::Ref<Eigen::MatrixXd> J, TreeWorkspace& ws);

// A force (N) acting at a point fixed in a body (body coordinates, m) and a moment (N·m) acting on
// that body, both in base coordinates, as generalised forces: tau += J^T [moment; force] (J of
// calc_point_jacobian; the principle of virtual work). Accumulates into tau, so several loads add.
void add_point_load(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, int body, const Vec3& point,
                    const Vec3& force, const Vec3& moment, Eigen::Ref<Eigen::VectorXd> tau, TreeWorkspace& ws);

// The joint transform X_J(q) of a body, body frame X joint frame: revolute rot(axis_angle(axis, q)^T),
// prismatic xlt(axis q), fixed the identity (q unused).
Transform joint_transform(const Body& body, double q);

}  // namespace ff
