// Reductions of a result table into readable tables: group-by summaries, Monte Carlo statistics
// with confidence intervals and spec misses, sensitivity indices. Pure text; plots live elsewhere.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "results/sensitivity.hpp"
#include "results/statistics.hpp"
#include "results/table.hpp"

namespace ff {

// "" when `name` is a parameter or metric column of t, else why not, with the closest name and the
// names there are (explain_unknown_column).
std::string explain_unknown_name(const ResultTable& t, const std::string& name);

// Values of a parameter or metric column by name; throws std::invalid_argument(explain_unknown_name)
// when it does not exist.
std::vector<double> column_values(const ResultTable& t, const std::string& name);

// The horizons of a censored summary (censoring.hpp) as text, "7.68-9.09" or "8" when they are one,
// 3 significant digits; "" when nothing is censored.
std::string horizon_range(const Summary& s);

// The case of a row of a study with `cases:` (its label up to " | ").
std::string case_label(const std::string& row_label);

// The horizons a metric is right-censored at (censoring.hpp): the values of its horizon column
// (calc_horizon_column) when it is a settling time and the table has that column, else none (a
// table without it: every NaN is missing).
std::vector<double> horizon_values(const ResultTable& t, const std::string& metric);

// One line per group of equal `by` values (all rows when `by` is empty) and metric: count (with a
// value), not settled (NaN with a horizon: right-censored), missing (NaN without one, e.g. a
// diverged run), horizon (the largest of the not-settled ones), mean, min, p5, p50, p95, max as
// calc_summary(values, horizons) (censoring.hpp); with a spec for the metric, the probability of
// missing it (value > limit or NaN: not settled misses) over every row, and its 95 % Wilson interval.
// A statistic above the horizon reads "> H" in Markdown; in CSV its cell holds H and the last
// column, `censored`, names those statistics ("mean" when the mean is the restricted mean), e.g.
// "mean p95 max".
// A `by` column with more than binning.bins distinct values (the default: 10) is grouped by its bins
// (Binning, statistics.hpp; `case`, a label, never is): its key reads as an interval, "[0.5, 1.25)"
// (the last bin closed, "[a, b]"); in CSV that text, then two numeric columns `<name>_lo` and
// `<name>_hi` with the edges (12 significant digits; empty for a NaN key, which stays its own group),
// so a spreadsheet can sort and plot by them. Markdown ends with a line naming each binned column,
// its number of distinct values and bins. An unbinned column prints its values (6 significant digits).
std::string format_groupby_md(const ResultTable& t, const std::vector<std::string>& by,
                              const std::vector<std::string>& metrics, const std::map<std::string, double>& specs,
                              const Binning& binning = {});
std::string format_groupby_csv(const ResultTable& t, const std::vector<std::string>& by,
                               const std::vector<std::string>& metrics, const std::map<std::string, double>& specs,
                               const Binning& binning = {});

// Monte Carlo summary of each metric: runs, not settled (with their horizons), no value, mean, p5,
// p50, p95, each with a 95 % percentile-bootstrap interval (1000 resamples that draw the
// not-settled runs too, deterministic in `seed`), and the miss probability of its spec over every
// run. With not-settled runs the mean is the restricted mean up to the horizon, percentiles are
// Kaplan–Meier ones, "> H (not settled)" above it, and a note under the table says so.
std::string format_monte_carlo_md(const ResultTable& t, const std::vector<std::string>& metrics,
                                  const std::map<std::string, double>& specs, std::uint64_t seed);

// A censored metric as a restricted response min(T, tau) (Royston & Parmar 2013): tau is the smallest
// horizon of the not-settled runs, so every run's restricted value is known exactly (a not-settled
// run's is tau). Values past tau become tau; NaN without a horizon stays NaN (a diverged run). With
// nothing censored, the values as they are and *tau = NaN.
std::vector<double> calc_restricted_values(const ResultTable& t, const std::string& metric, double* tau);

// Sobol' first-order and total indices of each metric from a Saltelli design over `params`. A
// censored metric is taken as its restricted response (calc_restricted_values), keyed
// "METRIC (restricted to TAU s)", so no base point is dropped for a run that did not settle.
std::map<std::string, SobolIndices> calc_sobol_for(const ResultTable& t, const std::vector<std::string>& metrics,
                                                   int nparams, std::uint64_t seed);
std::string format_sobol_md(const std::map<std::string, SobolIndices>& idx, const std::vector<std::string>& params);

// Morris mu*, mu and sigma of each metric, given the design in the unit cube; censored metrics as
// for calc_sobol_for.
std::map<std::string, MorrisIndices> calc_morris_for(const ResultTable& t, const std::vector<std::string>& metrics,
                                                     const std::vector<std::vector<double>>& x_unit);
std::string format_morris_md(const std::map<std::string, MorrisIndices>& idx, const std::vector<std::string>& params);

}  // namespace ff
