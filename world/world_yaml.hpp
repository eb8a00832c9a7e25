// The `world:` block of a model file (docs/formats.md, "World"): a map from obstacle name to its shape
// and pose, one field table for every type; the keys a type does not use are errors. Sweepable like
// any other key (`world.riser.radius`).
#pragma once

#include <string>
#include <vector>

#include "common/field_table.hpp"
#include "common/yaml_reader.hpp"
#include "world/world.hpp"

namespace ff {

// Reads the block `world` of `top` (absent: an empty world). Mesh files are resolved against the
// folder of `source`. Every error is one ConfigError naming the file, line and key (world.NAME.KEY).
World read_world(YamlReader& top, const std::string& source);

// The block's keys for the docs (world.NAME.*).
std::vector<KeyDoc> world_yaml_keys();

}  // namespace ff
