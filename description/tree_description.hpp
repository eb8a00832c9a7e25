// A kinematic tree read from a file (tree YAML, description/tree_yaml.hpp, or URDF, description/urdf.hpp):
// the TreeSpec of multibody/tree.hpp with the names of its bodies and joints and what the file says
// about each joint that the tree does not use yet.
#pragma once

#include <limits>
#include <map>
#include <string>
#include <vector>

#include "multibody/flexible_link.hpp"
#include "multibody/spatial.hpp"
#include "multibody/tree.hpp"

namespace ff {

// What a description says about a joint beyond the TreeSpec: kept, not used by the tree (yet).
struct JointInfo {
  static constexpr double kNone = std::numeric_limits<double>::infinity();
  std::string name;
  double lower = -kNone, upper = kNone;  // position limits, rad (prismatic: m); -inf, +inf = none
  double effort = kNone;                 // |tau| limit, N·m (prismatic: N); inf = none
  double velocity = kNone;               // |qd| limit, rad/s (prismatic: m/s); inf = none
  double friction = 0.0;                 // Coulomb friction, N·m (prismatic: N) (URDF <dynamics friction>)
};

// A body of the file made a flexible link (multibody/flexible_link.hpp): its bodies are
// spec.bodies[root_body..tip_body], contiguous, the root segment named after the file's body (or URDF
// link) and carrying its joint, then per cell j the bodies "<name>.cell<j>.z", ".y" (massless) and
// "<name>.seg<j>"; the cell joints are named "<name>.cell<j>.z", ".y", ".x" (the last on the segment).
struct FlexibleLinkInfo {
  std::string name;                 // the file's body (URDF: link) name, = the root body's name
  int root_body = -1;               // index into spec.bodies: the root segment
  int tip_body = -1;                // the last segment, to which the body's children are attached
  Vec3 tip_point = Vec3::Zero();    // the beam's end in the tip body's frame, m
  FlexibleLinkSpec link;            // as given to append_flexible_link (name, root_name, root_joint set)
  std::vector<int> dofs;            // the cell joints' dofs (elastic), in body order; not the root joint's
};

struct TreeDescription {
  TreeSpec spec;
  std::vector<JointInfo> joints;           // one per body, in the order of spec.bodies: the joint to its parent
  std::string base;                        // the base's name: `base` (YAML) or the URDF root link's
  std::map<std::string, int> body_index;   // body (URDF: link) name -> index into spec.bodies and Tree::bodies()
  std::map<std::string, int> dof_index;    // revolute or prismatic joint name -> dof (index into q, qd, tau)
  std::vector<std::string> notes;          // what was read and ignored, one line each ("FILE:LINE: ...")
  std::vector<FlexibleLinkInfo> flexible_links;  // the bodies made flexible, in body order
};

// The active rotation of fixed-axis roll, pitch, yaw (rad), URDF's convention:
// R = Rz(yaw) Ry(pitch) Rx(roll) (roll about x first, then pitch about the fixed y, then yaw about z).
Mat3 rpy_rotation(double roll, double pitch, double yaw);

// A compliant drive train on a moving joint (the reference rig's drive, docs/reference-rig.md, on any
// joint; output-side units): the actuator's rotor, of inertia ratio^2 x rotor_inertia about the joint
// axis, turns on the joint's own axis and placement, and the link follows it through a spring-damper.
struct DriveTrain {
  double rotor_inertia = 5.0;  // J_a, actuator-side inertia (rotor, pinion, gears) on the motor shaft, kg·m² (kg)
  double ratio = 1.0;          // n = motor angle / output angle
  double stiffness = 2.0e7;    // k, the drive's torsional (axial) stiffness at the output, N·m/rad (N/m)
  double damping = 2.0e3;      // c, N·m·s/rad (N·s/m)
  // The nonlinear part of the law (the reference rig's, kernel/drive.hpp calc_transmission_torque and
  // calc_efficiency_factor), which the tree cannot hold: the arm's lanes apply it at the twist
  // (multibody/lanes.hpp, add_tree_lanes_transmission). The tree's twist keeps the linear k and c, what
  // the modes and statics take (the teeth in contact).
  double cubic_stiffness = 0.0;  // k3, hardening, N·m/rad³ (N/m³)
  double backlash = 0.0;         // total free play 2b at the output, rad (m)
  double efficiency = 1.0;       // eta in (0, 1]
  bool closing_damping = false;  // c only while the teeth close, e de/dt > 0 (the rig's drive.closing_damping)
};

// Whether the drive's law is more than the linear spring and damper.
inline bool is_nonlinear_drive(const DriveTrain& d) {
  return d.cubic_stiffness != 0.0 || d.backlash != 0.0 || d.efficiency != 1.0 || d.closing_damping;
}

// Splits the moving joint `joint` into the drive's two: a massless rotor body "<body>.rotor" inserted
// between the parent and the body, carrying the joint (its name, type, axis, placement, limits and
// passive spring) with the armature n^2 J_a plus the joint's own, and the body's new joint
// "<joint>.twist" on the same axis at the rotor's origin, with the drive's stiffness and damping:
// the body turns by q_joint + q_twist. Later bodies' indices (the flexible links' too) move up by one.
// Returns "" or why not (no such moving joint, a name taken, bad values), leaving `d` unchanged then.
std::string insert_drive_train(TreeDescription& d, const std::string& joint, const DriveTrain& drive);

// For the readers: why make_tree would reject a body, "" when it would not, in make_tree's words
// without its "tree: body N" prefix. inertia_fault looks at the mass, centre of mass and inertia
// alone; joint_fault at everything else of the body (its parent and place in the tree not included).
std::string inertia_fault(const BodySpec& body);
std::string joint_fault(const BodySpec& body);

// Replaces body `body` (a rigid body of d, not yet flexible) by the flexible link `link` (its length,
// section, segments, ... ; name, root_name and root_joint are set here): the root segment takes the
// body's name, parent, placement, joint (type, axis, armature, springs) and JointInfo; the body's mass,
// centre of mass and inertia are dropped; its children are attached to the tip segment, their
// placements (written in the body's frame) re-expressed in the tip segment's frame (the tip segment's
// origin is at x = L - l_last in the straight link's root frame, with the same axes), so the straight
// link has the rigid body's geometry. Later bodies' indices (parents, flexible_links) are shifted.
// Returns "" or why it cannot (a generated body or joint name already taken, append_flexible_link's
// objection); on a fault d is unchanged. Call finish_description afterwards.
std::string make_flexible(TreeDescription& d, int body, FlexibleLinkSpec link);

// The readers' last step: fills body_index and dof_index from spec and joints (dofs numbered as
// make_tree numbers them) and each flexible link's dofs, and returns make_tree's verdict on the tree as a whole ("" when it builds;
// every body has passed inertia_fault and joint_fault alone before).
std::string finish_description(TreeDescription& d);

// The moving joints a file may name (not the generated ones of flexible links' cells and drive trains),
// in name order: for "did you mean" and the list an error shows.
std::vector<std::string> list_joint_names(const TreeDescription& d);
// Every body (URDF: link) by name, in name order.
std::vector<std::string> list_body_names(const TreeDescription& d);

}  // namespace ff
