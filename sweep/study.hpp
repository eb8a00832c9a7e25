// Study files (docs/formats.md): a model, overrides shared by every run, and the runs.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <utility>
#include <vector>

#include "kernel/model.hpp"
#include "sweep/paths.hpp"

namespace ff {

// One evaluation of the model.
struct Variant {
  int eval_id = 0;         // 0-based, stable: the row order of every result table
  std::string label;       // legend and table name
  std::vector<Assignment> set;
};

struct Study {
  std::string source;      // the study file
  std::string name;
  std::string description;
  std::string model_path;  // resolved relative to the study file
  std::string model_text;  // its contents, parsed afresh per variant (keeps line numbers)
  std::vector<Assignment> set;  // study-wide overrides, applied before each run's own
  std::vector<Variant> variants;
};

// Loads and checks a study: every variant's model is built once here, so a bad value fails
// before anything is written.
Study load_study(const std::string& path);

// The model of one variant. Errors in an overridden value name the study file, line and key.
Model make_variant_model(const Study& study, const Variant& v);

}  // namespace ff
