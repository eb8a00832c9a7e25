// The world around an arm (docs/formats.md, "World"): obstacles placed in the base frame, and the
// clearance of a capsule (a segment swept by a sphere: a link, a flexible link's segment) to each.
//
// Clearance is a signed distance, m: > 0 apart, 0 touching, < 0 overlapping (the depth of the deepest
// point of the capsule's segment inside the obstacle, less nothing: -(depth + r)).
//   sphere, capsule   closed forms: point to segment, segment to segment (Ericson, Real-Time
//                     Collision Detection, 2005, 5.1.9), less the radii;
//   plane             a half-space below the plane (its normal points out of it): the lower end of the
//                     segment's signed height, less r;
//   box, cylinder     the segment's least signed distance min_s sd(a + s (b - a)), s in [0, 1]: the
//                     signed distance sd of a convex solid is a convex function of the point, so along
//                     the segment it has one minimum, found by golden-section search to 1e-13 of the
//                     segment's length (a fixed count of steps: deterministic);
//   bore              the free space inside a cylinder (a tank's wall, a riser's bore) over its length:
//                     R - rho - r, rho the segment's largest distance from the axis over the part of it
//                     within the bore's length (rho is convex along a line, so at an end of that part);
//                     a segment wholly beyond the bore's ends is not constrained by it (+infinity);
//   mesh              a triangle mesh (STL, OBJ, ... read by assimp), through FCL 0.7's capsule-mesh
//                     distance; 0 when they overlap (FCL gives no depth for meshes).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "multibody/spatial.hpp"

namespace ff {

enum class ShapeType { kBox, kSphere, kCylinder, kCapsule, kBore, kPlane, kMesh };

// "box", "sphere", ... as the world block writes them; and back (false for an unknown name).
const char* shape_type_name(ShapeType t);
bool parse_shape_type(const std::string& name, ShapeType& out);

struct MeshGeometry;  // world/mesh.hpp: the triangles and FCL's bounding-volume tree

// One obstacle: its frame in the base frame and its size in that frame. Cylinders, capsules and bores
// lie along their frame's z axis, centred on its origin; a plane's boundary is its frame's xy plane,
// the solid below it (z < 0).
struct Obstacle {
  std::string name;
  ShapeType type = ShapeType::kBox;
  Mat3 rotation = Mat3::Identity();  // the obstacle's axes in the base frame
  Vec3 position = Vec3::Zero();      // its origin in the base frame, m
  Vec3 size = Vec3::Zero();          // box: full edge lengths along its x, y, z, m
  double radius = 0.0;               // sphere, cylinder, capsule, bore, m
  double length = 0.0;               // cylinder, bore: along z; capsule: between its cap centres, m
  std::shared_ptr<const MeshGeometry> mesh;  // mesh: in the obstacle's frame (scaled), m
  // A sphere about the origin holding the whole obstacle (infinity: a plane), m: the broad phase's bound.
  double bound = 0.0;
  int line = 0;                      // where it is written, for errors
};

// The obstacles of a model, in file order (world_yaml.hpp reads them).
struct World {
  std::vector<Obstacle> obstacles;
  bool empty() const { return obstacles.empty(); }
};

// A capsule's clearance to an obstacle and where it is least: the closest points on the capsule's
// segment and on the obstacle's surface (for a bore: on its wall), base frame, m.
struct Clearance {
  double distance = std::numeric_limits<double>::infinity();  // m, signed as above; radius subtracted
  Vec3 on_segment = Vec3::Zero();
  Vec3 on_obstacle = Vec3::Zero();
};

// The obstacle's bounding radius (Obstacle::bound) from its type and size; mesh: its farthest vertex.
double calc_obstacle_bound(const Obstacle& o);

// The clearance of the capsule of segment [a, b] (base frame, m) and radius r (m) to the obstacle.
Clearance calc_clearance(const Obstacle& o, const Vec3& a, const Vec3& b, double r);

// The clearance of two capsules: segments [a0, b0], [a1, b1] with radii r0, r1.
Clearance calc_capsule_clearance(const Vec3& a0, const Vec3& b0, double r0, const Vec3& a1, const Vec3& b1,
                                 double r1);

// A lower bound of calc_clearance (the broad phase): the distance of the segment's bounding sphere to
// the obstacle's; a mesh's: the clearance to its bounding box. -infinity for a plane and a bore.
double calc_clearance_bound(const Obstacle& o, const Vec3& a, const Vec3& b, double r);

// The nearest point of segment [a, b] to p: its parameter s in [0, 1] (a degenerate segment: 0).
double calc_point_segment_parameter(const Vec3& p, const Vec3& a, const Vec3& b);

// The closest points of segments [p0, q0] and [p1, q1]: the parameters s, t in [0, 1] of
// p0 + s (q0 - p0) and p1 + t (q1 - p1) (Ericson 5.1.9; a degenerate segment is its point).
void calc_segment_segment(const Vec3& p0, const Vec3& q0, const Vec3& p1, const Vec3& q1, double& s, double& t);

// The signed distance of point p (the obstacle's frame) to a convex obstacle (box, sphere, cylinder,
// capsule), m: < 0 inside.
double calc_signed_distance(const Obstacle& o, const Vec3& p);

}  // namespace ff
