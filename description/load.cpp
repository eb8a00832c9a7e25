#include "description/load.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>

#include "description/tree_yaml.hpp"
#include "description/urdf.hpp"
#include "common/errors.hpp"

namespace ff {

namespace {
bool is_urdf(const std::string& path) { return std::filesystem::path(path).extension() == ".urdf"; }
}  // namespace

bool is_tree_description(const std::string& path) {
  if (is_urdf(path)) return true;
  try {
    const YAML::Node doc = YAML::LoadFile(path);
    return doc.IsMap() && doc["bodies"];
  } catch (const std::exception&) {
    return false;
  }
}

TreeDescription load_tree_description(const std::string& path, const std::string& sidecar) {
  if (is_urdf(path)) return load_urdf(path, sidecar);
  if (!sidecar.empty())
    throw ConfigError(sidecar, 0, "sidecar", "a sidecar goes with a URDF file; " + path +
                                                 " is tree YAML (write the values there)");
  return load_tree_yaml(path);
}

}  // namespace ff
