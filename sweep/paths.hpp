// Model parameters addressed by path: "payload.mass", "notch.enabled", "trajectory.moves[1].target".
// A study (or `--set` on the command line) overrides them in the model document before it is parsed,
// so every override passes the same checks as the model file itself.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "arm/arm_model.hpp"
#include "kernel/model.hpp"

namespace ff {

// One model parameter set by path, and where the user wrote it (for error messages).
struct Assignment {
  std::string path;        // e.g. "payload.mass"
  YAML::Node value;
  std::string source;      // the study file, or "--set"
  int line = 0;            // line in `source`, 0 = none
  std::string key;         // how `source` names it, e.g. "runs[2].set.payload.mass"
  // Changes the plant only, not the controller's internal model (kernel/model.hpp ControllerSpec::model):
  // a study's variable or run, a Monte Carlo draw, diagnose's candidate, calibrate's fit, `--plant-set`.
  // The file and --set (the user's own edits) and a study's `set:` and `cases:` change both.
  bool plant_only = false;
};

// Whether an assignment to `path` changes the controller itself even when plant_only: the controller's,
// notch's, shaper's, sensors', trajectory's, simulation's, monitors' and metrics' blocks, and an arm
// joint's controller, notch, shaper and sensors (joints.NAME.controller...).
bool is_controller_path(const std::string& path);

// Replaces (or creates) the value at `path` in `doc` with `value`, and returns the path with each
// [NAME] as its index (bodies[beam].mass -> bodies[0].mass). Throws ConfigError naming `source` and
// the path when the path cannot exist (indexing a map, a key inside a number, ...).
std::string set_path(YAML::Node& doc, const std::string& path, const YAML::Node& value, const std::string& source);

// The value at `path`, or a null node when absent.
YAML::Node get_path(const YAML::Node& doc, const std::string& path);

// Parses a command-line "path=value" (value in YAML syntax); source "--set" (plant only: "--plant-set").
Assignment parse_assignment(const std::string& text, bool plant_only = false);

// Applies the assignments to a model document (loaded with line marks) and builds the model.
// An error in an assigned value is reported where the assignment was written; any other error
// names `model_source` and its line. With plant-only assignments (outside the controller's paths) and
// `controller.model: nominal`, the controller's model is the document with the others alone, built
// once per thread for the same document and assignments, and the plant carries it (make_model's and
// make_arm's `controller`).
Model make_model_with(YAML::Node doc, const std::string& model_source, const std::vector<Assignment>& set);

// The one way to load a model file with its --set overrides ("path=value") and --plant-set ones (the
// plant's alone, Assignment::plant_only, applied after):
// the model itself,
Model load_model_with(const std::string& path, const std::vector<std::string>& sets,
                      const std::vector<std::string>& plant_sets = {});
// or its source: the document, so that more paths can be set on it later (diagnose's candidates,
// calibrate's additions), and where it came from. The model is built once here, so that a bad file or
// override fails before any other input is read.
struct ModelSource {
  YAML::Node doc;
  std::string path;
  std::vector<Assignment> set;  // --set overrides, applied first
};
ModelSource load_model_source(const std::string& path, const std::vector<std::string>& sets);
// The source's document (a copy) with its --set overrides applied.
YAML::Node apply_overrides(const ModelSource& src);
// The model of a source, with `extra` assignments after its own.
Model build_model(const ModelSource& src, const std::vector<Assignment>& extra = {});

// Arm models (arm/arm_yaml.hpp) the same way: the document with the overrides applied, errors in an
// assigned value named where it was assigned.
ArmModel make_arm_with(YAML::Node doc, const std::string& model_source, const std::vector<Assignment>& set);
ArmModel load_arm_with(const std::string& path, const std::vector<std::string>& sets,
                       const std::vector<std::string>& plant_sets = {});
// An arm model's source, checked once as load_model_source checks a rig's, and its model with `extra`
// assignments after its own overrides.
ModelSource load_arm_source(const std::string& path, const std::vector<std::string>& sets);
ArmModel build_arm(const ModelSource& src, const std::vector<Assignment>& extra = {});
// Whether a model file is an arm model (a YAML document with `bodies` or `urdf`) rather than the
// reference rig's; false for a file that cannot be read or parsed (the loader then says why).
bool is_arm_model_file(const std::string& path);

// A model file's document (load_yaml_file), refusing a study file ("a study file, not a model: `flexfarm
// run` takes it"). Every loader above reads through it.
YAML::Node load_model_file(const std::string& path);
// Refuses a model file `doc` given where a study is wanted (as `flexfarm run`'s STUDY.yaml).
void check_not_model(const YAML::Node& doc, const std::string& path);

}  // namespace ff
