#include "sweep/study.hpp"

#include <filesystem>

#include "kernel/errors.hpp"
#include "kernel/model_io.hpp"
#include "kernel/yaml_reader.hpp"
#include "sweep/paths.hpp"

namespace ff {

namespace {

// Reads a `set:` map of path -> value.
std::vector<Assignment> read_assignments(YamlReader& parent, const std::string& key) {
  std::vector<Assignment> out;
  const YAML::Node node = parent.raw(key);
  if (!node) return out;
  if (!node.IsMap()) parent.fail(key, "expected a map of PARAMETER.PATH: value");
  for (const auto& kv : node) {
    const auto path = kv.first.as<std::string>();
    out.push_back({path, YAML::Clone(kv.second), kv.first.Mark().line + 1, parent.full_key(key) + "." + path});
  }
  return out;
}

// Applies assignments to a model document, errors pointing at the study line.
void apply(YAML::Node& doc, const std::vector<Assignment>& set, const std::string& source) {
  for (const auto& a : set) {
    try {
      set_path(doc, a.path, a.value, source);
    } catch (const ConfigError& e) {
      throw ConfigError(source, a.line, a.key, e.message());
    }
  }
}

}  // namespace

Study load_study(const std::string& path) {
  Study st;
  st.source = path;
  const YAML::Node doc = load_yaml_file(path);
  YamlReader top(doc, path, "", nullptr);
  if (!doc || doc.IsNull()) top.fail("model", "the file is empty");
  st.name = std::filesystem::path(path).stem().string();
  top.optional("name", st.name);
  top.optional("description", st.description);
  std::string model;
  if (!top.has("model")) top.fail("model", "missing required value (path of the model YAML, relative to this file)");
  top.optional("model", model);
  st.model_path = (std::filesystem::path(path).parent_path() / model).lexically_normal().string();
  if (!std::filesystem::exists(st.model_path)) top.fail("model", "model file '" + st.model_path + "' does not exist");
  st.model_doc = load_yaml_file(st.model_path);
  apply(st.model_doc, read_assignments(top, "set"), path);

  auto runs = top.sequence("runs", true);
  if (runs.empty()) top.fail("runs", "needs at least one run");
  for (std::size_t i = 0; i < runs.size(); ++i) {
    Variant v;
    v.eval_id = static_cast<int>(i);
    v.label = "run " + std::to_string(i);
    runs[i].optional("label", v.label);
    v.set = read_assignments(runs[i], "set");
    runs[i].finish();
    st.variants.push_back(std::move(v));
  }
  top.finish();
  // Build every variant once: a bad override fails now, before any output exists.
  for (const auto& v : st.variants) make_variant_model(st, v);
  return st;
}

Model make_variant_model(const Study& study, const Variant& v) {
  YAML::Node doc = YAML::Clone(study.model_doc);
  apply(doc, v.set, study.source);
  try {
    return parse_model(doc, study.model_path);
  } catch (const ConfigError& e) {
    // An error in a value this run overrides belongs to the study file's line.
    for (const auto& a : v.set)
      if (e.key() == a.path || e.key().rfind(a.path + ".", 0) == 0 || e.key().rfind(a.path + "[", 0) == 0 ||
          a.path.rfind(e.key(), 0) == 0) {
        // Name the exact key: an error below the overridden path (payload: {mass: -1}) keeps its tail.
        const bool below = e.key().size() > a.path.size() && e.key().rfind(a.path, 0) == 0;
        throw ConfigError(study.source, a.line, below ? a.key + e.key().substr(a.path.size()) : a.key, e.message());
      }
    throw;
  }
}

}  // namespace ff
