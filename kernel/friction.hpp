// The static friction map of FrictionSpec (kernel/model.hpp) as a pure function of the rate, shared by
// the reference rig's hub (kernel/dynamics.cpp: calc_hub_friction, calc_hub_friction_damping) and the
// arm models' actuated joints (multibody/lanes.hpp: TreeLanes::friction):
//   tau_f(w) = -(b w + (Fc + (Fs - Fc) exp(-(w/vs)^2)) tanh(w/eps))
// (Armstrong-Helouvry 1994, tanh smoothing). Never adds energy: tau_f w <= 0. A worn or eccentric gear's
// friction level varies with the joint angle q: Fc and Fs times 1 + a cos(p q) + b sin(p q), p waves a
// revolution (at_angle below).
#pragma once

#include <algorithm>
#include <cmath>

#include "kernel/model.hpp"

namespace ff {

// The map's coefficients, as the evaluation uses them.
struct FrictionMap {
  double b = 0.0;        // viscous, N·m·s/rad (prismatic: N·s/m)
  double fc = 0.0;       // Coulomb level Fc, N·m (N)
  double fs = 0.0;       // the Stribeck excess Fs - Fc (0 when stiction is 0), N·m (N)
  double inv_vs = 0.0;   // 1 / stribeck_velocity
  double inv_eps = 0.0;  // 1 / smoothing
  double waves = 0.0;    // p, the friction level's waves a revolution (0: independent of the angle)
  double wave_cos = 0.0, wave_sin = 0.0;  // a, b: its relative amplitudes
};

inline FrictionMap make_friction_map(const FrictionSpec& f) {
  return {f.viscous,          f.coulomb,         f.stiction > 0 ? f.stiction - f.coulomb : 0.0,
          1.0 / f.stribeck_velocity, 1.0 / f.smoothing, f.position_waves, f.position_cos, f.position_sin};
}

// The map at joint angle q (rad, m): its levels Fc and Fs - Fc times 1 + a cos(p q) + b sin(p q).
inline FrictionMap at_angle(FrictionMap f, double q) {
  if (f.waves == 0.0) return f;
  const double m = 1.0 + f.wave_cos * std::cos(f.waves * q) + f.wave_sin * std::sin(f.waves * q);
  f.fc *= m;
  f.fs *= m;
  return f;
}

// True when the map is not identically zero.
inline bool is_friction_on(const FrictionMap& f) { return f.b != 0.0 || f.fc != 0.0 || f.fs != 0.0; }

// tau_f at rate w, N·m (N).
inline double calc_friction_torque(const FrictionMap& f, double w) {
  if (f.b == 0.0 && f.fc == 0.0 && f.fs == 0.0) return 0.0;
  const double x = w * f.inv_vs;
  return -(f.b * w + (f.fc + f.fs * std::exp(-x * x)) * std::tanh(w * f.inv_eps));
}

// The map's damping -d tau_f / dw at rate w, not below 0 (the Stribeck drop's negative slope left
// out): b + g'(w) tanh(w/eps) + g(w) sech^2(w/eps) / eps, g = Fc + (Fs - Fc) exp(-(w/vs)^2).
// What a linearly implicit stage adds to the joint's armature (times its coefficient gh).
inline double calc_friction_damping(const FrictionMap& f, double w) {
  if (f.fc == 0.0 && f.fs == 0.0) return std::max(f.b, 0.0);
  const double x = w * f.inv_vs, e = std::exp(-x * x), th = std::tanh(w * f.inv_eps);
  const double g = f.fc + f.fs * e, dg = -2.0 * x * f.inv_vs * f.fs * e;
  return std::max(0.0, f.b + dg * th + g * (1.0 - th * th) * f.inv_eps);
}

// The damping of the Coulomb and Stribeck part alone, d/dw of g(w) tanh(w/eps), not below 0: the
// map's damping less b (where the Stribeck drop does not clip it). 0 when Fc = Fs = 0.
inline double calc_coulomb_friction_damping(const FrictionMap& f, double w) {
  if (f.fc == 0.0 && f.fs == 0.0) return 0.0;
  const double x = w * f.inv_vs, e = std::exp(-x * x), th = std::tanh(w * f.inv_eps);
  const double g = f.fc + f.fs * e, dg = -2.0 * x * f.inv_vs * f.fs * e;
  return std::max(0.0, dg * th + g * (1.0 - th * th) * f.inv_eps);
}

// LuGre bristles (Canudas de Wit, Olsson, Astrom & Lischinsky, IEEE TAC 40, 1995) on the map's
// coefficients (b, Fc, Fs - Fc, vs; the tanh smoothing unused): with g(w) = Fc + (Fs - Fc) exp(-(w/vs)^2),
//   dz/dt = w - sigma0 |w| z / g(w),   tau_f = -(sigma0 z + sigma1 dz/dt + b w).
// Needs Fc > 0. The reference rig's hub (kernel/drive.cpp) and the arm joints (multibody/lanes.hpp)
// call these two.
inline double calc_lugre_bristle_rate(const FrictionMap& f, double sigma0, double w, double z) {
  const double x = w * f.inv_vs;
  const double g = f.fc + f.fs * std::exp(-x * x);
  return w - sigma0 * std::abs(w) * z / g;
}
// An implicit stage of the bristles at a held rate w: z = zpre + gh dz/dt(w, z), linear in z, so
// z = (zpre + gh w) / (1 + gh sigma0 |w| / g(w)) exactly (0 < the denominator's inverse <= 1: stable
// at any gh).
inline double solve_lugre_stage(const FrictionMap& f, double sigma0, double w, double zpre, double gh) {
  const double x = w * f.inv_vs;
  const double g = f.fc + f.fs * std::exp(-x * x);
  return (zpre + gh * w) / (1.0 + gh * sigma0 * std::abs(w) / g);
}
inline double calc_lugre_torque(const FrictionMap& f, double sigma0, double sigma1, double w, double z, double zd) {
  return -(sigma0 * z + sigma1 * zd + f.b * w);
}

}  // namespace ff
