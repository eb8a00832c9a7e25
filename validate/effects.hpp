// The candidate effects diagnose tries: each a piece of physics (or a re-fit) the model may lack,
// switched on by model paths and fitted by its parameters (docs/validation.md).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "kernel/model.hpp"
#include "validate/replay.hpp"

namespace ff {

// A continuous parameter. Positive ones are fitted as log(value), within x/÷ 1000 of the start;
// signed ones (`linear`: a constant torque) as value / scale, within ±scale.
struct EffectParam {
  std::string path;      // model path, e.g. "friction.coulomb"
  double initial = 1.0;  // starting value, > 0 unless linear
  bool linear = false;   // signed and fitted linearly
  double scale = 1.0;    // linear only: the bound on |value| and its unit in the fit, > 0
};

struct Effect {
  std::string name;                                      // e.g. "coulomb_friction"
  std::string physics;                                   // one line: what it adds
  std::vector<std::pair<std::string, std::string>> set;  // fixed switches: path -> YAML value
  std::vector<EffectParam> params;                       // fitted by least squares
  std::string grid_path;                                 // a discrete parameter searched first ("" = none)
  std::vector<double> grid;                              // its values
  std::string extends;                                   // the simpler effect this one contains ("" = none)
};

// How much better (percentage points of fit, on some channel) an effect must do than the simpler
// effect it extends to be ranked above it: below this the extra parameters buy nothing a user sees.
inline constexpr double kNestedFitMargin = 0.5;

// Scales the candidates' starting values take from the base model's replay of the record.
struct EffectScales {
  double torque_rms = 1.0;  // N·m
  double rate_rms = 1.0;    // rad/s
  double torque_max = 1.0;  // N·m
};

// The parameter at `path` starting at `value`: signed (linear, bounded by twice the larger of
// |value| and the torque RMS) when the path is a signed one (hub.torque_offset), else positive.
EffectParam make_effect_param(const std::string& path, double value, const EffectScales& scales);

// The candidates that apply to `mode` on `base` (plant effects everywhere; controller-side
// effects - sensors, saturation - only in closed loop).
std::vector<Effect> make_candidate_effects(const Model& base, ReplayMode mode, const EffectScales& scales);

// Every candidate's name, in the order diagnose lists them.
std::vector<std::string> effect_names();

}  // namespace ff
