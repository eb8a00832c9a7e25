// The immutable model of a rigid-body kinematic tree in 3-D (Featherstone, Rigid Body Dynamics
// Algorithms, 2008, ch. 4): bodies in topological order, each joined to its parent (or to the fixed
// base) by a revolute, prismatic or fixed joint. Built and validated once by make_tree(); never
// written afterwards.
//
// Frames: the joint frame of body i sits at a fixed placement in its parent's body frame (the base
// frame for parent -1); the body frame is the joint frame moved by the joint (turned by q about the
// axis, or slid by q along it), so at q = 0 the two coincide. The body's inertia is given in its
// body frame. Gravity is a 3-vector in the base frame.
#pragma once

#include <string>
#include <vector>

#include "multibody/spatial.hpp"

namespace ff {

enum class JointType { kRevolute, kPrismatic, kFixed };

// One body as a user writes it.
struct BodySpec {
  std::string name;                       // for messages; may be empty
  int parent = -1;                        // index of the parent body, < this body's index; -1 = the base
  JointType joint = JointType::kRevolute;
  Vec3 axis = Vec3::UnitZ();              // joint axis in the joint frame (normalised by make_tree); unused when fixed
  Vec3 position = Vec3::Zero();           // joint frame origin in the parent's frame, m
  Mat3 rotation = Mat3::Identity();       // joint frame orientation in the parent's frame (active rotation)
  double mass = 0.0;                      // kg, >= 0
  Vec3 com = Vec3::Zero();                // centre of mass in the body frame, m
  Mat3 inertia = Mat3::Zero();            // rotational inertia about the centre of mass, body axes, kg·m²
  double armature = 0.0;                  // rotor inertia on M's diagonal, kg·m² (prismatic: kg); unused when fixed
  // The joint's passive spring and damper: tau = -stiffness (q - spring_reference) - damping qd
  // (N·m/rad and N·m·s/rad; prismatic N/m and N·s/m); unused when fixed. calc_passive_forces
  // (algorithms.hpp) evaluates them; the dynamics functions leave them to the caller's tau.
  double stiffness = 0.0;
  double damping = 0.0;
  double spring_reference = 0.0;          // rad (prismatic: m)
};

struct TreeSpec {
  std::vector<BodySpec> bodies;           // in topological order
  Vec3 gravity{0.0, 0.0, -9.81};          // gravitational acceleration in the base frame, m/s²
};

// One body of the derived tree.
struct Body {
  std::string name;
  int parent = -1;                        // < own index; -1 = the base
  JointType joint = JointType::kFixed;
  int dof = -1;                           // index into q, qd, qdd, tau; -1 for a fixed joint
  Vec3 axis = Vec3::UnitZ();              // unit joint axis (joint frame = body frame axes along it)
  SpatialMotion S = SpatialMotion::Zero();  // motion subspace: [axis; 0] revolute, [0; axis] prismatic, 0 fixed
  Transform X_tree;                       // joint frame X parent frame: E = rotation^T, r = position
  double mass = 0.0;                      // kg
  Vec3 com = Vec3::Zero();                // m, body frame
  Mat3 inertia_com = Mat3::Zero();        // kg·m² about the centre of mass
  SpatialMatrix inertia = SpatialMatrix::Zero();  // spatial inertia about the body origin (RBDA eq. 2.63)
  double armature = 0.0;
  double stiffness = 0.0, damping = 0.0, spring_reference = 0.0;  // the passive spring-damper (BodySpec)
};

class Tree {
 public:
  int num_bodies() const { return static_cast<int>(bodies_.size()); }
  int nq() const { return nv_; }  // one coordinate per revolute or prismatic joint
  int nv() const { return nv_; }
  const std::vector<Body>& bodies() const { return bodies_; }
  const Body& body(int i) const { return bodies_[static_cast<std::size_t>(i)]; }
  const Vec3& gravity() const { return gravity_; }
  // The base's spatial acceleration that stands in for gravity: a_0 = -a_g = [0; -gravity]
  // (RBDA Table 5.1: the base accelerates upwards instead of every body carrying its weight).
  SpatialMotion base_acceleration() const;

 private:
  friend Tree make_tree(const TreeSpec& spec);
  std::vector<Body> bodies_;
  Vec3 gravity_ = Vec3::Zero();
  int nv_ = 0;
};

// Derives and validates the tree. Throws std::invalid_argument naming the body on: a parent not
// before its child (or out of range), a zero or non-finite axis, a rotation that is not proper
// orthonormal, a negative or non-finite mass, armature, stiffness or damping (or a non-finite
// spring reference), a non-finite centre of mass or
// position, an inertia tensor that is not symmetric, not positive definite (for a body with mass;
// a massless body's must be zero) or whose principal moments violate the triangle inequality
// (I_a + I_b >= I_c); and on non-finite gravity. Not checked: that M(q) is positive definite when
// massless bodies are allowed to move without armature (two coaxial joints around a massless body).
Tree make_tree(const TreeSpec& spec);

}  // namespace ff
