// Helpers of the arm tests: an arm model from YAML text (named "arm.yaml" in errors), and the one
// error its reader throws.
#pragma once

#include <string>

#include "arm/arm_yaml.hpp"
#include "common/errors.hpp"
#include "common/yaml_reader.hpp"

namespace ff::test {

inline ArmModel arm_from(const std::string& text) { return parse_arm(load_yaml_text(text, "arm.yaml"), "arm.yaml"); }

// The ConfigError's text, or "no error".
inline std::string arm_error(const std::string& text) {
  try {
    arm_from(text);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace ff::test
