// Model parameters addressed by path: "payload.mass", "notch.enabled", "trajectory.moves[1].target".
// A study (or `--set` on the command line) overrides them in the model document before it is parsed,
// so every override passes the same checks as the model file itself.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace ff {

// Replaces (or creates) the value at `path` in `doc` with `value`. Throws ConfigError naming
// `source` and the path when the path cannot exist (indexing a map, a key inside a number, ...).
void set_path(YAML::Node& doc, const std::string& path, const YAML::Node& value, const std::string& source);

// The value at `path`, or a null node when absent.
YAML::Node get_path(const YAML::Node& doc, const std::string& path);

// Parses "path=value" (value in YAML syntax) and applies it.
void apply_assignment(YAML::Node& doc, const std::string& assignment, const std::string& source);

}  // namespace ff
