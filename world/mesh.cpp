// Mesh obstacles (mesh.hpp): assimp reads, FCL measures.
#include "world/mesh.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fcl/narrowphase/distance.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/sphere.h>

namespace ff {

namespace {

using Bvh = fcl::BVHModel<fcl::OBBRSSd>;

// The frame of a capsule of segment [a, b]: centred, its z axis along b - a.
fcl::Transform3d capsule_frame(const Vec3& a, const Vec3& b) {
  fcl::Transform3d X = fcl::Transform3d::Identity();
  X.translation() = 0.5 * (a + b);
  const Vec3 d = b - a;
  if (d.norm() > 0) X.linear() = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), d).toRotationMatrix();
  return X;
}

}  // namespace

std::shared_ptr<const MeshGeometry> make_mesh(std::vector<Vec3> vertices, std::vector<std::array<int, 3>> triangles) {
  if (triangles.empty()) throw std::invalid_argument("a mesh needs at least one triangle");
  for (const Vec3& v : vertices)
    if (!v.allFinite()) throw std::invalid_argument("a mesh vertex is not finite");
  std::vector<fcl::Triangle> tris;
  tris.reserve(triangles.size());
  for (const auto& t : triangles) {
    for (int i : t)
      if (i < 0 || i >= static_cast<int>(vertices.size())) throw std::invalid_argument("a mesh triangle's vertex index is out of range");
    tris.emplace_back(static_cast<std::size_t>(t[0]), static_cast<std::size_t>(t[1]), static_cast<std::size_t>(t[2]));
  }
  auto bvh = std::make_shared<Bvh>();
  bvh->beginModel();
  bvh->addSubModel(vertices, tris);
  bvh->endModel();
  auto m = std::make_shared<MeshGeometry>();
  m->vertices = std::move(vertices);
  m->triangles = std::move(triangles);
  m->bvh = std::move(bvh);
  Vec3 lo = m->vertices.front(), hi = lo;
  for (const Vec3& v : m->vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  m->box_centre = 0.5 * (lo + hi);
  m->box_size = hi - lo;
  return m;
}

std::shared_ptr<const MeshGeometry> load_mesh(const std::string& path, const Vec3& scale) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices);
  if (!scene) throw std::runtime_error(path + ": cannot read the mesh: " + importer.GetErrorString());
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  for (unsigned k = 0; k < scene->mNumMeshes; ++k) {
    const aiMesh* mesh = scene->mMeshes[k];
    const int base = static_cast<int>(vertices.size());
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D& v = mesh->mVertices[i];
      vertices.emplace_back(scale.x() * v.x, scale.y() * v.y, scale.z() * v.z);
    }
    for (unsigned i = 0; i < mesh->mNumFaces; ++i) {
      const aiFace& f = mesh->mFaces[i];
      if (f.mNumIndices != 3) continue;  // points and lines left by the triangulation
      triangles.push_back({base + static_cast<int>(f.mIndices[0]), base + static_cast<int>(f.mIndices[1]),
                           base + static_cast<int>(f.mIndices[2])});
    }
  }
  if (triangles.empty()) throw std::runtime_error(path + ": the mesh file holds no triangles");
  try {
    return make_mesh(std::move(vertices), std::move(triangles));
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

double calc_mesh_bound(const MeshGeometry& mesh) {
  double r = 0.0;
  for (const Vec3& v : mesh.vertices) r = std::max(r, v.norm());
  return r;
}

Clearance calc_mesh_clearance(const Obstacle& o, const Vec3& a, const Vec3& b, double r) {
  const auto bvh = std::static_pointer_cast<const Bvh>(o.mesh->bvh);
  // FCL's objects hold non-const geometry; the query only reads it.
  std::shared_ptr<fcl::CollisionGeometryd> g0;
  const double len = (b - a).norm();
  if (len > 0) g0 = std::make_shared<fcl::Capsuled>(r, len);
  else g0 = std::make_shared<fcl::Sphered>(r);
  fcl::Transform3d Xo = fcl::Transform3d::Identity();
  Xo.linear() = o.rotation;
  Xo.translation() = o.position;
  const fcl::CollisionObjectd capsule(g0, capsule_frame(a, b));
  const fcl::CollisionObjectd mesh(std::const_pointer_cast<Bvh>(bvh), Xo);
  fcl::DistanceRequestd request(true);
  fcl::DistanceResultd result;
  fcl::distance(&capsule, &mesh, request, result);
  Clearance c;
  c.distance = std::max(result.min_distance, 0.0);
  // FCL's point lies on the capsule's surface: back onto its segment.
  c.on_segment = a + calc_point_segment_parameter(result.nearest_points[0], a, b) * (b - a);
  c.on_obstacle = result.nearest_points[1];
  return c;
}

}  // namespace ff
