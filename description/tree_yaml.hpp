// Tree YAML files (docs/formats.md, "Kinematic trees (YAML) and URDF"): a kinematic tree as a list of
// bodies, parents first, each with the joint to its parent, rigid or flexible (a `flexible:` block,
// made a flexible link by make_flexible, tree_description.hpp). Read strictly (common/yaml_reader.hpp):
// every error, make_tree's included, is one ConfigError naming the file, the line and the key path.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "common/field_table.hpp"
#include "description/tree_description.hpp"
#include "common/yaml_reader.hpp"

namespace ff {

// Parses and validates a tree document; errors name `source`. The returned spec passes make_tree.
TreeDescription parse_tree_yaml(const YAML::Node& doc, const std::string& source);
// Loads a tree YAML file.
TreeDescription load_tree_yaml(const std::string& path);

std::vector<KeyDoc> tree_yaml_keys();

// A `flexible:` block (docs/formats.md; tree YAML bodies and the URDF sidecar's links): its keys read
// from `r` (the block's own reader, then finished), bounds, required keys and the payload inertia
// checked. The returned spec's name, root name and root joint are left for make_flexible.
FlexibleLinkSpec read_flexible_block(YamlReader& r);
std::vector<KeyDoc> flexible_keys(const std::string& prefix);

// The joint block's passive keys (armature, stiffness, damping, spring_reference): those present in
// `r` read into `body` and checked (>= 0 where make_tree wants it); for the URDF sidecar.
void read_joint_springs(YamlReader& r, BodySpec& body);
std::vector<KeyDoc> joint_spring_keys(const std::string& prefix);

}  // namespace ff
