// Helpers of the arm tests: an arm model from YAML text (named "arm.yaml" in errors), the one error its
// reader throws, and bitwise equality.
#pragma once

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <string>
#include <vector>

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

// The pendulum under a stiff tracking controller (kp 4000, kd 120, full feed-forward) at 1000 Hz, moving
// 0 -> q_end rad in 1 s (quintic), then settling 1 s; `head` before its controller (a tool), `more` after.
inline std::string tracking_pendulum(double q_end, const std::string& head, const std::string& more) {
  return pendulum_arm(head + R"(controller: {rate: 1000}
joints:
  arm: {controller: {kp: 4000, kd: 120, feedforward: 1, gravity_compensation: 1}}
trajectory:
  waypoints:
    - {time: 1.0, joints: {arm: )" + std::to_string(q_end) + R"(}}
simulation: {settle: 1.0}
)" + more);
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

// The same bits in two vectors (NaN as NaN): a trace column or metrics row of a lane of a batch and of the
// lane alone, or online and stored.
inline void expect_same_bits(const std::vector<double>& a, const std::vector<double>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i)
    ASSERT_EQ(std::bit_cast<std::uint64_t>(a[i]), std::bit_cast<std::uint64_t>(b[i])) << what << " [" << i << "]";
}

}  // namespace ff::test
