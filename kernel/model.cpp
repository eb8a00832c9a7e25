#include "kernel/model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <utility>

#include "common/errors.hpp"
#include "common/units_check.hpp"
#include "kernel/batch.hpp"
#include "kernel/drive.hpp"
#include "kernel/modes.hpp"
#include "kernel/notch.hpp"

namespace ff {

double calc_beam_mass(const BeamSpec& b) { return b.density * b.height * b.thickness * b.length; }

double calc_area_moment(const BeamSpec& b) { return b.height * b.thickness * b.thickness * b.thickness / 12.0; }

double calc_cantilever_stiffness(const BeamSpec& b, double length) {
  return 3.0 * b.youngs_modulus * calc_area_moment(b) / length;  // seed eq. 5
}

double calc_strain_tip_gain(const BeamSpec& b, int segments, int joint) {
  const double cell = b.length / (segments - 1);
  const double arm = b.length - (joint - 0.5) * cell;  // L - x_i, m
  return b.length * b.length * b.length / (3.0 * b.youngs_modulus * calc_area_moment(b) * arm);
}

namespace {

// Physical-range checks; the key names the YAML path so the loader can add the line.
void validate(const ModelSpec& s, const std::string& src) {
  auto positive = [&](double x, const char* key) {
    if (!(x > 0) || !std::isfinite(x)) throw ConfigError(src, 0, key, "must be a finite number > 0, got " + std::to_string(x));
  };
  auto non_negative = [&](double x, const char* key) {
    if (!(x >= 0) || !std::isfinite(x)) throw ConfigError(src, 0, key, "must be a finite number >= 0, got " + std::to_string(x));
  };
  positive(s.beam.length, "beam.length");
  positive(s.beam.height, "beam.height");
  positive(s.beam.thickness, "beam.thickness");
  non_negative(s.beam.density, "beam.density");
  positive(s.beam.youngs_modulus, "beam.youngs_modulus");
  // A unit mistake (GPa for Pa, g/cm³ for kg/m³, degrees for radians) unless the file allows it.
  auto plausible = [&](const std::string& why, const std::string& key) {
    if (s.units_check && !why.empty()) throw ConfigError(src, 0, key, why);
  };
  plausible(explain_modulus_unit(s.beam.youngs_modulus), "beam.youngs_modulus");
  plausible(explain_density_unit(s.beam.density), "beam.density");
  if (s.segments < 1) throw ConfigError(src, 0, "segments", "must be >= 1 (1 = a rigid arm), got " + std::to_string(s.segments));
  if (s.segments > 4096) throw ConfigError(src, 0, "segments", "must be <= 4096, got " + std::to_string(s.segments));
  positive(s.joints.stiffness, "joints.stiffness");
  non_negative(s.joints.damping, "joints.damping");
  non_negative(s.joints.cubic_stiffness, "joints.cubic_stiffness");
  positive(s.joints.reference_cell, "joints.reference_cell");
  non_negative(s.hub_inertia, "hub.inertia");
  if (!std::isfinite(s.hub_torque_offset)) throw ConfigError(src, 0, "hub.torque_offset", "must be finite");
  non_negative(s.payload_mass, "payload.mass");
  non_negative(s.payload_inertia, "payload.inertia");
  // Every dof needs inertia: a massless beam (beam.density 0) is one rigid segment (its joints would have
  // none), and the hub turns something (a singular mass matrix has modes of 0 Hz and no dynamics).
  if (s.beam.density == 0.0 && s.segments > 1)
    throw ConfigError(src, 0, "beam.density", "0 (a massless beam) needs segments: 1, a rigid axis: the joints of its " +
                                                  std::to_string(s.segments) + " segments would carry no inertia");
  if (s.beam.density == 0.0 && s.hub_inertia == 0.0 && s.payload_mass == 0.0 && s.payload_inertia == 0.0)
    throw ConfigError(src, 0, "beam.density", "the rig has no inertia: beam.density, hub.inertia, payload.mass and "
                                              "payload.inertia are all 0 (give one of them a value > 0)");
  double last = 0.0;
  for (std::size_t j = 0; j < s.payload_events.size(); ++j) {
    const auto& e = s.payload_events[j];
    const std::string key = "payload.events[" + std::to_string(j) + "]";
    if (!(e.time >= last) || !std::isfinite(e.time)) throw ConfigError(src, 0, key + ".time", "must be >= 0 and in time order");
    if (!(e.mass >= 0) || !std::isfinite(e.mass)) throw ConfigError(src, 0, key + ".mass", "must be a finite number >= 0");
    if (!(e.inertia >= 0) || !std::isfinite(e.inertia)) throw ConfigError(src, 0, key + ".inertia", "must be a finite number >= 0");
    last = e.time;
  }
  if (!s.payload_events.empty() && (s.simulation.integrator == Integrator::kCvodeDense ||
                                    s.simulation.integrator == Integrator::kCvodeKlu))
    throw ConfigError(src, 0, "payload.events", "need a fixed-step integrator (rk4, sdirk2 or midpoint)");
  positive(s.controller.rate, "controller.rate");
  non_negative(s.controller.kp, "controller.kp");
  non_negative(s.controller.ki, "controller.ki");
  non_negative(s.controller.kd, "controller.kd");
  non_negative(s.controller.torque_limit, "controller.torque_limit");
  if (!std::isfinite(s.controller.load_compensation))
    throw ConfigError(src, 0, "controller.load_compensation", "must be a finite number");
  if (!std::isfinite(s.controller.feedforward))
    throw ConfigError(src, 0, "controller.feedforward", "must be a finite number");
  if (s.notch.order < 1 || s.notch.order > 8)
    throw ConfigError(src, 0, "notch.order", "must be between 1 and 8, got " + std::to_string(s.notch.order));
  for (int i = 0; i < 2; ++i) {
    positive(s.notch.alpha[i], "notch.alpha");
    positive(s.notch.zeta[i], "notch.zeta");
    non_negative(s.notch.omega_z[i], "notch.omega_z");
  }
  if ((s.notch.omega_z[0] > 0) != (s.notch.omega_z[1] > 0))
    throw ConfigError(src, 0, "notch.omega_z", "give both zero frequencies or neither");
  if (s.notch.placement != "reference" && s.notch.placement != "feedback")
    throw ConfigError(src, 0, "notch.placement", "unknown placement '" + s.notch.placement + "' (reference, feedback)");
  non_negative(s.shaper.frequency, "shaper.frequency");
  if (!(s.shaper.damping < 1.0) || !std::isfinite(s.shaper.damping))
    throw ConfigError(src, 0, "shaper.damping", "must be < 1 (negative = the resonance's), got " + std::to_string(s.shaper.damping));
  if (!(s.shaper.vtol > 0.0 && s.shaper.vtol < 0.5))
    throw ConfigError(src, 0, "shaper.vtol", "must be in (0, 0.5), got " + std::to_string(s.shaper.vtol));
  positive(s.trajectory.move_time, "trajectory.move_time");
  double previous = 0.0;
  for (std::size_t j = 0; j < s.trajectory.moves.size(); ++j) {
    const auto& m = s.trajectory.moves[j];
    const std::string key = "trajectory.moves[" + std::to_string(j) + "]";
    if (!std::isfinite(m.target)) throw ConfigError(src, 0, key + ".target", "must be finite");
    plausible(explain_angle_unit(m.target), key + ".target");
    if (m.target == previous) throw ConfigError(src, 0, key + ".target", "a move must change the target (zero amplitude)");
    if (!(m.hold >= 0)) throw ConfigError(src, 0, key + ".hold", "must be >= 0");
    previous = m.target;
  }
  non_negative(s.simulation.duration, "simulation.duration");
  if (s.simulation.substeps < 0 || s.simulation.substeps > kMaxSubsteps)
    throw ConfigError(src, 0, "simulation.substeps", "must be between 0 (automatic) and 100000");
  positive(s.simulation.rtol, "simulation.rtol");
  non_negative(s.friction.viscous, "friction.viscous");
  non_negative(s.friction.coulomb, "friction.coulomb");
  non_negative(s.friction.stiction, "friction.stiction");
  if (s.friction.stiction > 0 && s.friction.stiction < s.friction.coulomb)
    throw ConfigError(src, 0, "friction.stiction", "must be >= friction.coulomb (or 0 for no Stribeck peak)");
  positive(s.friction.stribeck_velocity, "friction.stribeck_velocity");
  positive(s.friction.smoothing, "friction.smoothing");
  // Every sensor's values checked, recorded ones enabled or not; a rate must divide controller.rate.
  const std::pair<const ChannelSpec*, const char*> channels[] = {
      {&s.sensors.hub_angle, "sensors.hub_angle"},
      {&s.sensors.hub_rate, "sensors.hub_rate"},
      {&s.sensors.strain_gauge, "sensors.strain_gauge"},
      {&s.sensors.tip_accelerometer, "sensors.tip_accelerometer"},
      {&s.sensors.tip_position, "sensors.tip_position"},
      {&s.sensors.hub_torque, "sensors.hub_torque"},
      {&s.sensors.tip_deflection, "sensors.tip_deflection"},
      {&s.sensors.pressure_a, "sensors.pressure_a"},
      {&s.sensors.pressure_b, "sensors.pressure_b"}};
  for (const auto& [ch, key] : channels) {
    const std::string k(key);
    non_negative(ch->resolution, (k + ".resolution").c_str());
    non_negative(ch->noise, (k + ".noise").c_str());
    if (ch->delay < 0 || ch->delay > 10000)
      throw ConfigError(src, 0, k + ".delay", "must be between 0 and 10000 samples");
    non_negative(ch->rate, (k + ".rate").c_str());
    if (ch->rate > 0) {
      const double ratio = s.controller.rate / ch->rate;
      if (!(ratio >= 1.0 - 1e-9) || std::fabs(ratio - std::round(ratio)) > 1e-9 * ratio || ratio > 1e6) {
        char msg[160];
        std::snprintf(msg, sizeof msg, "must divide controller.rate = %g Hz a whole number of times, got %g Hz",
                      s.controller.rate, ch->rate);
        throw ConfigError(src, 0, k + ".rate", msg);
      }
    }
  }
  for (const auto& [ch, key] : {std::pair{&s.sensors.hub_angle, "sensors.hub_angle"},
                                std::pair{&s.sensors.hub_rate, "sensors.hub_rate"}})
    if (!is_logged_name(ch->logged))
      throw ConfigError(src, 0, std::string(key) + ".logged",
                        "unknown value '" + ch->logged + "' (read: what the controller read, true: on time)");
    else if (ch->logged_delay < 0 || ch->logged_delay > 10000)
      throw ConfigError(src, 0, std::string(key) + ".logged_delay", "must be between 0 and 10000 samples");
  const int joint = s.sensors.strain_gauge.joint;
  if ((joint < 1 || joint > s.segments - 1) && (s.segments > 1 || s.sensors.strain_gauge.enabled))
    throw ConfigError(src, 0, "sensors.strain_gauge.joint",
                      "must be a beam joint 1.." + std::to_string(s.segments - 1) + ", got " + std::to_string(joint));
  positive(s.simulation.atol, "simulation.atol");
  if (s.friction.model != "static" && s.friction.model != "lugre")
    throw ConfigError(src, 0, "friction.model", "unknown model '" + s.friction.model + "' (static, lugre)");
  positive(s.friction.bristle_stiffness, "friction.bristle_stiffness");
  non_negative(s.friction.position_waves, "friction.position_waves");
  if (!(std::hypot(s.friction.position_cos, s.friction.position_sin) < 1.0))
    throw ConfigError(src, 0, "friction.position_cos",
                      "the Coulomb level's ripple needs position_cos^2 + position_sin^2 < 1 (a level that never reaches zero)");
  non_negative(s.friction.bristle_damping, "friction.bristle_damping");
  if (s.friction.model == "lugre" && !(s.friction.coulomb > 0))
    throw ConfigError(src, 0, "friction.model", "lugre needs friction.coulomb > 0 (the level the bristles slip at), got " +
                                                    std::to_string(s.friction.coulomb));
  if (s.controller.load_signal != "moment" && s.controller.load_signal != "pressure")
    throw ConfigError(src, 0, "controller.load_signal", "unknown signal '" + s.controller.load_signal + "' (moment, pressure)");
  if (s.controller.model != "nominal" && s.controller.model != "plant")
    throw ConfigError(src, 0, "controller.model", "unknown model '" + s.controller.model + "' (nominal, plant)");
  if (s.controller.load_signal == "pressure" && !s.hydraulics.enabled)
    throw ConfigError(src, 0, "controller.load_signal", "'pressure' needs hydraulics.enabled: true");
  // The hub drive's values are checked whether its parts are enabled or not (as the recorded sensors').
  if (const auto [key, why] = explain_hydraulic_fault(s.hydraulics); !key.empty())
    throw ConfigError(src, 0, "hydraulics." + key, why);
  const auto& d = s.drive;
  {
    positive(d.inertia, "drive.inertia");
    positive(d.ratio, "drive.ratio");
    if (!(d.efficiency > 0 && d.efficiency <= 1)) throw ConfigError(src, 0, "drive.efficiency", "must be in (0, 1]");
    positive(d.stiffness, "drive.stiffness");
    non_negative(d.cubic_stiffness, "drive.cubic_stiffness");
    non_negative(d.damping, "drive.damping");
    non_negative(d.backlash, "drive.backlash");
  }
}

}  // namespace

namespace {
// Body i without payload, in its joint frame: the segment about its joint (parallel axis), plus the
// hub on body 0.
BodyInertia make_segment_body(const Model& m, int i) {
  const double li = m.seg_length[i], mi = m.seg_mass[i];
  BodyInertia b{mi, mi * 0.5 * li, m.seg_inertia[i] + mi * 0.25 * li * li};
  if (i == 0) b.inertia += m.spec.hub_inertia;
  return b;
}
}  // namespace

BodyInertia make_tip_body(const Model& m, double mass, double inertia) {
  // The last segment (with the hub on a one-segment arm), then the payload at its tip.
  const double li = m.seg_length[m.nseg - 1];
  BodyInertia b = make_segment_body(m, m.nseg - 1);
  b.mass += mass;
  b.first += mass * li;
  b.inertia += inertia + mass * li * li;
  return b;
}

Model make_model(const ModelSpec& spec, const std::string& source, const Model* controller) {
  validate(spec, source);
  Model m;
  m.spec = spec;
  const int n = spec.segments;
  m.nseg = n;
  const auto& b = spec.beam;

  // Segment lengths: joints at the centres of N-1 equal cells; end segments are half cells (reference-rig.md).
  // N = 1: one rigid segment, the whole beam, and no joints.
  m.cell = n > 1 ? b.length / (n - 1) : b.length;
  m.seg_length.assign(n, m.cell);
  if (n > 1) m.seg_length.front() = m.seg_length.back() = 0.5 * m.cell;

  // Segment mass rho h t L_i and centroidal inertia m (L_i^2 + t^2) / 12.
  for (int i = 0; i < n; ++i) {
    const double li = m.seg_length[i];
    const double mi = b.density * b.height * b.thickness * li;
    m.seg_mass.push_back(mi);
    m.seg_inertia.push_back(mi * (li * li + b.thickness * b.thickness) / 12.0);
  }

  // Body inertias about each joint axis: segment (parallel axis), hub on body 0, payload at the tip of body N-1
  // (make_tip_body, which payload events use too).
  for (int i = 0; i < n - 1; ++i) m.body.push_back(make_segment_body(m, i));
  m.body.push_back(make_tip_body(m, spec.payload_mass, spec.payload_inertia));

  // Joint springs and dampers scale as reference_cell / l (k = kappa EI / l).
  const double scale = spec.joints.reference_cell / m.cell;
  m.joint_k.assign(n, spec.joints.stiffness * scale);
  m.joint_c.assign(n, spec.joints.damping * scale);
  m.joint_k3.assign(n, spec.joints.cubic_stiffness * scale);
  m.joint_k[0] = m.joint_c[0] = m.joint_k3[0] = 0.0;

  m.control_period = 1.0 / spec.controller.rate;
  m.duration = spec.simulation.duration;
  if (m.duration == 0.0)
    for (const auto& mv : spec.trajectory.moves) m.duration += spec.trajectory.move_time + mv.hold;
  if (!(m.duration > 0))
    throw ConfigError(source, 0, "simulation.duration", "is 0 and there are no moves to take it from");
  if (m.duration / m.control_period > 1e8)
    throw ConfigError(source, 0, "simulation.duration", "needs more than 1e8 controller samples");

  // Fixed-step substeps from the fastest linearised eigenvalue; notch zeros at the closed-loop resonances.
  m.rigid_inertia = calc_mass_matrix(m, Eigen::VectorXd::Zero(n))(0, 0);
  const auto closed_loop = calc_closed_loop_modes(m);
  m.resonances = calc_resonances(closed_loop);
  if (spec.simulation.substeps > 0) {
    m.substeps = spec.simulation.substeps;
  } else {
    auto modes = calc_clamped_modes(m);
    modes.insert(modes.end(), closed_loop.begin(), closed_loop.end());
    m.substeps = calc_auto_substeps(modes, m.control_period, spec.simulation.integrator);
    // The hub drive's own rates (hydraulics, drive train, LuGre): h rate <= 1.
    m.substeps = std::max(m.substeps, calc_substeps_for_rate(calc_drive_rate(m), m.control_period));
    if (m.substeps > kMaxSubsteps)
      throw ConfigError(source, 0, "simulation.substeps",
                        "the automatic step would need more than 100000 substeps per controller sample: a mode or "
                        "the drive is far too fast for the controller's rate; check the model's values");
  }
  m.control_inertia = m.rigid_inertia;
  if (controller) {
    // The controller's model designed the feed-forward, the notch and the shaper (its spec's controller-side
    // blocks are this spec's: only plant-side values differ).
    m.control_inertia = controller->control_inertia;
    m.omega_z[0] = controller->omega_z[0];
    m.omega_z[1] = controller->omega_z[1];
    m.shaper = controller->shaper;
    return m;
  }
  m.omega_z[0] = spec.notch.omega_z[0];
  m.omega_z[1] = spec.notch.omega_z[1];
  if (spec.notch.enabled && m.omega_z[0] == 0.0) {
    const auto& res = m.resonances;
    if (res.size() < 2)
      throw ConfigError(source, 0, "notch.omega_z", "the closed loop has fewer than two resonances to place the notch at; give omega_z");
    m.omega_z[0] = res[0];
    m.omega_z[1] = res[1];
  }
  // Input shaper: designed on the first closed-loop mode unless told otherwise.
  const std::pair<const char*, ShaperKind> kinds[] = {
      {"none", ShaperKind::kNone}, {"zv", ShaperKind::kZv}, {"zvd", ShaperKind::kZvd}, {"ei", ShaperKind::kEi}};
  ShaperKind kind = ShaperKind::kNone;
  bool known = false;
  for (const auto& [name, k] : kinds)
    if (spec.shaper.type == name) {
      kind = k;
      known = true;
    }
  if (!known) throw ConfigError(source, 0, "shaper.type", "unknown shaper '" + spec.shaper.type + "' (none, zv, zvd, ei)");
  double w = spec.shaper.frequency, z = spec.shaper.damping;
  if (kind != ShaperKind::kNone && (w == 0.0 || z < 0.0)) {
    const Mode* first = nullptr;
    for (const auto& md : closed_loop)
      if (md.oscillatory && md.zeta < 0.3 && !first) first = &md;
    if (!first) throw ConfigError(source, 0, "shaper.frequency", "the closed loop has no resonance to design on; give frequency and damping");
    if (w == 0.0) w = first->omega_n;
    if (z < 0.0) z = first->zeta;
  }
  // What validate() cannot see (the designs on the computed resonances) the kernels check; their
  // messages start "<block>: ".
  auto design_error = [&](const std::string& block, const std::exception& e) {
    std::string message = e.what();
    if (message.rfind(block + ": ", 0) == 0) message.erase(0, block.size() + 2);
    return ConfigError(source, 0, block, message);
  };
  try {
    m.shaper = make_shaper(kind, w, z, spec.shaper.vtol);
  } catch (const std::invalid_argument& e) {
    throw design_error("shaper", e);
  }

  if (spec.notch.enabled) {
    try {
      make_notch_sections(make_notch_design(m), m.control_period);
    } catch (const std::invalid_argument& e) {
      throw design_error("notch", e);
    }
  }
  return m;
}

}  // namespace ff
