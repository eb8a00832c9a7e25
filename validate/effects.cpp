#include "validate/effects.hpp"

#include <algorithm>
#include <cmath>

namespace ff {

std::vector<std::string> effect_names() {
  return {"coulomb_friction",      "worn_gear_friction",     "viscous_friction",       "stribeck_friction",        "torque_offset",
          "lugre_friction",        "backlash",               "impact_backlash",          "drive_compliance",
          "mesh_hardening",        "hydraulic_compressibility", "torque_saturation",
          "joint_stiffening",      "sensor_delay.hub_angle", "sensor_delay.hub_rate",    "sensor_delay.hub_torque",
          "sensor_delay.tip_deflection", "loop_delay.hub_angle", "loop_delay.hub_rate", "logger_delay.hub_angle", "sensor_quantization", "extra_mode",
          "payload",               "hub_inertia"};
}

std::vector<std::string> effect_paths(const Effect& e) {
  std::vector<std::string> out;
  for (const auto& p : e.params) {
    out.push_back(p.path);
    if (!p.partner.empty()) out.push_back(p.partner);
  }
  if (!e.grid_path.empty()) out.push_back(e.grid_path);
  return out;
}

EffectParam make_effect_param(const std::string& path, double value, const EffectScales& sc) {
  if (path == "hub.torque_offset" || (path.size() > 14 && path.ends_with(".torque_offset"))) {
    const double b = 2.0 * std::max({std::abs(value), sc.torque_rms, 1e-6});
    return {path, value, -b, b, ParamScale::kLinear};
  }
  const double v = value > 0 ? value : 1.0;
  return {path, v, v / 1e3, v * 1e3, ParamScale::kLog};
}

EffectParam make_positive_param(const std::string& path, double current, double fallback, double lo, double hi) {
  const double start = std::clamp(current > 0 ? current : fallback, lo, hi);
  return {path, start, lo, hi, ParamScale::kLog};
}

std::vector<EffectParam> make_lugre_params(const std::string& prefix, const FrictionSpec& f, double tau, double inertia,
                                           std::vector<EffectParam> stribeck) {
  // Bristles deflecting z0 = Fc / sigma0 from 1 urad to 10 mrad at the Coulomb range's ends; damped from
  // a thousandth to ten times critical on the inertia J they hold (2 sqrt(sigma0 J) is critical).
  const bool lugre = f.model == "lugre";
  const double fc = std::max(f.coulomb, 0.05 * tau), j = std::max(inertia, 1e-9);
  const double s0 = lugre ? f.bristle_stiffness : fc / 1e-4;
  const double lo = 0.1 * tau, hi = 2e6 * tau;
  stribeck.push_back(make_positive_param(prefix + "bristle_stiffness", lugre ? s0 : 0.0, s0, lo, hi));
  stribeck.push_back(make_positive_param(prefix + "bristle_damping", lugre ? f.bristle_damping : 0.0, std::sqrt(s0 * j),
                                         2e-3 * std::sqrt(lo * j), 20.0 * std::sqrt(hi * j)));
  return stribeck;
}

EffectParam make_cubic_param(const std::string& path, double current, double k, double torque_max) {
  // k3 e^2 from 1e-4 to 1e4 times k at the twist e = torque_max / k the peak torque gives.
  const double e = std::max(torque_max, 1e-9) / std::max(k, 1e-9), s = k / (e * e);
  return make_positive_param(path, current, s, 1e-4 * s, 1e4 * s);
}

Effect make_worn_gear_effect(const std::string& name, const std::string& prefix, const std::string& extends,
                             const FrictionSpec& f, EffectParam coulomb, EffectParam smoothing) {
  Effect e{name, "friction whose level varies with the angle (a worn or eccentric gear)", {}, {coulomb, smoothing}, "",
           {}, false, extends};
  for (const auto& [k, now] : {std::pair{"position_cos", f.position_cos}, std::pair{"position_sin", f.position_sin}})
    e.params.push_back({prefix + k, std::clamp(now, -0.9, 0.9), -0.9, 0.9, ParamScale::kLinear});
  e.params.push_back(make_positive_param(prefix + "position_waves", f.position_waves, 10.0, 1.5, 60.0));
  // Each whole number of waves from 2 to 48 a start, as the valleys are about a wave apart on a record that
  // turns the joint a radian; at four phases of amplitude 0.4, as a ripple at the right waves but the wrong
  // phase adds as much misfit as it takes (four leave at most 45 degrees). The fit then refines all five.
  for (int p = 2; p <= 48; ++p)
    for (int k = 0; k < 4; ++k)
      e.starts.push_back({{prefix + "position_waves", p},
                          {prefix + "position_cos", 0.4 * std::cos(k * M_PI / 2)},
                          {prefix + "position_sin", 0.4 * std::sin(k * M_PI / 2)}});
  return e;
}

std::vector<double> make_delay_grid(int last) {
  std::vector<double> g;
  for (double x = 1.0; std::lround(x) <= last; x = std::max(x + 1.0, x * 4.0 / 3.0)) g.push_back(std::lround(x));
  if (g.back() != last) g.push_back(last);
  return g;
}

std::vector<double> make_encoder_quanta() {
  std::vector<double> quanta;
  for (int b = 9; b <= 22; ++b) quanta.push_back(2.0 * M_PI / std::ldexp(1.0, b));
  return quanta;
}

std::vector<Effect> make_candidate_effects(const Model& base, ReplayMode mode, const EffectScales& sc,
                                           const std::vector<std::string>& scored) {
  const auto& s = base.spec;
  const bool closed = mode == ReplayMode::kClosedLoop, inverse = mode == ReplayMode::kInverseDynamics;
  const double tau = std::max(sc.torque_rms, 1e-6), w = std::max(sc.rate_rms, 1e-6);
  const double kp = std::max(s.controller.kp, 1.0);
  std::vector<Effect> out;

  // Hub friction: levels from a thousandth of the torque RMS to twice it; the tanh smoothing from 1e-4 to 1e-2 of
  // the rate RMS (wider, a smooth Coulomb term imitates viscous friction: on EMPS the loop then ends at 7.8 %, not 6.2 %).
  const EffectParam coulomb = make_positive_param("friction.coulomb", s.friction.coulomb, 0.05 * tau, 1e-3 * tau, 2.0 * tau);
  const EffectParam smoothing = make_positive_param("friction.smoothing", s.friction.smoothing, 1e-3, 1e-4 * w, 1e-2 * w);
  out.push_back({"coulomb_friction", "Coulomb friction at the hub", {}, {coulomb, smoothing}, "", {}, false, ""});
  out.push_back({"viscous_friction", "viscous friction at the hub", {},
                 {make_positive_param("friction.viscous", s.friction.viscous, 0.05 * tau / w, 1e-4 * tau / w, 10.0 * tau / w)}, "",
                 {}, false, ""});
  const EffectParam stiction = make_positive_param("friction.stiction", s.friction.stiction,
                                                    std::max(0.1 * tau, 2.0 * s.friction.coulomb), 2e-3 * tau, 4.0 * tau);
  const EffectParam stribeck_velocity =
      make_positive_param("friction.stribeck_velocity", s.friction.stribeck_velocity, 0.05 * w, 1e-3 * w, w);
  out.push_back(make_worn_gear_effect("worn_gear_friction", "friction.", "coulomb_friction", s.friction, coulomb, smoothing));
  out.push_back({"stribeck_friction", "Coulomb friction with a Stribeck (stiction) peak", {},
                 {coulomb, stiction, stribeck_velocity, smoothing}, "", {}, false, "coulomb_friction"});
  out.push_back({"lugre_friction", "LuGre friction: the Stribeck curve with pre-sliding bristles", {{"friction.model", "lugre"}},
                 make_lugre_params("friction.", s.friction, tau, base.rigid_inertia, {coulomb, stiction, stribeck_velocity}), "",
                 {}, false, "stribeck_friction"});
  out.push_back({"torque_offset", "a constant load torque on the hub (cable drag, an unbalanced axis, amplifier bias)",
                 {}, {make_effect_param("hub.torque_offset", s.hub_torque_offset, sc)}, "", {}, false, ""});
  if (!inverse) {
    // The drive train: mesh stiffness from the PD's own spring to a thousand times it, its damping, and the
    // share of the hub's inertia that sits on the actuator side (the total kept).
    const double n2 = s.drive.ratio * s.drive.ratio;
    const double total = s.hub_inertia + (s.drive.enabled ? s.drive.inertia * n2 : 0.0);
    const double share0 = s.drive.enabled ? s.drive.inertia * n2 / total : 0.1;
    const EffectParam share{"drive.inertia", std::clamp(share0, 0.01, 0.9), 0.01, 0.9, ParamScale::kShare,
                            "hub.inertia", total, n2};
    const EffectParam stiffness = make_positive_param("drive.stiffness", s.drive.enabled ? s.drive.stiffness : 0.0, 200.0 * kp,
                                           kp, 1e3 * kp);
    const EffectParam damping = make_positive_param("drive.damping", s.drive.enabled ? s.drive.damping : 0.0, 2e3, 1.0, 1e5);
    out.push_back({"drive_compliance", "a compliant drive train between actuator and hub", {{"drive.enabled", "true"}},
                   {stiffness, damping, share}, "", {}, false, ""});
    const EffectParam play = make_positive_param("drive.backlash", s.drive.backlash, 1e-3, 1e-5, 3e-2);
    out.push_back({"backlash", "free play in the drive train", {{"drive.enabled", "true"}},
                   {play, stiffness, damping, share}, "", {}, false, "drive_compliance"});
    out.push_back({"impact_backlash", "free play whose mesh damps only as the teeth close (it rattles)",
                   {{"drive.enabled", "true"}, {"drive.closing_damping", "true"}}, {play, stiffness, damping, share}, "", {},
                   false, "backlash"});
    out.push_back({"mesh_hardening", "a compliant drive train whose mesh stiffens with its twist (k e + k3 e^3)",
                   {{"drive.enabled", "true"}},
                   {stiffness, damping, share,
                    make_cubic_param("drive.cubic_stiffness", s.drive.enabled ? s.drive.cubic_stiffness : 0.0, stiffness.initial,
                                     sc.torque_max)},
                   "", {}, false, "drive_compliance"});
    // The oil spring 4 beta D^2 / V: bulk modulus (entrained air lowers it by decades) and chamber volume.
    const double beta0 = s.hydraulics.enabled ? s.hydraulics.bulk_modulus : 1.4e9;
    const double v0 = s.hydraulics.chamber_volume;
    out.push_back({"hydraulic_compressibility", "oil compressibility of a hydraulic actuator",
                   {{"hydraulics.enabled", "true"}},
                   {make_positive_param("hydraulics.bulk_modulus", 0.5 * beta0, 0.5 * beta0, 1e7, 2e9),
                    make_positive_param("hydraulics.chamber_volume", v0, v0, 0.1 * v0, 10.0 * v0)},
                   "", {}, false, ""});
  }
  if (closed)
    out.push_back({"torque_saturation", "actuator torque saturation", {},
                   {make_positive_param("controller.torque_limit", 0.0, 0.8 * std::max(sc.torque_max, 1e-6),
                             0.05 * std::max(sc.torque_max, 1e-6), 1.5 * std::max(sc.torque_max, 1e-6))},
                   "", {}, false, ""});
  if (base.nseg > 1) {
    // Hardening k q + k3 q^3: k3 from a tenth of k (negligible at the rig's joint angles) to 1e5 k.
    const double k = s.joints.stiffness;
    out.push_back({"joint_stiffening", "hardening beam joints (cubic stiffness)", {},
                   {make_positive_param("joints.cubic_stiffness", s.joints.cubic_stiffness, 10.0 * k, 0.1 * k, 1e5 * k)}, "", {},
                   false, ""});
  }
  // Delays: from one controller sample to kMaxSearchedDelay. In the loop for the controller's sensors;
  // an output delay (the scored signal shifted only) for every scored output channel.
  const int last = std::max(24, static_cast<int>(std::ceil(kMaxSearchedDelay * s.controller.rate)));
  const std::vector<double> delays = make_delay_grid(last);
  if (closed) {
    out.push_back({"sensor_delay.hub_angle", "delay of the hub angle measurement (in the loop)", {}, {},
                   "sensors.hub_angle.delay", delays, true, ""});
    out.push_back({"sensor_delay.hub_rate", "delay of the hub rate measurement (in the loop)", {}, {},
                   "sensors.hub_rate.delay", delays, true, ""});
    // The same delay in the loop with the column logged on time (logged: true: a controller's latency, or
    // a logger that stamps each reading when taken), offered where the model says the column is as read.
    for (const auto& [c, ch] : {std::pair{"hub_angle", &s.sensors.hub_angle}, std::pair{"hub_rate", &s.sensors.hub_rate}})
      if (!is_logged_on_time(*ch) && std::find(scored.begin(), scored.end(), c) != scored.end())
        out.push_back({std::string("loop_delay.") + c,
                       std::string("delay of the ") + c + " in the loop only, its column logged on time",
                       {{std::string("sensors.") + c + ".logged", "true"}}, {}, std::string("sensors.") + c + ".delay",
                       delays, true, ""});
  }
  for (const char* c : {"hub_torque", "tip_deflection"})
    if (std::find(scored.begin(), scored.end(), c) != scored.end())
      out.push_back({std::string("sensor_delay.") + c, std::string("latency of the recorded ") + c + " (output only)",
                     {}, {}, std::string("sensors.") + c + ".delay", delays, true, ""});
  // A logger that stamps the on-time hub angle late (sensors.hub_angle.logged: true): the scored column
  // shifted, the loop untouched (with logged: read the column is as late as the loop's reading).
  if (!inverse && is_logged_on_time(s.sensors.hub_angle))
    out.push_back({"logger_delay.hub_angle", "latency of the logged hub angle (output only)", {}, {},
                   "sensors.hub_angle.logged_delay", delays, true, ""});
  if (closed) {
    // Binary encoders of 9 to 22 bits a turn (12 to 0.0015 mrad): a count is 2 pi / 2^b rad.
    out.push_back({"sensor_quantization", "quantisation of the hub angle encoder", {}, {},
                   "sensors.hub_angle.resolution", make_encoder_quanta(), false, ""});
  }
  if (s.beam.density > 0) {  // a massless arm has no mode to add
    std::vector<double> more;
    for (int n : {base.nseg + 1, 2 * base.nseg, 4 * base.nseg}) more.push_back(std::max(n, 2));
    out.push_back({"extra_mode", "more segments: a beam mode the model lacks", {}, {}, "segments", more, false, ""});
  }
  const double pm = s.payload_mass > 0 ? s.payload_mass : 1.0, pi = s.payload_inertia > 0 ? s.payload_inertia : 1.0;
  out.push_back({"payload", "payload mass and inertia (a re-fit, no new physics)", {},
                 {{"payload.mass", pm, pm / 10.0, pm * 10.0}, {"payload.inertia", pi, pi / 10.0, pi * 10.0}}, "", {},
                 false, ""});
  const double hj = s.hub_inertia > 0 ? s.hub_inertia : 1.0;
  out.push_back({"hub_inertia", "hub inertia (a re-fit, no new physics)", {}, {{"hub.inertia", hj, hj / 10.0, hj * 30.0}},
                 "", {}, false, ""});
  return out;
}

}  // namespace ff
