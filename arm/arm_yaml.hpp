// Arm model files (docs/formats.md, "Arm models"): a kinematic tree, inline (tree YAML's `gravity` and
// `bodies`) or from a URDF (`urdf`, `sidecar`), with the control of its actuated joints, the tool (or
// several by name: `tools`), a trajectory through waypoints and the simulation settings. Read strictly,
// each block from its field table; every error is one ConfigError naming the file, line and key path.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "arm/arm_model.hpp"
#include "common/field_table.hpp"

namespace ff {

// Whether a YAML document is an arm model (or a bare tree): its top level has `bodies` or `urdf`.
bool is_arm_document(const YAML::Node& doc);

// Parses a document into a spec (the tree read and checked, the rest checked for form); `source`
// names it in errors and resolves `urdf` and `sidecar` paths (relative to its folder).
ArmSpec parse_arm_spec(const YAML::Node& doc, const std::string& source);
// parse_arm_spec, then make_arm.
ArmModel parse_arm(const YAML::Node& doc, const std::string& source, std::shared_ptr<const ArmModel> controller = nullptr);

// Every key of the format beyond the tree's (tree_yaml_keys), for the docs test.
std::vector<KeyDoc> arm_yaml_keys();

}  // namespace ff
