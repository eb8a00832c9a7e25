// Strict reading of YAML maps: every key must be known, every value of the right type and finite.
// Errors name the file, the line and the full key path (e.g. "configs/fbtb.yaml:12: payload.mass: ...").
#pragma once

#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace ff {

// Line numbers (1-based) of every key path read, so later validation can point at the line.
using LineMap = std::map<std::string, int>;

class YamlReader {
 public:
  YamlReader(const YAML::Node& node, std::string file, std::string path, LineMap* lines);

  bool has(const std::string& key) const;
  // Optional values: leave `out` untouched when the key is absent.
  void optional(const std::string& key, double& out);
  void optional(const std::string& key, int& out);
  void optional(const std::string& key, bool& out);
  void optional(const std::string& key, std::string& out);
  // Required values: absent key is an error.
  void required(const std::string& key, double& out);
  void required(const std::string& key, int& out);
  // A list of numbers, or one number meaning "all `count` entries".
  void optional_array(const std::string& key, double* out, int count);
  // A nested map (absent: an empty reader, so optional children keep their defaults).
  YamlReader child(const std::string& key, bool required = false);
  // The raw node of a key (null when absent), marked as read.
  YAML::Node raw(const std::string& key) { return has(key) ? value(key, false) : YAML::Node(YAML::NodeType::Undefined); }
  // Elements of a sequence of maps.
  std::vector<YamlReader> sequence(const std::string& key, bool required = false);
  // The entries of a map of named blocks (`tools: {NAME: {body, point}}`), in file order: each name and
  // its block's reader. Absent or null: none; not a map, or empty: the error "expected <expected>".
  // With `name_rule`, a name that heads columns: empty or with a dot, space, comma or quote is that error.
  std::vector<std::pair<std::string, YamlReader>> named_blocks(const std::string& key, const std::string& expected,
                                                               const char* name_rule = nullptr);
  // Throws for any key that was not read, naming the closest key asked for ("did you mean").
  void finish() const;
  // Throws for any key not in `known`, before they are read: a misspelt required key is then reported
  // as the unknown key it is rather than as a missing one.
  void only(std::initializer_list<std::string> known) const;

  // Whether values whose unit is easily mistaken are checked (common/units_check.hpp); the readers of
  // its children inherit it. read_units_check: the map's own `units_check: false` turns it off.
  bool units_check() const { return units_check_; }
  void read_units_check() { optional("units_check", units_check_); }

  [[noreturn]] void fail(const std::string& key, const std::string& message) const;
  // A required `key` is absent: an unknown key of the map within a typo of it is reported as that
  // unknown key ("did you mean `key`?"), else `message` for `key`.
  [[noreturn]] void fail_missing(const std::string& key, const std::string& message = "missing required value") const;
  const std::string& file() const { return file_; }
  std::string full_key(const std::string& key) const;
  int line() const;

 private:
  // The value of `key` (marked as read); an absent required key is an error.
  YAML::Node value(const std::string& key, bool required);
  // Throws "unknown key" for the first key of the map that `known` rejects.
  template <class Known>
  void reject_unknown(Known known, const std::vector<std::string>& valid) const;
  YAML::Node node_;
  std::string file_;
  std::string path_;
  LineMap* lines_;
  std::set<std::string> used_;
  mutable std::set<std::string> asked_;
  bool units_check_ = true;  // every key has() was asked about: the valid names for "did you mean"
};

// The most values (scalars, lists and maps, aliases counted again) a document may hold.
inline constexpr long kMaxYamlNodes = 1000000;

// Loads a YAML file, turning parse errors into ConfigError with the file and line, and a key written
// twice in one map into one naming both lines (check_unique_keys).
YAML::Node load_yaml_file(const std::string& path);
// The same for YAML text; errors name `source`.
YAML::Node load_yaml_text(const std::string& text, const std::string& source);
// The checks of every loaded document, alone (for YAML parsed from elsewhere, e.g. a --set value):
// no key written twice in one map, every key a plain name, no alias inside the node it names, at most
// kMaxYamlNodes values. `prefix`: the path the document sits under, for the error's key.
void check_unique_keys(const YAML::Node& doc, const std::string& file, const std::string& prefix = "");

}  // namespace ff
