// The truth simulator (truth_sim.hpp; equations in README.md). Nothing here comes from kernel/.
#include "tests/validate/truth/truth_sim.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <type_traits>

namespace ff::truth {

// ---------------------------------------------------------------------------------------------
// The field table: the one place names map to TruthRig members.

namespace {

template <class Rig, class F>
void visit_fields(Rig& r, F&& f) {
  f("beam.length", r.beam.length, "m");
  f("beam.height", r.beam.height, "m");
  f("beam.thickness", r.beam.thickness, "m");
  f("beam.density", r.beam.density, "kg/m^3");
  f("beam.youngs_modulus", r.beam.youngs_modulus, "Pa");
  f("segments", r.segments, "");
  f("joint.stiffness", r.joint.stiffness, "N m/rad");
  f("joint.damping", r.joint.damping, "N m s/rad");
  f("joint.reference_cell", r.joint.reference_cell, "m");
  f("joint.stiffening", r.joint.stiffening, "");
  f("joint.stiffening_angle", r.joint.stiffening_angle, "rad");
  f("hub_inertia", r.hub_inertia, "kg m^2");
  f("payload.mass", r.payload.mass, "kg");
  f("payload.inertia", r.payload.inertia, "kg m^2");
  f("controller.rate", r.controller.rate, "Hz");
  f("controller.kp", r.controller.kp, "N m/rad");
  f("controller.kd", r.controller.kd, "N m s/rad");
  f("controller.ki", r.controller.ki, "N m/(rad s)");
  f("controller.torque_limit", r.controller.torque_limit, "N m");
  f("controller.feedforward", r.controller.feedforward, "");
  f("controller.nominal_hub_inertia", r.controller.nominal_hub_inertia, "kg m^2");
  f("controller.nominal_payload_mass", r.controller.nominal_payload_mass, "kg");
  f("controller.nominal_payload_inertia", r.controller.nominal_payload_inertia, "kg m^2");
  f("trajectory.move_time", r.trajectory.move_time, "s");
  f("trajectory.moves", r.trajectory.moves, "rad:s,...");
  f("friction.viscous", r.friction.viscous, "N m s/rad");
  f("friction.coulomb", r.friction.coulomb, "N m");
  f("friction.stiction", r.friction.stiction, "N m");
  f("friction.stribeck_velocity", r.friction.stribeck_velocity, "rad/s");
  f("friction.stribeck_exponent", r.friction.stribeck_exponent, "");
  f("friction.smoothing", r.friction.smoothing, "rad/s");
  f("friction.bristle_stiffness", r.friction.bristle_stiffness, "N m/rad");
  f("friction.bristle_damping", r.friction.bristle_damping, "N m s/rad");
  f("friction.position_amplitude", r.friction.position_amplitude, "");
  f("friction.position_waves", r.friction.position_waves, "1/rev");
  f("friction.position_phase", r.friction.position_phase, "rad");
  f("torque_offset", r.torque_offset, "N m");
  f("drive.enabled", r.drive.enabled, "");
  f("drive.inertia", r.drive.inertia, "kg m^2");
  f("drive.ratio", r.drive.ratio, "");
  f("drive.stiffness", r.drive.stiffness, "N m/rad");
  f("drive.cubic_stiffness", r.drive.cubic_stiffness, "N m/rad^3");
  f("drive.damping", r.drive.damping, "N m s/rad");
  f("drive.backlash", r.drive.backlash, "rad");
  f("drive.backlash_smoothing", r.drive.backlash_smoothing, "rad");
  f("drive.knee_1", r.drive.knee_1, "rad");
  f("drive.stiffness_2", r.drive.stiffness_2, "N m/rad");
  f("drive.knee_2", r.drive.knee_2, "rad");
  f("drive.stiffness_3", r.drive.stiffness_3, "N m/rad");
  f("drive.one_sided_damping", r.drive.one_sided_damping, "");
  f("hydraulics.enabled", r.hydraulics.enabled, "");
  f("hydraulics.piston_area", r.hydraulics.piston_area, "m^2");
  f("hydraulics.pinion_radius", r.hydraulics.pinion_radius, "m");
  f("hydraulics.chamber_volume", r.hydraulics.chamber_volume, "m^3");
  f("hydraulics.bulk_modulus", r.hydraulics.bulk_modulus, "Pa");
  f("hydraulics.supply_pressure", r.hydraulics.supply_pressure, "Pa");
  f("hydraulics.tank_pressure", r.hydraulics.tank_pressure, "Pa");
  f("hydraulics.rated_flow", r.hydraulics.rated_flow, "m^3/s");
  f("hydraulics.rated_drop", r.hydraulics.rated_drop, "Pa");
  f("hydraulics.laminar_drop", r.hydraulics.laminar_drop, "Pa");
  f("hydraulics.leakage", r.hydraulics.leakage, "m^3/(s Pa)");
  f("hydraulics.valve_frequency", r.hydraulics.valve_frequency, "Hz");
  f("hydraulics.valve_damping", r.hydraulics.valve_damping, "");
  f("hydraulics.pressure_gain", r.hydraulics.pressure_gain, "");
  f("sensors.hub_angle.noise", r.sensors.hub_angle.noise, "rad");
  f("sensors.hub_angle.delay", r.sensors.hub_angle.delay, "samples");
  f("sensors.hub_angle.quantize", r.sensors.hub_angle.quantize, "");
  f("sensors.hub_angle.encoder_bits", r.sensors.hub_angle.encoder_bits, "bits");
  f("sensors.hub_rate.noise", r.sensors.hub_rate.noise, "rad/s");
  f("sensors.hub_rate.delay", r.sensors.hub_rate.delay, "samples");
  f("sensors.hub_rate.recorded", r.sensors.hub_rate.recorded, "");
  f("sensors.hub_torque.noise", r.sensors.hub_torque.noise, "N m");
  f("sensors.hub_torque.delay", r.sensors.hub_torque.delay, "samples");
  f("sensors.tip_deflection.noise", r.sensors.tip_deflection.noise, "m");
  f("sensors.tip_deflection.delay", r.sensors.tip_deflection.delay, "samples");
  f("sensors.pressure.noise", r.sensors.pressure.noise, "Pa");
  f("sensors.pressure.delay", r.sensors.pressure.delay, "samples");
  f("record.decimate", r.record.decimate, "samples");
  f("record.as_seen", r.record.as_seen, "");
  f("seed", r.seed, "");
  f("duration", r.duration, "s");
  f("initial.joint_angle", r.initial.joint_angle, "rad");
  f("initial.hub_rate", r.initial.hub_rate, "rad/s");
  f("solver.rtol", r.solver.rtol, "");
  f("solver.atol", r.solver.atol, "");
  f("solver.max_steps", r.solver.max_steps, "");
}

[[noreturn]] void bad_value(const std::string& key, const std::string& value, const char* what) {
  throw std::invalid_argument(key + ": '" + value + "' is not " + what);
}

double parse_double(const std::string& key, const std::string& s) {
  std::size_t used = 0;
  double x = 0.0;
  try {
    x = std::stod(s, &used);
  } catch (const std::exception&) {
    bad_value(key, s, "a number");
  }
  if (used != s.size() || !std::isfinite(x)) bad_value(key, s, "a finite number");
  return x;
}

long long parse_integer(const std::string& key, const std::string& s) {
  std::size_t used = 0;
  long long x = 0;
  try {
    x = std::stoll(s, &used);
  } catch (const std::exception&) {
    bad_value(key, s, "a whole number");
  }
  if (used != s.size()) bad_value(key, s, "a whole number");
  return x;
}

// "target:hold,target:hold", rad and s.
std::vector<TruthMove> parse_moves(const std::string& key, const std::string& s) {
  std::vector<TruthMove> moves;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto colon = item.find(':');
    if (colon == std::string::npos) bad_value(key, s, "a list target:hold,target:hold (rad, s)");
    moves.push_back({parse_double(key, item.substr(0, colon)), parse_double(key, item.substr(colon + 1))});
  }
  if (moves.empty()) bad_value(key, s, "a list target:hold,target:hold (rad, s)");
  return moves;
}

template <class T>
void parse_into(const std::string& key, const std::string& s, T& x) {
  if constexpr (std::is_same_v<T, double>) {
    x = parse_double(key, s);
  } else if constexpr (std::is_same_v<T, bool>) {
    if (s == "true" || s == "1") x = true;
    else if (s == "false" || s == "0") x = false;
    else bad_value(key, s, "true, false, 1 or 0");
  } else if constexpr (std::is_same_v<T, std::uint64_t>) {
    if (s.empty() || s[0] == '-') bad_value(key, s, "a whole number >= 0");
    x = static_cast<std::uint64_t>(parse_integer(key, s));
  } else if constexpr (std::is_integral_v<T>) {
    const long long v = parse_integer(key, s);
    if (v < static_cast<long long>(std::numeric_limits<T>::min()) || v > static_cast<long long>(std::numeric_limits<T>::max()))
      bad_value(key, s, "in range");
    x = static_cast<T>(v);
  } else {
    x = parse_moves(key, s);
  }
}

template <class T>
std::string format_value(const T& x) {
  if constexpr (std::is_same_v<T, bool>) {
    return x ? "true" : "false";
  } else if constexpr (std::is_same_v<T, double>) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", x);
    return buf;
  } else if constexpr (std::is_integral_v<T>) {
    return std::to_string(x);
  } else {
    std::string out;
    for (const auto& m : x) {
      if (!out.empty()) out += ',';
      out += format_value(m.target);
      out += ':';
      out += format_value(m.hold);
    }
    return out;
  }
}

}  // namespace

void set_truth_field(TruthRig& rig, const std::string& key, const std::string& value) {
  bool found = false;
  visit_fields(rig, [&](const char* name, auto& member, const char*) {
    if (key != name) return;
    parse_into(key, value, member);
    found = true;
  });
  if (!found) throw std::invalid_argument("unknown key '" + key + "'");
}

std::vector<TruthFieldInfo> list_truth_fields(const TruthRig& rig) {
  std::vector<TruthFieldInfo> out;
  visit_fields(rig, [&](const char* name, const auto& member, const char* unit) {
    out.push_back({name, unit, format_value(member)});
  });
  return out;
}

// ---------------------------------------------------------------------------------------------
// Checks: one message naming the field.

namespace {

void require(bool ok, const char* key, const char* what, double got) {
  if (ok) return;
  char buf[200];
  std::snprintf(buf, sizeof buf, "%s: must be %s, got %g", key, what, got);
  throw std::invalid_argument(buf);
}

void validate(const TruthRig& r) {
  auto positive = [](const char* key, double x) { require(x > 0 && std::isfinite(x), key, "> 0", x); };
  auto non_negative = [](const char* key, double x) { require(x >= 0 && std::isfinite(x), key, ">= 0", x); };
  positive("beam.length", r.beam.length);
  positive("beam.height", r.beam.height);
  positive("beam.thickness", r.beam.thickness);
  non_negative("beam.density", r.beam.density);
  positive("beam.youngs_modulus", r.beam.youngs_modulus);
  require(r.segments >= 1 && r.segments <= 1000, "segments", "between 1 and 1000", r.segments);
  positive("joint.stiffness", r.joint.stiffness);
  non_negative("joint.damping", r.joint.damping);
  positive("joint.reference_cell", r.joint.reference_cell);
  non_negative("joint.stiffening", r.joint.stiffening);
  positive("joint.stiffening_angle", r.joint.stiffening_angle);
  non_negative("hub_inertia", r.hub_inertia);
  non_negative("payload.mass", r.payload.mass);
  non_negative("payload.inertia", r.payload.inertia);
  positive("controller.rate", r.controller.rate);
  non_negative("controller.kp", r.controller.kp);
  non_negative("controller.kd", r.controller.kd);
  non_negative("controller.ki", r.controller.ki);
  non_negative("controller.torque_limit", r.controller.torque_limit);
  require(std::isfinite(r.controller.feedforward), "controller.feedforward", "finite", r.controller.feedforward);
  positive("trajectory.move_time", r.trajectory.move_time);
  for (const auto& m : r.trajectory.moves) {
    require(std::isfinite(m.target), "trajectory.moves", "finite targets", m.target);
    non_negative("trajectory.moves (hold)", m.hold);
  }
  non_negative("friction.viscous", r.friction.viscous);
  non_negative("friction.coulomb", r.friction.coulomb);
  non_negative("friction.stiction", r.friction.stiction);
  require(r.friction.stiction == 0 || r.friction.stiction >= r.friction.coulomb, "friction.stiction",
          ">= friction.coulomb (or 0 for no peak)", r.friction.stiction);
  positive("friction.stribeck_velocity", r.friction.stribeck_velocity);
  positive("friction.smoothing", r.friction.smoothing);
  positive("friction.stribeck_exponent", r.friction.stribeck_exponent);
  non_negative("friction.bristle_stiffness", r.friction.bristle_stiffness);
  non_negative("friction.bristle_damping", r.friction.bristle_damping);
  require(r.friction.position_amplitude >= 0 && r.friction.position_amplitude < 1, "friction.position_amplitude",
          "in [0, 1)", r.friction.position_amplitude);
  require(std::isfinite(r.friction.position_waves), "friction.position_waves", "finite", r.friction.position_waves);
  require(std::isfinite(r.friction.position_phase), "friction.position_phase", "finite", r.friction.position_phase);
  require(std::isfinite(r.torque_offset), "torque_offset", "finite", r.torque_offset);
  positive("drive.inertia", r.drive.inertia);
  positive("drive.ratio", r.drive.ratio);
  positive("drive.stiffness", r.drive.stiffness);
  non_negative("drive.cubic_stiffness", r.drive.cubic_stiffness);
  non_negative("drive.damping", r.drive.damping);
  non_negative("drive.backlash", r.drive.backlash);
  positive("drive.backlash_smoothing", r.drive.backlash_smoothing);
  non_negative("drive.knee_1", r.drive.knee_1);
  if (r.drive.knee_1 > 0) positive("drive.stiffness_2", r.drive.stiffness_2);
  non_negative("drive.knee_2", r.drive.knee_2);
  if (r.drive.knee_2 > 0) {
    require(r.drive.knee_1 > 0 && r.drive.knee_2 > r.drive.knee_1, "drive.knee_2", "> drive.knee_1 > 0 (or 0)",
            r.drive.knee_2);
    positive("drive.stiffness_3", r.drive.stiffness_3);
  }
  const auto& h = r.hydraulics;
  positive("hydraulics.piston_area", h.piston_area);
  positive("hydraulics.pinion_radius", h.pinion_radius);
  positive("hydraulics.chamber_volume", h.chamber_volume);
  positive("hydraulics.bulk_modulus", h.bulk_modulus);
  positive("hydraulics.supply_pressure", h.supply_pressure);
  non_negative("hydraulics.tank_pressure", h.tank_pressure);
  require(h.tank_pressure < h.supply_pressure, "hydraulics.tank_pressure", "below hydraulics.supply_pressure",
          h.tank_pressure);
  positive("hydraulics.rated_flow", h.rated_flow);
  positive("hydraulics.rated_drop", h.rated_drop);
  positive("hydraulics.laminar_drop", h.laminar_drop);
  non_negative("hydraulics.leakage", h.leakage);
  positive("hydraulics.valve_frequency", h.valve_frequency);
  positive("hydraulics.valve_damping", h.valve_damping);
  non_negative("hydraulics.pressure_gain", h.pressure_gain);
  const std::pair<const TruthChannel*, const char*> channels[] = {{&r.sensors.hub_angle, "sensors.hub_angle"},
                                                                  {&r.sensors.hub_rate, "sensors.hub_rate"},
                                                                  {&r.sensors.hub_torque, "sensors.hub_torque"},
                                                                  {&r.sensors.tip_deflection, "sensors.tip_deflection"},
                                                                  {&r.sensors.pressure, "sensors.pressure"}};
  for (const auto& [ch, name] : channels) {
    const std::string n(name);
    non_negative((n + ".noise").c_str(), ch->noise);
    require(ch->delay >= 0 && ch->delay <= 1000000, (n + ".delay").c_str(), "between 0 and 1e6 samples", ch->delay);
  }
  require(r.sensors.hub_angle.encoder_bits >= 1 && r.sensors.hub_angle.encoder_bits <= 52,
          "sensors.hub_angle.encoder_bits", "between 1 and 52", r.sensors.hub_angle.encoder_bits);
  require(r.record.decimate >= 1, "record.decimate", ">= 1", r.record.decimate);
  non_negative("duration", r.duration);
  require(std::isfinite(r.initial.joint_angle), "initial.joint_angle", "finite", r.initial.joint_angle);
  require(std::isfinite(r.initial.hub_rate), "initial.hub_rate", "finite", r.initial.hub_rate);
  positive("solver.rtol", r.solver.rtol);
  positive("solver.atol", r.solver.atol);
  require(r.solver.max_steps >= 1, "solver.max_steps", ">= 1", static_cast<double>(r.solver.max_steps));
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The chain: segments, joints, and the mass-matrix coefficients.

TruthChain make_truth_chain(const TruthRig& r) {
  TruthChain ch;
  const int n = r.segments;
  ch.n = n;
  // Joints at the centres of N-1 equal cells l = L/(N-1): end segments l/2 (reference-rig.md).
  const double cell = n > 1 ? r.beam.length / (n - 1) : r.beam.length;
  ch.length.assign(n, cell);
  if (n > 1) ch.length.front() = ch.length.back() = 0.5 * cell;
  // k and c scale as reference_cell / l; k3 from the secant stiffening at the stiffening angle.
  const double scale = r.joint.reference_cell / cell;
  const double k = r.joint.stiffness * scale;
  ch.k.assign(n, k);
  ch.c.assign(n, r.joint.damping * scale);
  ch.k3.assign(n, r.joint.stiffening * k / (r.joint.stiffening_angle * r.joint.stiffening_angle));
  ch.k[0] = ch.c[0] = ch.k3[0] = 0.0;

  // Segment i: mass m_i = rho h t L_i, centroidal inertia m_i (L_i^2 + t^2)/12; mass beyond it
  // (outboard segments and the payload) B_i.
  std::vector<double> m(n), ic(n), beyond(n);
  for (int i = 0; i < n; ++i) {
    m[i] = r.beam.density * r.beam.height * r.beam.thickness * ch.length[i];
    ic[i] = m[i] * (ch.length[i] * ch.length[i] + r.beam.thickness * r.beam.thickness) / 12.0;
  }
  beyond[n - 1] = r.payload.mass;
  for (int i = n - 2; i >= 0; --i) beyond[i] = beyond[i + 1] + m[i + 1];
  // T = 1/2 sum_jk a_jk cos(phi_j - phi_k) w_j w_k:
  //   a_jj = Ic_j + m_j L_j^2/4 + B_j L_j^2 (+ J_hub on j = 0, + J_payload on j = N-1),
  //   a_jk = L_j (m_k L_k/2 + B_k L_k) for j < k (segment k's and everything beyond it's first moment).
  ch.a = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) {
    const double lj = ch.length[j];
    ch.a(j, j) = ic[j] + 0.25 * m[j] * lj * lj + beyond[j] * lj * lj;
    for (int k2 = j + 1; k2 < n; ++k2) {
      const double lk = ch.length[k2];
      ch.a(j, k2) = ch.a(k2, j) = lj * (0.5 * m[k2] * lk + beyond[k2] * lk);
    }
  }
  ch.a(0, 0) += r.hub_inertia;
  ch.a(n - 1, n - 1) += r.payload.inertia;
  return ch;
}

double calc_truth_rigid_inertia(const TruthRig& rig, bool nominal) {
  TruthRig r = rig;
  if (nominal) {  // the controller's model: its own hub and payload where given (>= 0)
    const auto& c = rig.controller;
    if (c.nominal_hub_inertia >= 0) r.hub_inertia = c.nominal_hub_inertia;
    if (c.nominal_payload_mass >= 0) r.payload.mass = c.nominal_payload_mass;
    if (c.nominal_payload_inertia >= 0) r.payload.inertia = c.nominal_payload_inertia;
  }
  return make_truth_chain(r).a.sum();  // 1' M(0) 1: every cos(phi_j - phi_k) = 1
}

Eigen::MatrixXd calc_truth_mass_matrix(const TruthChain& ch, const Eigen::VectorXd& phi) {
  Eigen::MatrixXd M(ch.n, ch.n);
  for (int j = 0; j < ch.n; ++j)
    for (int k = 0; k < ch.n; ++k) M(j, k) = ch.a(j, k) * std::cos(phi[j] - phi[k]);
  return M;
}

// ---------------------------------------------------------------------------------------------
// The plant: chain, hub friction, load, drive train, hydraulics. State
// y = [phi (N), w (N), theta_a, w_a (drive), x, x', p_a, p_b (hydraulics, pressures in MPa)].

namespace {

// The commanded hub angle of the cubic moves, rad.
double calc_ref(const TruthRig::Trajectory& tr, double t) {
  double r0 = 0.0, t0 = 0.0;
  for (const auto& mv : tr.moves) {
    const double u = (t - t0) / tr.move_time;
    if (u < 1.0) return r0 + (mv.target - r0) * u * u * (3.0 - 2.0 * u);
    r0 = mv.target;
    t0 += tr.move_time + mv.hold;
    if (t < t0) return r0;
  }
  return r0;
}

// Its rate r' = (r1 - r0) 6u(1 - u)/T (rad/s) and acceleration r'' = (r1 - r0) 6(1 - 2u)/T^2 (rad/s^2);
// 0 while holding.
void calc_ref_derivatives(const TruthRig::Trajectory& tr, double t, double& rate, double& accel) {
  double r0 = 0.0, t0 = 0.0;
  rate = accel = 0.0;
  const double T = tr.move_time;
  for (const auto& mv : tr.moves) {
    const double u = (t - t0) / T;
    if (u < 1.0) {
      rate = (mv.target - r0) * 6.0 * u * (1.0 - u) / T;
      accel = (mv.target - r0) * 6.0 * (1.0 - 2.0 * u) / (T * T);
      return;
    }
    r0 = mv.target;
    t0 += T + mv.hold;
    if (t < t0) return;
  }
}

class Plant {
 public:
  explicit Plant(const TruthRig& r)
      : rig_(r), ch_(make_truth_chain(r)), n_(ch_.n), sh_(rig_.drive.enabled ? 2 * n_ : -1),
        hy_(rig_.hydraulics.enabled ? 2 * n_ + (sh_ >= 0 ? 2 : 0) : -1),
        lu_(rig_.friction.bristle_stiffness > 0 ? 2 * n_ + (sh_ >= 0 ? 2 : 0) + (hy_ >= 0 ? 4 : 0) : -1), M_(n_, n_),
        llt_(n_), rhs_(n_), acc_(n_), s_(n_), c_(n_) {
    const auto& h = rig_.hydraulics;
    D_ = h.piston_area * h.pinion_radius;
    kv_ = h.rated_flow / std::sqrt(h.rated_drop);
  }

  int size() const { return 2 * n_ + (sh_ >= 0 ? 2 : 0) + (hy_ >= 0 ? 4 : 0) + (lu_ >= 0 ? 1 : 0); }
  int segments() const { return n_; }

  // Every beam joint bent by q0, the arm turning rigidly at w0 (at rest by default), the drive's shaft
  // at rest and aligned with the hub (centre of the gap), LuGre's bristles relaxed.
  std::vector<double> initial_state(double q0, double w0) const {
    std::vector<double> y(size(), 0.0);
    for (int i = 0; i < n_; ++i) y[i] = i * q0;
    for (int i = 0; i < n_; ++i) y[n_ + i] = w0;
    if (hy_ >= 0) y[hy_ + 2] = y[hy_ + 3] = 0.5 * (rig_.hydraulics.supply_pressure + rig_.hydraulics.tank_pressure) / kMPa;
    return y;
  }

  // The Stribeck curve with the worn gear's factor, N m:
  //   g(w, theta) = (1 + a cos(p theta + phase)) (Fc + (Fs - Fc) exp(-|w/vs|^delta)).
  double stribeck(double w, double theta) const {
    const auto& f = rig_.friction;
    const double fs = f.stiction > 0 ? f.stiction : f.coulomb;
    const double x = std::fabs(w / f.stribeck_velocity);
    const double g = f.coulomb + (fs - f.coulomb) * (f.stribeck_exponent == 2.0 ? std::exp(-x * x)
                                                                                 : std::exp(-std::pow(x, f.stribeck_exponent)));
    return (1.0 + f.position_amplitude * std::cos(f.position_waves * theta + f.position_phase)) * g;
  }

  // LuGre's bristle rate z' = w - sigma0 |w| z / g(w, theta), rad/s (Canudas de Wit et al. 1995, eq. 2).
  double bristle_rate(const double* y) const {
    const double w = y[n_], g = stribeck(w, y[0]);
    if (g <= 0.0) return w;  // no Coulomb level: the bristles follow the hub and carry no load
    return w - rig_.friction.bristle_stiffness * std::fabs(w) * y[lu_] / g;
  }

  // Hub friction, N m. Static: -(b w + g(w, theta) (2/pi) atan(w/eps)); LuGre: -(sigma0 z + sigma1 z' + b w).
  double friction(const double* y) const {
    const auto& f = rig_.friction;
    const double w = y[n_];
    if (lu_ >= 0) {
      // Without a Coulomb level the bristles carry nothing (z is kept, the force is the viscous part).
      if (stribeck(w, y[0]) <= 0.0) return -f.viscous * w;
      return -(f.bristle_stiffness * y[lu_] + f.bristle_damping * bristle_rate(y) + f.viscous * w);
    }
    return -(f.viscous * w + stribeck(w, y[0]) * M_2_PI * std::atan(w / f.smoothing));
  }

  double bristle(const double* y) const { return lu_ >= 0 ? y[lu_] : 0.0; }

  // The drive's dead zone e = g(d) and its slope g'(d): s(d - b) - s(-d - b) with the smooth ramp
  // s(x) = (x + sqrt(x^2 + delta^2))/2 (written without cancellation for x < 0); e = d without backlash.
  void dead_zone(double d, double& e, double& slope) const {
    const double b = 0.5 * rig_.drive.backlash, delta = rig_.drive.backlash_smoothing;
    if (b == 0.0) {
      e = d;
      slope = 1.0;
      return;
    }
    auto ramp = [&](double x) {
      const double h = std::hypot(x, delta);
      return x >= 0 ? 0.5 * (x + h) : 0.5 * delta * delta / (h - x);
    };
    auto ramp_slope = [&](double x) { return 0.5 * (1.0 + x / std::hypot(x, delta)); };
    e = ramp(d - b) - ramp(-d - b);
    slope = ramp_slope(d - b) + ramp_slope(-d - b);
  }

  // The multi-slope mesh spring s(e), N m (odd, continuous): slope k to knee_1, stiffness_2 to knee_2,
  // stiffness_3 beyond; and its potential V(e) = integral of s, J. knee_1 = 0: s = k e.
  double mesh_spring(double e) const {
    const auto& dr = rig_.drive;
    const double a = std::fabs(e);
    double s = dr.stiffness * std::min(a, dr.knee_1 > 0 ? dr.knee_1 : a);
    if (dr.knee_1 > 0 && a > dr.knee_1) {
      const double top = dr.knee_2 > 0 ? std::min(a, dr.knee_2) : a;
      s += dr.stiffness_2 * (top - dr.knee_1);
      if (dr.knee_2 > 0 && a > dr.knee_2) s += dr.stiffness_3 * (a - dr.knee_2);
    }
    return std::copysign(s, e);
  }
  double mesh_potential(double e) const {
    const auto& dr = rig_.drive;
    const double a = std::fabs(e);
    if (dr.knee_1 <= 0 || a <= dr.knee_1) return 0.5 * dr.stiffness * a * a;
    const double e1 = dr.knee_1, s1 = dr.stiffness * e1;
    double v = 0.5 * s1 * e1;
    const double top = dr.knee_2 > 0 ? std::min(a, dr.knee_2) : a;
    v += s1 * (top - e1) + 0.5 * dr.stiffness_2 * (top - e1) * (top - e1);  // linear from s(e1) with slope k2
    if (dr.knee_2 > 0 && a > dr.knee_2) {
      const double s2 = s1 + dr.stiffness_2 * (dr.knee_2 - e1), x = a - dr.knee_2;
      v += s2 * x + 0.5 * dr.stiffness_3 * x * x;
    }
    return v;
  }

  // Mesh torque on the hub, N m: s(e) + k3 e^3 + c de/dt; with backlash the teeth push, never pull; with
  // one-sided damping c acts only while the teeth close (e de/dt > 0).
  double mesh_torque(const double* y) const {
    const auto& dr = rig_.drive;
    const double d = y[sh_] / dr.ratio - y[0], dd = y[sh_ + 1] / dr.ratio - y[n_];
    double e, slope;
    dead_zone(d, e, slope);
    const double de = slope * dd;
    const double damping = dr.one_sided_damping && e * de <= 0.0 ? 0.0 : dr.damping * de;
    const double t = mesh_spring(e) + dr.cubic_stiffness * e * e * e + damping;
    if (dr.backlash == 0.0) return t;
    return e > 0 ? std::max(t, 0.0) : std::min(t, 0.0);
  }

  // The actuator's torque on its pinion (the hub, or the drive's shaft), N m: D (p_a - p_b), or the
  // demand (through the gear: tau/n).
  double pinion_torque(const double* y) const {
    if (hy_ >= 0) return D_ * (y[hy_ + 2] - y[hy_ + 3]) * kMPa;
    return sh_ >= 0 ? tau / rig_.drive.ratio : tau;
  }

  // The actuator's torque on the hub (what a torque sensor reads), N m.
  double actuator_torque(const double* y) const { return sh_ >= 0 ? mesh_torque(y) : pinion_torque(y); }

  double pressure_a(const double* y) const { return y[hy_ + 2] * kMPa; }
  double pressure_b(const double* y) const { return y[hy_ + 3] * kMPa; }

  // The valve's orifice root with a laminar core, R(dp) = dp / sqrt(|dp| + dp_l), Pa^(1/2).
  double root(double dp) const { return dp / std::sqrt(std::fabs(dp) + rig_.hydraulics.laminar_drop); }

  // Spool and chamber rates (README.md, "Hydraulics"). False when a chamber's volume is gone.
  bool hydraulics_rhs(const double* y, double* ydot) const {
    const auto& h = rig_.hydraulics;
    const double th_p = sh_ >= 0 ? y[sh_] : y[0], w_p = sh_ >= 0 ? y[sh_ + 1] : y[n_];  // the pinion
    const double x = y[hy_], xd = y[hy_ + 1], pa = pressure_a(y), pb = pressure_b(y);
    // The amplifier's torque loop and the second-order spool.
    const double demand = sh_ >= 0 ? tau / rig_.drive.ratio : tau;
    const double u = std::clamp(h.pressure_gain * (demand - D_ * (pa - pb)) / (D_ * h.supply_pressure), -1.0, 1.0);
    const double wv = 2.0 * M_PI * h.valve_frequency;
    ydot[hy_] = xd;
    ydot[hy_ + 1] = wv * wv * (u - x) - 2.0 * h.valve_damping * wv * xd;
    // Four lands, critically lapped: x > 0 connects supply to a and b to tank.
    const double xc = std::clamp(x, -1.0, 1.0), xp = std::max(xc, 0.0), xm = std::max(-xc, 0.0);
    const double ps = h.supply_pressure, pt = h.tank_pressure;
    const double qa = kv_ * (xp * root(ps - pa) - xm * root(pa - pt));
    const double qb = kv_ * (xm * root(ps - pb) - xp * root(pb - pt));
    const double ql = h.leakage * (pa - pb);
    // Continuity with compressibility: p' = beta / V (Q_in - dV/dt), V_a,b = V0 +- D theta_p.
    const double va = h.chamber_volume + D_ * th_p, vb = h.chamber_volume - D_ * th_p;
    if (!(va > 0 && vb > 0)) return false;
    ydot[hy_ + 2] = h.bulk_modulus / va * (qa - ql - D_ * w_p) / kMPa;
    ydot[hy_ + 3] = h.bulk_modulus / vb * (qb + ql + D_ * w_p) / kMPa;
    return true;
  }

  // ydot = f(y) under the held demand `tau`. False when the result is not finite.
  bool rhs(const double* y, double* ydot) {
    const double* phi = y;
    const double* w = y + n_;
    // Generalised forces on the absolute angles: joint i's moment m_i = -(k q + k3 q^3 + c q') with
    // q = phi_i - phi_{i-1} acts +m_i on segment i and -m_i on segment i-1.
    rhs_.setZero();
    for (int i = 1; i < n_; ++i) {
      const double q = phi[i] - phi[i - 1], qd = w[i] - w[i - 1];
      const double m = -((ch_.k[i] + ch_.k3[i] * q * q) * q + ch_.c[i] * qd);
      rhs_[i] += m;
      rhs_[i - 1] -= m;
    }
    // Hub (on segment 0): actuator, friction, the constant load; LuGre's bristles.
    rhs_[0] += actuator_torque(y) + friction(y) - rig_.torque_offset;
    if (lu_ >= 0) ydot[lu_] = bristle_rate(y);
    if (sh_ >= 0) {  // J_a theta_a'' = tau_pinion - tau_s/n
      ydot[sh_] = y[sh_ + 1];
      ydot[sh_ + 1] = (pinion_torque(y) - mesh_torque(y) / rig_.drive.ratio) / rig_.drive.inertia;
    }
    if (hy_ >= 0 && !hydraulics_rhs(y, ydot)) return false;
    // Lagrange: sum_k a_jk [cos(phi_j - phi_k) phi_k'' + sin(phi_j - phi_k) w_k^2] = Q_j.
    for (int i = 0; i < n_; ++i) {
      s_[i] = std::sin(phi[i]);
      c_[i] = std::cos(phi[i]);
    }
    for (int j = 0; j < n_; ++j)
      for (int k = 0; k < n_; ++k) {
        const double cjk = c_[j] * c_[k] + s_[j] * s_[k], sjk = s_[j] * c_[k] - c_[j] * s_[k];
        M_(j, k) = ch_.a(j, k) * cjk;
        rhs_[j] -= ch_.a(j, k) * sjk * w[k] * w[k];
      }
    llt_.compute(M_);  // M is symmetric positive definite (a kinetic energy)
    acc_ = rhs_;
    llt_.solveInPlace(acc_);
    for (int i = 0; i < n_; ++i) {
      ydot[i] = w[i];
      ydot[n_ + i] = acc_[i];
    }
    for (int i = 0; i < size(); ++i)
      if (!std::isfinite(ydot[i])) return false;
    return true;
  }

  double tip_deflection(const double* y) const {
    double d = 0.0;
    for (int i = 0; i < n_; ++i) d += ch_.length[i] * std::sin(y[i] - y[0]);
    return d;
  }

  double twist(const double* y) const { return sh_ >= 0 ? y[sh_] / rig_.drive.ratio - y[0] : 0.0; }
  double twist_rate(const double* y) const { return sh_ >= 0 ? y[sh_ + 1] / rig_.drive.ratio - y[n_] : 0.0; }

  // Kinetic energy 1/2 w' M w + 1/2 J_a w_a^2 plus the springs' energy (the drive mesh's exact without backlash;
  // not the oil's), J.
  double energy(const double* y) const {
    Eigen::Map<const Eigen::VectorXd> phi(y, n_), w(y + n_, n_);
    double e = 0.5 * w.dot(calc_truth_mass_matrix(ch_, phi) * w);
    for (int i = 1; i < n_; ++i) {
      const double q = y[i] - y[i - 1];
      e += 0.5 * ch_.k[i] * q * q + 0.25 * ch_.k3[i] * q * q * q * q;
    }
    if (rig_.drive.enabled) {
      const auto& dr = rig_.drive;
      double ez, slope;
      dead_zone(twist(y), ez, slope);
      e += 0.5 * dr.inertia * y[sh_ + 1] * y[sh_ + 1] + mesh_potential(ez) + 0.25 * dr.cubic_stiffness * ez * ez * ez * ez;
    }
    return e;
  }

  double tau = 0.0;  // the held demand of the controller, N m

 private:
  static constexpr double kMPa = 1e6;  // Pa per stored pressure unit
  const TruthRig& rig_;
  TruthChain ch_;
  int n_;
  int sh_, hy_, lu_;                  // first state of the drive's shaft, of the hydraulics, LuGre's z; -1 = off
  double D_ = 0.0, kv_ = 0.0;         // m^3/rad, m^3/(s Pa^1/2)
  Eigen::MatrixXd M_;
  Eigen::LLT<Eigen::MatrixXd> llt_;
  Eigen::VectorXd rhs_, acc_, s_, c_;
};

// ---------------------------------------------------------------------------------------------
// CVODE (BDF, Newton with the dense direct solver, finite-difference Jacobian).

class Cvode {
 public:
  Cvode(Plant& plant, const TruthRig::Solver& s) : plant_(plant), n_(plant.size()) {
    if (SUNContext_Create(nullptr, &ctx_) != 0) throw std::runtime_error("truth_sim: SUNContext_Create failed");
    y_ = N_VNew_Serial(n_, ctx_);
    mem_ = CVodeCreate(CV_BDF, ctx_);
    A_ = SUNDenseMatrix(n_, n_, ctx_);
    ls_ = SUNLinSol_Dense(y_, A_, ctx_);
    if (!y_ || !mem_ || !A_ || !ls_) throw std::runtime_error("truth_sim: CVODE could not allocate");
    N_VConst(0.0, y_);
    check(CVodeInit(mem_, &Cvode::f, 0.0, y_), "CVodeInit");
    check(CVodeSetErrHandlerFn(mem_, &Cvode::on_error, this), "CVodeSetErrHandlerFn");
    check(CVodeSetUserData(mem_, &plant_), "CVodeSetUserData");
    check(CVodeSStolerances(mem_, s.rtol, s.atol), "CVodeSStolerances");
    check(CVodeSetLinearSolver(mem_, ls_, A_), "CVodeSetLinearSolver");
    check(CVodeSetMaxNumSteps(mem_, s.max_steps), "CVodeSetMaxNumSteps");
  }
  ~Cvode() {
    CVodeFree(&mem_);
    SUNLinSolFree(ls_);
    SUNMatDestroy(A_);
    N_VDestroy(y_);
    SUNContext_Free(&ctx_);
  }
  Cvode(const Cvode&) = delete;
  Cvode& operator=(const Cvode&) = delete;

  double* state() { return N_VGetArrayPointer(y_); }

  // A fresh start at t from state(): the held torque has jumped, the history is no good.
  void restart(double t) { check(CVodeReInit(mem_, t, y_), "CVodeReInit"); }

  // Integrates state() to exactly t_next (stop time: never past the next sample).
  void advance(double t_next) {
    check(CVodeSetStopTime(mem_, t_next), "CVodeSetStopTime");
    double t_reached = 0.0;
    const int flag = CVode(mem_, t_next, y_, &t_reached, CV_NORMAL);
    if (flag < 0) {
      char buf[512];
      char* name = CVodeGetReturnFlagName(flag);  // malloc'd: the caller frees it (SUNDIALS 6)
      std::snprintf(buf, sizeof buf, "truth_sim: CVODE failed before t = %.6f s (%s)%s%s", t_next, name,
                    message_.empty() ? "" : ": ", message_.c_str());
      std::free(name);
      throw std::runtime_error(buf);
    }
  }

  // Counters since the last restart (CVodeReInit zeroes them).
  void add_stats(TruthSolverStats& s) const {
    long steps = 0, rhs = 0, jac = 0, fd_rhs = 0;
    CVodeGetNumSteps(mem_, &steps);
    CVodeGetNumRhsEvals(mem_, &rhs);
    CVodeGetNumJacEvals(mem_, &jac);
    CVodeGetNumLinRhsEvals(mem_, &fd_rhs);  // the finite-difference Jacobian's
    s.steps += steps;
    s.rhs_evals += rhs + fd_rhs;
    s.jacobian_evals += jac;
  }

 private:
  static int f(double, N_Vector y, N_Vector ydot, void* user) {
    return static_cast<Plant*>(user)->rhs(N_VGetArrayPointer(y), N_VGetArrayPointer(ydot)) ? 0 : 1;  // 1: retry smaller
  }
  static void on_error(int code, const char*, const char* function, char* msg, void* self) {
    if (code < 0) static_cast<Cvode*>(self)->message_ = std::string(function) + ": " + msg;  // warnings: ignored
  }
  void check(int flag, const char* what) {
    if (flag < 0) throw std::runtime_error(std::string("truth_sim: ") + what + " failed: " + message_);
  }

  Plant& plant_;
  int n_;
  SUNContext ctx_ = nullptr;
  N_Vector y_ = nullptr;
  void* mem_ = nullptr;
  SUNMatrix A_ = nullptr;
  SUNLinearSolver ls_ = nullptr;
  std::string message_;
};

// A sensor channel's readings at every controller sample, with its own noise stream.
class Channel {
 public:
  Channel(const TruthChannel& spec, std::uint64_t seed, unsigned id) : spec_(spec) {
    std::seed_seq s{static_cast<unsigned>(seed & 0xffffffffu), static_cast<unsigned>(seed >> 32), id};
    rng_.seed(s);
  }

  // Takes sample k's reading of the true value x (noise, then quantum q if > 0).
  void read(double x, double quantum = 0.0) {
    if (spec_.noise > 0) x += spec_.noise * normal_(rng_);
    if (quantum > 0) x = quantum * std::nearbyint(x / quantum);
    readings_.push_back(x);
  }
  // The reading taken at sample k, and the one `delay` samples before it (the first while k < delay).
  double now(std::size_t k) const { return readings_[k]; }
  double delayed(std::size_t k) const {
    const std::size_t d = static_cast<std::size_t>(spec_.delay);
    return readings_[k >= d ? k - d : 0];
  }

 private:
  const TruthChannel& spec_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_;
  std::vector<double> readings_;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// The run: controller samples, CVODE in between, the sensors, the record.

std::vector<std::string> truth_record_columns(const TruthRig& rig) {
  std::vector<std::string> cols = {"ref", "hub_torque", "hub_angle"};
  if (rig.sensors.hub_rate.recorded) cols.push_back("hub_rate");
  cols.push_back("tip_deflection");
  if (rig.hydraulics.enabled) cols.insert(cols.end(), {"pressure_a", "pressure_b"});
  return cols;
}

TruthRun run_truth(const TruthRig& rig) {
  validate(rig);
  double duration = rig.duration;
  if (duration == 0.0)
    for (const auto& mv : rig.trajectory.moves) duration += rig.trajectory.move_time + mv.hold;
  require(duration > 0, "duration", "> 0 (or moves to take it from)", duration);
  const double T = 1.0 / rig.controller.rate;
  const long last = std::lround(duration / T);  // samples 0..last

  Plant plant(rig);
  Cvode cvode(plant, rig.solver);
  double* y = cvode.state();
  const auto y0 = plant.initial_state(rig.initial.joint_angle, rig.initial.hub_rate);
  std::copy(y0.begin(), y0.end(), y);
  const int n = plant.segments();

  const auto& sn = rig.sensors;
  Channel angle(sn.hub_angle, rig.seed, 0), rate(sn.hub_rate, rig.seed, 1), torque(sn.hub_torque, rig.seed, 2),
      tip(sn.tip_deflection, rig.seed, 3), pa(sn.pressure, rig.seed, 4), pb(sn.pressure, rig.seed, 5);
  const bool hydraulic = rig.hydraulics.enabled;
  const double quantum = sn.hub_angle.quantize ? 2.0 * M_PI / std::ldexp(1.0, sn.hub_angle.encoder_bits) : 0.0;

  TruthRun run;
  TruthTrace& tr = run.trace;
  const auto& ctl = rig.controller;
  const double j_nominal = calc_truth_rigid_inertia(rig, true);  // the feed-forward's model, kg m^2
  double integral = 0.0, held = NAN;
  for (long k = 0; k <= last; ++k) {
    const double t = k * T;
    // The sensors read the plant at this instant; the controller sees hub angle and rate `delay` late.
    angle.read(y[0], quantum);
    rate.read(y[n]);
    const double seen_angle = angle.delayed(k), seen_rate = rate.delayed(k);
    // PID, zero-order hold, clamping anti-windup (the integral freezes while saturated in the error's direction).
    const double r = calc_ref(rig.trajectory, t);
    const double e = r - seen_angle;
    double r_rate = 0.0, r_accel = 0.0;
    if (ctl.feedforward != 0.0) calc_ref_derivatives(rig.trajectory, t, r_rate, r_accel);
    const double raw = ctl.kp * e + ctl.ki * integral - ctl.kd * seen_rate +
                       ctl.feedforward * (j_nominal * r_accel + ctl.kd * r_rate);
    const double lim = ctl.torque_limit > 0 ? ctl.torque_limit : INFINITY;
    plant.tau = std::clamp(raw, -lim, lim);
    if (!(raw != plant.tau && e * raw > 0)) integral += e * T;
    const double hub_torque = plant.actuator_torque(y);
    torque.read(hub_torque);
    tip.read(plant.tip_deflection(y));
    if (hydraulic) {
      pa.read(plant.pressure_a(y));
      pb.read(plant.pressure_b(y));
      tr.pressure_a.push_back(plant.pressure_a(y));
      tr.pressure_b.push_back(plant.pressure_b(y));
    }

    tr.t.push_back(t);
    tr.ref.push_back(r);
    tr.demand.push_back(plant.tau);
    tr.hub_torque.push_back(hub_torque);
    tr.hub_angle.push_back(y[0]);
    tr.hub_rate.push_back(y[n]);
    tr.tip_deflection.push_back(plant.tip_deflection(y));
    tr.root_joint.push_back(n > 1 ? y[1] - y[0] : 0.0);
    tr.twist.push_back(plant.twist(y));
    tr.twist_rate.push_back(plant.twist_rate(y));
    tr.energy.push_back(plant.energy(y));
    tr.friction.push_back(plant.friction(y));
    tr.bristle.push_back(plant.bristle(y));
    tr.seen_angle.push_back(seen_angle);
    tr.seen_rate.push_back(seen_rate);

    if (k == last) break;
    // The plant to the next sample under the held torque; a new torque restarts the BDF history.
    if (plant.tau != held) {
      if (k > 0) cvode.add_stats(run.stats);
      cvode.restart(t);
      ++run.stats.restarts;
    }
    held = plant.tau;
    cvode.advance((k + 1) * T);
  }

  cvode.add_stats(run.stats);

  // The record: every decimate-th sample; recorded channels shifted by their delay.
  Record& rec = run.record;
  rec.source = "<truth_sim>";
  const auto cols = truth_record_columns(rig);
  for (const auto& c : cols) rec.columns[c];
  for (long k = 0; k <= last; k += rig.record.decimate) {
    const auto j = static_cast<std::size_t>(k);
    rec.t.push_back(tr.t[j]);
    rec.columns["ref"].push_back(tr.ref[j]);
    rec.columns["hub_torque"].push_back(torque.delayed(j));
    rec.columns["hub_angle"].push_back(rig.record.as_seen ? angle.delayed(j) : angle.now(j));
    if (sn.hub_rate.recorded) rec.columns["hub_rate"].push_back(rig.record.as_seen ? rate.delayed(j) : rate.now(j));
    rec.columns["tip_deflection"].push_back(tip.delayed(j));
    if (hydraulic) {
      rec.columns["pressure_a"].push_back(pa.delayed(j));
      rec.columns["pressure_b"].push_back(pb.delayed(j));
    }
  }
  return run;
}

Record simulate_truth(const TruthRig& rig) { return run_truth(rig).record; }

Record simulate_truth(const TruthRig& rig, double duration) {
  TruthRig r = rig;
  r.duration = duration;
  return run_truth(r).record;
}

}  // namespace ff::truth
