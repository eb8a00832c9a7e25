// Spatial (6-D) vector algebra of Featherstone, "Rigid Body Dynamics Algorithms" (RBDA), 2008, ch. 2:
// motion and force vectors in Plücker coordinates, Plücker transforms, spatial cross products and
// the rigid-body spatial inertia.
//
// Conventions (those of RBDA and RBDL; Pinocchio stores the linear part first):
//   motion vector  m = [omega; v]: angular velocity (rad/s), then the linear velocity (m/s) of the
//                  body-fixed point at the coordinate frame's origin;
//   force vector   f = [n; f]: moment about the frame's origin (N·m), then the force (N);
//   power          f . m = n . omega + f . v (W), invariant under any change of coordinates;
//   B X_A          the Plücker transform of motion vectors from A coordinates to B coordinates, with
//                  E the 3x3 rotation taking A coordinates to B coordinates and r the position of
//                  B's origin in A coordinates: B X_A = [E 0; -E r× E] = rot(E) xlt(r).
//   Rotations      the helpers below return active rotations R (columns: the rotated frame's axes in
//                  the original frame's coordinates), as MJCF and URDF write a body's orientation.
//                  The frame with orientation R has E = R^T; RBDA's rx(θ) is rotx(θ)^T.
#pragma once

#include <Eigen/Dense>

namespace ff {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using SpatialMotion = Eigen::Matrix<double, 6, 1>;  // [omega; v]
using SpatialForce = Eigen::Matrix<double, 6, 1>;   // [n; f]
using SpatialMatrix = Eigen::Matrix<double, 6, 6>;  // 6x6 operators: inertias, cross products, transforms

// The 3x3 cross-product matrix: skew(a) b = a × b.
Mat3 skew(const Vec3& a);

// Active rotation by `angle` (rad) about the unit `axis` (Rodrigues' formula:
// R = I + sin θ [a]× + (1 - cos θ) [a]×²). The axis must be of unit length.
Mat3 axis_angle(const Vec3& axis, double angle);
// Active rotations about the coordinate axes (RBDA's rx, ry, rz are their transposes).
Mat3 rotx(double angle);
Mat3 roty(double angle);
Mat3 rotz(double angle);

// A Plücker transform B X_A (see the conventions above). The identity by default.
struct Transform {
  Mat3 E = Mat3::Identity();  // rotation: A coordinates -> B coordinates
  Vec3 r = Vec3::Zero();      // B's origin in A coordinates, m

  // The transform of the frame B placed at `position` with orientation `rotation` (both in A
  // coordinates): E = rotation^T, r = position.
  static Transform from_pose(const Mat3& rotation, const Vec3& position);
  static Transform rotation(const Mat3& E);     // rot(E): B rotated, same origin
  static Transform translation(const Vec3& r);  // xlt(r): B shifted by r, same orientation

  // B m = B X_A A m = [E omega; E (v - r × omega)].
  SpatialMotion apply(const SpatialMotion& m) const;
  // B f = B X*_A A f, X* = X^-T: [E (n - r × f); E f].
  SpatialForce apply_force(const SpatialForce& f) const;
  // A m = (B X_A)^-1 B m = [E^T omega; E^T v + r × E^T omega].
  SpatialMotion apply_inverse(const SpatialMotion& m) const;
  // A f = (B X_A)^T B f = [E^T n + r × E^T f; E^T f]: a force carried back from B to A (the RNEA's
  // and ABA's passes towards the root).
  SpatialForce apply_inverse_force(const SpatialForce& f) const;

  // A X_B = (B X_A)^-1: E' = E^T, r' = -E r.
  Transform inverse() const;
  // Composition C X_A = C X_B * B X_A (this = C X_B, `rhs` = B X_A): E = E_CB E_BA, r = r_BA + E_BA^T r_CB.
  Transform operator*(const Transform& rhs) const;

  // The 6x6 matrices: motion transform X = [E 0; -E r× E] and force transform X* = [E -E r×; 0 E].
  SpatialMatrix matrix() const;
  SpatialMatrix force_matrix() const;

  // The orientation and origin of B in A coordinates (the inverse of from_pose).
  Mat3 rotation_matrix() const { return E.transpose(); }
  const Vec3& position() const { return r; }
  // A point given in A coordinates, in B coordinates: E (p - r).
  Vec3 apply_point(const Vec3& p) const;
  // A point given in B coordinates, in A coordinates: r + E^T p.
  Vec3 apply_inverse_point(const Vec3& p) const;
};

// Spatial cross products (RBDA ch. 2): crm(v) m = v × m (motion), crf(v) f = v ×* f (force);
//   crm(v) = [omega× 0; v× omega×],  crf(v) = [omega× v×; 0 omega×] = -crm(v)^T.
SpatialMatrix crm(const SpatialMotion& v);
SpatialMatrix crf(const SpatialMotion& v);
// The same products without forming the matrices.
SpatialMotion cross_motion(const SpatialMotion& v, const SpatialMotion& m);  // [w×mw; w×mv + v×mw]
SpatialForce cross_force(const SpatialMotion& v, const SpatialForce& f);     // [w×n + v×f; w×f]

// Spatial inertia of a rigid body about the coordinate origin (RBDA eq. 2.63):
//   I = [I_c + m c× c×^T, m c×; m c×^T, m 1],
// mass m (kg), centre of mass c (m) and the 3x3 rotational inertia I_c about the centre of mass
// (kg·m²), all in the same coordinates.
SpatialMatrix spatial_inertia(double mass, const Vec3& com, const Mat3& inertia_com);

// A spatial inertia (or any 6x6 operator on motion giving force) given in B coordinates, in A
// coordinates: A I = (B X_A)^T B I (B X_A) (RBDA ch. 2); any symmetric 6x6 (articulated inertias too).
SpatialMatrix transform_inertia_to_parent(const Transform& X, const SpatialMatrix& I);

}  // namespace ff
