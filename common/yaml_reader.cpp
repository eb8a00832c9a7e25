#include "common/yaml_reader.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "common/closest.hpp"
#include "common/errors.hpp"
#include "common/text.hpp"

namespace ff {

namespace {
int line_of(const YAML::Node& n) { return n.Mark().is_null() ? 0 : n.Mark().line + 1; }
// The line of `key` itself in `map` (an empty value has no line of its own), else that of its value.
int key_line(const YAML::Node& map, const std::string& key) {
  for (const auto& kv : map)
    if (kv.first.IsScalar() && kv.first.Scalar() == key && line_of(kv.first) > 0) return line_of(kv.first);
  return line_of(map[key]);
}
}  // namespace

YamlReader::YamlReader(const YAML::Node& node, std::string file, std::string path, LineMap* lines)
    : node_(node), file_(std::move(file)), path_(std::move(path)), lines_(lines) {
  if (node_ && !node_.IsNull() && !node_.IsMap())
    throw ConfigError(file_, line_of(node_), path_.empty() ? "<top>" : path_, "expected a map of keys");
}

std::string YamlReader::full_key(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

int YamlReader::line() const { return line_of(node_); }

bool YamlReader::has(const std::string& key) const {
  asked_.insert(key);
  return node_ && node_.IsMap() && node_[key];
}

void YamlReader::fail(const std::string& key, const std::string& message) const {
  const auto full = full_key(key);
  int line = 0;
  if (has(key)) line = key_line(node_, key);
  else if (lines_ && lines_->count(full)) line = lines_->at(full);
  else line = line_of(node_);
  throw ConfigError(file_, line, full, message);
}

void YamlReader::fail_missing(const std::string& key, const std::string& message) const {
  if (node_ && node_.IsMap())
    for (const auto& kv : node_) {
      const std::string k = kv.first.as<std::string>();
      if (!asked_.count(k) && closest_name(k, {key}) == key)
        throw ConfigError(file_, line_of(kv.first), full_key(k), "unknown key (did you mean `" + key + "`?)");
    }
  fail(key, message);
}

YAML::Node YamlReader::value(const std::string& key, bool required) {
  if (!has(key)) {
    if (required) fail_missing(key);
    return YAML::Node(YAML::NodeType::Undefined);
  }
  used_.insert(key);
  YAML::Node v = node_[key];
  if (lines_) (*lines_)[full_key(key)] = key_line(node_, key);
  return v;
}

namespace {
double to_number(const YamlReader& r, const std::string& key, const YAML::Node& v) {
  if (!v.IsScalar()) r.fail(key, "expected a number");
  double x = 0;
  if (!YAML::convert<double>::decode(v, x)) r.fail(key, "expected a number, got '" + v.Scalar() + "'");
  if (!std::isfinite(x)) r.fail(key, "must be a finite number, got '" + v.Scalar() + "'");
  return x;
}
int to_int(const YamlReader& r, const std::string& key, const YAML::Node& v) {
  int x = 0;
  if (!v.IsScalar() || !YAML::convert<int>::decode(v, x))
    r.fail(key, "expected an integer, got '" + (v.IsScalar() ? v.Scalar() : std::string("a non-scalar")) + "'");
  return x;
}
}  // namespace

void YamlReader::optional(const std::string& key, double& out) {
  if (auto v = value(key, false)) out = to_number(*this, key, v);
}
void YamlReader::required(const std::string& key, double& out) { out = to_number(*this, key, value(key, true)); }
void YamlReader::optional(const std::string& key, int& out) {
  if (auto v = value(key, false)) out = to_int(*this, key, v);
}
void YamlReader::required(const std::string& key, int& out) { out = to_int(*this, key, value(key, true)); }

void YamlReader::optional(const std::string& key, bool& out) {
  auto v = value(key, false);
  if (!v) return;
  // true/false (YAML's spellings), or the numbers 1 and 0 that a study's sweep of the flag writes.
  bool x = false;
  double n = -1.0;
  if (v.IsScalar() && YAML::convert<bool>::decode(v, x)) {
    out = x;
  } else if (v.IsScalar() && YAML::convert<double>::decode(v, n) && (n == 0.0 || n == 1.0)) {
    out = n == 1.0;
  } else {
    fail(key, "expected true or false");
  }
}

void YamlReader::optional(const std::string& key, std::string& out) {
  auto v = value(key, false);
  if (!v) return;
  if (!v.IsScalar()) fail(key, "expected a string");
  out = v.Scalar();
}

void YamlReader::optional_array(const std::string& key, double* out, int count) {
  auto v = value(key, false);
  if (!v) return;
  if (v.IsScalar()) {
    const double x = to_number(*this, key, v);
    for (int i = 0; i < count; ++i) out[i] = x;
    return;
  }
  if (!v.IsSequence() || static_cast<int>(v.size()) != count)
    fail(key, "expected a number or a list of " + std::to_string(count) + " numbers");
  for (int i = 0; i < count; ++i) {
    const std::string element = key + "[" + std::to_string(i) + "]";
    if (lines_) (*lines_)[full_key(element)] = line_of(v[i]);  // so an error names the element's line
    out[i] = to_number(*this, element, v[i]);
  }
}

YamlReader YamlReader::child(const std::string& key, bool required) {
  YamlReader r(value(key, required), file_, full_key(key), lines_);
  r.units_check_ = units_check_;
  return r;
}

std::vector<YamlReader> YamlReader::sequence(const std::string& key, bool required) {
  std::vector<YamlReader> out;
  auto v = value(key, required);
  if (!v) return out;
  if (!v.IsSequence()) fail(key, "expected a list");
  for (std::size_t i = 0; i < v.size(); ++i)
    out.emplace_back(v[i], file_, full_key(key) + "[" + std::to_string(i) + "]", lines_).units_check_ = units_check_;
  return out;
}

std::vector<std::pair<std::string, YamlReader>> YamlReader::named_blocks(const std::string& key,
                                                                          const std::string& expected,
                                                                          const char* name_rule) {
  std::vector<std::pair<std::string, YamlReader>> out;
  const YAML::Node v = value(key, false);
  if (!v || v.IsNull()) return out;
  if (!v.IsMap() || v.size() == 0) fail(key, "expected " + expected);
  YamlReader map(v, file_, full_key(key), lines_);
  map.units_check_ = units_check_;
  for (const auto& kv : v) {
    const std::string name = kv.first.as<std::string>();
    if (name_rule && (name.empty() || name.find_first_of(". ,\"") != std::string::npos)) map.fail(name, name_rule);
    out.emplace_back(name, map.child(name));
  }
  return out;
}

template <class Known>
void YamlReader::reject_unknown(Known known, const std::vector<std::string>& valid) const {
  if (!node_ || !node_.IsMap()) return;
  for (const auto& kv : node_) {
    const auto key = kv.first.as<std::string>();
    if (!known(key))
      throw ConfigError(file_, line_of(kv.first), full_key(key), "unknown key" + format_did_you_mean(key, valid));
  }
}

void YamlReader::finish() const {
  reject_unknown([&](const std::string& key) { return used_.count(key) > 0; }, {asked_.begin(), asked_.end()});
}

void YamlReader::only(std::initializer_list<std::string> known) const {
  reject_unknown([&](const std::string& key) { return std::find(known.begin(), known.end(), key) != known.end(); },
                 known);
}

namespace {
// Walks every map and list of a document: a key written twice, a key that is not a plain value, and an
// alias inside the node it names (yaml-cpp makes `&a [*a]` a cycle) are errors. Aliases of aliases can
// make a short file a huge tree: the walk stops past kMaxYamlNodes values.
struct KeyCheck {
  const std::string& file;
  std::vector<YAML::Node> open;  // the maps and lists being walked, outermost first
  long visited = 0;

  void walk(const YAML::Node& n, const std::string& path) {
    if (++visited > kMaxYamlNodes)
      throw ConfigError(file, line_of(n), path,
                        "the document holds more than " + std::to_string(kMaxYamlNodes) + " values (aliases of aliases?)");
    if (!n.IsSequence() && !n.IsMap()) return;
    for (const auto& o : open)
      if (o.is(n)) throw ConfigError(file, line_of(n), path, "an alias inside the list or map it names (a cycle)");
    open.push_back(n);
    if (n.IsSequence()) {
      for (std::size_t i = 0; i < n.size(); ++i) walk(n[i], path + "[" + std::to_string(i) + "]");
    } else {
      std::map<std::string, int> seen;  // key -> line
      for (const auto& kv : n) {
        if (!kv.first.IsScalar())
          throw ConfigError(file, line_of(kv.first), path, "a key must be a plain name, not a list, a map or empty");
        const std::string& key = kv.first.Scalar();
        const std::string full = path.empty() ? key : path + "." + key;
        if (const auto it = seen.find(key); it != seen.end())
          throw ConfigError(file, line_of(kv.first), full,
                            "written twice (lines " + std::to_string(it->second) + " and " + std::to_string(line_of(kv.first)) + ")");
        seen.emplace(key, line_of(kv.first));
        walk(kv.second, full);
      }
    }
    open.pop_back();
  }
};
}  // namespace

void check_unique_keys(const YAML::Node& doc, const std::string& file, const std::string& prefix) {
  KeyCheck{file, {}, 0}.walk(doc, prefix);
}

YAML::Node load_yaml_text(const std::string& text, const std::string& source) {
  YAML::Node doc;
  try {
    doc = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source, e.mark.is_null() ? 0 : e.mark.line + 1, "", yaml_error_message(e));
  }
  check_unique_keys(doc, source);
  return doc;
}

YAML::Node load_yaml_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path, 0, "", "cannot open file");
  std::stringstream text;
  text << in.rdbuf();
  return load_yaml_text(text.str(), path);
}

}  // namespace ff
