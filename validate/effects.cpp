#include "validate/effects.hpp"

#include <algorithm>
#include <cmath>

namespace ff {

std::vector<std::string> effect_names() {
  return {"coulomb_friction", "viscous_friction", "stribeck_friction", "torque_offset", "backlash", "drive_compliance",
          "hydraulic_compressibility", "torque_saturation", "joint_stiffening", "sensor_delay.hub_angle",
          "sensor_delay.hub_rate", "sensor_quantization", "extra_mode", "payload", "hub_inertia"};
}

EffectParam make_effect_param(const std::string& path, double value, const EffectScales& sc) {
  if (path == "hub.torque_offset")
    return {path, value, true, 2.0 * std::max({std::abs(value), sc.torque_rms, 1e-6})};
  return {path, value > 0 ? value : 1.0, false, 1.0};
}

std::vector<Effect> make_candidate_effects(const Model& base, ReplayMode mode, const EffectScales& sc) {
  const auto& s = base.spec;
  const bool closed = mode == ReplayMode::kClosedLoop, inverse = mode == ReplayMode::kInverseDynamics;
  const double tau = std::max(sc.torque_rms, 1e-6), w = std::max(sc.rate_rms, 1e-6);
  auto start = [](double current, double fallback) { return current > 0 ? current : fallback; };
  std::vector<Effect> out;
  out.push_back({"coulomb_friction", "Coulomb friction at the hub", {},
                 {{"friction.coulomb", start(s.friction.coulomb, 0.05 * tau)}}, "", {}, ""});
  out.push_back({"viscous_friction", "viscous friction at the hub", {},
                 {{"friction.viscous", start(s.friction.viscous, 0.05 * tau / w)}}, "", {}, ""});
  out.push_back({"stribeck_friction", "Coulomb friction with a Stribeck (stiction) peak", {},
                 {{"friction.coulomb", start(s.friction.coulomb, 0.05 * tau)},
                  {"friction.stiction", start(s.friction.stiction, std::max(0.1 * tau, 2.0 * s.friction.coulomb))},
                  {"friction.stribeck_velocity", std::max(s.friction.stribeck_velocity, 0.05 * w)}},
                 "", {}, "coulomb_friction"});
  out.push_back({"torque_offset", "a constant load torque on the hub (cable drag, an unbalanced axis, amplifier bias)",
                 {}, {make_effect_param("hub.torque_offset", s.hub_torque_offset, sc)}, "", {}, ""});
  if (!inverse) {
    out.push_back({"backlash", "free play in the drive train", {{"drive.enabled", "true"}},
                   {{"drive.backlash", start(s.drive.backlash, 1e-3)}}, "", {}, ""});
    out.push_back({"drive_compliance", "a compliant drive train between actuator and hub", {{"drive.enabled", "true"}},
                   {{"drive.stiffness", s.drive.enabled ? s.drive.stiffness : 200.0 * std::max(s.controller.kp, 1.0)}},
                   "", {}, ""});
    out.push_back({"hydraulic_compressibility", "oil compressibility of a hydraulic actuator",
                   {{"hydraulics.enabled", "true"}},
                   {{"hydraulics.bulk_modulus", s.hydraulics.enabled ? 0.5 * s.hydraulics.bulk_modulus : 1.4e9}}, "",
                   {}, ""});
  }
  if (closed)
    out.push_back({"torque_saturation", "actuator torque saturation", {},
                   {{"controller.torque_limit", 0.8 * std::max(sc.torque_max, 1e-6)}}, "", {}, ""});
  if (base.nseg > 1)
    out.push_back({"joint_stiffening", "hardening beam joints (cubic stiffness)", {},
                   {{"joints.cubic_stiffness", start(s.joints.cubic_stiffness, 0.1 * s.joints.stiffness)}}, "", {}, ""});
  if (closed) {
    out.push_back({"sensor_delay.hub_angle", "delay of the hub angle measurement", {}, {}, "sensors.hub_angle.delay",
                   {1, 2, 3, 4, 6, 8, 12, 16, 24}, ""});
    out.push_back({"sensor_delay.hub_rate", "delay of the hub rate measurement", {}, {}, "sensors.hub_rate.delay",
                   {1, 2, 3, 4, 6, 8, 12, 16, 24}, ""});
    std::vector<double> quanta;
    for (int i = 0; i <= 12; ++i) quanta.push_back(1e-6 * std::pow(10.0, i / 3.0));  // 1e-6 .. 1e-2 rad
    out.push_back({"sensor_quantization", "quantisation of the hub angle encoder", {}, {},
                   "sensors.hub_angle.resolution", quanta, ""});
  }
  if (s.beam.density > 0) {  // a massless arm has no mode to add
    std::vector<double> more;
    for (int n : {base.nseg + 1, 2 * base.nseg, 4 * base.nseg}) more.push_back(std::max(n, 2));
    out.push_back({"extra_mode", "more segments: a beam mode the model lacks", {}, {}, "segments", more, ""});
  }
  out.push_back({"payload", "payload mass and inertia (a re-fit, no new physics)", {},
                 {{"payload.mass", start(s.payload_mass, 1.0)}, {"payload.inertia", start(s.payload_inertia, 1.0)}}, "",
                 {}, ""});
  out.push_back({"hub_inertia", "hub inertia (a re-fit, no new physics)", {}, {{"hub.inertia", start(s.hub_inertia, 1.0)}},
                 "", {}, ""});
  return out;
}

}  // namespace ff
