// The candidate effects diagnose tries: each a piece of physics (or a re-fit) the model may lack,
// switched on by model paths and fitted jointly over the parameters that shape its signature
// (docs/validation.md, "The candidate effects").
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "kernel/model.hpp"
#include "validate/replay.hpp"

namespace ff {

// How a parameter is fitted: its coordinate theta, searched over [lo, hi] (values).
enum class ParamScale {
  kLog,     // positive: theta = ln(value), 0 < lo < hi
  kLinear,  // signed: theta = value / max(|lo|, |hi|)
  kShare,   // a share x in [lo, hi] within (0, 1) of `total`: path = x total / divisor, partner = (1 - x) total
};

struct EffectParam {
  std::string path;        // model path, e.g. "friction.coulomb"
  double initial = 1.0;    // starting value, in [lo, hi]
  double lo = 1e-3, hi = 1e3;
  ParamScale scale = ParamScale::kLog;
  std::string partner;     // kShare: the path that keeps the rest (e.g. hub.inertia)
  double total = 0.0;      // kShare: what the two share, in the partner's unit
  double divisor = 1.0;    // kShare: path = x total / divisor (the drive's ratio squared: shaft coordinates)
};

struct Effect {
  std::string name;                                      // e.g. "coulomb_friction"
  std::string physics;                                   // one line: what it adds
  std::vector<std::pair<std::string, std::string>> set;  // fixed switches: path -> YAML value
  std::vector<EffectParam> params;                       // fitted jointly by least squares
  std::string grid_path;                                 // a discrete parameter searched instead ("" = none)
  std::vector<double> grid;                              // its values, ascending
  bool grid_integer = false;                             // whole numbers: refined between the best one's neighbours
  std::string extends;                                   // the simpler effect this one contains ("" = none)
  // Starting points scanned instead of the global scan's Sobol' points, each some params' values (the rest at
  // their initial values): where the sum of squares has many narrow valleys the Sobol' points miss (a
  // ripple's waves at each of four phases). Empty: the global scan.
  std::vector<std::map<std::string, double>> starts;
};

// How much better (percentage points of fit, on some channel) an effect must do than the simpler
// effect it extends to be ranked above it: below this the extra parameters buy nothing a user sees.
inline constexpr double kNestedFitMargin = 0.5;

// Scales the candidates' ranges take from the base model's replay of the record.
struct EffectScales {
  double torque_rms = 1.0;  // N·m
  double rate_rms = 1.0;    // rad/s
  double torque_max = 1.0;  // N·m
};

// The longest delay searched: at least this, s (and at least 24 controller samples).
inline constexpr double kMaxSearchedDelay = 0.12;

// An existing parameter at `path` with value `value`, re-fitted: signed (within twice the larger of
// |value| and the torque RMS) when the path is a signed one (hub.torque_offset, an arm's joints.NAME.torque_offset), else positive within
// x/÷ 1000 of its value.
EffectParam make_effect_param(const std::string& path, double value, const EffectScales& scales);

// A positive parameter searched over [lo, hi], starting at `current` when the model has it (> 0), else at
// `fallback` (clamped to the range).
EffectParam make_positive_param(const std::string& path, double current, double fallback, double lo, double hi);

// LuGre's parameters (kernel/friction.hpp) under `prefix` ("friction.", "joints.j1.friction."): the Stribeck
// curve's `stribeck` (coulomb, stiction, stribeck_velocity) and the bristles' stiffness sigma0 and damping
// sigma1, started from `f` when it is LuGre; `tau` the torque RMS (N m), `inertia` what the joint moves.
std::vector<EffectParam> make_lugre_params(const std::string& prefix, const FrictionSpec& f, double tau, double inertia,
                                           std::vector<EffectParam> stribeck);

// A hardening mesh's cubic stiffness k3 (N m/rad^3) at `path` for a mesh of stiffness k: k3 e^2 from 1e-4 to
// 1e4 times k at the twist the peak torque gives.
EffectParam make_cubic_param(const std::string& path, double current, double k, double torque_max);

// A worn or eccentric gear named `name`: the Coulomb friction of `coulomb` and `smoothing` (paths under
// `prefix`, e.g. "friction." or "joints.J.friction.") with its level times 1 + a cos(p q) + b sin(p q):
// p started at whole waves a revolution, 2 to 48, each at four phases, and fitted (1.5 to 60) with a and b
// (within +-0.9).
// Extends `extends` (the Coulomb candidate).
Effect make_worn_gear_effect(const std::string& name, const std::string& prefix, const std::string& extends,
                             const FrictionSpec& f, EffectParam coulomb, EffectParam smoothing);

// Whole numbers from 1 to `last`, spaced by about a factor 4/3 (every one up to 5): the delays searched.
std::vector<double> make_delay_grid(int last);

// Binary encoders of 9 to 22 bits a turn (12 to 0.0015 mrad): a count is 2 pi / 2^b rad.
std::vector<double> make_encoder_quanta();

// The candidates that apply to `mode` on `base` (plant effects everywhere; controller-side effects -
// sensors in the loop, saturation - only in closed loop; an output delay for every scored output channel).
std::vector<Effect> make_candidate_effects(const Model& base, ReplayMode mode, const EffectScales& scales,
                                           const std::vector<std::string>& scored);

// Every candidate's name, in the order diagnose lists them.
std::vector<std::string> effect_names();

// The paths an effect writes (its parameters, their partners, its grid path).
std::vector<std::string> effect_paths(const Effect& e);

}  // namespace ff
