#include "sweep/study.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "kernel/errors.hpp"
#include "kernel/model_io.hpp"
#include "kernel/yaml_reader.hpp"

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
    out.push_back({path, YAML::Clone(kv.second), parent.file(), kv.first.Mark().line + 1, parent.full_key(key) + "." + path});
  }
  return out;
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
  std::ifstream model_in(st.model_path);
  std::stringstream text;
  text << model_in.rdbuf();
  st.model_text = text.str();
  load_yaml_file(st.model_path);  // syntax errors name the model file and line
  st.set = read_assignments(top, "set");

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
  std::vector<Assignment> set = study.set;
  set.insert(set.end(), v.set.begin(), v.set.end());
  return make_model_with(YAML::Load(study.model_text), study.model_path, set);
}

}  // namespace ff
