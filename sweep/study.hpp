// Study files (docs/formats.md): a model, overrides shared by every run, and the runs.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <utility>
#include <vector>

#include "kernel/model.hpp"

namespace ff {

// One model parameter set by path (sweep/paths.hpp) and where it was written.
struct Assignment {
  std::string path;
  YAML::Node value;
  int line = 0;            // line in the study file, 0 = unknown
  std::string key;         // the study key that holds it, e.g. "runs[2].set.payload.mass"
};

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
  YAML::Node model_doc;    // the model document with the study-wide overrides applied
  std::vector<Variant> variants;
};

// Loads and checks a study: every variant's model is built once here, so a bad value fails
// before anything is written.
Study load_study(const std::string& path);

// The model of one variant. Errors in an overridden value name the study file, line and key.
Model make_variant_model(const Study& study, const Variant& v);

}  // namespace ff
