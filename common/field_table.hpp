// One field table per YAML block: each key of a block written once, with where its value goes, its
// unit, whether it is required, its bound and its default. The readers read, bound and require from
// the table, and list it for docs/formats.md (a test holds the docs to the list).
#pragma once

#include <array>
#include <limits>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "common/files.hpp"  // is_blank_path
#include "common/units_check.hpp"
#include "common/yaml_reader.hpp"
#include <Eigen/Core>

namespace ff {

using Vec3 = Eigen::Vector3d;  // as multibody/spatial.hpp's

// One key of a format as docs/formats.md lists it.
struct KeyDoc {
  std::string key;       // full path, list elements as [i] ("bodies[i].joint.axis")
  std::string unit;      // "" for none
  std::string required;  // "yes" or "no"
  std::string fallback;  // the default ("" when required)
};

// The key that turns the unit checks off, at the top of a model file (YamlReader::read_units_check).
inline const KeyDoc kUnitsCheckKey{"units_check", "", "no", "true"};

// kModulus and kDensity: > 0 and, unless the file turns it off, within any engineering material's range
// (common/units_check.hpp).
enum class Bound { kAny, kNonNegative, kPositive, kNonZero, kModulus, kDensity };

template <class T>
struct Field {
  const char* key;
  std::variant<double T::*, int T::*, bool T::*, Vec3 T::*, std::string T::*> member;
  const char* unit = "";
  bool required = false;
  Bound bound = Bound::kAny;
  bool moving_only = false;        // revolute and prismatic joints only: an error on a fixed joint
  const char* fallback = nullptr;  // the default as the docs write it (a text key's, or a special one)
};

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;  // clang 14 has no CTAD for aggregates

inline std::string format_key_number(double x) {
  if (x == std::numeric_limits<double>::infinity()) return "none";
  if (x == -std::numeric_limits<double>::infinity()) return "none";
  std::ostringstream o;
  o << x;
  return o.str();
}

inline std::string format_key_vector(const Vec3& v) {
  return "[" + format_key_number(v.x()) + ", " + format_key_number(v.y()) + ", " + format_key_number(v.z()) + "]";
}

// A list of exactly three numbers (not YamlReader's one-number-for-all).
inline void read_vec3(YamlReader& r, const std::string& key, Vec3& out) {
  const YAML::Node v = r.raw(key);
  if (!v.IsSequence() || v.size() != 3) r.fail(key, "expected a list of 3 numbers");
  double x[3];
  r.optional_array(key, x, 3);
  out = Vec3(x[0], x[1], x[2]);
}

template <class V>
void check_bound(const YamlReader& r, const char* key, Bound bound, V value) {
  if (bound == Bound::kNonNegative && value < 0)
    r.fail(key, "must be >= 0, got " + format_key_number(static_cast<double>(value)));
  const bool positive = bound == Bound::kPositive || bound == Bound::kModulus || bound == Bound::kDensity;
  if (positive && !(value > 0)) r.fail(key, "must be > 0, got " + format_key_number(static_cast<double>(value)));
  const std::string why = !r.units_check()                ? ""
                          : bound == Bound::kModulus ? explain_modulus_unit(static_cast<double>(value))
                          : bound == Bound::kDensity ? explain_density_unit(static_cast<double>(value))
                                                     : "";
  if (!why.empty()) r.fail(key, why);
}

// Reads the fields present in `r` into `out`, checking their bounds; absent ones keep their defaults.
template <class T, std::size_t N>
void read_present(YamlReader& r, const std::array<Field<T>, N>& fields, T& out) {
  for (const Field<T>& f : fields) {
    if (!r.has(f.key)) continue;
    std::visit(Overloaded{[&](double T::*m) {
                            r.optional(f.key, out.*m);
                            check_bound(r, f.key, f.bound, out.*m);
                          },
                          [&](int T::*m) {
                            r.optional(f.key, out.*m);
                            if (f.bound == Bound::kPositive && out.*m < 1)
                              r.fail(f.key, "must be >= 1, got " + std::to_string(out.*m));
                            check_bound(r, f.key, f.bound, out.*m);
                          },
                          [&](bool T::*m) { r.optional(f.key, out.*m); },
                          [&](Vec3 T::*m) {
                            read_vec3(r, f.key, out.*m);
                            if (f.bound == Bound::kNonZero && (out.*m).norm() == 0.0)
                              r.fail(f.key, "is zero: an axis needs a direction");
                          },
                          [&](std::string T::*m) {
                            r.optional(f.key, out.*m);
                            if (is_blank_path(out.*m)) r.fail(f.key, "must not be empty or blank");  // a path ("  ": no file)
                          }},
               f.member);
  }
}

// Reads the fields in table order as YamlReader's required and optional do, without bounds or checks
// (a reader whose model checks the values later: the reference rig's make_model): a required field
// absent is reported where it comes, before a later field's error.
template <class T, std::size_t N>
void read_unchecked(YamlReader& r, const std::array<Field<T>, N>& fields, T& out) {
  for (const Field<T>& f : fields) r.has(f.key);  // every key of the table valid before one is missed
  for (const Field<T>& f : fields) {
    if (f.required && !r.has(f.key)) r.fail_missing(f.key);
    std::visit(Overloaded{[&](Vec3 T::*m) {
                            if (r.has(f.key)) read_vec3(r, f.key, out.*m);
                          },
                          [&](auto T::*m) { r.optional(f.key, out.*m); }},
               f.member);
  }
}

// YamlReader::only from a table: a key not in it is unknown before any value is read (a misspelt
// required key is then reported as the unknown key it is, not as a missing one).
template <class T, std::size_t N>
void only_keys(const YamlReader& r, const std::array<Field<T>, N>& fields) {
  YamlReader probe = r;
  for (const Field<T>& f : fields) probe.raw(f.key);
  probe.finish();
}

// After finish() (so a misspelt key is reported as unknown, not as the required one it misses).
template <class T, std::size_t N>
void require(const YamlReader& r, const std::array<Field<T>, N>& fields) {
  for (const Field<T>& f : fields)
    if (f.required && !r.has(f.key)) r.fail_missing(f.key);
}

// The table's keys for the docs, under `prefix`, defaults from a default-constructed block.
template <class T, std::size_t N>
void add_keys(std::vector<KeyDoc>& out, const std::string& prefix, const std::array<Field<T>, N>& fields) {
  static const T defaults{};  // static: GCC 12 warns of a local one as maybe uninitialised
  for (const Field<T>& f : fields) {
    std::string fallback;
    if (f.fallback)
      fallback = f.fallback;
    else if (!f.required)
      fallback = std::visit(Overloaded{[&](double T::*m) { return format_key_number(defaults.*m); },
                                       [&](int T::*m) { return std::to_string(defaults.*m); },
                                       [&](bool T::*m) { return std::string(defaults.*m ? "true" : "false"); },
                                       [&](Vec3 T::*m) { return format_key_vector(defaults.*m); },
                                       [&](std::string T::*m) { return defaults.*m; }},
                            f.member);
    out.push_back({prefix + f.key, f.unit, f.required ? "yes" : "no", fallback});
  }
}

}  // namespace ff
