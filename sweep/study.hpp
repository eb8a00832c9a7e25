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
#include "results/requirements.hpp"
#include "results/tolerances.hpp"
#include "sweep/design.hpp"
#include "sweep/paths.hpp"

namespace ff {

// One evaluation of the model.
struct Variant {
  int eval_id = 0;              // 0-based, stable: the row order of every result table
  std::uint64_t seed = 0;       // calc_variant_seed(study seed, eval_id)
  std::string label;            // legend and table name
  std::vector<double> params;   // value of each study parameter (Study::params), NaN = not numeric
};

struct Study {
  std::string source;           // the study file
  std::string text;             // its contents, as read
  std::string name;
  std::string description;
  std::uint64_t seed = 1;
  std::string model_path;       // resolved relative to the study file
  std::string model_text;       // its contents: each variant builds on a copy of it (sweep/study.cpp)
  std::vector<Assignment> set;  // study-wide overrides, applied before each variant's own
  DesignSpec design;            // kind, sample counts and seed (ignored for a list of runs)
  bool listed = false;          // runs given one by one (`runs:`) rather than by a design
  std::vector<Variable> variables;
  std::vector<bool> integer;    // (variables) rounded to whole numbers
  std::vector<int> variable_lines;          // (variables) where each is written in the study file
  std::vector<std::vector<Assignment>> run_sets;   // a list of runs: each run's overrides
  std::vector<std::string> case_labels;     // `cases:` crossed with the design (parameter `case` = index)
  std::vector<std::vector<Assignment>> case_sets;  // (case_labels) each case's overrides
  std::vector<std::string> params;          // parameter columns: variable paths, or the paths the runs set
  std::vector<Variant> variants;
  bool arm = false;             // the model is an arm model (arm/arm_yaml.hpp), not the reference rig's
  ArmModel arm_nominal;         // then its nominal model (as `nominal`); `nominal` is left default
  Model nominal;                // the study-wide overrides (and case 0's) with every variable at its nominal
                                // value: the result table's columns; a bad override fails at load
  bool drawn = false;           // the values are drawn from distributions, not written in the file
  std::map<std::string, double> specs;      // response -> limit a run must not exceed (Monte Carlo summaries)
  std::map<std::string, int> spec_lines;    // response -> where its spec is written
  std::vector<Tolerance> tolerances;        // how much worse than the last run is a regression (flexfarm diff)
  RequirementSet requirements;  // `requirements:` (results/requirements.hpp); their metrics checked by check_models
  bool keep_traces = false;     // write every variant's trace (default: when there are at most 50)
  std::string hash;             // fingerprint of the study and model text: journals refuse another study's rows
};

// The most variants a study may have: the farm holds every variant's values and, when it assembles
// the results, every row (about 1.4 kB a variant).
inline constexpr int kMaxStudyVariants = 1000000;

// What a study holds its runs to, read from its text alone (no model, no design): `specs:`,
// `tolerances:` (a p_miss one needs its metric's spec) and `requirements:`, whose bootstrap draws from
// the study's `seed:`. read_study reads them so; flexfarm diff from a run's recorded study text.
struct StudyCriteria {
  std::map<std::string, double> specs;
  std::map<std::string, int> spec_lines;  // where each spec is written
  std::vector<Tolerance> tolerances;
  RequirementSet requirements;
  std::string file;                       // the study file, for errors
};
StudyCriteria read_study_criteria(YamlReader& top, std::uint64_t seed);
StudyCriteria read_study_criteria(const std::string& text, const std::string& source);
// Every metric the criteria name (each spec, tolerance and requirement) is one of `columns`, else a
// ConfigError naming the file, line and key, the closest column and the columns there are
// (explain_unknown_column): a misspelled name would be a spec or a regression guard that never fires.
void check_criteria_columns(const StudyCriteria& c, const std::vector<std::string>& columns);

// Loads and checks a study: read_study, then check_models.
Study load_study(const std::string& path);

// The two halves of load_study. read_study reads and checks the file and makes the variants (no
// models); a study of more than `max_variants` variants is refused before its design is drawn.
Study read_study(const std::string& path, int max_variants = kMaxStudyVariants);
// Builds the nominal model (Study::nominal) and checks the values written in the file (a list of
// runs, a grid, a centered design) by building every variant's model on all cores (and dropping it),
// so a bad value fails before anything is written; the first bad variant by eval_id is the one
// reported. Drawn values (Monte Carlo, LHS, Sobol', Saltelli, Morris) are checked at each case's
// nominal point only (its written set, every variable at its median): a draw from a distribution's
// tail that the model rejects is a result of the run (status `invalid`), not an error. Models are
// built again, per batch, when the variants run: memory does not grow with the study. Every metric
// a spec, tolerance or requirement names must be one of the nominal model's result columns.
void check_models(Study& st);

// The legends of variants shown together (`flexfarm plot`): each one's label less the `path=value`
// items all of them share, so the legend names what differs. One variant, or a list of runs, keeps
// its whole label; variants that differ in nothing keep theirs too.
std::vector<std::string> calc_legend_labels(const Study& st, const std::vector<int>& eval_ids);

// The overrides that make a variant, in the order applied: the study's `set:`, then its run's or its
// case's, then its variables' values (Variant::params).
std::vector<Assignment> make_variant_set(const Study& study, const Variant& v);

// The model of one variant. Errors in an overridden value name the study file, line and key.
Model make_variant_model(const Study& study, const Variant& v);

// The unit of a study parameter (a path as `--set` takes it) from the model's field tables
// (docs/formats.md): "kg" for bodies[forearm].flexible.payload.mass, "m" for world.floor.position[2];
// a joint's key written "rad (m)" by the joint's type (prismatic: m). "" when it has none (a count, a
// gain without one, `case`) or the path is not in the tables.
std::string parameter_unit(const Study& study, const std::string& path);
// A plot axis of a parameter: "bodies[forearm].flexible.payload.mass (kg)", or the path alone.
std::string parameter_axis_label(const Study& study, const std::string& path);
// Whether `name`, an actuated joint's (`joints.NAME`) or a body's (`bodies[NAME]`), moves along a
// prismatic joint: its values are m (N, N/m) where a revolute one's are rad (N·m, N·m/rad).
bool is_prismatic(const ArmModel& m, const std::string& name);

// The arm model of one variant (a study whose model is an arm's).
ArmModel make_variant_arm(const Study& study, const Variant& v);
// Every variant of an arm study has the nominal model's metric columns (joints, links): "" when a does,
// else why not.
std::string explain_columns_mismatch(const Study& study, const ArmModel& a);

// Every variant of a study has the nominal model's number of moves (its metric columns): "" when m
// does, else why not.
std::string explain_moves_mismatch(const Study& study, const Model& m);

}  // namespace ff
