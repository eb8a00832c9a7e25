#include "sweep/paths.hpp"

#include <cctype>
#include <climits>
#include <memory>
#include <vector>

#include "arm/arm_yaml.hpp"
#include "common/closest.hpp"
#include "common/errors.hpp"
#include "common/text.hpp"
#include "common/yaml_reader.hpp"
#include "kernel/model_io.hpp"

namespace ff {

namespace {

// One step of a path: a map key, a sequence index, or a sequence element by its `name` ([NAME]:
// bodies[forearm] is the element of `bodies` with `name: forearm`).
struct Step {
  std::string key;
  int index = -1;
  std::string name;  // by name when not empty
};

// The index of the element named `name` in a sequence of maps, or -1.
int find_named(const YAML::Node& seq, const std::string& name) {
  if (!seq.IsSequence()) return -1;
  for (std::size_t i = 0; i < seq.size(); ++i)
    if (seq[i].IsMap() && seq[i]["name"] && seq[i]["name"].IsScalar() && seq[i]["name"].Scalar() == name)
      return static_cast<int>(i);
  return -1;
}

// The `name`s of a sequence's elements.
std::vector<std::string> list_names(const YAML::Node& seq) {
  std::vector<std::string> out;
  if (seq.IsSequence())
    for (const auto& e : seq)
      if (e.IsMap() && e["name"] && e["name"].IsScalar()) out.push_back(e["name"].Scalar());
  return out;
}

std::vector<Step> split_path(const std::string& path, const std::string& source) {
  std::vector<Step> steps;
  std::size_t i = 0;
  auto bad = [&](const std::string& why) { throw ConfigError(source, 0, path, "bad parameter path: " + why); };
  if (path.empty()) bad("empty");
  while (i < path.size()) {
    if (path[i] == '[') {
      const auto close = path.find(']', i);
      if (close == std::string::npos || close == i + 1) bad("unclosed or empty [ ]");
      const std::string digits = path.substr(i + 1, close - i - 1);
      bool number = true;
      for (char c : digits) number &= std::isdigit(static_cast<unsigned char>(c)) != 0;
      const bool name = std::isalpha(static_cast<unsigned char>(digits[0])) || digits[0] == '_';
      if (!number && !name) bad("index '" + digits + "' is neither a number nor a name");
      if (number) {
        // An index past any list's length (int's range included) names no element.
        const auto index = parse_integer(digits, 0, INT_MAX);
        if (!index) throw ConfigError(source, 0, path, "index [" + digits + "] is not in the list");
        steps.push_back({"", static_cast<int>(*index), ""});
      } else {
        steps.push_back({"", -1, digits});
      }
      i = close + 1;
      if (i < path.size() && path[i] == '.') ++i;
      continue;
    }
    std::size_t end = i;
    while (end < path.size() && path[end] != '.' && path[end] != '[') ++end;
    if (end == i) bad("empty key");
    steps.push_back({path.substr(i, end - i), -1, ""});
    i = end;
    if (i < path.size() && path[i] == '.') ++i;
  }
  return steps;
}

}  // namespace

std::string set_path(YAML::Node& doc, const std::string& path, const YAML::Node& value, const std::string& source) {
  const auto steps = split_path(path, source);
  std::string resolved;  // the path with each [NAME] as its index
  YAML::Node node = doc;  // yaml-cpp nodes are handles: walking reassigns the handle, not the value
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const bool last = s + 1 == steps.size();
    Step st = steps[s];
    if (!st.name.empty()) {
      st.index = find_named(node, st.name);
      if (st.index < 0)
        throw ConfigError(source, 0, path, "no element of the list is named '" + st.name + "'" + format_did_you_mean(st.name, list_names(node)));
    }
    if (st.index >= 0) {
      if (!node.IsSequence() || st.index >= static_cast<int>(node.size()))
        throw ConfigError(source, 0, path, "index [" + std::to_string(st.index) + "] is not in the list");
      resolved += "[" + std::to_string(st.index) + "]";
      if (last) {
        node[st.index] = YAML::Clone(value);  // a fresh copy: assigning shared nodes merges their documents
        return resolved;
      }
      YAML::Node next = node[st.index];
      node.reset(next);
    } else {
      if (node.IsDefined() && !node.IsMap() && !node.IsNull())
        throw ConfigError(source, 0, path, "'" + st.key + "' is inside a value that is not a map");
      resolved += (resolved.empty() ? "" : ".") + st.key;
      if (last) {
        node[st.key] = YAML::Clone(value);
        return resolved;
      }
      YAML::Node next = node[st.key];
      node.reset(next);
    }
  }
  return resolved;
}

YAML::Node get_path(const YAML::Node& doc, const std::string& path) {
  YAML::Node node = YAML::Clone(doc);
  for (Step st : split_path(path, "<path>")) {
    if (!st.name.empty() && (st.index = find_named(node, st.name)) < 0) return YAML::Node();
    if (st.index >= 0) {
      if (!node.IsSequence() || st.index >= static_cast<int>(node.size())) return YAML::Node();
      YAML::Node next = node[st.index];
      node.reset(next);
    } else {
      if (!node.IsMap() || !node[st.key]) return YAML::Node();
      YAML::Node next = node[st.key];
      node.reset(next);
    }
  }
  return node;
}

Assignment parse_assignment(const std::string& text, bool plant_only) {
  const std::string option = plant_only ? "--plant-set" : "--set";
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ConfigError(option, 0, text, "expected PATH=VALUE, e.g. payload.mass=400");
  Assignment a;
  a.path = text.substr(0, eq);
  a.source = option;
  a.key = a.path;
  a.plant_only = plant_only;
  try {
    a.value = YAML::Load(text.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw ConfigError(option, 0, a.path, "value is not valid YAML: " + yaml_error_message(e));
  }
  check_unique_keys(a.value, option, a.path);
  split_path(a.path, option);  // reject a malformed path now
  return a;
}

bool is_controller_path(const std::string& path) {
  const auto steps = split_path(path, "<path>");
  static const char* const top[] = {"controller", "notch", "shaper", "sensors", "trajectory", "simulation", "monitors", "metrics"};
  for (const char* t : top)
    if (steps[0].key == t) return true;
  // An arm joint's own controller blocks: joints.NAME.{controller, notch, shaper, sensors}[...] (the rig's
  // joints.stiffness ... are its beam's).
  static const char* const joint[] = {"controller", "notch", "shaper", "sensors"};
  if (steps[0].key == "joints" && steps.size() >= 3)
    for (const char* t : joint)
      if (steps[2].key == t) return true;
  return false;
}

namespace {
// The assignment an error key falls under (the same path, one below it, or one above it), by its path
// as written or as resolved (bodies[beam] as bodies[0], as the parser names it), and the path matched;
// {null, ""} when none.
std::pair<const Assignment*, std::string> owner_of(const std::string& key, const std::vector<Assignment>& set,
                                                   const std::vector<std::string>& resolved) {
  for (std::size_t i = set.size(); i-- > 0;)  // the last assignment wins
    for (const std::string& p : {set[i].path, resolved[i]})
      if (key == p || key.rfind(p + ".", 0) == 0 || key.rfind(p + "[", 0) == 0 || p.rfind(key + ".", 0) == 0 ||
          p.rfind(key + "[", 0) == 0)
        return {&set[i], p};
  return {nullptr, ""};
}
}  // namespace

// Applies the assignments to `doc` and parses it with `parse(doc, source)`, naming an error in an
// assigned value where it was assigned.
template <class Parse>
auto parse_set(YAML::Node doc, const std::string& model_source, const std::vector<Assignment>& set, Parse parse) {
  std::vector<std::string> resolved;
  for (const auto& a : set) {
    try {
      resolved.push_back(set_path(doc, a.path, a.value, a.source));
    } catch (const ConfigError& e) {
      throw ConfigError(a.source, a.line, a.key, e.message());
    }
  }
  try {
    return parse(doc, model_source);
  } catch (const ConfigError& e) {
    const auto [a, path] = owner_of(e.key(), set, resolved);
    if (!a) throw;
    // Name the exact key: an error below the assigned path (payload: {mass: -1}) keeps its tail.
    const bool below = e.key().size() > path.size() && e.key().rfind(path, 0) == 0;
    throw ConfigError(a->source, a->line, below ? a->key + e.key().substr(path.size()) : a->key, e.message());
  }
}

namespace {
// The assignments that reach the controller's model: all but the plant-only ones outside its paths.
std::vector<Assignment> controller_assignments(const std::vector<Assignment>& set) {
  std::vector<Assignment> out;
  for (const Assignment& a : set)
    if (!a.plant_only || is_controller_path(a.path)) out.push_back(a);
  return out;
}

// The controller's models of the last documents built, per thread (diagnose's trial builds, a study's
// variants: the same document and controller-side assignments each time), by document and assignments.
template <class T>
struct NominalCache {
  std::vector<std::pair<std::string, std::shared_ptr<const T>>> entries;  // newest last
  static constexpr std::size_t kSize = 8;
  std::shared_ptr<const T> find(const std::string& key) const {
    for (const auto& [k, v] : entries)
      if (k == key) return v;
    return nullptr;
  }
  void put(std::string key, std::shared_ptr<const T> v) {
    if (entries.size() == kSize) entries.erase(entries.begin());
    entries.emplace_back(std::move(key), std::move(v));
  }
};

std::string nominal_key(const YAML::Node& doc, const std::string& model_source, const std::vector<Assignment>& set) {
  std::string key = model_source + '\n' + YAML::Dump(doc);
  for (const Assignment& a : set) key += '\n' + a.path + '=' + YAML::Dump(a.value);
  return key;
}

// Builds the plant of `doc` with `set` by parse(doc, source, controller): with plant-only assignments
// outside the controller's paths and the controller's model nominal (not plant_controlled), the
// controller is the model built without them; else null (the plant's own).
template <class T, class Parse, class PlantControlled>
T parse_with(YAML::Node doc, const std::string& model_source, const std::vector<Assignment>& set, Parse parse,
             PlantControlled plant_controlled) {
  auto with = [&](std::shared_ptr<const T> controller) {
    return [&parse, controller](const YAML::Node& d, const std::string& source) { return parse(d, source, controller); };
  };
  const std::vector<Assignment> control = controller_assignments(set);
  if (control.size() == set.size()) return parse_set(doc, model_source, set, with(nullptr));
  thread_local NominalCache<T> cache;
  std::string key = nominal_key(doc, model_source, control);
  std::shared_ptr<const T> nominal = cache.find(key);
  if (!nominal) {
    try {
      nominal = std::make_shared<const T>(parse_set(YAML::Clone(doc), model_source, control, with(nullptr)));
    } catch (const ConfigError&) {
      parse_set(doc, model_source, set, with(nullptr));  // the same error with its line in the file (a clone has none)
      throw;
    }
    cache.put(std::move(key), nominal);
  }
  return parse_set(doc, model_source, set, with(plant_controlled(*nominal) ? nullptr : nominal));
}
}  // namespace

Model make_model_with(YAML::Node doc, const std::string& model_source, const std::vector<Assignment>& set) {
  return parse_with<Model>(
      doc, model_source, set,
      [](const YAML::Node& d, const std::string& s, const std::shared_ptr<const Model>& c) { return parse_model(d, s, c.get()); },
      [](const Model& m) { return m.spec.controller.model == "plant"; });
}

ArmModel make_arm_with(YAML::Node doc, const std::string& model_source, const std::vector<Assignment>& set) {
  return parse_with<ArmModel>(
      doc, model_source, set,
      [](const YAML::Node& d, const std::string& s, const std::shared_ptr<const ArmModel>& c) { return parse_arm(d, s, c); },
      [](const ArmModel& m) { return m.spec.controller_model == "plant"; });
}

namespace {
std::vector<Assignment> parse_assignments(const std::vector<std::string>& sets, const std::vector<std::string>& plant_sets = {}) {
  std::vector<Assignment> out;
  for (const auto& s : sets) out.push_back(parse_assignment(s));
  for (const auto& s : plant_sets) out.push_back(parse_assignment(s, true));
  return out;
}
}  // namespace

namespace {
// The line of a top-level key itself (a block's value starts on the next).
int line_of_key(const YAML::Node& doc, const char* key) {
  for (const auto& kv : doc)
    if (kv.first.IsScalar() && kv.first.Scalar() == key && !kv.first.Mark().is_null()) return kv.first.Mark().line + 1;
  return 0;
}
}  // namespace

YAML::Node load_model_file(const std::string& path) {
  YAML::Node doc = load_yaml_file(path);
  if (doc.IsMap() && doc["model"] && !doc["beam"] && !is_arm_document(doc))
    throw ConfigError(path, line_of_key(doc, "model"), "model",
                      "this is a study file (it names a `model:`), not a model: run it with `flexfarm run " + path +
                          " --out DIR`; this verb takes a model file (the rig's `beam:` or an arm's `bodies:`/`urdf:`)");
  // A URDF sidecar: `joints` or `links` by name and none of a rig's other blocks.
  const bool sidecar = doc.IsMap() && (doc["links"] || doc["joints"]) && !doc["beam"] && !doc["segments"] &&
                       !doc["payload"] && !doc["hub"] && !is_arm_document(doc);
  if (sidecar)
    throw ConfigError(path, line_of_key(doc, doc["links"] ? "links" : "joints"), "",
                      "this is a URDF sidecar, not a model: give it with its URDF (`flexfarm modes ROBOT.urdf --sidecar " +
                          path + "`) or as an arm model's `sidecar:`");
  return doc;
}

void check_not_model(const YAML::Node& doc, const std::string& path) {
  if (!doc.IsMap() || doc["model"]) return;
  const char* key = doc["beam"] ? "beam" : doc["bodies"] ? "bodies" : doc["urdf"] ? "urdf" : nullptr;
  if (key)
    throw ConfigError(path, line_of_key(doc, key), "",
                      std::string("this is a model file (it has `") + key + ":`), not a study: simulate it with " +
                          "`flexfarm simulate " + path + " --out DIR` (or `flexfarm modes " + path +
                          "`); `flexfarm run` takes a study file, whose `model:` names a model file");
}

// Not build_model: YAML::Clone drops the line marks an error in the file is reported at.
Model load_model_with(const std::string& path, const std::vector<std::string>& sets, const std::vector<std::string>& plant_sets) {
  return make_model_with(load_model_file(path), path, parse_assignments(sets, plant_sets));
}

ModelSource load_model_source(const std::string& path, const std::vector<std::string>& sets) {
  YAML::Node doc = load_model_file(path);
  ModelSource src{YAML::Clone(doc), path, parse_assignments(sets)};
  make_model_with(doc, path, src.set);  // on the document as read, so that an error names its line
  return src;
}

ArmModel load_arm_with(const std::string& path, const std::vector<std::string>& sets, const std::vector<std::string>& plant_sets) {
  return make_arm_with(load_model_file(path), path, parse_assignments(sets, plant_sets));
}

ModelSource load_arm_source(const std::string& path, const std::vector<std::string>& sets) {
  YAML::Node doc = load_model_file(path);
  ModelSource src{YAML::Clone(doc), path, parse_assignments(sets)};
  make_arm_with(doc, path, src.set);  // on the document as read, so that an error names its line
  return src;
}

ArmModel build_arm(const ModelSource& src, const std::vector<Assignment>& extra) {
  std::vector<Assignment> all = src.set;
  all.insert(all.end(), extra.begin(), extra.end());
  return make_arm_with(YAML::Clone(src.doc), src.path, all);
}

bool is_arm_model_file(const std::string& path) {
  try {
    return is_arm_document(load_model_file(path));
  } catch (const std::exception&) {
    return false;
  }
}

YAML::Node apply_overrides(const ModelSource& src) {
  YAML::Node doc = YAML::Clone(src.doc);
  for (const auto& a : src.set) set_path(doc, a.path, a.value, "--set");
  return doc;
}

Model build_model(const ModelSource& src, const std::vector<Assignment>& extra) {
  std::vector<Assignment> all = src.set;
  all.insert(all.end(), extra.begin(), extra.end());
  return make_model_with(YAML::Clone(src.doc), src.path, all);
}

}  // namespace ff
