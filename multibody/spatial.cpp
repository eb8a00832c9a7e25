// Spatial vector algebra (spatial.hpp): Featherstone, Rigid Body Dynamics Algorithms, 2008, ch. 2.
#include "multibody/spatial.hpp"

#include <cmath>

namespace ff {

Mat3 skew(const Vec3& a) {
  Mat3 s;
  s << 0.0, -a.z(), a.y(),
       a.z(), 0.0, -a.x(),
       -a.y(), a.x(), 0.0;
  return s;
}

// Rodrigues: R = I + sin θ [a]× + (1 - cos θ) [a]×² for a unit axis a.
Mat3 axis_angle(const Vec3& axis, double angle) {
  const Mat3 k = skew(axis);
  return Mat3::Identity() + std::sin(angle) * k + (1.0 - std::cos(angle)) * (k * k);
}

Mat3 rotx(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Mat3 r;
  r << 1.0, 0.0, 0.0,
       0.0, c, -s,
       0.0, s, c;
  return r;
}

Mat3 roty(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Mat3 r;
  r << c, 0.0, s,
       0.0, 1.0, 0.0,
       -s, 0.0, c;
  return r;
}

Mat3 rotz(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Mat3 r;
  r << c, -s, 0.0,
       s, c, 0.0,
       0.0, 0.0, 1.0;
  return r;
}

Transform Transform::from_pose(const Mat3& rotation, const Vec3& position) {
  return Transform{rotation.transpose(), position};
}

Transform Transform::rotation(const Mat3& E) { return Transform{E, Vec3::Zero()}; }

Transform Transform::translation(const Vec3& r) { return Transform{Mat3::Identity(), r}; }

// X m = [E w; E (v - r × w)].
SpatialMotion Transform::apply(const SpatialMotion& m) const {
  const Vec3 w = m.head<3>();
  SpatialMotion out;
  out.head<3>() = E * w;
  out.tail<3>() = E * (m.tail<3>() - r.cross(w));
  return out;
}

// X* f = [E (n - r × f); E f].
SpatialForce Transform::apply_force(const SpatialForce& f) const {
  const Vec3 lin = f.tail<3>();
  SpatialForce out;
  out.head<3>() = E * (f.head<3>() - r.cross(lin));
  out.tail<3>() = E * lin;
  return out;
}

// X^-1 m = [E^T w; E^T v + r × E^T w].
SpatialMotion Transform::apply_inverse(const SpatialMotion& m) const {
  const Vec3 w = E.transpose() * m.head<3>();
  SpatialMotion out;
  out.head<3>() = w;
  out.tail<3>() = E.transpose() * m.tail<3>() + r.cross(w);
  return out;
}

// X^T f = [E^T n + r × E^T f; E^T f].
SpatialForce Transform::apply_inverse_force(const SpatialForce& f) const {
  const Vec3 lin = E.transpose() * f.tail<3>();
  SpatialForce out;
  out.head<3>() = E.transpose() * f.head<3>() + r.cross(lin);
  out.tail<3>() = lin;
  return out;
}

// A X_B: rotation E^T, and A's origin seen from B: -E r.
Transform Transform::inverse() const { return Transform{E.transpose(), -(E * r)}; }

// C X_A = C X_B B X_A: C's origin in A coordinates is B's origin plus C's offset rotated back to A.
Transform Transform::operator*(const Transform& rhs) const {
  return Transform{E * rhs.E, rhs.r + rhs.E.transpose() * r};
}

SpatialMatrix Transform::matrix() const {
  SpatialMatrix x;
  x.topLeftCorner<3, 3>() = E;
  x.topRightCorner<3, 3>().setZero();
  x.bottomLeftCorner<3, 3>() = -E * skew(r);
  x.bottomRightCorner<3, 3>() = E;
  return x;
}

SpatialMatrix Transform::force_matrix() const {
  SpatialMatrix x;
  x.topLeftCorner<3, 3>() = E;
  x.topRightCorner<3, 3>() = -E * skew(r);
  x.bottomLeftCorner<3, 3>().setZero();
  x.bottomRightCorner<3, 3>() = E;
  return x;
}

Vec3 Transform::apply_point(const Vec3& p) const { return E * (p - r); }

Vec3 Transform::apply_inverse_point(const Vec3& p) const { return r + E.transpose() * p; }

// crm(v) = [w× 0; v× w×].
SpatialMatrix crm(const SpatialMotion& v) {
  const Mat3 w = skew(v.head<3>());
  SpatialMatrix x;
  x.topLeftCorner<3, 3>() = w;
  x.topRightCorner<3, 3>().setZero();
  x.bottomLeftCorner<3, 3>() = skew(v.tail<3>());
  x.bottomRightCorner<3, 3>() = w;
  return x;
}

// crf(v) = [w× v×; 0 w×] = -crm(v)^T (skew matrices are antisymmetric).
SpatialMatrix crf(const SpatialMotion& v) {
  const Mat3 w = skew(v.head<3>());
  SpatialMatrix x;
  x.topLeftCorner<3, 3>() = w;
  x.topRightCorner<3, 3>() = skew(v.tail<3>());
  x.bottomLeftCorner<3, 3>().setZero();
  x.bottomRightCorner<3, 3>() = w;
  return x;
}

SpatialMotion cross_motion(const SpatialMotion& v, const SpatialMotion& m) {
  const Vec3 w = v.head<3>(), vl = v.tail<3>(), mw = m.head<3>(), mv = m.tail<3>();
  SpatialMotion out;
  out.head<3>() = w.cross(mw);
  out.tail<3>() = w.cross(mv) + vl.cross(mw);
  return out;
}

SpatialForce cross_force(const SpatialMotion& v, const SpatialForce& f) {
  const Vec3 w = v.head<3>(), vl = v.tail<3>(), n = f.head<3>(), fl = f.tail<3>();
  SpatialForce out;
  out.head<3>() = w.cross(n) + vl.cross(fl);
  out.tail<3>() = w.cross(fl);
  return out;
}

// RBDA eq. 2.63: [I_c + m c× c×^T, m c×; m c×^T, m 1] (c×^T = -c×).
SpatialMatrix spatial_inertia(double mass, const Vec3& com, const Mat3& inertia_com) {
  const Mat3 c = skew(com);
  SpatialMatrix I;
  I.topLeftCorner<3, 3>() = inertia_com + mass * (c * c.transpose());
  I.topRightCorner<3, 3>() = mass * c;
  I.bottomLeftCorner<3, 3>() = mass * c.transpose();
  I.bottomRightCorner<3, 3>() = mass * Mat3::Identity();
  return I;
}

// A I = X^T (B I) X: the kinetic energy 1/2 (X m)^T B I (X m) is the same in either coordinates.
SpatialMatrix transform_inertia_to_parent(const Transform& X, const SpatialMatrix& I) {
  const SpatialMatrix x = X.matrix();
  return x.transpose() * I * x;
}

}  // namespace ff
