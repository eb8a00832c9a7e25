// What changed between two runs of a study (`flexfarm diff`): the inputs (model and study keys,
// version), each metric's move with a bootstrap test of whether it is beyond Monte Carlo noise
// (paired by variant when both runs drew the same variants), and the regressions: a metric worse by
// more than the study's tolerance and beyond noise, more failed variants, a requirement whose
// verdict got worse.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "results/history.hpp"
#include "results/requirements.hpp"
#include "results/statistics.hpp"
#include "results/table.hpp"
#include "results/tolerances.hpp"

namespace ff {

// One key whose value differs: the dotted path ("beam.damping", "moves[1].to") and its value in each
// (as YAML text; "" when the key is absent there).
struct KeyChange {
  std::string key, a, b;
};
// The keys that differ between two YAML documents, in path order. A text that is not YAML gives one
// change with the key "(document)".
std::vector<KeyChange> diff_yaml_text(const std::string& a, const std::string& b);

// A statistic of a metric in two runs and the bootstrap interval of its change b - a.
struct MetricChange {
  std::string metric, statistic = "mean";  // mean, p5, p50, p95, p_miss, not_settled
  double spec = kStatsNaN;                  // p_miss: the spec
  double a = kStatsNaN, b = kStatsNaN, change = kStatsNaN, lower = kStatsNaN, upper = kStatsNaN;
  int n_a = 0, n_b = 0;     // values used (diverged rows dropped; not settled at the common horizon)
  double horizon = kStatsNaN;  // the common horizon not-settled values are restricted to (NaN: none)
  bool paired = false;      // resampled by variant (the same variants in both runs)
  bool identical = false;   // every value equal
  bool beyond_noise = false;  // the interval excludes 0
  std::string tolerance;    // the tolerance it was held to ("" when none)
  bool regression = false;
};

// The change of `statistic` of `metric` from table a to table b: 1000 percentile-bootstrap resamples
// at `confidence`, deterministic in `seed`; paired (resampling variants) when `paired`. A censored
// metric is compared as its restricted response min(T, tau) with tau the smaller of the two runs'
// least horizons, so not-settled runs count, at tau, in both. Statistic "p_miss": the share of rows
// that miss `spec` (value > spec, or no value: not settled, diverged), every row counted; "not_settled":
// the share of rows not settled (no value, with a horizon).
MetricChange compare_metric(const ResultTable& a, const ResultTable& b, const std::string& metric,
                            const std::string& statistic, bool paired, double confidence, std::uint64_t seed,
                            double spec = kStatsNaN);

// "mean", "p95", or "P(miss: > 3 or no value)".
std::string describe_statistic(const MetricChange& c);

// Whether two tables hold the same variants: the same eval_ids, seeds and parameter values, in order.
bool same_variants(const ResultTable& a, const ResultTable& b);

// A requirement's verdict in each run ("" when the run has none).
struct VerdictChange {
  std::string requirement, a, b;
  bool worse = false;       // pass -> undecided or fail, undecided -> fail
};

struct RunDiff {
  RunRecord a, b;
  std::vector<KeyChange> model, study;  // input keys that differ
  bool paired = false;
  std::vector<MetricChange> metrics;    // every common metric, in b's column order
  std::vector<VerdictChange> verdicts;
  std::vector<std::string> regressions;  // one line each; empty: nothing got worse
};

// The diff of two runs; `tolerances` and `requirements` are the later run's (b's study). The
// requirements are evaluated on both tables, so both runs are held to the same statements (a metric the
// earlier run lacks gives it no verdict); without them, the verdicts each run recorded are compared.
// A metric with a spec (b's study's `specs:`) is compared by its P(miss) too, and a censored one (not
// settled somewhere in either run) by its share not settled.
RunDiff diff_runs(const RunDir& a, const RunDir& b, const std::vector<Tolerance>& tolerances,
                  const RequirementSet& requirements = {}, const std::map<std::string, double>& specs = {},
                  std::uint64_t seed = 1);

// The diff as Markdown: inputs, metrics that have a tolerance or moved beyond noise (and how many did
// not), verdicts, and the regressions (or "nothing got worse").
std::string format_diff_md(const RunDiff& d);

}  // namespace ff
