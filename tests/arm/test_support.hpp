// Helpers of the arm tests: an arm model from YAML text (named "arm.yaml" in errors), and the one
// error its reader throws.
#pragma once

#include <string>

#include "arm/arm_yaml.hpp"
#include "common/errors.hpp"
#include "common/yaml_reader.hpp"

namespace ff::test {

// A 2 kg bob 0.5 m out on a hinge about y (gravity -z: at q = 0 the arm is horizontal), rotor 0.05: the
// file's first 8 lines (gravity and bodies), then `rest`.
inline std::string pendulum_arm(const std::string& rest) {
  return R"(gravity: [0, 0, -9.81]
bodies:
  - name: arm
    parent: base
    mass: 2.0
    com: [0.5, 0, 0]
    inertia: {ixx: 0.001, iyy: 0.01, izz: 0.01}
    joint: {type: revolute, axis: [0, 1, 0], armature: 0.05}
)" + rest;
}

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
