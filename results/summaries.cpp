#include "results/summaries.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "results/censoring.hpp"
#include "results/run_metrics.hpp"
#include "results/statistics.hpp"
#include "common/text.hpp"

namespace ff {

namespace {

std::string num(double x, const char* f = "%.4g") { return format_cell(x, f); }

std::string join(const std::vector<std::string>& cells, const char* sep) {
  std::string out;
  for (std::size_t i = 0; i < cells.size(); ++i) out += (i ? sep : "") + cells[i];
  return out;
}

// A statistic of a censored response (censoring.hpp): +inf lies above the horizon, "> H".
bool above_horizon(double x) { return x == std::numeric_limits<double>::infinity(); }
std::string bound(double x, double horizon) { return above_horizon(x) ? "> " + num(horizon) : num(x); }

}  // namespace

std::string horizon_range(const Summary& s) {
  if (s.censored == 0) return "";
  return (s.horizon_min < s.horizon ? num(s.horizon_min, "%.3g") + "-" : "") + num(s.horizon, "%.3g");
}

std::string case_label(const std::string& row_label) { return row_label.substr(0, row_label.find(" | ")); }

namespace {

// The rows of each group, and the group's key as text (a case by its label).
struct GroupRows {
  std::vector<std::string> key;
  std::vector<int> rows;
};

// A `by` column: its bin edges (none: not binned) and their text, with the fewest significant digits
// from 6 on that tell every two edges apart.
struct ByColumn {
  std::string name;
  std::vector<double> values, edges;
  std::vector<std::string> edge_text;
  int levels = 0;  // distinct finite keys of a binned column
};

ByColumn by_column(const ResultTable& t, const std::string& name, const Binning& binning) {
  ByColumn c{name, column_values(t, name), {}, {}, 0};
  if (name == "case") return c;  // a label, never binned
  c.edges = calc_bin_edges(c.values, binning);
  for (int digits = 6; !c.edges.empty() && digits <= 17; ++digits) {
    c.edge_text.clear();
    for (double e : c.edges) c.edge_text.push_back(num(e, ("%." + std::to_string(digits) + "g").c_str()));
    if (std::adjacent_find(c.edge_text.begin(), c.edge_text.end()) == c.edge_text.end()) break;
  }
  if (!c.edges.empty()) {
    std::vector<Group> levels = make_groups({c.values});
    c.levels = static_cast<int>(std::count_if(levels.begin(), levels.end(), [](const Group& g) { return std::isfinite(g.key[0]); }));
  }
  return c;
}

// The key cells of a group in column c, whose key (a value, or a bin from calc_bin_key) is `key`: the
// value, or the bin as an interval "[a, b)" ("[a, b]" the last one), in CSV followed by its two edges
// (`<name>_lo`, `<name>_hi`; NaN and +-inf keys: "-" there).
void add_key_cells(const ByColumn& c, double key, const std::string& row_label, bool csv, std::vector<std::string>* cells) {
  if (c.name == "case") {
    cells->push_back(case_label(row_label));
    return;
  }
  if (c.edges.empty()) {
    cells->push_back(num(key, "%.6g"));
    return;
  }
  if (!std::isfinite(key)) {
    cells->push_back(num(key, "%.6g"));
    if (csv) cells->insert(cells->end(), 2, "-");
    return;
  }
  const auto i = static_cast<std::size_t>(key);
  const bool last = i + 2 == c.edges.size();
  cells->push_back("[" + c.edge_text[i] + ", " + c.edge_text[i + 1] + (last ? "]" : ")"));
  if (csv) {
    cells->push_back(num(c.edges[i], "%.12g"));
    cells->push_back(num(c.edges[i + 1], "%.12g"));
  }
}

// The groups of the table by `by` (all rows when it is empty), each column binned as `binning` says;
// *head gets the key columns' names (a binned one's in CSV with its `_lo` and `_hi`), *notes names each
// binned column with its number of values and bins.
std::vector<GroupRows> group_rows(const ResultTable& t, const std::vector<std::string>& by, const Binning& binning,
                                  bool csv, std::vector<std::string>* head, std::string* notes) {
  std::vector<GroupRows> out;
  if (by.empty()) {
    GroupRows all;
    for (int i = 0; i < static_cast<int>(t.rows.size()); ++i) all.rows.push_back(i);
    out.push_back(all);
    return out;
  }
  std::vector<ByColumn> cols;
  std::vector<std::vector<double>> keys;
  for (const auto& b : by) {
    cols.push_back(by_column(t, b, binning));
    const ByColumn& c = cols.back();
    head->push_back(b);
    if (c.edges.empty()) {
      keys.push_back(c.values);
      continue;
    }
    if (csv) {
      head->push_back(b + "_lo");
      head->push_back(b + "_hi");
    }
    std::vector<double> bin(c.values.size());
    for (std::size_t r = 0; r < bin.size(); ++r) bin[r] = calc_bin_key(c.edges, c.values[r]);
    keys.push_back(bin);
    *notes += (notes->empty() ? "" : "; ") + b + " (" + std::to_string(c.levels) + " values) in " +
              std::to_string(c.edges.size() - 1) +
              (binning.kind == Binning::kQuantile ? " quantile bins (about equal numbers of rows)" : " equal-width bins");
  }
  for (const auto& g : make_groups(keys)) {
    GroupRows gr;
    for (std::size_t i = 0; i < by.size(); ++i) add_key_cells(cols[i], g.key[i], t.rows[g.rows[0]].label, csv, &gr.key);
    gr.rows = g.rows;
    out.push_back(gr);
  }
  return out;
}

// The cells of one group and metric: count, not settled, missing, horizon, mean, min, p5, p50, p95, max,
// [miss, interval]; statistics above the horizon as "> H" (Markdown), or in CSV as the number H with
// their names in a last cell `censored` (the mean too when it is the restricted mean).
std::vector<std::string> summary_cells(const std::vector<double>& v, const std::vector<double>& h,
                                       const std::map<std::string, double>& specs, const std::string& metric, bool csv) {
  const Summary s = calc_summary(v, h);
  // With runs not settled the mean is the restricted mean, a lower bound of the mean: "> x" (CSV: the
  // number, "mean" in the `censored` cell).
  std::vector<std::string> c = {std::to_string(s.count), std::to_string(s.censored), std::to_string(s.missing),
                                num(s.horizon), s.censored > 0 && !csv ? "> " + num(s.mean) : num(s.mean)};
  std::string censored = s.censored > 0 ? "mean" : "";
  const std::pair<const char*, double> stats[] = {{"min", s.min}, {"p5", s.p5}, {"p50", s.p50}, {"p95", s.p95}, {"max", s.max}};
  for (const auto& [name, x] : stats) {
    c.push_back(csv && above_horizon(x) ? num(s.horizon) : bound(x, s.horizon));
    if (above_horizon(x)) censored += std::string(censored.empty() ? "" : " ") + name;
  }
  auto spec = specs.find(metric);
  if (spec != specs.end()) {
    const Interval m = calc_miss_probability(v, spec->second, 0.95);
    c.push_back(num(m.estimate, "%.3f"));
    c.push_back("[" + num(m.lower, "%.3f") + ", " + num(m.upper, "%.3f") + "]");
  } else {
    c.push_back("");
    c.push_back("");
  }
  if (csv) c.push_back(censored);
  return c;
}

template <class Row>
std::string groupby(const ResultTable& t, const std::vector<std::string>& by, const std::vector<std::string>& metrics,
                    const std::map<std::string, double>& specs, const Binning& binning, bool csv, Row row) {
  std::vector<std::string> head;
  std::string notes;
  const std::vector<GroupRows> groups = group_rows(t, by, binning, csv, &head, &notes);
  for (const char* h : {"metric", "count", "not settled", "missing", "horizon", "mean", "min", "p5", "p50", "p95", "max",
                        "P(miss spec)", "95% CI"})
    head.push_back(h);
  if (csv) head.push_back("censored");
  std::string out = row(head, true);
  std::vector<std::vector<double>> cols, horizons;
  for (const auto& m : metrics) {
    cols.push_back(column_values(t, m));
    horizons.push_back(horizon_values(t, m));
  }
  for (const auto& g : groups) {
    for (std::size_t k = 0; k < metrics.size(); ++k) {
      std::vector<double> v, h;
      for (int r : g.rows) v.push_back(cols[k][r]);
      if (!horizons[k].empty())
        for (int r : g.rows) h.push_back(horizons[k][r]);
      std::vector<std::string> cells = g.key;
      cells.push_back(metrics[k]);
      for (auto& c : summary_cells(v, h, specs, metrics[k], csv)) cells.push_back(c);
      out += row(cells, false);
    }
  }
  if (!csv && !notes.empty())
    out += "\nBinned: " + notes + "; [a, b) holds a <= value < b, the last bin [a, b] its upper end too.\n";
  return out;
}

}  // namespace

std::string explain_unknown_name(const ResultTable& t, const std::string& name) {
  std::vector<std::string> names = t.params;
  names.insert(names.end(), t.columns.begin(), t.columns.end());
  return explain_unknown_column(name, names, "a parameter or result column", "the parameters and columns");
}

std::vector<double> column_values(const ResultTable& t, const std::string& name) {
  std::vector<double> out;
  for (std::size_t c = 0; c < t.params.size(); ++c)
    if (t.params[c] == name) {
      for (const auto& r : t.rows) out.push_back(r.params[c]);
      return out;
    }
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    if (t.columns[c] == name) {
      for (const auto& r : t.rows) out.push_back(r.values[c]);
      return out;
    }
  throw std::invalid_argument(explain_unknown_name(t, name));
}

std::vector<double> horizon_values(const ResultTable& t, const std::string& metric) {
  const std::string h = calc_horizon_column(metric);
  if (h.empty() || std::find(t.columns.begin(), t.columns.end(), h) == t.columns.end()) return {};
  return column_values(t, h);
}

std::string format_groupby_md(const ResultTable& t, const std::vector<std::string>& by,
                              const std::vector<std::string>& metrics, const std::map<std::string, double>& specs,
                              const Binning& binning) {
  return groupby(t, by, metrics, specs, binning, false, [](const std::vector<std::string>& cells, bool header) {
    std::string line = "|";
    for (const std::string& c : cells) line += " " + md_cell(c) + " |";
    line += "\n";
    if (header) {
      line += "|";
      for (std::size_t i = 0; i < cells.size(); ++i) line += "---|";
      line += "\n";
    }
    return line;
  });
}

std::string format_groupby_csv(const ResultTable& t, const std::vector<std::string>& by,
                               const std::vector<std::string>& metrics, const std::map<std::string, double>& specs,
                               const Binning& binning) {
  return groupby(t, by, metrics, specs, binning, true, [](const std::vector<std::string>& cells, bool) {
    std::vector<std::string> quoted;
    for (const auto& c : cells)  // no number: an empty cell
      quoted.push_back(c == "-" ? std::string() : c.find_first_of(", ") != std::string::npos ? "\"" + c + "\"" : c);
    return join(quoted, ",") + "\n";
  });
}

std::string format_monte_carlo_md(const ResultTable& t, const std::vector<std::string>& metrics,
                                  const std::map<std::string, double>& specs, std::uint64_t seed) {
  std::string out =
      "| metric | runs | not settled | no value | mean [95% CI] | p5 [95% CI] | p50 [95% CI] | p95 [95% CI] | spec | "
      "P(miss) [95% CI] |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n";
  // An interval whose ends may lie above the horizon H; an estimate above it reads "> H (not settled)".
  auto ci = [](const Interval& i, double horizon) {
    if (above_horizon(i.estimate)) return "> " + num(horizon) + " (not settled)";
    return num(i.estimate) + " [" + bound(i.lower, horizon) + ", " + bound(i.upper, horizon) + "]";
  };
  bool any_censored = false;
  for (const auto& m : metrics) {
    const auto v = column_values(t, m);
    const auto h = horizon_values(t, m);
    const Summary s = calc_summary(v, h);
    // Not settled: how many, and the range of their horizons.
    std::string censored = std::to_string(s.censored);
    if (s.censored > 0) {
      censored += " (horizon " + horizon_range(s) + " s)";
      any_censored = true;
    }
    std::string line = "| " + md_cell(m) + " | " + std::to_string(v.size()) + " | " + censored + " | " +
                       std::to_string(s.missing) + " | " + ci(calc_bootstrap_mean(v, h, 1000, 0.95, seed), s.horizon) +
                       (s.censored > 0 ? " restricted to " + num(s.horizon, "%.3g") + " s" : "") + " | ";
    for (double p : {5.0, 50.0, 95.0}) line += ci(calc_bootstrap_percentile(v, h, p, 1000, 0.95, seed), s.horizon) + " | ";
    auto spec = specs.find(m);
    if (spec != specs.end()) {
      const Interval miss = calc_miss_probability(v, spec->second, 0.95);
      line += "<= " + num(spec->second) + " | " + num(miss.estimate, "%.3f") + " [" + num(miss.lower, "%.3f") + ", " +
              num(miss.upper, "%.3f") + "] |";
    } else {
      line += " | |";
    }
    out += line + "\n";
  }
  if (any_censored)
    out += "\nNot settled: the run could not confirm a settling time up to its horizon (the hold minus one period of "
           "the slowest closed-loop resonance), so the value is known only to exceed it (right-censored). The mean is "
           "the restricted mean up to the largest horizon (the area under the Kaplan-Meier curve); percentiles are "
           "Kaplan-Meier percentiles, \"> H (not settled)\" where fewer than that fraction settled; the bootstrap "
           "resamples the not-settled runs too. P(miss) counts not settled (and no value) as a miss, over all runs.\n";
  return out;
}

std::vector<double> calc_restricted_values(const ResultTable& t, const std::string& metric, double* tau) {
  std::vector<double> v = column_values(t, metric);
  const std::vector<double> h = horizon_values(t, metric);
  *tau = kStatsNaN;
  for (std::size_t i = 0; i < h.size(); ++i)
    if (std::isnan(v[i]) && !std::isnan(h[i]) && !(h[i] >= *tau)) *tau = h[i];
  if (std::isnan(*tau)) return v;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isnan(v[i])) v[i] = std::min(v[i], *tau);
    else if (!std::isnan(h[i])) v[i] = *tau;
  return v;
}

namespace {
// The response a sensitivity estimator sees, and its name in the table.
std::pair<std::string, std::vector<double>> sensitivity_response(const ResultTable& t, const std::string& metric) {
  double tau = kStatsNaN;
  std::vector<double> v = calc_restricted_values(t, metric, &tau);
  return {std::isnan(tau) ? metric : metric + " (restricted to " + num(tau, "%.3g") + " s)", std::move(v)};
}
}  // namespace

std::map<std::string, SobolIndices> calc_sobol_for(const ResultTable& t, const std::vector<std::string>& metrics,
                                                   int nparams, std::uint64_t seed) {
  std::map<std::string, SobolIndices> out;
  for (const auto& m : metrics) {
    auto [name, y] = sensitivity_response(t, m);
    out[name] = calc_sobol_indices(y, nparams, 1000, seed);
  }
  return out;
}

std::string format_sobol_md(const std::map<std::string, SobolIndices>& idx, const std::vector<std::string>& params) {
  std::string out = "| metric | parameter | first order S_i (± 95 %) | total S_Ti (± 95 %) |\n|---|---|---|---|\n";
  for (const auto& [m, s] : idx)
    for (std::size_t i = 0; i < params.size(); ++i)
      out += "| " + md_cell(m) + " | " + md_cell(params[i]) + " | " + num(s.first[i], "%.3f") + " ± " + num(s.first_ci[i], "%.3f") +
             " | " + num(s.total[i], "%.3f") + " ± " + num(s.total_ci[i], "%.3f") + " |\n";
  return out;
}

std::map<std::string, MorrisIndices> calc_morris_for(const ResultTable& t, const std::vector<std::string>& metrics,
                                                     const std::vector<std::vector<double>>& x_unit) {
  std::map<std::string, MorrisIndices> out;
  const int d = x_unit.empty() ? 0 : static_cast<int>(x_unit[0].size());
  for (const auto& m : metrics) {
    auto [name, y] = sensitivity_response(t, m);
    out[name] = calc_morris_indices(x_unit, y, d);
  }
  return out;
}

std::string format_morris_md(const std::map<std::string, MorrisIndices>& idx, const std::vector<std::string>& params) {
  std::string out = "| metric | parameter | mu* | mu | sigma |\n|---|---|---|---|---|\n";
  for (const auto& [m, s] : idx)
    for (std::size_t i = 0; i < params.size(); ++i)
      out += "| " + md_cell(m) + " | " + md_cell(params[i]) + " | " + num(s.mu_star[i]) + " | " + num(s.mu[i]) + " | " + num(s.sigma[i]) + " |\n";
  return out;
}

}  // namespace ff
