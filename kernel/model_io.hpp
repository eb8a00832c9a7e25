// Model YAML files (docs/formats.md): strict parsing into a ModelSpec, then make_model.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <string>
#include <vector>

#include "common/field_table.hpp"
#include "kernel/model.hpp"

namespace ff {

// Parses and validates a model document; errors name `source`, the line and the key. `controller`: the
// controller's internal model (make_model), nullptr = the document's own.
Model parse_model(const YAML::Node& doc, const std::string& source, const Model* controller = nullptr);
// Loads a model YAML file.
Model load_model(const std::string& path);

const char* integrator_name(Integrator i);

// The reference rig's model keys, from its readers' field tables (docs/formats.md, "Model").
std::vector<KeyDoc> rig_model_keys();

// The hydraulic actuator's keys (kernel/model.hpp HydraulicSpec), one table for the rig's
// `hydraulics:` block (which reads them without bounds: make_model checks them, explain_hydraulic_fault)
// and an arm joint's `joints.NAME.hydraulics:` (arm/arm_yaml.cpp: read with the bounds). `enabled` is
// the rig's alone (an arm's block is on by its presence). Units: a prismatic joint's in parentheses.
inline constexpr std::size_t kHydraulicFieldCount = 19;
const std::array<Field<HydraulicSpec>, kHydraulicFieldCount>& hydraulic_fields();

// k_v and D in one form each: a physical key given (> 0) next to a rated one in the block `hy` is
// named (hy.fail).
void check_hydraulic_forms(YamlReader& hy, const HydraulicSpec& h);

}  // namespace ff
