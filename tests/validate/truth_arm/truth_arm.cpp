// The truth arm (truth_arm.hpp, README.md): a planar N-link arm in absolute link angles, CVODE between
// controller samples. No code from arm/, multibody/ or kernel/.
#include "tests/validate/truth_arm/truth_arm.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "common/text.hpp"

namespace ff::truth {

std::string truth_arm_joint_name(int i) { return "j" + std::to_string(i + 1); }

// ---------------------------------------------------------------------------------------------
// The suite's arms: the values of tests/data/truth_arm/arm<n>.yaml (README.md there maps them).

TruthArm make_suite_arm(int joints) {
  TruthArm a;
  a.joints = joints;
  auto set = [&](int i, double L, double m, double J, double kp, double kd) {
    TruthArmJoint& j = a.joint[static_cast<std::size_t>(i)];
    j.link = {L, m, L / 2.0, m * L * L / 12.0};  // a uniform bar
    j.drive.motor_inertia = J;
    j.drive.ratio = 100.0;
    j.controller.kp = kp;
    j.controller.kd = kd;
  };
  if (joints == 2) {
    set(0, 0.5, 4.0, 2e-5, 600.0, 60.0);
    set(1, 0.4, 2.5, 1e-5, 150.0, 14.0);
    a.payload = {1.0, 1e-3};
    a.trajectory.start = {-0.5, 0.8};
    a.trajectory.waypoints = {{1.2, {0.4, -0.3}}, {1.2, {-0.2, 0.6}}};
  } else if (joints == 3) {
    set(0, 0.5, 4.0, 2e-5, 800.0, 80.0);
    set(1, 0.4, 2.5, 1e-5, 250.0, 22.0);
    set(2, 0.3, 1.2, 4e-6, 50.0, 3.5);
    a.payload = {0.5, 5e-4};
    a.trajectory.start = {-0.4, 0.6, 0.3};
    a.trajectory.waypoints = {{1.2, {0.3, -0.2, -0.4}}, {1.2, {-0.2, 0.5, 0.2}}};
  } else if (joints == 6) {
    const double L[] = {0.3, 0.3, 0.25, 0.25, 0.2, 0.2}, m[] = {2.0, 1.6, 1.2, 0.9, 0.6, 0.4},
                 J[] = {2e-5, 1.5e-5, 1e-5, 6e-6, 3e-6, 2e-6}, kp[] = {900, 500, 250, 120, 50, 20},
                 kd[] = {90, 45, 20, 9, 3.5, 1.2};
    for (int i = 0; i < 6; ++i) set(i, L[i], m[i], J[i], kp[i], kd[i]);
    a.payload = {0.3, 2e-4};
    a.trajectory.start = {-0.3, 0.4, 0.3, -0.2, 0.3, 0.2};
    a.trajectory.waypoints = {{1.2, {0.3, -0.2, 0.4, 0.3, -0.3, -0.2}}, {1.2, {-0.1, 0.3, -0.2, 0.1, 0.2, 0.3}}};
  } else {
    throw std::invalid_argument("make_suite_arm: the suite has arms of 2, 3 and 6 joints, not " + std::to_string(joints));
  }
  a.trajectory.settle = 0.8;
  return a;
}

// ---------------------------------------------------------------------------------------------
// The field table: the one place names map to TruthArm members.

namespace {

using Waypoints = std::vector<TruthArm::Trajectory::Waypoint>;

template <class Arm, class F>
void visit_fields(Arm& a, F&& f) {
  f("joints", a.joints, "");
  f("gravity", a.gravity, "m/s^2");
  f("payload.mass", a.payload.mass, "kg");
  f("payload.inertia", a.payload.inertia, "kg m^2");
  f("controller.rate", a.controller.rate, "Hz");
  f("controller.payload_mass", a.controller.payload_mass, "kg");
  f("trajectory.start", a.trajectory.start, "rad/rad/...");
  f("trajectory.waypoints", a.trajectory.waypoints, "s:rad/rad,...");
  f("trajectory.settle", a.trajectory.settle, "s");
  f("duration", a.duration, "s");
  f("seed", a.seed, "");
  f("solver.rtol", a.solver.rtol, "");
  f("solver.atol", a.solver.atol, "");
  f("solver.max_steps", a.solver.max_steps, "");
  for (int i = 0; i < kMaxTruthArmJoints; ++i) {
    auto& j = a.joint[static_cast<std::size_t>(i)];
    const std::string p = truth_arm_joint_name(i) + ".";
    auto g = [&](const char* key, auto& member, const char* unit) { f((p + key).c_str(), member, unit); };
    g("link.length", j.link.length, "m");
    g("link.mass", j.link.mass, "kg");
    g("link.com", j.link.com, "m");
    g("link.inertia", j.link.inertia, "kg m^2");
    g("drive.motor_inertia", j.drive.motor_inertia, "kg m^2");
    g("drive.ratio", j.drive.ratio, "");
    g("drive.compliant", j.drive.compliant, "");
    g("drive.stiffness", j.drive.stiffness, "N m/rad");
    g("drive.knee", j.drive.knee, "rad");
    g("drive.stiffness2", j.drive.stiffness2, "N m/rad");
    g("drive.knee2", j.drive.knee2, "rad");
    g("drive.stiffness3", j.drive.stiffness3, "N m/rad");
    g("drive.damping", j.drive.damping, "N m s/rad");
    g("drive.backlash", j.drive.backlash, "rad");
    g("controller.kp", j.controller.kp, "N m/rad");
    g("controller.kd", j.controller.kd, "N m s/rad");
    g("controller.ki", j.controller.ki, "N m/(rad s)");
    g("controller.torque_limit", j.controller.torque_limit, "N m");
    g("controller.gravity_compensation", j.controller.gravity_compensation, "");
    g("controller.link_side", j.controller.link_side, "");
    g("friction.viscous", j.friction.viscous, "N m s/rad");
    g("friction.coulomb", j.friction.coulomb, "N m");
    g("friction.stiction", j.friction.stiction, "N m");
    g("friction.stribeck_velocity", j.friction.stribeck_velocity, "rad/s");
    g("friction.stribeck_exponent", j.friction.stribeck_exponent, "");
    g("friction.smoothing", j.friction.smoothing, "rad/s");
    g("friction.lugre", j.friction.lugre, "");
    g("friction.bristle_stiffness", j.friction.bristle_stiffness, "N m/rad");
    g("friction.bristle_damping", j.friction.bristle_damping, "N m s/rad");
    g("friction.position_amplitude", j.friction.position_amplitude, "");
    g("friction.position_period", j.friction.position_period, "rad");
    g("friction.position_phase", j.friction.position_phase, "rad");
    g("torque_offset", j.torque_offset, "N m");
    g("sensors.angle.noise", j.sensors.angle.noise, "rad");
    g("sensors.angle.delay", j.sensors.angle.delay, "samples");
    g("sensors.angle.encoder_bits", j.sensors.angle.encoder_bits, "bits");
    g("sensors.rate.noise", j.sensors.rate.noise, "rad/s");
    g("sensors.rate.delay", j.sensors.rate.delay, "samples");
    g("sensors.torque_noise", j.sensors.torque_noise, "N m");
  }
}

[[noreturn]] void bad_value(const std::string& key, const std::string& value, const char* what) {
  throw std::invalid_argument(key + ": '" + value + "' is not " + what);
}

double parse_double(const std::string& key, const std::string& s) {
  const std::optional<double> x = parse_finite(s);
  if (!x) bad_value(key, s, "a finite number");
  return *x;
}

std::vector<double> parse_list(const std::string& key, const std::string& s) {
  std::vector<double> out;
  std::stringstream in(s);
  for (std::string x; std::getline(in, x, '/');) out.push_back(parse_double(key, x));
  if (out.empty() || out.size() > kMaxTruthArmJoints) bad_value(key, s, "a list a/b/c of 1 to 6 angles (rad)");
  return out;
}

// "T:a/b,T:a/b": s after the waypoint before, rad per joint.
Waypoints parse_waypoints(const std::string& key, const std::string& s) {
  Waypoints out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');) {
    const auto colon = item.find(':');
    if (colon == std::string::npos) bad_value(key, s, "a list T:a/b,T:a/b (s, rad per joint)");
    out.push_back({parse_double(key, item.substr(0, colon)), parse_list(key, item.substr(colon + 1))});
  }
  if (out.empty()) bad_value(key, s, "a list T:a/b,T:a/b (s, rad per joint)");
  return out;
}

template <class T>
void parse_into(const std::string& key, const std::string& s, T& x) {
  if constexpr (std::is_same_v<T, double>) {
    x = parse_double(key, s);
  } else if constexpr (std::is_same_v<T, bool>) {
    if (s == "true" || s == "1") x = true;
    else if (s == "false" || s == "0") x = false;
    else bad_value(key, s, "true, false, 1 or 0");
  } else if constexpr (std::is_integral_v<T>) {
    const std::optional<T> v = parse_integer<T>(s);
    if (!v) bad_value(key, s, std::is_unsigned_v<T> ? "a whole number >= 0 (in range)" : "a whole number (in range)");
    x = *v;
  } else if constexpr (std::is_same_v<T, std::vector<double>>) {
    x = parse_list(key, s);
  } else {
    x = parse_waypoints(key, s);
  }
}

std::string format_double(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", x);
  return buf;
}

std::string format_list(const std::vector<double>& v) {
  std::string out;
  for (double x : v) out += (out.empty() ? "" : "/") + format_double(x);
  return out;
}

template <class T>
std::string format_value(const T& x) {
  if constexpr (std::is_same_v<T, bool>) return x ? "true" : "false";
  else if constexpr (std::is_same_v<T, double>) return format_double(x);
  else if constexpr (std::is_integral_v<T>) return std::to_string(x);
  else if constexpr (std::is_same_v<T, std::vector<double>>) return format_list(x);
  else {
    std::string out;
    for (const auto& w : x) out += (out.empty() ? "" : ",") + format_double(w.time) + ":" + format_list(w.q);
    return out;
  }
}

}  // namespace

void set_truth_arm_field(TruthArm& arm, const std::string& key, const std::string& value) {
  bool found = false;
  visit_fields(arm, [&](const char* name, auto& member, const char*) {
    if (key != name) return;
    parse_into(key, value, member);
    found = true;
  });
  if (!found) throw std::invalid_argument("unknown key '" + key + "'");
}

std::vector<TruthArmField> list_truth_arm_fields(const TruthArm& arm) {
  std::vector<TruthArmField> out;
  visit_fields(arm, [&](const char* name, const auto& member, const char* unit) {
    out.push_back({name, unit, format_value(member)});
  });
  return out;
}

// ---------------------------------------------------------------------------------------------
// Checks: one message naming the field.

namespace {

void require(bool ok, const std::string& key, const char* what, double got) {
  if (ok) return;
  char buf[300];
  std::snprintf(buf, sizeof buf, "%s: must be %s, got %g", key.c_str(), what, got);
  throw std::invalid_argument(buf);
}

void validate(const TruthArm& a) {
  auto positive = [](const std::string& key, double x) { require(x > 0 && std::isfinite(x), key, "> 0", x); };
  auto non_negative = [](const std::string& key, double x) { require(x >= 0 && std::isfinite(x), key, ">= 0", x); };
  require(a.joints >= 1 && a.joints <= kMaxTruthArmJoints, "joints", "between 1 and 6", a.joints);
  non_negative("gravity", a.gravity);
  non_negative("payload.mass", a.payload.mass);
  non_negative("payload.inertia", a.payload.inertia);
  positive("controller.rate", a.controller.rate);
  require(std::isfinite(a.controller.payload_mass), "controller.payload_mass", "finite", a.controller.payload_mass);
  require(a.trajectory.start.size() <= static_cast<std::size_t>(a.joints), "trajectory.start", "at most `joints` angles",
          static_cast<double>(a.trajectory.start.size()));
  for (const auto& w : a.trajectory.waypoints) {
    positive("trajectory.waypoints (time)", w.time);
    require(w.q.size() == static_cast<std::size_t>(a.joints), "trajectory.waypoints", "one angle per joint",
            static_cast<double>(w.q.size()));
  }
  non_negative("trajectory.settle", a.trajectory.settle);
  non_negative("duration", a.duration);
  positive("solver.rtol", a.solver.rtol);
  positive("solver.atol", a.solver.atol);
  require(a.solver.max_steps >= 1, "solver.max_steps", ">= 1", static_cast<double>(a.solver.max_steps));
  for (int i = 0; i < a.joints; ++i) {
    const TruthArmJoint& j = a.joint[static_cast<std::size_t>(i)];
    const std::string p = truth_arm_joint_name(i) + ".";
    positive(p + "link.length", j.link.length);
    non_negative(p + "link.mass", j.link.mass);
    require(std::isfinite(j.link.com), p + "link.com", "finite", j.link.com);
    non_negative(p + "link.inertia", j.link.inertia);
    non_negative(p + "drive.motor_inertia", j.drive.motor_inertia);
    positive(p + "drive.ratio", j.drive.ratio);
    positive(p + "drive.stiffness", j.drive.stiffness);
    non_negative(p + "drive.knee", j.drive.knee);
    non_negative(p + "drive.stiffness2", j.drive.stiffness2);
    non_negative(p + "drive.knee2", j.drive.knee2);
    require(j.drive.knee2 == 0 || j.drive.knee2 > j.drive.knee, p + "drive.knee2", "> drive.knee (or 0)", j.drive.knee2);
    non_negative(p + "drive.stiffness3", j.drive.stiffness3);
    non_negative(p + "drive.damping", j.drive.damping);
    non_negative(p + "drive.backlash", j.drive.backlash);
    require(!j.drive.compliant || j.drive.motor_inertia > 0, p + "drive.motor_inertia", "> 0 with a compliant drive",
            j.drive.motor_inertia);
    non_negative(p + "controller.kp", j.controller.kp);
    non_negative(p + "controller.kd", j.controller.kd);
    non_negative(p + "controller.ki", j.controller.ki);
    non_negative(p + "controller.torque_limit", j.controller.torque_limit);
    require(std::isfinite(j.controller.gravity_compensation), p + "controller.gravity_compensation", "finite",
            j.controller.gravity_compensation);
    const auto& f = j.friction;
    non_negative(p + "friction.viscous", f.viscous);
    non_negative(p + "friction.coulomb", f.coulomb);
    non_negative(p + "friction.stiction", f.stiction);
    require(f.stiction == 0 || f.stiction >= f.coulomb, p + "friction.stiction", ">= friction.coulomb (or 0)", f.stiction);
    positive(p + "friction.stribeck_velocity", f.stribeck_velocity);
    positive(p + "friction.stribeck_exponent", f.stribeck_exponent);
    positive(p + "friction.smoothing", f.smoothing);
    require(!f.lugre || f.coulomb > 0, p + "friction.coulomb", "> 0 with friction.lugre", f.coulomb);
    positive(p + "friction.bristle_stiffness", f.bristle_stiffness);
    non_negative(p + "friction.bristle_damping", f.bristle_damping);
    require(f.position_amplitude >= 0 && f.position_amplitude < 1, p + "friction.position_amplitude", "in [0, 1)",
            f.position_amplitude);
    positive(p + "friction.position_period", f.position_period);
    require(std::isfinite(f.position_phase), p + "friction.position_phase", "finite", f.position_phase);
    require(std::isfinite(j.torque_offset), p + "torque_offset", "finite", j.torque_offset);
    non_negative(p + "sensors.angle.noise", j.sensors.angle.noise);
    require(j.sensors.angle.delay >= 0 && j.sensors.angle.delay <= 100000, p + "sensors.angle.delay", "in 0..1e5",
            j.sensors.angle.delay);
    require(j.sensors.angle.encoder_bits >= 0 && j.sensors.angle.encoder_bits <= 52, p + "sensors.angle.encoder_bits",
            "in 0..52", j.sensors.angle.encoder_bits);
    non_negative(p + "sensors.rate.noise", j.sensors.rate.noise);
    require(j.sensors.rate.delay >= 0 && j.sensors.rate.delay <= 100000, p + "sensors.rate.delay", "in 0..1e5",
            j.sensors.rate.delay);
    non_negative(p + "sensors.torque_noise", j.sensors.torque_noise);
  }
}

// h_k = m_k c_k + B_k L_k: link k's first moment about its joint, with everything beyond it at its end
// (B_k = the mass beyond link k: later links and the payload), kg m.
Eigen::VectorXd first_moments(const TruthArm& a, double payload_mass) {
  const int n = a.joints;
  Eigen::VectorXd h(n);
  double beyond = payload_mass;
  for (int k = n - 1; k >= 0; --k) {
    const auto& l = a.joint[static_cast<std::size_t>(k)].link;
    h[k] = l.mass * l.com + beyond * l.length;
    beyond += l.mass;
  }
  return h;
}

// The absolute angles phi_k = q_1 + ... + q_k.
Eigen::VectorXd absolute_angles(const Eigen::VectorXd& q) {
  Eigen::VectorXd phi(q.size());
  double s = 0.0;
  for (int k = 0; k < q.size(); ++k) phi[k] = (s += q[k]);
  return phi;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The Lagrangian (README.md): T = 1/2 phi'^T M(phi) phi', M_jk = a_jk cos(phi_j - phi_k) + rotors,
// V = g sum_k h_k sin(phi_k).

namespace {

// a_jk: a_kk = I_k + m_k c_k^2 + B_k L_k^2 (+ J_p for the last), a_jk = L_j h_k for j < k, kg m^2.
Eigen::MatrixXd link_coefficients(const TruthArm& a) {
  const int n = a.joints;
  const Eigen::VectorXd h = first_moments(a, a.payload.mass);
  Eigen::MatrixXd c(n, n);
  double beyond = a.payload.mass;
  for (int k = n - 1; k >= 0; --k) {
    const auto& l = a.joint[static_cast<std::size_t>(k)].link;
    c(k, k) = l.inertia + l.mass * l.com * l.com + beyond * l.length * l.length + (k == n - 1 ? a.payload.inertia : 0.0);
    beyond += l.mass;
    for (int j = 0; j < k; ++j) c(j, k) = c(k, j) = a.joint[static_cast<std::size_t>(j)].link.length * h[k];
  }
  return c;
}

// Adds a rigid drive's rotor 1/2 J n^2 (phi_i' - phi_{i-1}')^2 to M.
void add_rigid_rotors(const TruthArm& a, Eigen::MatrixXd& M) {
  for (int i = 0; i < a.joints; ++i) {
    const auto& d = a.joint[static_cast<std::size_t>(i)].drive;
    if (d.compliant) continue;
    const double r = d.motor_inertia * d.ratio * d.ratio;
    M(i, i) += r;
    if (i > 0) {
      M(i - 1, i - 1) += r;
      M(i, i - 1) -= r;
      M(i - 1, i) -= r;
    }
  }
}

}  // namespace

Eigen::MatrixXd calc_truth_arm_mass_matrix(const TruthArm& a, const Eigen::VectorXd& phi) {
  const Eigen::MatrixXd c = link_coefficients(a);
  Eigen::MatrixXd M(a.joints, a.joints);
  for (int j = 0; j < a.joints; ++j)
    for (int k = 0; k < a.joints; ++k) M(j, k) = c(j, k) * std::cos(phi[j] - phi[k]);
  add_rigid_rotors(a, M);
  return M;
}

// dV/dq_i = sum_{k >= i} g h_k cos(phi_k) (phi_k depends on q_i for every k >= i).
Eigen::VectorXd calc_truth_arm_gravity(const TruthArm& a, const Eigen::VectorXd& q, double payload_mass) {
  const Eigen::VectorXd h = first_moments(a, payload_mass), phi = absolute_angles(q);
  Eigen::VectorXd g(a.joints);
  double s = 0.0;
  for (int i = a.joints - 1; i >= 0; --i) g[i] = (s += a.gravity * h[i] * std::cos(phi[i]));
  return g;
}

double calc_truth_arm_potential(const TruthArm& a, const Eigen::VectorXd& q) {
  const Eigen::VectorXd h = first_moments(a, a.payload.mass), phi = absolute_angles(q);
  double v = 0.0;
  for (int k = 0; k < a.joints; ++k) v += a.gravity * h[k] * std::sin(phi[k]);
  return v;
}

// ---------------------------------------------------------------------------------------------
// Joint laws.

namespace {

// The multi-slope mesh: torque and stored energy at a tooth penetration x >= 0 (README.md).
void eval_mesh_spring(const TruthArmJoint::Drive& d, double x, double& torque, double& energy) {
  const double e1 = d.knee > 0 ? d.knee : std::numeric_limits<double>::infinity();
  const double e2 = d.knee2 > 0 ? d.knee2 : std::numeric_limits<double>::infinity();
  const double x1 = std::min(x, e1), x2 = std::clamp(x - e1, 0.0, e2 - e1), x3 = std::max(x - e2, 0.0);
  const double t1 = d.stiffness * std::min(x, e1), t2 = t1 + d.stiffness2 * x2;
  torque = t2 + d.stiffness3 * x3;
  energy = 0.5 * d.stiffness * x1 * x1 + (x2 > 0 ? x2 * (t1 + 0.5 * d.stiffness2 * x2) : 0.0) +
           (x3 > 0 ? x3 * (t2 + 0.5 * d.stiffness3 * x3) : 0.0);
}

// The mesh torque on the link at twist d and its rate: without backlash k(d) + c d'; with a gap 2b the
// teeth touch past |d| = b and the damper is one-sided: it acts only in contact and only while the teeth
// close (penetration rate x' = d' sign(d) > 0), so the teeth never pull.
double eval_mesh(const TruthArmJoint::Drive& dr, double d, double dd, double* energy = nullptr) {
  const double b = dr.backlash / 2.0, s = d < 0 ? -1.0 : 1.0;
  const double x = std::abs(d) - b;
  double spring = 0.0, e = 0.0;
  if (x > 0) eval_mesh_spring(dr, x, spring, e);
  if (energy) *energy = e;
  if (b == 0.0) return s * spring + dr.damping * dd;
  if (x <= 0) return 0.0;
  return s * (spring + dr.damping * std::max(dd * s, 0.0));
}

// p(x): the position-dependent friction level.
double friction_level(const TruthArmJoint::Friction& f, double x) {
  return 1.0 + f.position_amplitude * std::sin(2.0 * M_PI * x / f.position_period + f.position_phase);
}

// g(v) of Stribeck: p(x) (Fc + (Fs - Fc) exp(-|v/vs|^delta)), N m.
double stribeck_level(const TruthArmJoint::Friction& f, double v, double x) {
  const double fs = f.stiction > 0 ? f.stiction : f.coulomb;
  return friction_level(f, x) * (f.coulomb + (fs - f.coulomb) * std::exp(-std::pow(std::abs(v / f.stribeck_velocity), f.stribeck_exponent)));
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The plant: y = [phi (n), phi' (n), per compliant joint theta, theta', per LuGre joint z].

namespace {

class Plant {
 public:
  explicit Plant(const TruthArm& a) : a_(a), n_(a.joints), coef_(link_coefficients(a)), h_(first_moments(a, a.payload.mass)) {
    int next = 2 * n_;
    motor_.assign(static_cast<std::size_t>(n_), -1);
    bristle_.assign(static_cast<std::size_t>(n_), -1);
    for (int i = 0; i < n_; ++i)
      if (joint(i).drive.compliant) motor_[static_cast<std::size_t>(i)] = (next += 2) - 2;
    for (int i = 0; i < n_; ++i)
      if (joint(i).friction.lugre) bristle_[static_cast<std::size_t>(i)] = next++;
    size_ = next;
    tau_ = Eigen::VectorXd::Zero(n_);
    M_.resize(n_, n_);
    rhs_.resize(n_);
  }
  int size() const { return size_; }
  int joints() const { return n_; }
  const TruthArmJoint& joint(int i) const { return a_.joint[static_cast<std::size_t>(i)]; }
  int motor(int i) const { return motor_[static_cast<std::size_t>(i)]; }
  void hold(const Eigen::VectorXd& tau) { tau_ = tau; }

  // Joint angles and rates (link side) from the state.
  void joints_of(const double* y, Eigen::VectorXd& q, Eigen::VectorXd& qd) const {
    q.resize(n_), qd.resize(n_);
    for (int i = 0; i < n_; ++i) {
      q[i] = y[i] - (i > 0 ? y[i - 1] : 0.0);
      qd[i] = y[n_ + i] - (i > 0 ? y[n_ + i - 1] : 0.0);
    }
  }
  // Where the motor's side is (joint units): the motor's own state, or the joint with a rigid drive.
  double motor_angle(const double* y, int i, const Eigen::VectorXd& q) const { return motor(i) < 0 ? q[i] : y[motor(i)]; }
  double motor_rate(const double* y, int i, const Eigen::VectorXd& qd) const { return motor(i) < 0 ? qd[i] : y[motor(i) + 1]; }

  // The friction torque on the motor side (opposing), and the LuGre state's rate into zdot.
  double friction(const double* y, int i, double x, double v, double* zdot) const {
    const auto& f = joint(i).friction;
    if (f.lugre) {
      const double z = y[bristle_[static_cast<std::size_t>(i)]];
      const double dz = v - f.bristle_stiffness * std::abs(v) * z / stribeck_level(f, v, x);
      *zdot = dz;
      return -(f.bristle_stiffness * z + f.bristle_damping * dz + f.viscous * v);
    }
    if (f.coulomb == 0.0 && f.stiction == 0.0) return -f.viscous * v;
    return -(f.viscous * v + stribeck_level(f, v, x) * (2.0 / M_PI) * std::atan(v / f.smoothing));
  }

  bool rhs(const double* y, double* yd) {
    Eigen::VectorXd q, qd;
    joints_of(y, q, qd);
    // Torques on the joints (relative coordinates): drive, friction and offset on a rigid drive's joint,
    // the mesh on a compliant one's link; the motors' own equations alongside.
    Eigen::VectorXd tj(n_);
    for (int i = 0; i < n_; ++i) {
      const TruthArmJoint& j = joint(i);
      double zdot = 0.0;
      const double x = motor_angle(y, i, q), v = motor_rate(y, i, qd);
      const double motor_side = tau_[i] - j.torque_offset + friction(y, i, x, v, &zdot);
      if (bristle_[static_cast<std::size_t>(i)] >= 0) yd[bristle_[static_cast<std::size_t>(i)]] = zdot;
      if (motor(i) < 0) {
        tj[i] = motor_side;
      } else {
        const double mesh = eval_mesh(j.drive, x - q[i], v - qd[i]);
        tj[i] = mesh;
        yd[motor(i)] = v;
        yd[motor(i) + 1] = (motor_side - mesh) / (j.drive.motor_inertia * j.drive.ratio * j.drive.ratio);
      }
    }
    // M(phi) phi'' = Q - c(phi, phi'): Q_i = t_i - t_{i+1} - g h_i cos(phi_i), c_j = sum_k a_jk sin(phi_j - phi_k) phi_k'^2.
    for (int j = 0; j < n_; ++j) {
      double c = 0.0;
      for (int k = 0; k < n_; ++k) {
        M_(j, k) = coef_(j, k) * std::cos(y[j] - y[k]);
        c += coef_(j, k) * std::sin(y[j] - y[k]) * y[n_ + k] * y[n_ + k];
      }
      rhs_[j] = tj[j] - (j + 1 < n_ ? tj[j + 1] : 0.0) - a_.gravity * h_[j] * std::cos(y[j]) - c;
    }
    add_rigid_rotors(a_, M_);
    ldlt_.compute(M_);
    const Eigen::VectorXd acc = ldlt_.solve(rhs_);
    for (int j = 0; j < n_; ++j) {
      yd[j] = y[n_ + j];
      yd[n_ + j] = acc[j];
    }
    for (int i = 0; i < size_; ++i)
      if (!std::isfinite(yd[i])) return false;
    return true;
  }

  // Kinetic + potential + the meshes' elastic energy, J.
  double energy(const double* y) const {
    Eigen::VectorXd q, qd;
    joints_of(y, q, qd);
    Eigen::Map<const Eigen::VectorXd> phi(y, n_), w(y + n_, n_);
    double e = 0.5 * w.dot(calc_truth_arm_mass_matrix(a_, phi) * w) + calc_truth_arm_potential(a_, q);
    for (int i = 0; i < n_; ++i) {
      if (motor(i) < 0) continue;
      const auto& d = joint(i).drive;
      double el = 0.0;
      eval_mesh(d, y[motor(i)] - q[i], 0.0, &el);
      e += el + 0.5 * d.motor_inertia * d.ratio * d.ratio * y[motor(i) + 1] * y[motor(i) + 1];
    }
    return e;
  }

  // At rest at the joint angles q0: a compliant drive's motor held at q0 (the controller's target) and
  // its link sagged by the twist that carries the true gravity torque (fixed-point iteration).
  std::vector<double> initial_state(const Eigen::VectorXd& q0) const {
    std::vector<double> y(static_cast<std::size_t>(size_), 0.0);
    Eigen::VectorXd q = q0;
    for (int it = 0; it < 50; ++it) {
      const Eigen::VectorXd g = calc_truth_arm_gravity(a_, q, a_.payload.mass);
      for (int i = 0; i < n_; ++i)
        if (motor(i) >= 0) q[i] = q0[i] - invert_mesh(joint(i).drive, g[i]);
    }
    const Eigen::VectorXd phi = absolute_angles(q);
    for (int i = 0; i < n_; ++i) {
      y[static_cast<std::size_t>(i)] = phi[i];
      if (motor(i) >= 0) y[static_cast<std::size_t>(motor(i))] = q0[i];
    }
    return y;
  }

 private:
  // The twist whose static mesh torque is tau (bisection).
  static double invert_mesh(const TruthArmJoint::Drive& d, double tau) {
    if (tau == 0.0) return 0.0;
    double lo = 0.0, hi = d.backlash + 1e-6;
    while (eval_mesh(d, hi, 0.0) < std::abs(tau) && hi < 10.0) hi *= 2.0;
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (lo + hi);
      (eval_mesh(d, mid, 0.0) < std::abs(tau) ? lo : hi) = mid;
    }
    return std::copysign(0.5 * (lo + hi), tau);
  }

  const TruthArm& a_;
  int n_, size_ = 0;
  Eigen::MatrixXd coef_;
  Eigen::VectorXd h_;
  std::vector<int> motor_, bristle_;
  Eigen::VectorXd tau_;
  Eigen::MatrixXd M_;
  Eigen::VectorXd rhs_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
};

// ---------------------------------------------------------------------------------------------
// CVODE (BDF, Newton with the dense direct solver, finite-difference Jacobian), as truth_sim.cpp's.

class Cvode {
 public:
  Cvode(Plant& plant, const TruthArm::Solver& s) : plant_(plant), n_(plant.size()) {
    if (SUNContext_Create(nullptr, &ctx_) != 0) throw std::runtime_error("truth_arm: SUNContext_Create failed");
    y_ = N_VNew_Serial(n_, ctx_);
    mem_ = CVodeCreate(CV_BDF, ctx_);
    A_ = SUNDenseMatrix(n_, n_, ctx_);
    ls_ = SUNLinSol_Dense(y_, A_, ctx_);
    if (!y_ || !mem_ || !A_ || !ls_) throw std::runtime_error("truth_arm: CVODE could not allocate");
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
  void restart(double t) { check(CVodeReInit(mem_, t, y_), "CVodeReInit"); }
  void advance(double t_next) {
    check(CVodeSetStopTime(mem_, t_next), "CVodeSetStopTime");
    double t_reached = 0.0;
    const int flag = CVode(mem_, t_next, y_, &t_reached, CV_NORMAL);
    if (flag < 0) {
      char buf[512];
      char* name = CVodeGetReturnFlagName(flag);
      std::snprintf(buf, sizeof buf, "truth_arm: CVODE failed before t = %.6f s (%s)%s%s", t_next, name,
                    message_.empty() ? "" : ": ", message_.c_str());
      std::free(name);
      throw std::runtime_error(buf);
    }
  }
  long steps() const {
    long s = 0;
    CVodeGetNumSteps(mem_, &s);
    return s;
  }

 private:
  static int f(double, N_Vector y, N_Vector ydot, void* user) {
    return static_cast<Plant*>(user)->rhs(N_VGetArrayPointer(y), N_VGetArrayPointer(ydot)) ? 0 : 1;
  }
  static void on_error(int code, const char*, const char* function, char* msg, void* self) {
    if (code < 0) static_cast<Cvode*>(self)->message_ = std::string(function) + ": " + msg;
  }
  void check(int flag, const char* what) {
    if (flag < 0) throw std::runtime_error(std::string("truth_arm: ") + what + " failed: " + message_);
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

// A sensor channel with its own noise stream: readings at every sample, read back `delay` samples late.
class Channel {
 public:
  Channel(double noise, int delay, std::uint64_t seed, unsigned id) : noise_(noise), delay_(delay) {
    std::seed_seq s{static_cast<unsigned>(seed & 0xffffffffu), static_cast<unsigned>(seed >> 32), id};
    rng_.seed(s);
  }
  void read(double x, double quantum = 0.0) {
    if (noise_ > 0) x += noise_ * normal_(rng_);
    if (quantum > 0) x = quantum * std::nearbyint(x / quantum);
    readings_.push_back(x);
  }
  double delayed(std::size_t k) const {
    const std::size_t d = static_cast<std::size_t>(delay_);
    return readings_[k >= d ? k - d : 0];
  }

 private:
  double noise_;
  int delay_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_;
  std::vector<double> readings_;
};

// The quintic reference of every joint at t (rest to rest between waypoints, held after the last).
Eigen::VectorXd eval_reference(const TruthArm& a, double t) {
  Eigen::VectorXd r = Eigen::VectorXd::Zero(a.joints);
  for (std::size_t i = 0; i < a.trajectory.start.size(); ++i) r[static_cast<int>(i)] = a.trajectory.start[i];
  double t0 = 0.0;
  for (const auto& w : a.trajectory.waypoints) {
    const double u = std::clamp((t - t0) / w.time, 0.0, 1.0);
    const double s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
    for (int i = 0; i < a.joints; ++i) r[i] += s * (w.q[static_cast<std::size_t>(i)] - r[i]);
    t0 += w.time;
    if (t < t0) break;
  }
  return r;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The run.

std::vector<std::string> truth_arm_record_columns(const TruthArm& a) {
  std::vector<std::string> cols;
  for (int i = 0; i < a.joints; ++i)
    for (const char* s : {".ref", ".angle", ".rate", ".torque"}) cols.push_back(truth_arm_joint_name(i) + s);
  return cols;
}

TruthArmRun run_truth_arm(const TruthArm& a) {
  validate(a);
  double duration = a.duration;
  if (duration == 0.0) {
    for (const auto& w : a.trajectory.waypoints) duration += w.time;
    duration += a.trajectory.settle;
  }
  require(duration > 0, "duration", "> 0 (or waypoints to take it from)", duration);
  const double T = 1.0 / a.controller.rate;
  const long last = std::lround(duration / T);
  const int n = a.joints;
  const double nominal_payload = a.controller.payload_mass >= 0 ? a.controller.payload_mass : a.payload.mass;

  Plant plant(a);
  Cvode cvode(plant, a.solver);
  double* y = cvode.state();
  const std::vector<double> y0 = plant.initial_state(eval_reference(a, 0.0));
  std::copy(y0.begin(), y0.end(), y);
  cvode.restart(0.0);

  std::vector<Channel> angle, rate, torque;
  for (int i = 0; i < n; ++i) {
    const auto& s = a.joint[static_cast<std::size_t>(i)].sensors;
    angle.emplace_back(s.angle.noise, s.angle.delay, a.seed, static_cast<unsigned>(3 * i));
    rate.emplace_back(s.rate.noise, s.rate.delay, a.seed, static_cast<unsigned>(3 * i + 1));
    torque.emplace_back(s.torque_noise, 0, a.seed, static_cast<unsigned>(3 * i + 2));
  }
  TruthArmRun run;
  Record& rec = run.record;
  rec.source = "<truth arm>";
  const std::vector<std::string> cols = truth_arm_record_columns(a);
  for (const auto& c : cols) rec.columns[c].reserve(static_cast<std::size_t>(last + 1));
  Eigen::VectorXd integral = Eigen::VectorXd::Zero(n), tau = Eigen::VectorXd::Zero(n), q, qd;
  TruthArmTrace& tr = run.trace;
  for (long k = 0; k <= last; ++k) {
    const double t = static_cast<double>(k) * T;
    const std::size_t ks = static_cast<std::size_t>(k);
    plant.joints_of(y, q, qd);
    Eigen::VectorXd motor(n);
    for (int i = 0; i < n; ++i) motor[i] = plant.motor_angle(y, i, q);
    // 1. the sensors read the plant: the sensed side's angle (noise, then the encoder's quantum), its rate.
    for (int i = 0; i < n; ++i) {
      const TruthArmJoint& j = a.joint[static_cast<std::size_t>(i)];
      const bool link = j.controller.link_side;
      const int bits = j.sensors.angle.encoder_bits;
      angle[static_cast<std::size_t>(i)].read(link ? q[i] : motor[i], bits > 0 ? 2.0 * M_PI / std::ldexp(1.0, bits) : 0.0);
      rate[static_cast<std::size_t>(i)].read(link ? qd[i] : plant.motor_rate(y, i, qd));
    }
    // 2. the controller: PD(+I) on what it read (late), the nominal model's gravity torque at r.
    const Eigen::VectorXd r = eval_reference(a, t);
    const Eigen::VectorXd g = calc_truth_arm_gravity(a, r, nominal_payload);
    for (int i = 0; i < n; ++i) {
      const auto& c = a.joint[static_cast<std::size_t>(i)].controller;
      const double yq = angle[static_cast<std::size_t>(i)].delayed(ks), yw = rate[static_cast<std::size_t>(i)].delayed(ks);
      const double err = r[i] - yq;
      const double u = c.kp * err + c.ki * integral[i] - c.kd * yw + c.gravity_compensation * g[i];
      const bool sat = c.torque_limit > 0 && std::abs(u) > c.torque_limit;
      tau[i] = sat ? std::copysign(c.torque_limit, u) : u;
      if (!(sat && err * u > 0)) integral[i] += T * err;
      torque[static_cast<std::size_t>(i)].read(tau[i]);
      // 3. the logger: what the controller read, the torque command with the torque sensor's noise.
      const std::string name = truth_arm_joint_name(i);
      rec.columns[name + ".ref"].push_back(r[i]);
      rec.columns[name + ".angle"].push_back(yq);
      rec.columns[name + ".rate"].push_back(yw);
      rec.columns[name + ".torque"].push_back(torque[static_cast<std::size_t>(i)].delayed(ks));
    }
    rec.t.push_back(t);
    tr.t.push_back(t);
    tr.q.push_back(q);
    tr.qd.push_back(qd);
    tr.motor.push_back(motor);
    tr.tau.push_back(tau);
    tr.energy.push_back(plant.energy(y));
    if (k == last) break;
    // 4. CVODE to the next sample with the torque held (restarted: the right-hand side jumped).
    plant.hold(tau);
    cvode.restart(t);
    cvode.advance(static_cast<double>(k + 1) * T);
    run.steps += cvode.steps();
  }
  return run;
}

}  // namespace ff::truth
