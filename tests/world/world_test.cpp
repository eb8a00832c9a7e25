// Capsule clearances (world/world.hpp) against closed forms and against FCL 0.7 (another implementation:
// GJK/EPA and its own primitives), over random poses and sizes with fixed seeds.
#include "world/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <fcl/narrowphase/distance.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>

#include "multibody/spatial.hpp"
#include "world/mesh.hpp"

namespace ff {
namespace {

Obstacle make_obstacle(ShapeType type, const Vec3& size, double radius, double length,
                       const Mat3& R = Mat3::Identity(), const Vec3& p = Vec3::Zero()) {
  Obstacle o;
  o.type = type;
  o.size = size;
  o.radius = radius;
  o.length = length;
  o.rotation = R;
  o.position = p;
  o.bound = calc_obstacle_bound(o);
  return o;
}

TEST(CapsuleClearance, AParallelCapsuleAboveABoxFaceIsItsGapLessItsRadius) {
  const Obstacle box = make_obstacle(ShapeType::kBox, Vec3(2, 1, 0.5), 0, 0);
  // The segment 0.3 m above the top face (z = 0.25), along x and longer than the box.
  const Clearance c = calc_clearance(box, Vec3(-3, 0.1, 0.55), Vec3(3, 0.1, 0.55), 0.1);
  EXPECT_NEAR(c.distance, 0.3 - 0.1, 1e-12);
  EXPECT_NEAR(c.on_obstacle.z(), 0.25, 1e-12);
  EXPECT_NEAR(c.on_segment.z(), 0.55, 1e-12);
}

TEST(CapsuleClearance, ASegmentPassingAnEdgeOfABoxDiagonallyMeetsItsClosedForm) {
  // Box [-1, 1]^3; the segment in the plane z = 0 along x + y = 2 + sqrt(2) d: its nearest point to
  // the edge x = y = 1 is d away (the edge's corner region), d = 0.4.
  const Obstacle box = make_obstacle(ShapeType::kBox, Vec3(2, 2, 2), 0, 0);
  const double d = 0.4, k = 2 + std::sqrt(2.0) * d;
  const Clearance c = calc_clearance(box, Vec3(k + 1, -1, 0), Vec3(-1, k + 1, 0), 0.05);
  EXPECT_NEAR(c.distance, d - 0.05, 1e-12);
  EXPECT_NEAR(c.on_obstacle.x(), 1.0, 1e-9);
  EXPECT_NEAR(c.on_obstacle.y(), 1.0, 1e-9);
}

TEST(CapsuleClearance, ASegmentInsideABoxIsAsDeepAsItsDeepestPoint) {
  const Obstacle box = make_obstacle(ShapeType::kBox, Vec3(4, 2, 2), 0, 0);
  // Through the centre along x: its deepest point is 1 m from the nearest (y and z) faces.
  EXPECT_NEAR(calc_clearance(box, Vec3(-0.5, 0, 0), Vec3(0.5, 0, 0), 0.1).distance, -1.1, 1e-12);
}

TEST(CapsuleClearance, ACapsuleBesideACylinderParallelToItsAxisIsTheAxisGapLessBothRadii) {
  const Mat3 R = rotx(0.7) * rotz(0.3);
  const Vec3 p(1, -2, 0.5);
  const Obstacle cyl = make_obstacle(ShapeType::kCylinder, Vec3::Zero(), 0.4, 3.0, R, p);
  // 1.5 m from the axis, within the length.
  const Vec3 off = R * Vec3(1.5, 0, 0);
  const Clearance c = calc_clearance(cyl, p + off + R * Vec3(0, 0, -1), p + off + R * Vec3(0, 0, 1), 0.2);
  EXPECT_NEAR(c.distance, 1.5 - 0.4 - 0.2, 1e-12);
  // Above the cap, across the axis: its height above the cap.
  const Clearance above = calc_clearance(cyl, p + R * Vec3(-1, 0.1, 2.1), p + R * Vec3(1, 0.1, 2.1), 0.05);
  EXPECT_NEAR(above.distance, 2.1 - 1.5 - 0.05, 1e-12);
}

TEST(CapsuleClearance, TwoSkewCapsulesAreTheirLinesDistanceLessTheRadii) {
  // The lines x-axis at z = 0 and y-axis at z = 0.9 are 0.9 apart; both segments straddle the crossing.
  const Clearance c = calc_capsule_clearance(Vec3(-1, 0, 0), Vec3(2, 0, 0), 0.1, Vec3(0.5, -1, 0.9),
                                             Vec3(0.5, 1, 0.9), 0.15);
  EXPECT_NEAR(c.distance, 0.9 - 0.25, 1e-14);
  EXPECT_NEAR(c.on_segment.x(), 0.5, 1e-14);
  // Parallel and overlapping in their span: the lines' distance.
  EXPECT_NEAR(calc_capsule_clearance(Vec3(0, 0, 0), Vec3(1, 0, 0), 0, Vec3(0.5, 0.3, 0), Vec3(3, 0.3, 0), 0).distance,
              0.3, 1e-14);
  // Collinear, end to end with a gap.
  EXPECT_NEAR(calc_capsule_clearance(Vec3(0, 0, 0), Vec3(1, 0, 0), 0, Vec3(1.25, 0, 0), Vec3(3, 0, 0), 0).distance,
              0.25, 1e-14);
}

TEST(CapsuleClearance, ACapsuleInARiserBoreIsTheBoreRadiusLessItsFarthestPointFromTheAxis) {
  // A bore of radius 0.3 along z over z in [-1, 1]; a tilted segment from (0.05, 0, -2) to (0.15, 0, 2):
  // within the bore's length its end at z = 1 is farthest, x = 0.05 + 0.1 * 3/4 = 0.125.
  const Obstacle bore = make_obstacle(ShapeType::kBore, Vec3::Zero(), 0.3, 2.0);
  const Clearance c = calc_clearance(bore, Vec3(0.05, 0, -2), Vec3(0.15, 0, 2), 0.05);
  EXPECT_NEAR(c.distance, 0.3 - 0.125 - 0.05, 1e-14);
  EXPECT_NEAR(c.on_obstacle.x(), 0.3, 1e-14);
  EXPECT_NEAR(c.on_obstacle.z(), 1.0, 1e-14);
  // Wholly above the bore: not constrained.
  EXPECT_EQ(calc_clearance(bore, Vec3(2, 0, 1.5), Vec3(3, 0, 3), 0.1).distance, std::numeric_limits<double>::infinity());
}

TEST(CapsuleClearance, ASegmentThroughAPlaneIsAsDeepAsItsLowerEnd) {
  const Obstacle floor = make_obstacle(ShapeType::kPlane, Vec3::Zero(), 0, 0, roty(0.2), Vec3(0, 0, -1));
  const Vec3 n = roty(0.2).col(2);
  const Vec3 a = Vec3(0, 0, -1) + 0.5 * n, b = Vec3(0, 0, -1) - 0.3 * n + Vec3(0, 1, 0);
  EXPECT_NEAR(calc_clearance(floor, a, b, 0.1).distance, -0.3 - 0.1, 1e-14);
}

// ---- Against FCL over random poses and sizes ----

fcl::Transform3d to_fcl(const Mat3& R, const Vec3& p) {
  fcl::Transform3d X = fcl::Transform3d::Identity();
  X.linear() = R;
  X.translation() = p;
  return X;
}

// FCL's distance between the capsule [a, b], r and the obstacle (FCL's own primitives).
double fcl_distance(const Obstacle& o, const Vec3& a, const Vec3& b, double r) {
  std::shared_ptr<fcl::CollisionGeometryd> g;
  switch (o.type) {
    case ShapeType::kBox: g = std::make_shared<fcl::Boxd>(o.size); break;
    case ShapeType::kCylinder: g = std::make_shared<fcl::Cylinderd>(o.radius, o.length); break;
    case ShapeType::kCapsule: g = std::make_shared<fcl::Capsuled>(o.radius, o.length); break;
    case ShapeType::kSphere: g = std::make_shared<fcl::Sphered>(o.radius); break;
    default: ADD_FAILURE() << "no FCL shape";
  }
  const Vec3 d = b - a;
  const auto cap = std::make_shared<fcl::Capsuled>(r, d.norm());
  const Mat3 Rc = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), d).toRotationMatrix();
  const fcl::CollisionObjectd o0(cap, to_fcl(Rc, 0.5 * (a + b))), o1(g, to_fcl(o.rotation, o.position));
  fcl::DistanceRequestd request(true);
  request.distance_tolerance = 1e-9;
  fcl::DistanceResultd result;
  fcl::distance(&o0, &o1, request, result);
  return result.min_distance;
}

Mat3 random_rotation(std::mt19937_64& g) {
  std::normal_distribution<double> n;
  return Eigen::Quaterniond(n(g), n(g), n(g), n(g)).normalized().toRotationMatrix();
}

// Random obstacles of sizes 0.05-3 m and capsules of length 0-4 m placed within 4 m: the pairs apart by
// more than 1 mm (FCL reports -1 for overlapping primitives), compared to 1e-6 m.
void expect_fcl_agrees(ShapeType type, std::uint64_t seed) {
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> size(0.05, 3.0), len(0.0, 4.0), pos(-4.0, 4.0), rad(0.01, 0.5);
  int compared = 0;
  for (int k = 0; k < 400; ++k) {
    const Obstacle o = make_obstacle(type, Vec3(size(g), size(g), size(g)), size(g) / 2, size(g), random_rotation(g),
                                     Vec3(pos(g), pos(g), pos(g)) / 4);
    const Vec3 a(pos(g), pos(g), pos(g));
    const Vec3 b = a + random_rotation(g).col(0) * std::max(len(g), 1e-3);
    const double r = rad(g);
    const double ours = calc_clearance(o, a, b, r).distance;
    if (ours < 1e-3) continue;
    const double theirs = fcl_distance(o, a, b, r);
    EXPECT_NEAR(ours, theirs, 1e-6) << shape_type_name(type) << " case " << k;
    // The witness points are that far apart (and on the segment / the surface).
    const Clearance c = calc_clearance(o, a, b, r);
    EXPECT_NEAR((c.on_segment - c.on_obstacle).norm() - r, ours, 1e-9);
    ++compared;
  }
  EXPECT_GT(compared, 150);
}

TEST(CapsuleClearance, CapsuleToBoxAgreesWithFclOnRandomPairs) { expect_fcl_agrees(ShapeType::kBox, 11); }
TEST(CapsuleClearance, CapsuleToCylinderAgreesWithFclOnRandomPairs) { expect_fcl_agrees(ShapeType::kCylinder, 12); }
TEST(CapsuleClearance, CapsuleToCapsuleAgreesWithFclOnRandomPairs) { expect_fcl_agrees(ShapeType::kCapsule, 13); }
TEST(CapsuleClearance, CapsuleToSphereAgreesWithFclOnRandomPairs) { expect_fcl_agrees(ShapeType::kSphere, 14); }

// A box as a mesh of 12 triangles measures as the analytic box.
TEST(CapsuleClearance, ABoxMeshMeasuresAsTheAnalyticBox) {
  std::vector<Vec3> v;
  const Vec3 h(0.6, 0.4, 0.3);
  for (int i = 0; i < 8; ++i) v.emplace_back(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  const std::vector<std::array<int, 3>> t{{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  Obstacle mesh = make_obstacle(ShapeType::kMesh, Vec3::Zero(), 0, 0, rotz(0.4), Vec3(0.2, 0.1, 0));
  mesh.mesh = make_mesh(v, t);
  mesh.bound = calc_obstacle_bound(mesh);
  const Obstacle box = make_obstacle(ShapeType::kBox, 2 * h, 0, 0, rotz(0.4), Vec3(0.2, 0.1, 0));
  std::mt19937_64 g(21);
  std::uniform_real_distribution<double> pos(-3.0, 3.0);
  for (int k = 0; k < 100; ++k) {
    const Vec3 a(pos(g), pos(g), pos(g)), b(pos(g), pos(g), pos(g));
    const double exact = calc_clearance(box, a, b, 0.05).distance;
    if (exact < 1e-3) continue;
    EXPECT_NEAR(calc_clearance(mesh, a, b, 0.05).distance, exact, 1e-6) << k;
  }
  EXPECT_NEAR(mesh.bound, h.norm(), 1e-12);
}

}  // namespace
}  // namespace ff

namespace ff {
namespace {

TEST(MeshFile, AnStlIsReadWithItsScaleAndAMissingFileIsNamed) {
  // configs/meshes/pump.stl: a 12-sided column of radius 0.125 m up to z = 5 m over a head of 0.35 m down
  // to z = -1 m: its farthest vertex is sqrt(5^2 + 0.125^2) from the origin, scaled by 0.5 on every axis.
  const std::string file = std::string(FLEXFARM_SOURCE_DIR) + "/configs/meshes/pump.stl";
  const auto mesh = load_mesh(file, Vec3(0.5, 0.5, 0.5));
  EXPECT_EQ(mesh->triangles.size(), 2u * 4u * 12u);
  EXPECT_NEAR(calc_mesh_bound(*mesh), 0.5 * std::hypot(5.0, 0.125), 1e-6);
  EXPECT_NEAR(mesh->box_size.z(), 0.5 * 6.0, 1e-6);
  try {
    load_mesh("no/such/mesh.stl", Vec3::Ones());
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("no/such/mesh.stl: cannot read the mesh", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace ff
