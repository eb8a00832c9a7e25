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

// The reference rig's model file: one field table per block, read in table order without bounds
// (make_model checks the values and names the key).
const std::array<Field<BeamSpec>, 5> kBeamFields{{
    {.key = "length", .member = &BeamSpec::length, .unit = "m", .required = true},
    {.key = "height", .member = &BeamSpec::height, .unit = "m", .required = true},
    {.key = "thickness", .member = &BeamSpec::thickness, .unit = "m", .required = true},
    {.key = "density", .member = &BeamSpec::density, .unit = "kg/m³", .required = true},
    {.key = "youngs_modulus", .member = &BeamSpec::youngs_modulus, .unit = "Pa", .required = true},
}};
const std::array<Field<ModelSpec>, 1> kTopFields{{
    {.key = "segments", .member = &ModelSpec::segments, .required = true},
}};
const std::array<Field<JointSpec>, 4> kJointFields{{
    {.key = "stiffness", .member = &JointSpec::stiffness, .unit = "N·m/rad", .required = true},
    {.key = "damping", .member = &JointSpec::damping, .unit = "N·m·s/rad", .required = true},
    {.key = "reference_cell", .member = &JointSpec::reference_cell, .unit = "m", .required = true},
    {.key = "cubic_stiffness", .member = &JointSpec::cubic_stiffness, .unit = "N·m/rad³"},
}};
const std::array<Field<ModelSpec>, 2> kHubFields{{
    {.key = "inertia", .member = &ModelSpec::hub_inertia, .unit = "kg·m²", .required = true},
    {.key = "torque_offset", .member = &ModelSpec::hub_torque_offset, .unit = "N·m"},
}};
const std::array<Field<ModelSpec>, 2> kPayloadFields{{
    {.key = "mass", .member = &ModelSpec::payload_mass, .unit = "kg", .required = true},
    {.key = "inertia", .member = &ModelSpec::payload_inertia, .unit = "kg·m²", .required = true},
}};
const std::array<Field<PayloadEvent>, 3> kEventFields{{
    {.key = "time", .member = &PayloadEvent::time, .unit = "s", .required = true},
    {.key = "mass", .member = &PayloadEvent::mass, .unit = "kg", .required = true},
    {.key = "inertia", .member = &PayloadEvent::inertia, .unit = "kg·m²", .required = true},
}};
const std::array<Field<ControllerSpec>, 9> kControllerFields{{
    {.key = "rate", .member = &ControllerSpec::rate, .unit = "Hz"},
    {.key = "kp", .member = &ControllerSpec::kp, .unit = "N·m/rad"},
    {.key = "ki", .member = &ControllerSpec::ki, .unit = "N·m/(rad·s)"},
    {.key = "kd", .member = &ControllerSpec::kd, .unit = "N·m·s/rad"},
    {.key = "torque_limit", .member = &ControllerSpec::torque_limit, .unit = "N·m", .fallback = "0: unlimited"},
    {.key = "load_compensation", .member = &ControllerSpec::load_compensation},
    {.key = "feedforward", .member = &ControllerSpec::feedforward},
    {.key = "load_signal", .member = &ControllerSpec::load_signal},
    {.key = "model", .member = &ControllerSpec::model},
}};
const std::array<Field<NotchSpec>, 3> kNotchFields{{
    {.key = "enabled", .member = &NotchSpec::enabled},
    {.key = "order", .member = &NotchSpec::order},
    {.key = "placement", .member = &NotchSpec::placement},
}};
// The notch's pairs (sections 1 and 2; one number means both; fallback nullptr: the default pair).
struct NotchPair { const char* key; double (NotchSpec::*member)[2]; const char* unit; const char* fallback; };
const NotchPair kNotchPairs[] = {
    {"alpha", &NotchSpec::alpha, "", nullptr},
    {"zeta", &NotchSpec::zeta, "", nullptr},
    {"omega_z", &NotchSpec::omega_z, "rad/s", "[0, 0]: the first two closed-loop resonances"}};
const std::array<Field<ShaperSpec>, 4> kShaperFields{{
    {.key = "type", .member = &ShaperSpec::type},
    {.key = "frequency", .member = &ShaperSpec::frequency, .unit = "rad/s",
     .fallback = "0: the first closed-loop resonance"},
    {.key = "damping", .member = &ShaperSpec::damping, .fallback = "-1: that resonance's"},
    {.key = "vtol", .member = &ShaperSpec::vtol},
}};

// Every sensor channel: resolution and noise in the channel's unit, delay and rate; the recorded ones
// can be enabled, the strain gauge placed.
std::array<Field<ChannelSpec>, 4> channel_fields(const char* unit) {
  return {{{.key = "resolution", .member = &ChannelSpec::resolution, .unit = unit, .fallback = "0: none"},
           {.key = "noise", .member = &ChannelSpec::noise, .unit = unit, .fallback = "0: none"},
           {.key = "delay", .member = &ChannelSpec::delay, .unit = "controller samples"},
           {.key = "rate", .member = &ChannelSpec::rate, .unit = "Hz", .fallback = "0: controller.rate"}}};
}
const std::array<Field<RecordedChannelSpec>, 1> kRecordedFields{{
    {.key = "enabled", .member = &RecordedChannelSpec::enabled},
}};
// The channels the controller reads: what a record's column of them holds.
const std::array<Field<LoopChannelSpec>, 2> kLoggedFields{{
    {.key = "logged", .member = &LoopChannelSpec::logged},
    {.key = "logged_delay", .member = &LoopChannelSpec::logged_delay, .unit = "controller samples"},
}};
const std::array<Field<StrainGaugeSpec>, 1> kStrainGaugeFields{{{.key = "joint", .member = &StrainGaugeSpec::joint}}};
struct Channel {
  const char* name; const char* unit; ChannelSpec* channel; RecordedChannelSpec* recorded; LoopChannelSpec* loop;
};
std::array<Channel, 9> channels(SensorSpec& ss) {
  return {{{"hub_angle", "rad", &ss.hub_angle, nullptr, &ss.hub_angle},
           {"hub_rate", "rad/s", &ss.hub_rate, nullptr, &ss.hub_rate},
           {"strain_gauge", "N·m", &ss.strain_gauge, &ss.strain_gauge, nullptr},
           {"tip_accelerometer", "m/s²", &ss.tip_accelerometer, &ss.tip_accelerometer, nullptr},
           {"tip_position", "m", &ss.tip_position, &ss.tip_position, nullptr},
           {"hub_torque", "N·m", &ss.hub_torque, nullptr, nullptr},
           {"tip_deflection", "m", &ss.tip_deflection, nullptr, nullptr},
           {"pressure_a", "Pa", &ss.pressure_a, nullptr, nullptr},
           {"pressure_b", "Pa", &ss.pressure_b, nullptr, nullptr}}};
}

const std::array<Field<FrictionSpec>, 11> kFrictionFields{{
    {.key = "viscous", .member = &FrictionSpec::viscous, .unit = "N·m·s/rad"},
    {.key = "coulomb", .member = &FrictionSpec::coulomb, .unit = "N·m"},
    {.key = "stiction", .member = &FrictionSpec::stiction, .unit = "N·m", .fallback = "0: no Stribeck peak"},
    {.key = "stribeck_velocity", .member = &FrictionSpec::stribeck_velocity, .unit = "rad/s"},
    {.key = "smoothing", .member = &FrictionSpec::smoothing, .unit = "rad/s"},
    {.key = "model", .member = &FrictionSpec::model},
    {.key = "bristle_stiffness", .member = &FrictionSpec::bristle_stiffness, .unit = "N·m/rad"},
    {.key = "bristle_damping", .member = &FrictionSpec::bristle_damping, .unit = "N·m·s/rad"},
    {.key = "position_waves", .member = &FrictionSpec::position_waves, .unit = "1/rev"},
    {.key = "position_cos", .member = &FrictionSpec::position_cos},
    {.key = "position_sin", .member = &FrictionSpec::position_sin},
}};
// The rest of the block is hydraulic_fields(), the arm's too.
const std::array<Field<HydraulicSpec>, 1> kHydraulicEnabledFields{{
    {.key = "enabled", .member = &HydraulicSpec::enabled},
}};
const std::array<Field<DriveSpec>, 9> kDriveFields{{
    {.key = "enabled", .member = &DriveSpec::enabled},
    {.key = "inertia", .member = &DriveSpec::inertia, .unit = "kg·m²"},
    {.key = "ratio", .member = &DriveSpec::ratio},
    {.key = "efficiency", .member = &DriveSpec::efficiency},
    {.key = "stiffness", .member = &DriveSpec::stiffness, .unit = "N·m/rad"},
    {.key = "cubic_stiffness", .member = &DriveSpec::cubic_stiffness, .unit = "N·m/rad³"},
    {.key = "damping", .member = &DriveSpec::damping, .unit = "N·m·s/rad"},
    {.key = "backlash", .member = &DriveSpec::backlash, .unit = "rad"},
    {.key = "closing_damping", .member = &DriveSpec::closing_damping},
}};
const std::array<Field<TrajectorySpec>, 1> kTrajectoryFields{{
    {.key = "move_time", .member = &TrajectorySpec::move_time, .unit = "s"},
}};
const std::array<Field<MoveSpec>, 2> kMoveFields{{
    {.key = "target", .member = &MoveSpec::target, .unit = "rad", .required = true},
    {.key = "hold", .member = &MoveSpec::hold, .unit = "s"},
}};
// The integrator by name and the seed as a number, checked after reading.
struct SimulationBlock : SimulationSpec { std::string integrator_name = "rk4"; double seed_number = 1; };
const std::array<Field<SimulationBlock>, 7> kSimulationFields{{
    {.key = "duration", .member = &SimulationBlock::duration, .unit = "s", .fallback = "0: the end of the last hold"},
    {.key = "integrator", .member = &SimulationBlock::integrator_name},
    {.key = "substeps", .member = &SimulationBlock::substeps, .fallback = "0: from the modes"},
    {.key = "rtol", .member = &SimulationBlock::rtol},
    {.key = "atol", .member = &SimulationBlock::atol},
    {.key = "seed", .member = &SimulationBlock::seed_number},
    {.key = "expected_readings", .member = &SimulationBlock::expected_readings},
}};

// The block `name` of `top` read through its table; the caller reads the rest and finishes it.
template <class T, std::size_t N>
YamlReader read_block(YamlReader& top, const char* name, const std::array<Field<T>, N>& fields, T& out,
                      bool required = false) {
  YamlReader r = top.child(name, required);
  read_unchecked(r, fields, out);
  return r;
}

ModelSpec parse_spec(const YAML::Node& doc, const std::string& src, LineMap& lines) {
  ModelSpec s;
  YamlReader top(doc, src, "", &lines);
  if (!doc || doc.IsNull()) top.fail("beam", "the file is empty");
  top.read_units_check();
  s.units_check = top.units_check();

  read_block(top, "beam", kBeamFields, s.beam, true).finish();
  read_unchecked(top, kTopFields, s);
  read_block(top, "joints", kJointFields, s.joints, true).finish();
  read_block(top, "hub", kHubFields, s, true).finish();

  auto payload = read_block(top, "payload", kPayloadFields, s, true);
  for (auto& ev : payload.sequence("events")) {
    only_keys(ev, kEventFields);
    read_unchecked(ev, kEventFields, s.payload_events.emplace_back());
    ev.finish();
  }
  payload.finish();

  read_block(top, "controller", kControllerFields, s.controller).finish();

  auto notch = read_block(top, "notch", kNotchFields, s.notch);
  for (const auto& p : kNotchPairs) notch.optional_array(p.key, s.notch.*p.member, 2);
  notch.finish();

  read_block(top, "shaper", kShaperFields, s.shaper).finish();

  auto sensors = top.child("sensors");
  for (const auto& [name, unit, ch, recorded, loop] : channels(s.sensors)) {
    auto c = read_block(sensors, name, channel_fields(unit), *ch);
    if (recorded) read_unchecked(c, kRecordedFields, *recorded);
    if (loop) read_unchecked(c, kLoggedFields, *loop);
    if (ch == &s.sensors.strain_gauge) read_unchecked(c, kStrainGaugeFields, s.sensors.strain_gauge);
    c.finish();
  }
  sensors.finish();

  read_block(top, "friction", kFrictionFields, s.friction).finish();

  auto hy = read_block(top, "hydraulics", kHydraulicEnabledFields, s.hydraulics);
  read_unchecked(hy, hydraulic_fields(), s.hydraulics);
  check_hydraulic_forms(hy, s.hydraulics);
  hy.finish();

  read_block(top, "drive", kDriveFields, s.drive).finish();

  auto traj = read_block(top, "trajectory", kTrajectoryFields, s.trajectory);
  for (auto& mv : traj.sequence("moves")) {
    read_unchecked(mv, kMoveFields, s.trajectory.moves.emplace_back());
    mv.finish();
  }
  traj.finish();

  SimulationBlock sim_block;
  auto sim = read_block(top, "simulation", kSimulationFields, sim_block);
  s.simulation = sim_block;
  bool known = false;
  for (auto i : {Integrator::kRk4, Integrator::kSdirk2, Integrator::kCvodeDense, Integrator::kCvodeKlu,
                 Integrator::kMidpoint})
    if (sim_block.integrator_name == integrator_name(i)) s.simulation.integrator = i, known = true;
  if (!known)
    sim.fail("integrator", "unknown integrator '" + sim_block.integrator_name +
                               "' (rk4, sdirk2, cvode_dense, cvode_klu, midpoint)");
  const double seed = sim_block.seed_number;
  if (seed < 0 || seed != std::floor(seed) || seed > 9.0e15) sim.fail("seed", "must be a whole number >= 0");
  s.simulation.seed = static_cast<std::uint64_t>(seed);
  sim.finish();

  top.finish();
  return s;
}

}  // namespace

std::vector<KeyDoc> rig_model_keys() {
  std::vector<KeyDoc> out;
  add_keys(out, "beam.", kBeamFields);
  add_keys(out, "", kTopFields);
  out.push_back(kUnitsCheckKey);
  add_keys(out, "joints.", kJointFields);
  add_keys(out, "hub.", kHubFields);
  add_keys(out, "payload.", kPayloadFields);
  add_keys(out, "payload.events[i].", kEventFields);
  add_keys(out, "controller.", kControllerFields);
  add_keys(out, "notch.", kNotchFields);
  static const NotchSpec notch{};
  for (const auto& p : kNotchPairs) {
    const double* x = notch.*p.member;
    out.push_back({std::string("notch.") + p.key, p.unit, "no",
                   p.fallback ? p.fallback : "[" + format_key_number(x[0]) + ", " + format_key_number(x[1]) + "]"});
  }
  add_keys(out, "shaper.", kShaperFields);
  SensorSpec sensors;
  for (const auto& [name, unit, ch, recorded, loop] : channels(sensors)) {
    const std::string prefix = std::string("sensors.") + name + ".";
    add_keys(out, prefix, channel_fields(unit));
    if (recorded) add_keys(out, prefix, kRecordedFields);
    if (loop) add_keys(out, prefix, kLoggedFields);
    if (ch == &sensors.strain_gauge) add_keys(out, prefix, kStrainGaugeFields);
  }
  add_keys(out, "friction.", kFrictionFields);
  add_keys(out, "hydraulics.", kHydraulicEnabledFields);
  add_keys(out, "hydraulics.", hydraulic_fields());
  add_keys(out, "drive.", kDriveFields);
  add_keys(out, "trajectory.", kTrajectoryFields);
  add_keys(out, "trajectory.moves[i].", kMoveFields);
  add_keys(out, "simulation.", kSimulationFields);
  return out;
}

Model parse_model(const YAML::Node& doc, const std::string& source, const Model* controller) {
  LineMap lines;
  const ModelSpec spec = parse_spec(doc, source, lines);
  try {
    return make_model(spec, source, controller);
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
