#include "sweep/study.hpp"

#include "arm/arm_metrics.hpp"
#include "arm/arm_yaml.hpp"
#include "description/tree_yaml.hpp"
#include "description/urdf.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/errors.hpp"
#include "common/files.hpp"
#include "kernel/model_io.hpp"
#include "common/yaml_reader.hpp"
#include "common/random.hpp"
#include "results/run_metrics.hpp"

namespace ff {

namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// 64-bit FNV-1a of a text: the study's fingerprint.
std::uint64_t fnv1a(const std::string& s, std::uint64_t h = 0xcbf29ce484222325ull) {
  for (unsigned char c : s) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

// Reads a `set:` map of path -> value.
std::vector<Assignment> read_assignments(YamlReader& parent, const std::string& key) {
  std::vector<Assignment> out;
  const YAML::Node node = parent.raw(key);
  if (!node) return out;
  if (!node.IsMap()) parent.fail(key, "expected a map of PARAMETER.PATH: value");
  for (const auto& kv : node) {
    const auto path = kv.first.as<std::string>();
    out.push_back({path, YAML::Clone(kv.second), parent.file(), kv.first.Mark().line + 1, parent.full_key(key) + "." + path});
  }
  return out;
}

// A numeric reading of a YAML scalar (true/false as 1/0), NaN otherwise.
double numeric_value(const YAML::Node& v) {
  double x = 0;
  bool b = false;
  if (v.IsScalar() && YAML::convert<double>::decode(v, x)) return x;
  if (v.IsScalar() && YAML::convert<bool>::decode(v, b)) return b ? 1.0 : 0.0;
  return std::nan("");
}

// A parameter value as YAML: integers without a decimal point, others exactly (17 digits).
YAML::Node value_node(double x) {
  char buf[40];
  if (x == std::floor(x) && std::fabs(x) < 1e15) std::snprintf(buf, sizeof buf, "%.0f", x);
  else std::snprintf(buf, sizeof buf, "%.17g", x);
  return YAML::Load(buf);
}

std::string short_number(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

DesignKind parse_design_kind(YamlReader& r, const std::string& name) {
  const std::pair<const char*, DesignKind> kinds[] = {
      {"grid", DesignKind::kGrid},           {"centered", DesignKind::kCentered},
      {"monte_carlo", DesignKind::kMonteCarlo}, {"lhs", DesignKind::kLatinHypercube},
      {"sobol", DesignKind::kSobol},         {"saltelli", DesignKind::kSaltelli},
      {"morris", DesignKind::kMorris}};
  for (const auto& [n, k] : kinds)
    if (name == n) return k;
  r.fail("type", "unknown design '" + name + "' (list, grid, centered, monte_carlo, lhs, sobol, saltelli, morris)");
}

Distribution parse_distribution(YamlReader r) {
  Distribution d;
  std::string type;
  if (!r.has("type")) r.fail_missing("type", "missing required value (uniform, normal, truncated_normal, lognormal, choice)");
  r.optional("type", type);
  if (type == "uniform") {
    d.kind = DistributionKind::kUniform;
    r.required("lower", d.lower);
    r.required("upper", d.upper);
  } else if (type == "normal" || type == "truncated_normal") {
    d.kind = type == "normal" ? DistributionKind::kNormal : DistributionKind::kTruncatedNormal;
    r.required("mean", d.mean);
    r.required("std", d.std);
    if (d.kind == DistributionKind::kTruncatedNormal) {
      r.required("lower", d.lower);
      r.required("upper", d.upper);
    }
  } else if (type == "lognormal") {
    d.kind = DistributionKind::kLognormal;
    r.required("mu", d.mu);
    r.required("sigma", d.sigma);
  } else if (type == "choice") {
    d.kind = DistributionKind::kChoice;
    for (const auto* key : {"values", "weights"}) {
      const YAML::Node v = r.raw(key);
      if (!v) continue;
      if (!v.IsSequence()) r.fail(key, "expected a list of numbers");
      auto& out = std::string(key) == "values" ? d.values : d.weights;
      for (const auto& e : v) {
        const double x = numeric_value(e);
        if (std::isnan(x)) r.fail(key, "expected a list of numbers");
        out.push_back(x);
      }
    }
  } else {
    r.fail("type", "unknown distribution '" + type + "' (uniform, normal, truncated_normal, lognormal, choice)");
  }
  r.finish();
  try {
    validate_distribution(d);
  } catch (const std::invalid_argument& e) {
    // Point at the key the message is about.
    const std::string what = e.what();
    std::string key = "type";
    for (const char* k : {"weights", "values", "sigma", "std", "lower", "upper", "mean", "mu"})
      if (what.find(k) != std::string::npos && r.has(k)) {
        key = k;
        break;
      }
    r.fail(key, what);
  }
  return d;
}

// One entry of `variables:`. A range's levels are made as it is read: first its count is held to the
// variant limit `max_variants` with the ranges before it. A grid or centered design has at least
// 1 + sum(count - 1) rows, so that sum over the ranges is kept within the limit (`levels_left` counts
// it down from max_variants - 1), which refuses no design the limit would let through.
Variable parse_variable(YamlReader& r, bool& integer, int max_variants, long long& levels_left) {
  Variable v;
  if (!r.has("path")) r.fail_missing("path", "missing required value (the model parameter, e.g. payload.mass)");
  r.optional("path", v.path);
  if (const YAML::Node lv = r.raw("levels")) {
    if (!lv.IsSequence() || lv.size() == 0) r.fail("levels", "expected a non-empty list of numbers");
    for (const auto& e : lv) {
      const double x = numeric_value(e);
      if (!std::isfinite(x)) r.fail("levels", "expected a list of finite numbers");
      v.levels.push_back(x);
    }
  }
  if (r.has("range")) {
    auto rg = r.child("range");
    double lo = 0, hi = 0;
    int count = 0;
    rg.required("lower", lo);
    rg.required("upper", hi);
    rg.required("count", count);
    rg.finish();
    if (count < 2 || !(hi > lo)) r.fail("range", "needs upper > lower and count >= 2");
    if (!v.levels.empty()) r.fail("range", "give levels or range, not both");
    if (count - 1 > levels_left)
      rg.fail("count", std::to_string(count) + " levels take the study's ranges over " + std::to_string(max_variants) +
                           " variants, its limit (a grid or centered design has at least 1 + the sum of count - 1)");
    levels_left -= count - 1;
    for (int i = 0; i < count; ++i) v.levels.push_back(lo + (hi - lo) * i / (count - 1));
  }
  v.nominal = v.levels.empty() ? 0.0 : v.levels[v.levels.size() / 2];
  r.optional("nominal", v.nominal);
  if (r.has("distribution")) v.dist = parse_distribution(r.child("distribution"));
  integer = false;
  r.optional("integer", integer);
  r.finish();
  return v;
}

// Crosses every case (a labelled set of overrides) with every variant of the design: the case's
// overrides come first, its index is the parameter `case`, its label leads the variant's label.
void cross_cases(Study& st, YamlReader& top) {
  auto cases = top.sequence("cases", true);
  if (cases.empty()) top.fail("cases", "needs at least one case");
  for (std::size_t i = 0; i < cases.size(); ++i) {
    std::string label = "case " + std::to_string(i);
    cases[i].optional("label", label);
    if (label.find(" | ") != std::string::npos) cases[i].fail("label", "must not contain ' | '");
    st.case_sets.push_back(read_assignments(cases[i], "set"));
    cases[i].finish();
    st.case_labels.push_back(label);
  }
  const std::vector<Variant> design = std::move(st.variants);
  st.variants.clear();
  st.params.insert(st.params.begin(), "case");
  for (std::size_t c = 0; c < st.case_labels.size(); ++c)
    for (const auto& d : design) {
      Variant v = d;
      v.eval_id = static_cast<int>(st.variants.size());
      v.label = st.case_labels[c] + " | " + d.label;
      v.params.insert(v.params.begin(), static_cast<double>(c));
      st.variants.push_back(std::move(v));
    }
}

void parse_design(Study& st, YamlReader& top, int max_variants) {
  const bool has_runs = top.has("runs"), has_vars = top.has("variables");
  if (has_runs == has_vars) top.fail("runs", "give either `runs:` (a list of runs) or `variables:` with a `design:`");
  if (has_runs && top.has("cases")) top.fail("cases", "cases are crossed with `variables:`; a list of `runs:` takes none");

  if (has_runs) {
    st.listed = true;
    if (top.has("design")) top.fail("design", "a list of `runs:` takes no design");
    auto runs = top.sequence("runs", true);
    if (runs.empty()) top.fail("runs", "needs at least one run");
    if (runs.size() > static_cast<std::size_t>(max_variants))
      top.fail("runs", std::to_string(runs.size()) + " runs exceed the limit of " + std::to_string(max_variants) + " variants");
    for (std::size_t i = 0; i < runs.size(); ++i) {
      Variant v;
      v.eval_id = static_cast<int>(i);
      v.label = "run " + std::to_string(i);
      runs[i].optional("label", v.label);
      st.run_sets.push_back(read_assignments(runs[i], "set"));
      runs[i].finish();
      for (const auto& a : st.run_sets.back())
        if (std::find(st.params.begin(), st.params.end(), a.path) == st.params.end()) st.params.push_back(a.path);
      st.variants.push_back(std::move(v));
    }
    for (auto& v : st.variants) {
      v.params.assign(st.params.size(), std::nan(""));
      for (const auto& a : st.run_sets[v.eval_id])
        v.params[std::find(st.params.begin(), st.params.end(), a.path) - st.params.begin()] = numeric_value(a.value);
    }
    return;
  }

  auto vars = top.sequence("variables", true);
  if (vars.empty()) top.fail("variables", "needs at least one variable");
  std::vector<bool>& integer = st.integer;
  integer.assign(vars.size(), false);
  std::vector<int>& lines = st.variable_lines;
  long long levels_left = static_cast<long long>(max_variants) - 1;
  for (std::size_t i = 0; i < vars.size(); ++i) {
    bool is_int = false;
    st.variables.push_back(parse_variable(vars[i], is_int, max_variants, levels_left));
    integer[i] = is_int;
    lines.push_back(vars[i].line());
    st.params.push_back(st.variables.back().path);
  }
  auto design = top.child("design", true);
  DesignSpec spec;
  std::string type;
  if (!design.has("type")) design.fail_missing("type");
  design.optional("type", type);
  spec.kind = parse_design_kind(design, type);
  design.optional("samples", spec.samples);
  design.optional("trajectories", spec.trajectories);
  design.optional("levels", spec.morris_levels);
  design.finish();
  spec.seed = st.seed;
  st.design = spec;
  const bool needs_levels = spec.kind == DesignKind::kGrid || spec.kind == DesignKind::kCentered;
  for (std::size_t i = 0; i < vars.size(); ++i) {
    if (needs_levels && st.variables[i].levels.empty())
      vars[i].fail("levels", "a " + type + " design needs `levels:` or `range:` for every variable");
    if (!needs_levels && !vars[i].has("distribution"))
      vars[i].fail("distribution", "a " + type + " design needs a `distribution:` for every variable");
  }

  // The variant count (design rows times cases) is checked before the design is drawn.
  const YAML::Node cases = top.raw("cases");
  const long long ncases = cases && cases.IsSequence() ? static_cast<long long>(cases.size()) : 1;
  std::vector<std::vector<double>> rows;
  try {
    const long long n = static_cast<long long>(calc_design_size(spec, st.variables)) * ncases;
    if (n > max_variants)
      design.fail("type", "the design has " + std::to_string(n) + " variants, over the limit of " +
                              std::to_string(max_variants));
    rows = make_design(spec, st.variables);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(st.source, design.line(), "design", e.what());
  }
  // Each design row becomes a variant: its values set by path (rounded where the variable is an integer).
  for (std::size_t k = 0; k < rows.size(); ++k) {
    Variant v;
    v.eval_id = static_cast<int>(k);
    for (std::size_t j = 0; j < st.variables.size(); ++j) {
      const double x = integer[j] ? std::nearbyint(rows[k][j]) : rows[k][j];
      v.params.push_back(x);
      v.label += (j ? ", " : "") + st.variables[j].path + "=" + short_number(x);
    }
    st.variants.push_back(std::move(v));
  }
  if (top.has("cases")) cross_cases(st, top);
}

// The nominal point of case c of a drawn design: variant 0 with that case and every variable at the
// median of its distribution.
Variant make_nominal_variant(const Study& st, std::size_t c) {
  Variant v = st.variants.front();
  if (!st.case_labels.empty()) v.params[0] = static_cast<double>(c);
  const std::size_t first = v.params.size() - st.variables.size();  // after the case index
  for (std::size_t j = 0; j < st.variables.size(); ++j) {
    const double x = calc_quantile(st.variables[j].dist, 0.5);
    v.params[first + j] = st.integer[j] ? std::nearbyint(x) : x;
  }
  return v;
}

}  // namespace

std::vector<std::string> calc_legend_labels(const Study& st, const std::vector<int>& eval_ids) {
  std::vector<std::string> out;
  for (int id : eval_ids) out.push_back(st.variants[static_cast<std::size_t>(id)].label);
  if (st.listed || eval_ids.size() < 2) return out;
  const bool cases = !st.case_labels.empty();
  const std::size_t first = cases ? 1 : 0;  // params[0] is the case's index
  const auto param = [&](int id, std::size_t j) { return st.variants[static_cast<std::size_t>(id)].params[first + j]; };
  std::vector<std::size_t> differ;
  for (std::size_t j = 0; j < st.variables.size(); ++j)
    for (int id : eval_ids)
      if (short_number(param(id, j)) != short_number(param(eval_ids[0], j))) {
        differ.push_back(j);
        break;
      }
  for (std::size_t k = 0; k < eval_ids.size(); ++k) {
    std::string vars;
    for (std::size_t j : differ)
      vars += (vars.empty() ? "" : ", ") + st.variables[j].path + "=" + short_number(param(eval_ids[k], j));
    const auto& v = st.variants[static_cast<std::size_t>(eval_ids[k])];
    const std::string c = cases ? st.case_labels[static_cast<std::size_t>(v.params[0])] : "";
    const std::string s = c.empty() ? vars : vars.empty() ? c : c + " | " + vars;
    if (!s.empty()) out[k] = s;
  }
  return out;
}

namespace {
// `seed:` (default 1): every variant's seed and every design's randomness.
std::uint64_t read_seed(YamlReader& top) {
  double seed = 1;
  top.optional("seed", seed);
  if (seed < 0 || seed != std::floor(seed) || seed > 9.0e15) top.fail("seed", "must be a whole number >= 0");
  return static_cast<std::uint64_t>(seed);
}
}  // namespace

StudyCriteria read_study_criteria(YamlReader& top, std::uint64_t seed) {
  StudyCriteria c;
  c.file = top.file();
  if (const YAML::Node specs = top.raw("specs")) {
    if (!specs.IsMap()) top.fail("specs", "expected a map of RESPONSE: limit");
    for (const auto& kv : specs) {
      const double x = numeric_value(kv.second);
      if (!std::isfinite(x)) top.fail("specs", "limit of '" + kv.first.as<std::string>() + "' must be a number");
      c.specs[kv.first.as<std::string>()] = x;
      c.spec_lines[kv.first.as<std::string>()] = kv.first.Mark().line + 1;
    }
  }
  c.tolerances = read_tolerances(top);
  for (const Tolerance& t : c.tolerances)
    if (t.statistic == "p_miss" && !c.specs.count(t.metric))
      throw ConfigError(top.file(), t.line, "tolerances." + t.metric + ".statistic",
                        "p_miss needs a spec for " + t.metric + " (specs: {" + t.metric + ": LIMIT})");
  c.requirements = read_requirements(top);
  c.requirements.seed = seed;
  return c;
}

void check_criteria_columns(const StudyCriteria& c, const std::vector<std::string>& columns) {
  for (const auto& [metric, line] : c.spec_lines)
    if (const std::string why = explain_unknown_column(metric, columns); !why.empty())
      throw ConfigError(c.file, line, "specs." + metric, why);
  for (const Tolerance& t : c.tolerances)
    if (const std::string why = explain_unknown_column(t.metric, columns); !why.empty())
      throw ConfigError(c.file, t.line, "tolerances." + t.metric, why);
  check_requirement_columns(c.requirements, columns);
}

StudyCriteria read_study_criteria(const std::string& text, const std::string& source) {
  YamlReader top(load_yaml_text(text, source), source, "", nullptr);
  return read_study_criteria(top, read_seed(top));
}

Study read_study(const std::string& path, int max_variants) {
  Study st;
  st.source = path;
  const YAML::Node doc = load_yaml_file(path);
  st.text = read_text(path);
  YamlReader top(doc, path, "", nullptr);
  if (!doc || doc.IsNull()) top.fail("model", "the file is empty");
  check_not_model(doc, path);
  st.name = std::filesystem::path(path).stem().string();
  top.optional("name", st.name);
  top.optional("description", st.description);
  st.seed = read_seed(top);

  std::string model;
  if (!top.has("model")) top.fail_missing("model", "missing required value (path of the model YAML, relative to this file)");
  top.optional("model", model);
  if (is_blank_path(model)) top.fail("model", "must not be empty or blank (the path of the model YAML)");  // not this directory
  st.model_path = (std::filesystem::path(path).parent_path() / model).lexically_normal().string();
  if (!std::filesystem::exists(st.model_path)) top.fail("model", "model file '" + st.model_path + "' does not exist");
  load_model_file(st.model_path);  // syntax errors name the model file and line
  st.model_text = read_text(st.model_path);
  st.set = read_assignments(top, "set");

  parse_design(st, top, max_variants);
  for (auto& v : st.variants) v.seed = calc_variant_seed(st.seed, static_cast<std::uint64_t>(v.eval_id));

  StudyCriteria criteria = read_study_criteria(top, st.seed);
  st.specs = std::move(criteria.specs);
  st.spec_lines = std::move(criteria.spec_lines);
  st.tolerances = std::move(criteria.tolerances);
  st.requirements = std::move(criteria.requirements);
  if (st.requirements.stop_when_decided && (st.listed || st.design.kind != DesignKind::kMonteCarlo || !st.case_labels.empty()))
    throw ConfigError(path, st.requirements.stop_line, st.requirements.key + ".stop_when_decided",
                      "only for `design: {type: monte_carlo}` without `cases:` (a prefix of another design is not a sample of it)");
  st.keep_traces = st.variants.size() <= 50;
  auto outputs = top.child("outputs");
  outputs.optional("traces", st.keep_traces);
  outputs.finish();
  top.finish();

  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx",
                static_cast<unsigned long long>(fnv1a(st.model_text, fnv1a(st.text))));
  st.hash = hash;
  st.drawn = !st.listed && st.design.kind != DesignKind::kGrid && st.design.kind != DesignKind::kCentered;
  return st;
}

void check_models(Study& st) {
  // What is written in the file is checked now, so a bad value fails before any output exists: every
  // variant when the values are written; when they are drawn, each case's nominal point (its written
  // set, every variable at its median). A draw the model rejects is a result (`invalid`), not an error.
  const std::size_t n = st.drawn ? std::max<std::size_t>(1, st.case_labels.size()) : st.variants.size();
  auto point = [&](std::size_t i) { return st.drawn ? make_nominal_variant(st, i) : st.variants[i]; };
  auto build = [&](std::size_t i) {
    try {
      return make_variant_model(st, point(i));
    } catch (const ConfigError& e) {
      if (!st.drawn) throw;
      throw ConfigError(e.file(), e.line(), e.key(), e.message() + " (at the design's nominal point, every variable at its median)");
    }
  };
  st.arm = is_arm_document(YAML::Load(st.model_text));
  auto build_arm = [&](std::size_t i) {
    try {
      return make_variant_arm(st, point(i));
    } catch (const ConfigError& e) {
      if (!st.drawn) throw;
      throw ConfigError(e.file(), e.line(), e.key(), e.message() + " (at the design's nominal point, every variable at its median)");
    }
  };
  if (st.arm) st.arm_nominal = build_arm(0);
  else st.nominal = build(0);  // variant 0, or case 0's nominal point
  check_criteria_columns({st.specs, st.spec_lines, st.tolerances, st.requirements, st.source},
                         st.arm ? arm_metric_columns(st.arm_nominal)
                                : calc_metric_columns(static_cast<int>(st.nominal.spec.trajectory.moves.size())));
  std::vector<std::exception_ptr> errors(n);
#pragma omp parallel for schedule(dynamic, 8)
  for (std::size_t i = 1; i < n; ++i) {
    try {
      const std::string mismatch = st.arm ? explain_columns_mismatch(st, build_arm(i)) : explain_moves_mismatch(st, build(i));
      if (!mismatch.empty())
        throw std::invalid_argument((st.drawn ? "case " + st.case_labels[i] : "eval_id " + std::to_string(i)) + ": " + mismatch);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  }
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

Study load_study(const std::string& path) {
  Study st = read_study(path);
  check_models(st);  // a bad override fails before any output exists
  return st;
}

std::vector<Assignment> make_variant_set(const Study& study, const Variant& v) {
  // The study's `set:` and its case's are the model the controller knows; a run's and the variables'
  // values change the plant only (Assignment::plant_only; docs/formats.md, "The controller's model").
  std::vector<Assignment> set = study.set;
  if (study.listed) {
    for (Assignment a : study.run_sets[v.eval_id]) {
      a.plant_only = true;
      set.push_back(std::move(a));
    }
    return set;
  }
  std::size_t j0 = 0;  // the first variable's column in v.params
  if (!study.case_labels.empty()) {
    const auto& c = study.case_sets[static_cast<std::size_t>(v.params[0])];
    set.insert(set.end(), c.begin(), c.end());
    j0 = 1;
  }
  for (std::size_t j = 0; j < study.variables.size(); ++j) {
    const std::string& path = study.variables[j].path;
    set.push_back({path, value_node(v.params[j0 + j]), study.source, study.variable_lines[j],
                   "variables[" + std::to_string(j) + "] (" + path + ")", true});
  }
  return set;
}

namespace {
// build(doc) on a copy of the study's model document: parsed once per thread and cloned for each
// variant (parsing the text took ~8 % of a 512-variant run). A clone keeps no line marks, so a variant
// the model rejects is built again from the text, and its error names the line as before.
template <typename Build>
auto build_from_model_text(const Study& study, const Build& build) {
  thread_local std::string text;
  thread_local YAML::Node doc;
  if (text != study.model_text || !doc) {
    doc = YAML::Load(study.model_text);
    text = study.model_text;
  }
  try {
    return build(YAML::Clone(doc));
  } catch (const std::exception&) {
    return build(YAML::Load(study.model_text));
  }
}
}  // namespace

Model make_variant_model(const Study& study, const Variant& v) {
  const std::vector<Assignment> set = make_variant_set(study, v);
  Model m = build_from_model_text(study, [&](YAML::Node doc) { return make_model_with(doc, study.model_path, set); });
  m.spec.simulation.seed = v.seed;  // each variant its own sensor noise
  return m;
}

ArmModel make_variant_arm(const Study& study, const Variant& v) {
  // Each variant its own sensor noise, as the rig's: its seed set last.
  std::vector<Assignment> set = make_variant_set(study, v);
  set.push_back({"simulation.seed", YAML::Node(std::to_string(v.seed)), study.source, 0, "the variant's seed"});
  return build_from_model_text(study, [&](YAML::Node doc) { return make_arm_with(doc, study.model_path, set); });
}

std::string explain_columns_mismatch(const Study& study, const ArmModel& a) {
  if (arm_metric_columns(a) == arm_metric_columns(study.arm_nominal)) return "";
  return study.source + ": its joints or flexible links differ from the study's nominal model's (every variant of a "
                        "study needs the same metric columns)";
}

std::string explain_moves_mismatch(const Study& study, const Model& m) {
  const std::size_t n = m.spec.trajectory.moves.size(), nominal = study.nominal.spec.trajectory.moves.size();
  if (n == nominal) return "";
  auto moves = [](std::size_t k) { return std::to_string(k) + (k == 1 ? " move" : " moves"); };
  return study.source + ": " + moves(n) + " where the study's nominal model has " + moves(nominal) +
         " (every variant of a study needs the same number of moves)";
}

namespace {

// A path's segments: "bodies[forearm].flexible.mass" -> bodies, [forearm], flexible, mass.
std::vector<std::string> path_segments(const std::string& path) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : path) {
    if (c == '.' || c == '[') {
      if (!cur.empty()) out.push_back(cur);
      cur = c == '[' ? "[" : "";
    } else {
      cur += c;
      if (c == ']') out.push_back(cur), cur.clear();
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

}  // namespace

std::string parameter_unit(const Study& study, const std::string& path) {
  std::vector<KeyDoc> keys;
  if (study.arm) {
    for (auto* list : {arm_yaml_keys, tree_yaml_keys, urdf_sidecar_keys})
      for (KeyDoc& k : list()) keys.push_back(std::move(k));
  } else {
    keys = rig_model_keys();
  }
  const std::vector<std::string> p = path_segments(path);
  // [i] in a key stands for any index or name, NAME for any one key; past the key's end one more segment
  // may follow (a vector's element, [2], or a joint of a map of joints, trajectory.start.shoulder), tried
  // after the keys of the whole path.
  for (std::size_t extra : {0, 1})
    for (const KeyDoc& k : keys) {
      const std::vector<std::string> d = path_segments(k.key);
      if (d.empty() || p.size() != d.size() + extra) continue;
      std::string name;  // the joint or body named (the last one): its type picks "rad (m)"'s unit
      bool match = true;
      for (std::size_t i = 0; i < d.size() && match; ++i) {
        if (d[i] == "[i]" && p[i].front() == '[') name = p[i].substr(1, p[i].size() - 2);
        else if (d[i] == "NAME") name = p[i];
        else match = d[i] == p[i];
      }
      if (!match) continue;
      if (extra) name = p.back();
      const auto open = k.unit.find(" (");
      if (open == std::string::npos || !k.unit.ends_with(")")) return k.unit;
      return study.arm && is_prismatic(study.arm_nominal, name) ? k.unit.substr(open + 2, k.unit.size() - open - 3)
                                                                 : k.unit.substr(0, open);
    }
  return "";
}

bool is_prismatic(const ArmModel& m, const std::string& name) {
  for (const ActuatedJoint& j : m.actuated)
    if (j.name == name) return m.tree.body(j.body).joint == JointType::kPrismatic;
  for (const Body& b : m.tree.bodies())
    if (b.name == name) return b.joint == JointType::kPrismatic;
  return false;
}

std::string parameter_axis_label(const Study& study, const std::string& path) {
  const std::string unit = parameter_unit(study, path);
  return unit.empty() ? path : path + " (" + unit + ")";
}

}  // namespace ff
