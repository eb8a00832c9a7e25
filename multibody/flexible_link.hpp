// A flexible link lumped into rigid segments joined by elastic spherical joints, appended to a
// TreeSpec (multibody/tree.hpp).
//
// Source: the planar lumping of the reference rig (docs/reference-rig.md, "Segments and joints"),
// extended to two bending planes and torsion. The link lies along its local +x axis from its
// placement's origin (its neutral axis), bends about its local y and z axes and twists about x.
//   Segments   N >= 2: N-1 equal cells of length l = L/(N-1), joints at the cell centres, so the
//              segments are l/2, (N-2) x l, l/2 long; N = 2: two halves L/2; N = 1: one rigid
//              segment of length L and no joints.
//   Segment s  a rigid slender prism of length l_s: mass rho A l_s, centre of mass at mid-length,
//              inertia about its centre (link axes)
//                I_xx = rho l_s (I_y + I_z),
//                I_yy = rho A l_s³/12 + rho I_y l_s,
//                I_zz = rho A l_s³/12 + rho I_z l_s
//              (the rig's m (l_s² + t²)/12 about its bending axis is I_zz with I_z = h t³/12).
//   Cell joint at each cell centre, three revolute joints in series: bending about z, bending about
//              y, torsion about x (the two inner bodies massless, so together an elastic spherical
//              joint with the rotation Rz(q_z) Ry(q_y) Rx(q_x)), with the springs
//                k_z = kappa E I_z / l,  k_y = kappa E I_y / l,  k_x = kappa G J / l
//              (N·m/rad; a beam element of length l has end moment E I theta / l; kappa = 1 is the
//              plain lumping, the rig's kappa = 39.5e3 (L/5) / (E I) = 0.905 gives its seed value
//              k = 39.5 kN·m/rad at N = 6). `planar`: the z-bending joint only (the rig's chain);
//              `torsion` off: the two bending joints only.
//   Damping    stiffness-proportional, joint by joint: c = beta k (N·m·s/rad, beta in s). Since
//              k scales as 1/l, so does c: this is the rig's rule c_N = 90.4 (L/5)/l, with
//              beta = 90.4 / 39.5e3 = 2.289e-3 s.
//   Root       the first segment is attached to the parent at the placement by the root joint: fixed
//              by default (rigidly attached), or a revolute or prismatic joint that moves the root
//              segment directly (a motor at the link's hub, with no extra body).
//   Payload    an optional rigid body fixed to the last segment, its centre of mass at the tip
//              point (L along the link) plus an offset; merged into the last segment's body.
// Body frames: each segment's frame has its origin on the neutral axis at the segment's inboard end
// (the root, or the cell centre) and the link's axes turned by the joints; the tip point is
// (l_last, 0, 0) in the last segment's frame (flexible_link_tip_point).
#pragma once

#include <string>
#include <vector>

#include "multibody/spatial.hpp"
#include "multibody/tree.hpp"

namespace ff {

// The link's cross-section and material.
struct BeamSection {
  double youngs_modulus = 0.0;   // E, Pa
  double shear_modulus = 0.0;    // G, Pa (torsion only)
  double density = 0.0;          // rho, kg/m³
  double area = 0.0;             // A, m²
  double second_moment_y = 0.0;  // I_y, m⁴: bending about the local y axis (deflection along z)
  double second_moment_z = 0.0;  // I_z, m⁴: bending about the local z axis (deflection along y)
  double torsion_constant = 0.0; // J, m⁴ (torsion only; a circle's polar moment, a thin strip's b t³/3)
};

// A rigid body fixed at the link's tip.
struct TipPayload {
  double mass = 0.0;               // kg, >= 0
  Vec3 com_offset = Vec3::Zero();  // centre of mass from the tip point, link (tip segment) axes, m
  Mat3 inertia = Mat3::Zero();     // about its centre of mass, link axes, kg·m² (symmetric, >= 0)
};

// The joint between the parent and the root segment: a BodySpec's joint fields (multibody/tree.hpp).
struct FlexibleRootJoint {
  JointType type = JointType::kFixed;
  Vec3 axis = Vec3::UnitZ();       // in the joint frame (the placement's axes); unused when fixed
  double armature = 0.0;           // kg·m² (prismatic: kg)
  double stiffness = 0.0;          // N·m/rad (N/m)
  double damping = 0.0;            // N·m·s/rad (N·s/m)
  double spring_reference = 0.0;   // rad (m)
};

struct FlexibleLinkSpec {
  std::string name = "link";     // prefix of the bodies' names
  std::string root_name;         // the root segment's body name; "" = "<name>.seg0"
  FlexibleRootJoint root_joint;  // default: fixed to the parent
  double length = 0.0;           // L, m
  BeamSection section;
  int segments = 1;              // N >= 1
  double stiffness_factor = 1.0; // kappa > 0: k = kappa E I / l (the rig: 0.905)
  double damping_time = 0.0;     // beta >= 0, s: c = beta k for every spring
  TipPayload payload;
  bool torsion = true;           // the torsion joint in each cell
  bool planar = false;           // only the z-bending joint in each cell (then `torsion` is ignored)
};

// The segment lengths l/2, l, ..., l, l/2 (N = 1: L), m.
std::vector<double> flexible_link_segment_lengths(const FlexibleLinkSpec& link);
// The tip point in the last segment's body frame: (l_last, 0, 0), m.
Vec3 flexible_link_tip_point(const FlexibleLinkSpec& link);

// Appends the link's bodies to `tree` (in topological order, after the existing ones): its root
// segment (named root_name, else "<name>.seg0") joined by link.root_joint (default fixed) to body
// `parent` (-1 = the base) at `position` with orientation `rotation` (active rotation of the link's
// axes, in the parent's frame; the joint frame), then for each cell its joint bodies (massless,
// named "<name>.cell<j>.z" and ".y") and segment j ("<name>.seg<j>", carrying the cell's last joint).
// The cell joints' spring references are 0 (the straight link). Returns the index of the last segment's
// body, the tip body to which further joints attach. Throws std::invalid_argument naming the link on
// a parent out of range, a non-positive or non-finite length, N < 1, a non-positive density, area,
// E, I_y or I_z, a non-positive G or J with torsion, kappa <= 0, beta < 0, or a payload with a
// negative mass or a non-finite, non-symmetric or indefinite inertia. (make_tree checks the rest,
// e.g. the rotation and the root joint's axis and values.)
int append_flexible_link(TreeSpec& tree, int parent, const Vec3& position, const Mat3& rotation,
                         const FlexibleLinkSpec& link);

}  // namespace ff
