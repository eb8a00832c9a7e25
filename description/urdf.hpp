// URDF import (docs/formats.md, "Kinematic trees (YAML) and URDF"): links and joints through liburdfdom,
// the Gazebo spring tags and every line number through a TinyXML pass of the same text. The root link is
// the fixed base; every other link is a body, listed parents first (children in the order of their
// joints in the file). Every error is one ConfigError "FILE:LINE: joint "elbow": what is wrong"; nothing
// is printed (liburdfdom's console output is captured into the error or the notes).
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "description/tree_description.hpp"
#include "description/tree_yaml.hpp"

namespace ff {

// The deepest nesting of XML elements a URDF may have (one holds about 5: robot, link, visual, geometry,
// mesh); a deeper file is refused before it is parsed, at the line of the first element too deep.
inline constexpr int kMaxUrdfDepth = 100;

// Parses URDF text; errors and notes name `source`. The returned spec passes make_tree.
TreeDescription parse_urdf(const std::string& xml, const std::string& source);
// Loads a URDF file and, when `sidecar` is not empty, applies that flexfarm sidecar YAML to it.
TreeDescription load_urdf(const std::string& path, const std::string& sidecar = "");

// The sidecar: `joints: {NAME: {armature:, stiffness:, damping:, spring_reference:}}`, each given value
// replacing the URDF's for that (revolute or prismatic) joint, and `links: {NAME: {flexible: {...}}}`,
// each link (not the root) made a flexible link (the tree YAML block, read_flexible_block; make_flexible):
// its <inertial> replaced by the beam (with a note), the beam along the link frame's +x, its child
// joints moved onto the tip segment. Read strictly; errors name `source`, the line and the key.
void apply_urdf_sidecar(TreeDescription& d, const YAML::Node& doc, const std::string& source);
std::vector<KeyDoc> urdf_sidecar_keys();

}  // namespace ff
