// Clearances of capsules to obstacles (world.hpp); meshes in mesh.cpp.
#include "world/world.hpp"

#include <algorithm>
#include <cmath>

#include "world/mesh.hpp"

namespace ff {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Golden-section steps: 0.618^62 < 1e-13 of the segment's length.
constexpr int kGoldenSteps = 62;

double clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

// The signed distance of a point to the rectangle [-hx, hx] x [-hy, hy] (2-D) or the box of half sizes h.
double box_signed_distance(const Vec3& p, const Vec3& h) {
  const Vec3 q = p.cwiseAbs() - h;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}
double rect_signed_distance(double x, double y, double hx, double hy) {
  const double qx = std::abs(x) - hx, qy = std::abs(y) - hy;
  return std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
}

// The point of the box's surface nearest p (box frame).
Vec3 box_surface_point(const Vec3& p, const Vec3& h) {
  Vec3 c = p.cwiseMax(-h).cwiseMin(h);
  if (c != p) return c;  // outside: the clamp
  int k = 0;             // inside: onto the nearest face
  (h - p.cwiseAbs()).minCoeff(&k);
  c[k] = p[k] < 0 ? -h[k] : h[k];
  return c;
}

// The point of the cylinder's surface (radius R, half length hz along z) nearest p.
Vec3 cylinder_surface_point(const Vec3& p, double R, double hz) {
  const double rho = std::hypot(p.x(), p.y());
  const Vec3 radial = rho > 0 ? Vec3(p.x() / rho, p.y() / rho, 0.0) : Vec3::UnitX();
  const bool inside = rho <= R && std::abs(p.z()) <= hz;
  if (!inside) {
    const double r = std::min(rho, R), z = std::clamp(p.z(), -hz, hz);
    return Vec3(radial.x() * r, radial.y() * r, z);
  }
  if (R - rho < hz - std::abs(p.z())) return Vec3(radial.x() * R, radial.y() * R, p.z());
  return Vec3(p.x(), p.y(), p.z() < 0 ? -hz : hz);
}

// min over s in [0, 1] of a convex f(s): golden-section search, the ends included. Returns s.
template <class F>
double minimise_convex(const F& f) {
  constexpr double g = 0.6180339887498949;
  double lo = 0.0, hi = 1.0;
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < kGoldenSteps; ++i) {
    if (f1 <= f2) {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - g * (hi - lo), f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + g * (hi - lo), f2 = f(x2);
    }
  }
  double s = f1 <= f2 ? x1 : x2, fs = std::min(f1, f2);
  if (const double f0 = f(0.0); f0 <= fs) s = 0.0, fs = f0;
  if (f(1.0) < fs) s = 1.0;
  return s;
}

}  // namespace

const char* shape_type_name(ShapeType t) {
  switch (t) {
    case ShapeType::kBox: return "box";
    case ShapeType::kSphere: return "sphere";
    case ShapeType::kCylinder: return "cylinder";
    case ShapeType::kCapsule: return "capsule";
    case ShapeType::kBore: return "bore";
    case ShapeType::kPlane: return "plane";
    case ShapeType::kMesh: return "mesh";
  }
  return "?";
}

bool parse_shape_type(const std::string& name, ShapeType& out) {
  for (ShapeType t : {ShapeType::kBox, ShapeType::kSphere, ShapeType::kCylinder, ShapeType::kCapsule, ShapeType::kBore,
                      ShapeType::kPlane, ShapeType::kMesh})
    if (name == shape_type_name(t)) return out = t, true;
  return false;
}

double calc_obstacle_bound(const Obstacle& o) {
  switch (o.type) {
    case ShapeType::kBox: return 0.5 * o.size.norm();
    case ShapeType::kSphere: return o.radius;
    case ShapeType::kCylinder: return std::hypot(o.radius, 0.5 * o.length);
    case ShapeType::kCapsule: return o.radius + 0.5 * o.length;
    case ShapeType::kBore:
    case ShapeType::kPlane: return kInf;
    case ShapeType::kMesh: return o.mesh ? calc_mesh_bound(*o.mesh) : 0.0;
  }
  return kInf;
}

double calc_point_segment_parameter(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double dd = d.squaredNorm();
  return dd > 0 ? clamp01((p - a).dot(d) / dd) : 0.0;
}

void calc_segment_segment(const Vec3& p0, const Vec3& q0, const Vec3& p1, const Vec3& q1, double& s, double& t) {
  const Vec3 d0 = q0 - p0, d1 = q1 - p1, r = p0 - p1;
  const double a = d0.squaredNorm(), e = d1.squaredNorm(), f = d1.dot(r);
  if (a == 0.0 && e == 0.0) {
    s = t = 0.0;
    return;
  }
  if (a == 0.0) {
    s = 0.0, t = clamp01(f / e);
    return;
  }
  const double c = d0.dot(r);
  if (e == 0.0) {
    t = 0.0, s = clamp01(-c / a);
    return;
  }
  const double b = d0.dot(d1), denom = a * e - b * b;
  s = denom > 0.0 ? clamp01((b * f - c * e) / denom) : 0.0;  // parallel: any s; take 0
  t = (b * s + f) / e;
  if (t < 0.0) t = 0.0, s = clamp01(-c / a);
  else if (t > 1.0) t = 1.0, s = clamp01((b - c) / a);
}

Clearance calc_capsule_clearance(const Vec3& a0, const Vec3& b0, double r0, const Vec3& a1, const Vec3& b1,
                                 double r1) {
  double s = 0.0, t = 0.0;
  calc_segment_segment(a0, b0, a1, b1, s, t);
  Clearance c;
  c.on_segment = a0 + s * (b0 - a0);
  c.on_obstacle = a1 + t * (b1 - a1);
  c.distance = (c.on_segment - c.on_obstacle).norm() - r0 - r1;
  return c;
}

double calc_signed_distance(const Obstacle& o, const Vec3& p) {
  switch (o.type) {
    case ShapeType::kBox: return box_signed_distance(p, 0.5 * o.size);
    case ShapeType::kSphere: return p.norm() - o.radius;
    case ShapeType::kCylinder: return rect_signed_distance(std::hypot(p.x(), p.y()), p.z(), o.radius, 0.5 * o.length);
    case ShapeType::kCapsule: {
      const double z = std::clamp(p.z(), -0.5 * o.length, 0.5 * o.length);
      return (p - Vec3(0, 0, z)).norm() - o.radius;
    }
    case ShapeType::kPlane: return p.z();
    default: return kInf;  // not convex solids
  }
}

double calc_clearance_bound(const Obstacle& o, const Vec3& a, const Vec3& b, double r) {
  if (o.type == ShapeType::kPlane || o.type == ShapeType::kBore) return -kInf;
  if (o.type == ShapeType::kMesh) {  // the clearance to the mesh's bounding box (exact for a box, cheap)
    Obstacle box;
    box.type = ShapeType::kBox;
    box.rotation = o.rotation;
    box.position = o.position + o.rotation * o.mesh->box_centre;
    box.size = o.mesh->box_size;
    return calc_clearance(box, a, b, r).distance;
  }
  return (0.5 * (a + b) - o.position).norm() - 0.5 * (b - a).norm() - r - o.bound;
}

Clearance calc_clearance(const Obstacle& o, const Vec3& a_base, const Vec3& b_base, double r) {
  if (o.type == ShapeType::kMesh) return calc_mesh_clearance(o, a_base, b_base, r);  // FCL places the mesh itself
  // The segment in the obstacle's frame.
  const Vec3 a = o.rotation.transpose() * (a_base - o.position);
  const Vec3 b = o.rotation.transpose() * (b_base - o.position);
  const auto to_base = [&](const Vec3& p) -> Vec3 { return o.position + o.rotation * p; };
  Clearance c;
  switch (o.type) {
    case ShapeType::kSphere: {
      const Vec3 p = a + calc_point_segment_parameter(Vec3::Zero(), a, b) * (b - a);
      const double n = p.norm();
      c.on_segment = to_base(p);
      c.on_obstacle = to_base(n > 0 ? Vec3(p * (o.radius / n)) : Vec3(o.radius, 0, 0));
      c.distance = n - o.radius - r;
      return c;
    }
    case ShapeType::kCapsule: {
      const Vec3 h(0, 0, 0.5 * o.length);
      c = calc_capsule_clearance(a, b, r, -h, h, o.radius);
      const Vec3 dir = c.on_segment - c.on_obstacle;  // the axis point towards the segment
      const double n = dir.norm();
      c.on_obstacle += n > 0 ? Vec3(dir * (o.radius / n)) : Vec3(o.radius, 0, 0);
      c.on_segment = to_base(c.on_segment), c.on_obstacle = to_base(c.on_obstacle);
      return c;
    }
    case ShapeType::kPlane: {
      const Vec3 p = a.z() <= b.z() ? a : b;
      c.on_segment = to_base(p);
      c.on_obstacle = to_base(Vec3(p.x(), p.y(), 0.0));
      c.distance = p.z() - r;
      return c;
    }
    case ShapeType::kBore: {
      // The part of the segment within |z| <= L/2, then its end farther from the axis.
      const double hz = 0.5 * o.length, dz = b.z() - a.z();
      double s0 = 0.0, s1 = 1.0;
      if (dz != 0.0) {
        const double u = (-hz - a.z()) / dz, v = (hz - a.z()) / dz;
        s0 = std::max(s0, std::min(u, v)), s1 = std::min(s1, std::max(u, v));
      } else if (std::abs(a.z()) > hz) {
        s1 = -1.0;
      }
      if (s0 > s1) return c;  // wholly beyond the ends: +infinity
      const Vec3 p0 = a + s0 * (b - a), p1 = a + s1 * (b - a);
      const double rho0 = std::hypot(p0.x(), p0.y()), rho1 = std::hypot(p1.x(), p1.y());
      const Vec3 p = rho0 >= rho1 ? p0 : p1;
      const double rho = std::max(rho0, rho1);
      const Vec3 radial = rho > 0 ? Vec3(p.x() / rho, p.y() / rho, 0.0) : Vec3::UnitX();
      c.on_segment = to_base(p);
      c.on_obstacle = to_base(Vec3(radial.x() * o.radius, radial.y() * o.radius, p.z()));
      c.distance = o.radius - rho - r;
      return c;
    }
    case ShapeType::kBox:
    case ShapeType::kCylinder: {
      const auto sd = [&](double s) { return calc_signed_distance(o, a + s * (b - a)); };
      const double s = minimise_convex(sd);
      const Vec3 p = a + s * (b - a);
      c.on_segment = to_base(p);
      c.on_obstacle = to_base(o.type == ShapeType::kBox ? box_surface_point(p, 0.5 * o.size)
                                                        : cylinder_surface_point(p, o.radius, 0.5 * o.length));
      c.distance = sd(s) - r;
      return c;
    }
    case ShapeType::kMesh: break;  // measured above
  }
  return c;
}

}  // namespace ff
