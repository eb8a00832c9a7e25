// Triangle-mesh obstacles (world.hpp's ShapeType::kMesh): read from a file by assimp (STL, OBJ, PLY, ...:
// every mesh of the file in its root frame, triangulated), held with FCL 0.7's bounding-volume tree,
// and a capsule's clearance to them through FCL's distance query.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "world/world.hpp"

namespace ff {

struct MeshGeometry {
  std::vector<Vec3> vertices;                 // the obstacle's frame, m (scaled)
  std::vector<std::array<int, 3>> triangles;  // vertex indices
  std::shared_ptr<const void> bvh;            // FCL's BVHModel<OBBRSSd> (mesh.cpp keeps FCL's headers)
  Vec3 box_centre = Vec3::Zero();             // the vertices' axis-aligned bounding box, the obstacle's frame, m
  Vec3 box_size = Vec3::Zero();
};

// The mesh of vertices and triangles (the obstacle's frame, m) with its bounding-volume tree. Throws
// std::invalid_argument for no triangles, an index out of range or a non-finite vertex.
std::shared_ptr<const MeshGeometry> make_mesh(std::vector<Vec3> vertices, std::vector<std::array<int, 3>> triangles);

// Every mesh of a file (assimp: STL, OBJ, PLY, ...), each vertex multiplied by `scale` (per axis). Throws
// std::runtime_error naming the file when it cannot be read or holds no triangles.
std::shared_ptr<const MeshGeometry> load_mesh(const std::string& path, const Vec3& scale);

// The farthest vertex from the frame's origin, m.
double calc_mesh_bound(const MeshGeometry& mesh);

// The clearance of the capsule [a, b] (base frame, m), radius r, to the mesh obstacle o (world.hpp): FCL's
// distance and nearest points; 0 when they overlap.
Clearance calc_mesh_clearance(const Obstacle& o, const Vec3& a, const Vec3& b, double r);

}  // namespace ff
