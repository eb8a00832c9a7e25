#include "kernel/drive.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>

#include "kernel/dynamics.hpp"
#include "kernel/friction.hpp"

namespace ff {

DriveLayout make_drive_layout(const ModelSpec& spec) {
  DriveLayout d;
  if (spec.hydraulics.enabled) {
    d.spool = d.nz;
    d.pressure = d.nz + 2;
    d.nz += 4;
  }
  if (spec.drive.enabled) {
    d.shaft = d.nz;
    d.nz += 2;
  }
  if (spec.friction.model == "lugre") d.bristle = d.nz++;
  return d;
}

LaneDrive make_hydraulic_drive(const HydraulicSpec& h) {
  LaneDrive p;
  p.D = calc_displacement(h);
  p.V0 = h.chamber_volume;
  p.beta = h.bulk_modulus;
  p.ps = h.supply_pressure;
  p.pt = h.tank_pressure;
  p.pr = h.relief_pressure > 0 ? h.relief_pressure : 1.1 * h.supply_pressure;
  p.dp_lam = h.laminar_drop;
  p.kv = calc_valve_coefficient(h);  // Q = kv x root(dp)
  // Relief valves pass the rated flow 10 % above their cracking pressure.
  p.kr = calc_rated_flow(h) / (0.1 * p.pr);
  p.leak = h.leakage;
  p.wv = 2.0 * M_PI * h.valve_frequency;
  p.zv = h.valve_damping;
  p.gain = h.pressure_gain;
  return p;
}

LaneDrive make_lane_drive(const Model& m) {
  const auto& h = m.spec.hydraulics;
  const auto& d = m.spec.drive;
  const auto& f = m.spec.friction;
  LaneDrive p = h.enabled ? make_hydraulic_drive(h) : LaneDrive{};
  p.lugre = f.model == "lugre";
  p.sigma0 = f.bristle_stiffness;
  p.sigma1 = f.bristle_damping;
  if (d.enabled) {
    p.ja = d.inertia;
    p.n = d.ratio;
    p.eta = d.efficiency;
    p.k = d.stiffness;
    p.k3 = d.cubic_stiffness;
    p.c = d.damping;
    p.b = 0.5 * d.backlash;
    p.closing = d.closing_damping;
  }
  return p;
}

double calc_orifice_root(double dp, double dp_lam) { return dp / std::sqrt(std::sqrt(dp * dp + dp_lam * dp_lam)); }

double calc_valve_coefficient(const HydraulicSpec& h) {
  if (h.discharge_coefficient > 0)  // Q = C_d w x_max x sqrt(2 dp / rho)
    return h.discharge_coefficient * h.port_width * h.spool_stroke * std::sqrt(2.0 / h.oil_density);
  return h.rated_flow / calc_orifice_root(h.rated_drop, h.laminar_drop);  // the rated flow at full opening
}

double calc_rated_flow(const HydraulicSpec& h) {
  if (h.discharge_coefficient > 0) return calc_valve_coefficient(h) * calc_orifice_root(h.rated_drop, h.laminar_drop);
  return h.rated_flow;
}

double calc_displacement(const HydraulicSpec& h) {
  return h.piston_area > 0 ? h.piston_area * h.pinion_radius : h.displacement;
}

// The mesh's damping coefficient at twist e and rate de: c, or with closing damping c only while |e| grows.
static double mesh_damping(const LaneDrive& p, double e, double de) { return p.closing && e * de <= 0.0 ? 0.0 : p.c; }

double calc_transmission_torque(const LaneDrive& p, double d, double dd) {
  if (p.b == 0.0) return (p.k + p.k3 * d * d) * d + mesh_damping(p, d, dd) * dd;
  // Free play: no torque inside +-b; in contact the gear teeth push, never pull.
  const double e = d > p.b ? d - p.b : (d < -p.b ? d + p.b : 0.0);
  if (e == 0.0) return 0.0;
  const double t = (p.k + p.k3 * e * e) * e + mesh_damping(p, e, dd) * dd;
  return e > 0.0 ? std::max(t, 0.0) : std::min(t, 0.0);
}

TransmissionTangent calc_transmission_tangent(const LaneDrive& p, double d, double dd) {
  const double e = p.b == 0.0 ? d : (d > p.b ? d - p.b : (d < -p.b ? d + p.b : 0.0));
  if (p.b != 0.0 && (e == 0.0 || calc_transmission_torque(p, d, dd) == 0.0)) return {};
  return {p.k + 3.0 * p.k3 * e * e, mesh_damping(p, e, dd)};
}

double calc_efficiency_factor(double eta, double power) {
  const double driving = 0.5 * (1.0 + std::tanh(power));
  return driving / eta + (1.0 - driving) * eta;
}

double calc_hydraulic_damping(const HydraulicSpec& h) {
  const double kq =
      calc_valve_coefficient(h) * calc_orifice_root(0.5 * (h.supply_pressure - h.tank_pressure), h.laminar_drop);
  const double D = calc_displacement(h);
  return D * D * h.supply_pressure / (h.pressure_gain * kq);
}

double calc_hydraulic_frequency(const HydraulicSpec& h, double inertia) {
  const double D = calc_displacement(h);
  return std::sqrt(4.0 * h.bulk_modulus * D * D / (2.0 * h.chamber_volume * inertia));
}

double calc_hydraulic_rate(const LaneDrive& p, double inertia) {
  const double spring = std::sqrt(2.0 * p.beta * p.D * p.D / (p.V0 * inertia));  // oil spring on the pinion
  const double kq = p.kv * std::sqrt(0.5 * p.ps);                                // flow gain at full supply, m^3/s
  return std::max({spring, p.wv, 2.0 * p.beta * kq * p.gain / (p.V0 * p.ps), p.beta * p.kr / p.V0});
}

double calc_drive_rate(const Model& m) {
  const LaneDrive p = make_lane_drive(m);
  const DriveLayout L = make_drive_layout(m.spec);
  const double j0 = m.body[0].inertia;  // the hub's own inertia: what a stiff drive shakes first
  double coupled = 0.0, own = 0.0;
  if (L.pressure >= 0) own = calc_hydraulic_rate(p, L.shaft >= 0 ? p.ja : j0);
  if (L.shaft >= 0) {
    const double inv = 1.0 / (p.ja * p.n * p.n) + 1.0 / j0;  // shaft reflected to the output, and the hub
    coupled = std::max({coupled, std::sqrt(p.k * inv), p.c * inv});
  }
  // The static friction map's slope at rest, (F_s or F_c) / eps, on the hub's own inertia: a real
  // eigenvalue, which RK4 keeps stable up to h rate = 2.78 (allowed 2.5). SDIRK and the midpoint rule
  // take the map linearly implicit (kernel/fixed_step.cpp): SDIRK follows CVODE at one substep
  // whatever the slope; the midpoint rule does at h rate <= 250 (measured on the rig, with eps down
  // to 1e-5 rad/s: tests/kernel/friction_test.cpp).
  const auto& f = m.spec.friction;
  const Integrator integ = m.spec.simulation.integrator;
  const double slope = std::max(f.coulomb, f.stiction) / (f.smoothing * j0);
  if (L.bristle < 0 && integ == Integrator::kRk4) own = std::max(own, slope / 2.5);
  if (L.bristle < 0 && integ == Integrator::kMidpoint) own = std::max(own, slope / 250.0);
  if (L.bristle >= 0) {
    coupled = std::max({coupled, std::sqrt(p.sigma0 / j0), p.sigma1 / j0});
    own = std::max(own, p.sigma0 / m.spec.friction.coulomb);  // bristle relaxation at 1 rad/s
  }
  return std::max(coupled, own);
}

double eval_hydraulic_actuator(const LaneDrive& p, double demand, double theta, double omega, const double* x,
                               std::size_t stride, double* xdot) {
  const double pa = x[2 * stride] * kPressureUnit, pb = x[3 * stride] * kPressureUnit;
  const double tau_p = p.D * (pa - pb);
  if (!xdot) return tau_p;
  // Servo valve: second-order spool driven by the torque loop's command, travel limited to +-1.
  const double u = std::clamp(p.gain * (demand - tau_p) / (p.D * p.ps), -1.0, 1.0);
  const double xv = x[0], xvd = x[stride];
  xdot[0] = xvd;
  xdot[stride] = p.wv * p.wv * (u - xv) - 2.0 * p.zv * p.wv * xvd;
  // Orifice flows of the four lands (critically lapped), Q = kv x root(dp), m^3/s.
  const double xs = std::clamp(xv, -1.0, 1.0), xp = std::max(xs, 0.0), xm = std::max(-xs, 0.0);
  const double qa = p.kv * (xp * calc_orifice_root(p.ps - pa, p.dp_lam) - xm * calc_orifice_root(pa - p.pt, p.dp_lam));
  const double qb = p.kv * (xm * calc_orifice_root(p.ps - pb, p.dp_lam) - xp * calc_orifice_root(pb - p.pt, p.dp_lam));
  const double ql = p.leak * (pa - pb);  // cross-port leakage a -> b
  // Relief to tank above p_r, anti-cavitation from tank below p_t.
  const double ra = p.kr * (std::max(p.pt - pa, 0.0) - std::max(pa - p.pr, 0.0));
  const double rb = p.kr * (std::max(p.pt - pb, 0.0) - std::max(pb - p.pr, 0.0));
  // Chamber continuity with compressibility: dp/dt = beta / V (Q_in - dV/dt), V = V0 +- D theta.
  const double va = std::max(p.V0 + p.D * theta, 0.05 * p.V0), vb = std::max(p.V0 - p.D * theta, 0.05 * p.V0);
  xdot[2 * stride] = p.beta / va * (qa - ql + ra - p.D * omega) / kPressureUnit;
  xdot[3 * stride] = p.beta / vb * (qb + ql + rb + p.D * omega) / kPressureUnit;
  return tau_p;
}

void solve_small_system(int n, double* A, double* b) {
  for (int c = 0; c < n; ++c) {
    int piv = c;
    for (int r = c + 1; r < n; ++r)
      if (std::abs(A[r * n + c]) > std::abs(A[piv * n + c])) piv = r;
    if (piv != c) {
      for (int k = 0; k < n; ++k) std::swap(A[c * n + k], A[piv * n + k]);
      std::swap(b[c], b[piv]);
    }
    const double d = A[c * n + c];
    for (int r = c + 1; r < n; ++r) {
      const double f = A[r * n + c] / d;
      for (int k = c; k < n; ++k) A[r * n + k] -= f * A[c * n + k];
      b[r] -= f * b[c];
    }
  }
  for (int r = n - 1; r >= 0; --r) {
    double x = b[r];
    for (int k = r + 1; k < n; ++k) x -= A[r * n + k] * b[k];
    b[r] = x / A[r * n + r];
  }
}

void calc_hydraulic_jacobian(const LaneDrive& p, double demand, double theta, double omega, const double* x,
                             double* f0, double* jac) {
  constexpr int n = kHydraulicStates;
  static const double srur = std::sqrt(std::numeric_limits<double>::epsilon());
  double xp[n], fp[n];
  eval_hydraulic_actuator(p, demand, theta, omega, x, 1, f0);
  std::copy(x, x + n, xp);
  for (int j = 0; j < n; ++j) {
    const double delta = (x[j] + srur * std::max(std::abs(x[j]), 1.0)) - x[j];
    xp[j] = x[j] + delta;
    eval_hydraulic_actuator(p, demand, theta, omega, xp, 1, fp);
    xp[j] = x[j];
    for (int i = 0; i < n; ++i) jac[i * n + j] = (fp[i] - f0[i]) / delta;
  }
}

void solve_hydraulic_stage(const LaneDrive& p, double demand, double theta, double omega, const double* xpre,
                           double gh, double* X) {
  constexpr int n = kHydraulicStates;
  double f[n], jac[n * n], A[n * n], r[n];
  calc_hydraulic_jacobian(p, demand, theta, omega, xpre, f, jac);
  std::copy(xpre, xpre + n, X);
  for (int it = 0; it < 4; ++it) {
    if (it > 0) eval_hydraulic_actuator(p, demand, theta, omega, X, 1, f);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) A[i * n + j] = (i == j ? 1.0 : 0.0) - gh * jac[i * n + j];
      r[i] = -(X[i] - xpre[i] - gh * f[i]);
    }
    solve_small_system(n, A, r);
    for (int i = 0; i < n; ++i) X[i] += r[i];
  }
}

std::pair<std::string, std::string> explain_hydraulic_fault(const HydraulicSpec& h) {
  using Fault = std::pair<std::string, std::string>;
  const auto positive = [](double x) { return x > 0 && std::isfinite(x); };
  const auto non_negative = [](double x) { return x >= 0 && std::isfinite(x); };
  const auto need = [](const char* key, const char* what, double x) {
    return Fault{key, std::string("must be a finite number ") + what + ", got " + std::to_string(x)};
  };
  const std::pair<const char*, double> pos1[] = {{"displacement", h.displacement},
                                                 {"chamber_volume", h.chamber_volume},
                                                 {"bulk_modulus", h.bulk_modulus},
                                                 {"supply_pressure", h.supply_pressure}};
  for (const auto& [key, x] : pos1)
    if (!positive(x)) return need(key, "> 0", x);
  if (!non_negative(h.tank_pressure)) return need("tank_pressure", ">= 0", h.tank_pressure);
  if (!(h.tank_pressure < h.supply_pressure)) return {"tank_pressure", "must be below hydraulics.supply_pressure"};
  if (!non_negative(h.relief_pressure)) return need("relief_pressure", ">= 0", h.relief_pressure);
  if (h.relief_pressure > 0 && !(h.relief_pressure > h.tank_pressure))
    return {"relief_pressure", "must be above hydraulics.tank_pressure (or 0 for 1.1 p_s)"};
  const std::pair<const char*, double> pos2[] = {
      {"rated_flow", h.rated_flow}, {"rated_drop", h.rated_drop}, {"laminar_drop", h.laminar_drop}};
  for (const auto& [key, x] : pos2)
    if (!positive(x)) return need(key, "> 0", x);
  if (!non_negative(h.leakage)) return need("leakage", ">= 0", h.leakage);
  if (!positive(h.valve_frequency)) return need("valve_frequency", "> 0", h.valve_frequency);
  if (!positive(h.valve_damping)) return need("valve_damping", "> 0", h.valve_damping);
  if (!non_negative(h.pressure_gain)) return need("pressure_gain", ">= 0", h.pressure_gain);
  // The physical forms of k_v and D (0 = not given): all of a group or none, named at the first given.
  const auto whole = [&](std::initializer_list<std::pair<double, const char*>> group, const char* law) -> Fault {
    const char* given = nullptr;
    std::string missing;
    for (const auto& [x, key] : group) {
      if (!non_negative(x)) return need(key, ">= 0", x);
      if (x > 0 && !given) given = key;
      if (x == 0) missing += std::string(missing.empty() ? "" : ", ") + "hydraulics." + key;
    }
    if (given && !missing.empty()) return {given, "needs " + missing + " too (" + law + ": all of them or none)"};
    return {};
  };
  if (Fault f = whole({{h.discharge_coefficient, "discharge_coefficient"},
                       {h.port_width, "port_width"},
                       {h.spool_stroke, "spool_stroke"},
                       {h.oil_density, "oil_density"}},
                      "k_v = C_d w x_max sqrt(2 / rho)");
      !f.first.empty())
    return f;
  return whole({{h.piston_area, "piston_area"}, {h.pinion_radius, "pinion_radius"}}, "D = A r");
}

void init_drive_state(const BatchModel& bm, double* z) {
  const int W = bm.W;
  const DriveLayout& L = bm.layout;
  std::fill(z, z + static_cast<std::size_t>(L.nz) * W, 0.0);
  if (L.pressure >= 0)
    for (int l = 0; l < W; ++l) {
      const LaneDrive& p = bm.drive[l];
      z[L.pressure * W + l] = z[(L.pressure + 1) * W + l] = 0.5 * (p.ps + p.pt) / kPressureUnit;
    }
}

namespace {

// One lane of compute_hub_drive / compute_actuator_torque. Writes zdot only when given.
double lane_drive(const BatchModel& bm, int l, const double* q, const double* v, const double* z, double tau_cmd,
                  double* zdot, double* tau_act) {
  const int W = bm.W;
  const DriveLayout& L = bm.layout;
  const LaneDrive& p = bm.drive[l];
  auto Z = [&](int row) { return z[row * W + l]; };
  auto set = [&](int row, double x) {
    if (zdot) zdot[row * W + l] = x;
  };
  const double th_h = q[l], w_h = v[l];
  // The pinion (or motor rotor) turns with the hub, or with the drive train's shaft.
  const double th_p = L.shaft >= 0 ? Z(L.shaft) : th_h;
  const double w_p = L.shaft >= 0 ? Z(L.shaft + 1) : w_h;
  const double demand = tau_cmd / p.n;  // at the shaft, N·m
  double tau_p = demand;                // what the actuator puts on its shaft, N·m

  if (L.pressure >= 0)  // the spool's rows, then the pressures' (make_drive_layout)
    tau_p = eval_hydraulic_actuator(p, demand, th_p, w_p, z + L.spool * W + l, static_cast<std::size_t>(W),
                                    zdot ? zdot + L.spool * W + l : nullptr);

  double tau_hub = tau_p;
  if (L.shaft >= 0) {
    // Gear n, free play and compliance between shaft and hub; efficiency loses power in either direction.
    const double ts = calc_transmission_torque(p, th_p / p.n - th_h, w_p / p.n - w_h);
    // P = tau_s w_p / n the power to the load.
    const double reaction = ts / p.n * calc_efficiency_factor(p.eta, ts * w_p / p.n);
    set(L.shaft, w_p);
    set(L.shaft + 1, (tau_p - reaction) / p.ja);
    tau_hub = ts;
  }
  if (tau_act) *tau_act = tau_hub;

  // Friction at the hub: the LuGre bristles or the static map.
  if (L.bristle >= 0) {
    const FrictionMap f = at_angle(bm.friction[l], th_h);
    const double zb = Z(L.bristle);
    const double zd = calc_lugre_bristle_rate(f, p.sigma0, w_h, zb);
    set(L.bristle, zd);
    tau_hub += calc_lugre_torque(f, p.sigma0, p.sigma1, w_h, zb, zd);
  } else {
    tau_hub += calc_hub_friction(bm, l, th_h, w_h);
  }
  return tau_hub - bm.hub_offset[l];  // the constant load torque (hub.torque_offset)
}

}  // namespace

void compute_hub_drive(const BatchModel& bm, const double* q, const double* v, const double* z, const double* tau_cmd,
                       double* tau_hub, double* zdot) {
  for (int l = 0; l < bm.W; ++l) tau_hub[l] = lane_drive(bm, l, q, v, z, tau_cmd[l], zdot, nullptr);
}

void compute_actuator_torque(const BatchModel& bm, const double* q, const double* v, const double* z,
                             const double* tau_cmd, double* tau_act) {
  for (int l = 0; l < bm.W; ++l) lane_drive(bm, l, q, v, z, tau_cmd[l], nullptr, &tau_act[l]);
}

}  // namespace ff
