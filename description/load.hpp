// One way to read a kinematic tree from a file, whatever its format: URDF (by its .urdf extension;
// description/urdf.hpp) or tree YAML (a YAML document with a top-level `bodies` list;
// description/tree_yaml.hpp). flexfarm's own model files (configs/fbtb.yaml) are neither.
#pragma once

#include <string>

#include "description/tree_description.hpp"

namespace ff {

// Whether `path` names a tree description rather than a flexfarm model file: a .urdf file, or YAML
// whose top level has `bodies`. Reads the file; a file that cannot be read or parsed is not one (the
// model loader then reports it).
bool is_tree_description(const std::string& path);

// Loads a tree description; `sidecar` (URDF only, may be empty) as load_urdf. Errors are ConfigErrors
// naming the file and line; a sidecar given with tree YAML is an error.
TreeDescription load_tree_description(const std::string& path, const std::string& sidecar = "");

}  // namespace ff
