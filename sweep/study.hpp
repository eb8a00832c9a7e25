// Study files (docs/formats.md): a model, overrides shared by every run, and either a list of
// runs or variables with a design (grid, centered, Monte Carlo, LHS, Sobol', Saltelli, Morris).
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "kernel/model.hpp"
#include "sweep/design.hpp"
#include "sweep/paths.hpp"

namespace ff {

// One evaluation of the model.
struct Variant {
  int eval_id = 0;              // 0-based, stable: the row order of every result table
  std::uint64_t seed = 0;       // calc_variant_seed(study seed, eval_id)
  std::string label;            // legend and table name
  std::vector<double> params;   // value of each study parameter (Study::params), NaN = not numeric
  std::vector<Assignment> set;  // the overrides that make this variant
};

struct Study {
  std::string source;           // the study file
  std::string name;
  std::string description;
  std::uint64_t seed = 1;
  std::string model_path;       // resolved relative to the study file
  std::string model_text;       // its contents, parsed afresh per variant (keeps line numbers)
  std::vector<Assignment> set;  // study-wide overrides, applied before each variant's own
  DesignSpec design;            // kind, sample counts and seed (ignored for a list of runs)
  bool listed = false;          // runs given one by one (`runs:`) rather than by a design
  std::vector<Variable> variables;
  std::vector<std::string> case_labels;     // `cases:` crossed with the design (parameter `case` = index)
  std::vector<std::string> params;          // parameter columns: variable paths, or the paths the runs set
  std::vector<Variant> variants;
  std::vector<Model> models;                // (variants), built and checked when the study is loaded
  std::map<std::string, double> specs;      // response -> limit a run must not exceed (Monte Carlo summaries)
  bool keep_traces = false;     // write every variant's trace (default: when there are at most 50)
  std::string hash;             // fingerprint of the study and model text: journals refuse another study's rows
};

// The most variants a study may have: the farm holds every variant's model (about 3 KB each).
inline constexpr int kMaxStudyVariants = 1000000;

// Loads and checks a study: every variant's model is built here (on all cores), so a bad value
// fails before anything is written; the first bad variant by eval_id is the one reported.
Study load_study(const std::string& path);

// The two halves of load_study. read_study reads and checks the file and makes the variants (no
// models yet); a study of more than `max_variants` variants is refused before its design is drawn.
Study read_study(const std::string& path, int max_variants = kMaxStudyVariants);
// Builds every variant's model (Study::models); the first bad variant by eval_id is the one reported.
void build_models(Study& st);

// The model of one variant. Errors in an overridden value name the study file, line and key.
Model make_variant_model(const Study& study, const Variant& v);

}  // namespace ff
