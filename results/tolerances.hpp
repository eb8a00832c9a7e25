// A study's `tolerances:` block: by how much each metric may get worse from one run to the next
// before `flexfarm diff` (results/diff.hpp) calls it a regression.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "common/field_table.hpp"
#include "common/yaml_reader.hpp"

namespace ff {

// `tolerances: {METRIC: {increase: X, decrease: X, statistic: mean}}`: by how much a statistic of a
// metric may get worse before a diff calls it a regression. X is in the metric's unit, or "N%" of the
// earlier run's statistic. statistic: mean (default), p5, p50, p95, or p_miss (the share of runs that
// miss the metric's spec: above it, or without a value; the study must have a spec for the metric), or
// not_settled (the share of runs that did not settle).
struct Tolerance {
  std::string metric;
  std::string statistic = "mean";
  double increase = std::numeric_limits<double>::quiet_NaN(), decrease = std::numeric_limits<double>::quiet_NaN();  // NaN: that direction is not a regression
  bool increase_relative = false, decrease_relative = false;  // a fraction of the earlier statistic
  int line = 0;
  std::string describe() const;  // "increase > 0.05", "decrease > 5 %"
};
std::vector<Tolerance> read_tolerances(YamlReader& top);
// The keys of the tolerance block, as docs/formats.md lists them (a test holds the docs to it).
std::vector<KeyDoc> tolerance_keys();

}  // namespace ff
