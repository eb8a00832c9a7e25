// The `world:` block (world_yaml.hpp).
#include "world/world_yaml.hpp"

#include <array>
#include <filesystem>
#include <stdexcept>

#include "world/mesh.hpp"

namespace ff {

namespace {

struct ObstacleBlock {
  std::string type;
  Vec3 position = Vec3::Zero();
  Vec3 rpy = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();
  Vec3 size = Vec3::Zero();
  double radius = 0.0, length = 0.0;
  std::string file;
  Vec3 scale = Vec3::Ones();
};

const std::array<Field<ObstacleBlock>, 9> kObstacleFields{{
    {.key = "type", .member = &ObstacleBlock::type, .required = true},
    {.key = "position", .member = &ObstacleBlock::position, .unit = "m"},
    {.key = "rpy", .member = &ObstacleBlock::rpy, .unit = "rad"},
    {.key = "axis", .member = &ObstacleBlock::axis, .bound = Bound::kNonZero,
     .fallback = "[0, 0, 1]: the frame's z (not with rpy)"},
    {.key = "size", .member = &ObstacleBlock::size, .unit = "m", .fallback = "box: required"},
    {.key = "radius", .member = &ObstacleBlock::radius, .unit = "m", .bound = Bound::kPositive,
     .fallback = "sphere, cylinder, capsule, bore: required"},
    {.key = "length", .member = &ObstacleBlock::length, .unit = "m", .bound = Bound::kNonNegative,
     .fallback = "cylinder, capsule, bore: required"},
    {.key = "file", .member = &ObstacleBlock::file, .fallback = "mesh: required"},
    {.key = "scale", .member = &ObstacleBlock::scale},
}};

// Which keys (beyond type, position, rpy) each type takes.
bool uses(ShapeType t, const std::string& key) {
  if (key == "type" || key == "position" || key == "rpy") return true;
  switch (t) {
    case ShapeType::kBox: return key == "size";
    case ShapeType::kSphere: return key == "radius";
    case ShapeType::kCylinder:
    case ShapeType::kCapsule:
    case ShapeType::kBore: return key == "radius" || key == "length" || key == "axis";
    case ShapeType::kPlane: return key == "axis";
    case ShapeType::kMesh: return key == "file" || key == "scale";
  }
  return false;
}

bool needs(ShapeType t, const std::string& key) {
  switch (t) {
    case ShapeType::kBox: return key == "size";
    case ShapeType::kSphere: return key == "radius";
    case ShapeType::kCylinder:
    case ShapeType::kCapsule:
    case ShapeType::kBore: return key == "radius" || key == "length";
    case ShapeType::kPlane: return false;
    case ShapeType::kMesh: return key == "file";
  }
  return false;
}

}  // namespace

World read_world(YamlReader& top, const std::string& source) {
  World w;
  for (auto& [name, one] : top.named_blocks("world", "a map from obstacle name to its {type, position, ...}",
                                            "an obstacle's name heads its columns (NAME.clearance): no dots, spaces, "
                                            "commas or quotes")) {
    Obstacle o;
    o.name = name;
    if (!one.has("type")) one.fail_missing("type", "missing required value (box, sphere, cylinder, capsule, bore, plane, mesh)");
    ObstacleBlock b;
    read_present(one, kObstacleFields, b);
    if (!parse_shape_type(b.type, o.type))
      one.fail("type", "unknown obstacle type '" + b.type + "' (box, sphere, cylinder, capsule, bore, plane, mesh)");
    for (const auto& f : kObstacleFields) {
      if (one.has(f.key) && !uses(o.type, f.key)) one.fail(f.key, std::string("is not a key of a ") + b.type);
      if (!one.has(f.key) && needs(o.type, f.key)) one.fail(f.key, std::string("missing: a ") + b.type + " needs it");
    }
    one.finish();
    if (one.has("axis") && one.has("rpy")) one.fail("axis", "give the orientation either as rpy or as axis, not both");
    o.position = b.position;
    o.rotation = one.has("axis") ? Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), b.axis).toRotationMatrix()
                                 : Mat3(Eigen::AngleAxisd(b.rpy.z(), Vec3::UnitZ()) *
                                        Eigen::AngleAxisd(b.rpy.y(), Vec3::UnitY()) *
                                        Eigen::AngleAxisd(b.rpy.x(), Vec3::UnitX()));
    o.size = b.size;
    o.radius = b.radius;
    o.length = b.length;
    if (o.type == ShapeType::kBox && !(b.size.minCoeff() > 0))
      one.fail("size", "every edge of a box must be > 0, got " + format_key_vector(b.size));
    if ((o.type == ShapeType::kCylinder || o.type == ShapeType::kBore) && !(b.length > 0))
      one.fail("length", "must be > 0");
    if (o.type == ShapeType::kMesh) {
      if (!(b.scale.minCoeff() > 0)) one.fail("scale", "every factor must be > 0, got " + format_key_vector(b.scale));
      std::filesystem::path file(b.file);
      if (file.is_relative()) file = std::filesystem::path(source).parent_path() / file;
      try {
        o.mesh = load_mesh(file.lexically_normal().string(), b.scale);
      } catch (const std::runtime_error& e) {
        one.fail("file", e.what());
      }
    }
    o.bound = calc_obstacle_bound(o);
    o.line = one.line();
    w.obstacles.push_back(std::move(o));
  }
  return w;
}

std::vector<KeyDoc> world_yaml_keys() {
  std::vector<KeyDoc> out;
  add_keys(out, "world.NAME.", kObstacleFields);
  return out;
}

}  // namespace ff
