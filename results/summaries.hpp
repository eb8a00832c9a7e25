// Reductions of a result table into readable tables: group-by summaries, Monte Carlo statistics
// with confidence intervals and spec misses, sensitivity indices. Pure text; plots live elsewhere.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "results/sensitivity.hpp"
#include "results/table.hpp"

namespace ff {

// Values of a parameter or metric column by name; throws std::invalid_argument naming the column
// and the columns there are when it does not exist.
std::vector<double> column_values(const ResultTable& t, const std::string& name);

// The case of a row of a study with `cases:` (its label up to " | ").
std::string case_label(const std::string& row_label);

// One line per group of equal `by` values (all rows when `by` is empty) and metric: count,
// missing (NaN: e.g. not settled), mean, min, p5, p50, p95, max; with a spec for the metric, the
// probability of missing it (value > limit or NaN) and its 95 % Wilson interval.
std::string format_groupby_md(const ResultTable& t, const std::vector<std::string>& by,
                              const std::vector<std::string>& metrics, const std::map<std::string, double>& specs);
std::string format_groupby_csv(const ResultTable& t, const std::vector<std::string>& by,
                               const std::vector<std::string>& metrics, const std::map<std::string, double>& specs);

// Monte Carlo summary of each metric: mean, p5, p50, p95, each with a 95 % percentile-bootstrap
// interval (1000 resamples, deterministic in `seed`), and the miss probability of its spec.
std::string format_monte_carlo_md(const ResultTable& t, const std::vector<std::string>& metrics,
                                  const std::map<std::string, double>& specs, std::uint64_t seed);

// Sobol' first-order and total indices of each metric from a Saltelli design over `params`.
std::map<std::string, SobolIndices> calc_sobol_for(const ResultTable& t, const std::vector<std::string>& metrics,
                                                   int nparams, std::uint64_t seed);
std::string format_sobol_md(const std::map<std::string, SobolIndices>& idx, const std::vector<std::string>& params);

// Morris mu*, mu and sigma of each metric, given the design in the unit cube.
std::map<std::string, MorrisIndices> calc_morris_for(const ResultTable& t, const std::vector<std::string>& metrics,
                                                     const std::vector<std::vector<double>>& x_unit);
std::string format_morris_md(const std::map<std::string, MorrisIndices>& idx, const std::vector<std::string>& params);

}  // namespace ff
