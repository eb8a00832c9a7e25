// diagnose and calibrate on arm models (docs/validation.md, "Arm models"): the rig's search
// (validate/diagnose.hpp: a global scan, Ceres, Delta BIC in effective samples, the residual tests)
// over candidate effects tried at every actuated joint and every flexible link, named after where
// they act:
//   per actuated joint J        coulomb_friction@J, viscous_friction@J, stribeck_friction@J,
//                               torque_offset@J, drive_compliance@J, torque_saturation@J,
//                               sensor_delay.J_angle, sensor_delay.J_rate (with kd > 0),
//                               sensor_quantization@J (revolute), armature@J (inline bodies)
//   per flexible link L         link_stiffness@L, link_damping@L, extra_mode@L, payload@L (with one)
//   the tool's rigid body B     payload@B (inline bodies, with mass)
// The record is an arm record (validate/arm_record.hpp), replayed in closed loop (its references drive
// the model's controllers); every `<joint>.angle`, `<joint>.torque`, tool and deflection column both
// have and the record does not hold constant is scored, weighted by its own noise floor.
#pragma once

#include <string>
#include <vector>

#include "sweep/paths.hpp"
#include "validate/diagnose.hpp"
#include "validate/record.hpp"

namespace ff {

// The candidates an arm model offers (their names, whether or not the record scores what they change).
std::vector<Effect> make_arm_candidate_effects(const ArmModel& base, const YAML::Node& doc, const Record& r);

// The diagnosis of an arm model (src: load_arm_source) against an arm record. Only closed loop:
// another opt.mode is std::invalid_argument.
Diagnosis diagnose_arm(const ModelSource& src, const Record& r, const DiagnoseOptions& opt);

// Effects fitted in turn, combined (calibrate --add a,b); an effect the model does not offer is std::invalid_argument.
EffectFit fit_arm_effects(const ModelSource& src, const Record& r, const DiagnoseOptions& opt, const std::vector<std::string>& effects);

// The calibrated arm model's YAML (format_calibrated_model) to be written at out_path: its `urdf` and
// `sidecar` re-based from the source's directory to out_path's.
std::string format_calibrated_arm(const ModelSource& src, const EffectFit& fit, const std::string& record_path,
                                  const std::string& out_path);

// Fit % and RMSE of every channel an arm diagnosis scores, of a model replayed on the record.
std::map<std::string, Fit> calc_arm_record_fits(const ArmModel& m, const Record& r);

}  // namespace ff
