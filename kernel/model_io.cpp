#include "kernel/model_io.hpp"

#include <cmath>
#include <initializer_list>
#include <string>
#include <utility>
#include <variant>

#include "common/errors.hpp"
#include "common/yaml_reader.hpp"

namespace ff {

const std::array<Field<HydraulicSpec>, kHydraulicFieldCount>& hydraulic_fields() {
  using H = HydraulicSpec;
  static const std::array<Field<H>, kHydraulicFieldCount> fields{{
      {.key = "displacement", .member = &H::displacement, .unit = "m³/rad (m²)", .bound = Bound::kPositive},
      {.key = "piston_area", .member = &H::piston_area, .unit = "m²", .bound = Bound::kNonNegative,
       .fallback = "0: not given"},
      {.key = "pinion_radius", .member = &H::pinion_radius, .unit = "m", .bound = Bound::kNonNegative,
       .fallback = "0: not given"},
      {.key = "chamber_volume", .member = &H::chamber_volume, .unit = "m³", .bound = Bound::kPositive},
      {.key = "bulk_modulus", .member = &H::bulk_modulus, .unit = "Pa", .bound = Bound::kPositive},
      {.key = "supply_pressure", .member = &H::supply_pressure, .unit = "Pa", .bound = Bound::kPositive},
      {.key = "tank_pressure", .member = &H::tank_pressure, .unit = "Pa", .bound = Bound::kNonNegative},
      {.key = "relief_pressure", .member = &H::relief_pressure, .unit = "Pa", .bound = Bound::kNonNegative,
       .fallback = "0: 1.1 p_s"},
      {.key = "rated_flow", .member = &H::rated_flow, .unit = "m³/s", .bound = Bound::kPositive},
      {.key = "rated_drop", .member = &H::rated_drop, .unit = "Pa", .bound = Bound::kPositive},
      {.key = "discharge_coefficient", .member = &H::discharge_coefficient, .bound = Bound::kNonNegative,
       .fallback = "0: not given"},
      {.key = "port_width", .member = &H::port_width, .unit = "m", .bound = Bound::kNonNegative,
       .fallback = "0: not given"},
      {.key = "spool_stroke", .member = &H::spool_stroke, .unit = "m", .bound = Bound::kNonNegative,
       .fallback = "0: not given"},
      {.key = "oil_density", .member = &H::oil_density, .unit = "kg/m³", .bound = Bound::kNonNegative,
       .fallback = "0: not given"},
      {.key = "laminar_drop", .member = &H::laminar_drop, .unit = "Pa", .bound = Bound::kPositive},
      {.key = "leakage", .member = &H::leakage, .unit = "m³/(s·Pa)", .bound = Bound::kNonNegative},
      {.key = "valve_frequency", .member = &H::valve_frequency, .unit = "Hz", .bound = Bound::kPositive},
      {.key = "valve_damping", .member = &H::valve_damping, .bound = Bound::kPositive},
      {.key = "pressure_gain", .member = &H::pressure_gain, .bound = Bound::kNonNegative},
  }};
  return fields;
}

void check_hydraulic_forms(YamlReader& hy, const HydraulicSpec& h) {
  // k_v and D in one form each: a physical key given (> 0) next to a rated one in the file is named.
  auto one_form = [&](std::initializer_list<std::pair<const char*, double>> physical,
                      std::initializer_list<const char*> rated, const std::string& forms) {
    for (const auto& [key, x] : physical)
      for (const char* r : rated)
        if (x > 0 && hy.has(r)) hy.fail(key, std::string("given with hydraulics.") + r + ": " + forms + ", not both");
  };
  one_form({{"discharge_coefficient", h.discharge_coefficient},
            {"port_width", h.port_width},
            {"spool_stroke", h.spool_stroke},
            {"oil_density", h.oil_density}},
           {"rated_flow", "rated_drop"},
           "k_v comes from rated_flow and rated_drop or from discharge_coefficient, port_width, spool_stroke and "
           "oil_density");
  one_form({{"piston_area", h.piston_area}, {"pinion_radius", h.pinion_radius}}, {"displacement"},
           "D is displacement or piston_area times pinion_radius");
}

const char* integrator_name(Integrator i) {
  switch (i) {
    case Integrator::kRk4: return "rk4";
    case Integrator::kSdirk2: return "sdirk2";
    case Integrator::kCvodeDense: return "cvode_dense";
    case Integrator::kCvodeKlu: return "cvode_klu";
    case Integrator::kMidpoint: return "midpoint";
    case Integrator::kCvodeGmres: return "cvode_gmres";
  }
  return "?";
}

namespace {

Integrator parse_integrator(YamlReader& r) {
  std::string name = "rk4";
  r.optional("integrator", name);
  for (auto i : {Integrator::kRk4, Integrator::kSdirk2, Integrator::kCvodeDense, Integrator::kCvodeKlu,
                 Integrator::kMidpoint})
    if (name == integrator_name(i)) return i;
  r.fail("integrator", "unknown integrator '" + name + "' (rk4, sdirk2, cvode_dense, cvode_klu, midpoint)");
}

ModelSpec parse_spec(const YAML::Node& doc, const std::string& src, LineMap& lines) {
  ModelSpec s;
  YamlReader top(doc, src, "", &lines);
  if (!doc || doc.IsNull()) top.fail("beam", "the file is empty");

  auto beam = top.child("beam", true);
  beam.required("length", s.beam.length);
  beam.required("height", s.beam.height);
  beam.required("thickness", s.beam.thickness);
  beam.required("density", s.beam.density);
  beam.required("youngs_modulus", s.beam.youngs_modulus);
  beam.finish();

  top.required("segments", s.segments);

  auto joints = top.child("joints", true);
  joints.required("stiffness", s.joints.stiffness);
  joints.required("damping", s.joints.damping);
  joints.required("reference_cell", s.joints.reference_cell);
  joints.optional("cubic_stiffness", s.joints.cubic_stiffness);
  joints.finish();

  auto hub = top.child("hub", true);
  hub.required("inertia", s.hub_inertia);
  hub.optional("torque_offset", s.hub_torque_offset);
  hub.finish();

  auto payload = top.child("payload", true);
  payload.required("mass", s.payload_mass);
  payload.required("inertia", s.payload_inertia);
  for (auto& ev : payload.sequence("events")) {
    ev.only({"time", "mass", "inertia"});  // a misspelt key is unknown, not a missing one
    PayloadEvent e;
    ev.required("time", e.time);
    ev.required("mass", e.mass);
    ev.required("inertia", e.inertia);
    ev.finish();
    s.payload_events.push_back(e);
  }
  payload.finish();

  auto ctrl = top.child("controller");
  ctrl.optional("rate", s.controller.rate);
  ctrl.optional("kp", s.controller.kp);
  ctrl.optional("ki", s.controller.ki);
  ctrl.optional("kd", s.controller.kd);
  ctrl.optional("torque_limit", s.controller.torque_limit);
  ctrl.optional("load_compensation", s.controller.load_compensation);
  ctrl.optional("feedforward", s.controller.feedforward);
  ctrl.optional("load_signal", s.controller.load_signal);
  ctrl.finish();

  auto notch = top.child("notch");
  notch.optional("enabled", s.notch.enabled);
  notch.optional("order", s.notch.order);
  notch.optional_array("alpha", s.notch.alpha, 2);
  notch.optional_array("zeta", s.notch.zeta, 2);
  notch.optional_array("omega_z", s.notch.omega_z, 2);
  notch.optional("placement", s.notch.placement);
  notch.finish();

  auto shaper = top.child("shaper");
  shaper.optional("type", s.shaper.type);
  shaper.optional("frequency", s.shaper.frequency);
  shaper.optional("damping", s.shaper.damping);
  shaper.optional("vtol", s.shaper.vtol);
  shaper.finish();

  auto sensors = top.child("sensors");
  // Every channel: resolution, noise, delay, rate; the recorded ones can be enabled, the strain gauge placed;
  // the output channels (hub_torque ... pressure_b) are the record's columns.
  auto& ss = s.sensors;
  const struct {
    const char* name;
    ChannelSpec* ch;
    bool* enabled;  // recorded sensors only
  } channels[] = {{"hub_angle", &ss.hub_angle, nullptr},
                  {"hub_rate", &ss.hub_rate, nullptr},
                  {"strain_gauge", &ss.strain_gauge, &ss.strain_gauge.enabled},
                  {"tip_accelerometer", &ss.tip_accelerometer, &ss.tip_accelerometer.enabled},
                  {"tip_position", &ss.tip_position, &ss.tip_position.enabled},
                  {"hub_torque", &ss.hub_torque, nullptr},
                  {"tip_deflection", &ss.tip_deflection, nullptr},
                  {"pressure_a", &ss.pressure_a, nullptr},
                  {"pressure_b", &ss.pressure_b, nullptr}};
  for (const auto& [name, ch, enabled] : channels) {
    auto c = sensors.child(name);
    c.optional("resolution", ch->resolution);
    c.optional("noise", ch->noise);
    c.optional("delay", ch->delay);
    c.optional("rate", ch->rate);
    if (enabled) c.optional("enabled", *enabled);
    if (ch == &ss.strain_gauge) c.optional("joint", ss.strain_gauge.joint);
    c.finish();
  }
  sensors.finish();

  auto fr = top.child("friction");
  fr.optional("viscous", s.friction.viscous);
  fr.optional("coulomb", s.friction.coulomb);
  fr.optional("stiction", s.friction.stiction);
  fr.optional("stribeck_velocity", s.friction.stribeck_velocity);
  fr.optional("smoothing", s.friction.smoothing);
  fr.optional("model", s.friction.model);
  fr.optional("bristle_stiffness", s.friction.bristle_stiffness);
  fr.optional("bristle_damping", s.friction.bristle_damping);
  fr.finish();

  auto hy = top.child("hydraulics");
  auto& h = s.hydraulics;
  hy.optional("enabled", h.enabled);
  for (const Field<HydraulicSpec>& f : hydraulic_fields()) hy.optional(f.key, h.*std::get<double HydraulicSpec::*>(f.member));
  check_hydraulic_forms(hy, h);
  hy.finish();

  auto dr = top.child("drive");
  auto& d = s.drive;
  dr.optional("enabled", d.enabled);
  dr.optional("inertia", d.inertia);
  dr.optional("ratio", d.ratio);
  dr.optional("efficiency", d.efficiency);
  dr.optional("stiffness", d.stiffness);
  dr.optional("cubic_stiffness", d.cubic_stiffness);
  dr.optional("damping", d.damping);
  dr.optional("backlash", d.backlash);
  dr.finish();

  auto traj = top.child("trajectory");
  traj.optional("move_time", s.trajectory.move_time);
  for (auto& mv : traj.sequence("moves")) {
    MoveSpec m;
    mv.required("target", m.target);
    mv.optional("hold", m.hold);
    mv.finish();
    s.trajectory.moves.push_back(m);
  }
  traj.finish();

  auto sim = top.child("simulation");
  sim.optional("duration", s.simulation.duration);
  s.simulation.integrator = parse_integrator(sim);
  sim.optional("substeps", s.simulation.substeps);
  sim.optional("rtol", s.simulation.rtol);
  sim.optional("atol", s.simulation.atol);
  double seed = 1;
  sim.optional("seed", seed);
  if (seed < 0 || seed != std::floor(seed) || seed > 9.0e15) sim.fail("seed", "must be a whole number >= 0");
  s.simulation.seed = static_cast<std::uint64_t>(seed);
  sim.finish();

  top.finish();
  return s;
}

}  // namespace

Model parse_model(const YAML::Node& doc, const std::string& source) {
  LineMap lines;
  const ModelSpec spec = parse_spec(doc, source, lines);
  try {
    return make_model(spec, source);
  } catch (const ConfigError& e) {
    // Point a range error at the line of its key, or of the nearest block above it that the file has
    // (a key left at its default has no line: friction.coulomb -> friction).
    if (e.line() > 0) throw;
    int line = 0;
    for (std::string key = e.key(); !key.empty() && line == 0;) {
      if (auto it = lines.find(key); it != lines.end()) line = it->second;
      const auto dot = key.find_last_of(".[");
      key.resize(dot == std::string::npos ? 0 : dot);
    }
    throw ConfigError(source, line, e.key(), e.message());
  }
}

Model load_model(const std::string& path) { return parse_model(load_yaml_file(path), path); }

}  // namespace ff
