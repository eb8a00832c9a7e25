// Model YAML files (docs/formats.md): strict parsing into a ModelSpec, then make_model.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

#include "kernel/model.hpp"

namespace ff {

// Parses and validates a model document; errors name `source`, the line and the key.
Model parse_model(const YAML::Node& doc, const std::string& source);
// Loads a model YAML file.
Model load_model(const std::string& path);

const char* integrator_name(Integrator i);

}  // namespace ff
