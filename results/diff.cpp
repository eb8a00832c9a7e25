#include "results/diff.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "common/version.hpp"
#include "results/summaries.hpp"
#include "common/text.hpp"

namespace ff {

namespace {

std::string num(double x, const char* f = "%.4g") { return format_cell(x, f); }

// Every leaf of a YAML document by its dotted path; a list of scalars is one leaf ("[0, 0, 1]").
void flatten(const YAML::Node& n, const std::string& path, std::map<std::string, std::string>& out) {
  if (n.IsMap()) {
    if (n.size() == 0) out[path] = "{}";
    for (const auto& kv : n) flatten(kv.second, (path.empty() ? "" : path + ".") + kv.first.Scalar(), out);
  } else if (n.IsSequence()) {
    bool scalars = true;
    for (const auto& e : n) scalars = scalars && (e.IsScalar() || e.IsNull());
    if (scalars) {
      std::string s = "[";
      for (std::size_t i = 0; i < n.size(); ++i) s += (i ? ", " : "") + (n[i].IsNull() ? std::string("null") : n[i].Scalar());
      out[path] = s + "]";
    } else {
      for (std::size_t i = 0; i < n.size(); ++i) flatten(n[i], path + "[" + std::to_string(i) + "]", out);
    }
  } else {
    out[path] = n.IsNull() ? "null" : n.Scalar();
  }
}

}  // namespace

std::string describe_statistic(const MetricChange& c) {
  if (c.statistic == "p_miss") return "P(miss: > " + num(c.spec) + " or no value)";
  return c.statistic == "not_settled" ? "share not settled" : c.statistic;
}

std::vector<KeyChange> diff_yaml_text(const std::string& a, const std::string& b) {
  if (a == b) return {};
  std::map<std::string, std::string> fa, fb;
  try {
    flatten(YAML::Load(a), "", fa);
    flatten(YAML::Load(b), "", fb);
  } catch (const YAML::Exception&) {
    return {{"(document)", a.empty() ? "" : "(text)", b.empty() ? "" : "(text)"}};
  }
  std::vector<KeyChange> out;
  for (const auto& [k, v] : fa) {
    const auto it = fb.find(k);
    if (it == fb.end()) out.push_back({k, v, ""});
    else if (it->second != v) out.push_back({k, v, it->second});
  }
  for (const auto& [k, v] : fb)
    if (!fa.count(k)) out.push_back({k, "", v});
  std::sort(out.begin(), out.end(), [](const KeyChange& x, const KeyChange& y) { return x.key < y.key; });
  return out;
}

bool same_variants(const ResultTable& a, const ResultTable& b) {
  if (a.rows.size() != b.rows.size() || a.params != b.params) return false;
  for (std::size_t i = 0; i < a.rows.size(); ++i) {
    const ResultRow &x = a.rows[i], &y = b.rows[i];
    if (x.eval_id != y.eval_id || x.seed != y.seed || x.params.size() != y.params.size()) return false;
    for (std::size_t j = 0; j < x.params.size(); ++j)
      if (!(x.params[j] == y.params[j] || (std::isnan(x.params[j]) && std::isnan(y.params[j])))) return false;
  }
  return true;
}

namespace {

// The smallest horizon of a column's not-settled entries (NaN when none is censored).
double least_horizon(const std::vector<double>& v, const std::vector<double>& h) {
  double tau = kStatsNaN;
  for (std::size_t i = 0; i < h.size(); ++i)
    if (std::isnan(v[i]) && !std::isnan(h[i]) && !(h[i] >= tau)) tau = h[i];
  return tau;
}

// min(T, tau): a settled value capped at tau, a not-settled one at tau; diverged stays NaN.
std::vector<double> restrict_to(std::vector<double> v, const std::vector<double>& h, double tau) {
  if (std::isnan(tau)) return v;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isnan(v[i])) v[i] = std::min(v[i], tau);
    else if (i < h.size() && !std::isnan(h[i])) v[i] = tau;
  return v;
}

double statistic_of(const std::vector<double>& x, const std::string& stat) {
  if (x.empty()) return kStatsNaN;
  if (stat == "mean" || stat == "p_miss" || stat == "not_settled") {
    double s = 0.0;
    for (double v : x) s += v;
    return s / static_cast<double>(x.size());
  }
  return calc_percentile(x, std::stod(stat.substr(1)));
}

}  // namespace

MetricChange compare_metric(const ResultTable& a, const ResultTable& b, const std::string& metric,
                            const std::string& statistic, bool paired, double confidence, std::uint64_t seed, double spec) {
  MetricChange c;
  c.metric = metric;
  c.statistic = statistic;
  c.spec = spec;
  c.paired = paired;
  const auto va = column_values(a, metric), ha = horizon_values(a, metric);
  const auto vb = column_values(b, metric), hb = horizon_values(b, metric);
  std::vector<double> ra, rb;
  if (statistic == "p_miss") {
    // 1 for a miss (above the spec, not settled, diverged), 0 for a row within it; its mean is P(miss).
    const auto misses = [&](const std::vector<double>& v) {
      std::vector<double> x;
      for (double y : v) x.push_back(std::isnan(y) || y > spec ? 1.0 : 0.0);
      return x;
    };
    ra = misses(va);
    rb = misses(vb);
  } else if (statistic == "not_settled") {
    // 1 for a run that did not settle (no value, a horizon), else 0; its mean is the share not settled.
    const auto censored = [](const std::vector<double>& v, const std::vector<double>& h) {
      std::vector<double> x;
      for (std::size_t i = 0; i < v.size(); ++i) x.push_back(std::isnan(v[i]) && i < h.size() && !std::isnan(h[i]) ? 1.0 : 0.0);
      return x;
    };
    ra = censored(va, ha);
    rb = censored(vb, hb);
  } else {
    c.horizon = std::fmin(least_horizon(va, ha), least_horizon(vb, hb));
    ra = restrict_to(va, ha, c.horizon);
    rb = restrict_to(vb, hb, c.horizon);
  }
  std::vector<double> xa, xb;
  for (std::size_t i = 0; i < (paired ? ra.size() : 0); ++i)
    if (!std::isnan(ra[i]) && !std::isnan(rb[i])) xa.push_back(ra[i]), xb.push_back(rb[i]);
  if (!paired) {
    for (double x : ra)
      if (!std::isnan(x)) xa.push_back(x);
    for (double x : rb)
      if (!std::isnan(x)) xb.push_back(x);
  }
  c.n_a = static_cast<int>(xa.size());
  c.n_b = static_cast<int>(xb.size());
  if (xa.empty() || xb.empty()) return c;
  c.a = statistic_of(xa, statistic);
  c.b = statistic_of(xb, statistic);
  c.change = c.b - c.a;
  c.identical = xa == xb;
  if (c.identical) {
    c.lower = c.upper = 0.0;
    return c;
  }
  // Percentile bootstrap of the change: resample variants (paired) or each run's values alone.
  const int resamples = 1000;
  std::vector<double> changes(resamples), sa(xa.size()), sb(xb.size());
  const std::size_t na = xa.size(), nb = xb.size();
  for (int r = 0; r < resamples; ++r) {
    const std::uint64_t base = static_cast<std::uint64_t>(r) * (na + nb);
    for (std::size_t j = 0; j < na; ++j) {
      const std::size_t i = draw_index(seed, base + j, na);
      sa[j] = xa[i];
      if (paired) sb[j] = xb[i];
    }
    if (!paired)
      for (std::size_t j = 0; j < nb; ++j) sb[j] = xb[draw_index(seed, base + na + j, nb)];
    changes[static_cast<std::size_t>(r)] = statistic_of(sb, statistic) - statistic_of(sa, statistic);
  }
  c.lower = calc_percentile(changes, 50.0 * (1.0 - confidence));
  c.upper = calc_percentile(changes, 50.0 * (1.0 + confidence));
  c.beyond_noise = c.lower > 0.0 || c.upper < 0.0;
  return c;
}

namespace {
// A run's verdicts on `requirements` ("" verdicts when a metric is not in its table).
std::vector<Verdict> verdicts_of(const RunDir& run, const RequirementSet& requirements) {
  if (requirements.statements.empty()) return run.record.verdicts;
  const bool complete = run.record.planned == 0 || static_cast<int>(run.table.rows.size()) >= run.record.planned;
  try {
    return evaluate_requirements(requirements, run.table, complete, run.record.planned);
  } catch (const std::invalid_argument&) {
    std::vector<Verdict> none;
    for (const Requirement& r : requirements.statements) {
      Verdict v;
      v.requirement = r.text;
      none.push_back(v);
    }
    return none;
  }
}
}  // namespace

RunDiff diff_runs(const RunDir& a, const RunDir& b, const std::vector<Tolerance>& tolerances,
                  const RequirementSet& requirements, const std::map<std::string, double>& specs, std::uint64_t seed) {
  RunDiff d;
  d.a = a.record;
  d.b = b.record;
  d.model = diff_yaml_text(a.record.model_text, b.record.model_text);
  d.study = diff_yaml_text(a.record.study_text, b.record.study_text);
  d.paired = same_variants(a.table, b.table);
  for (const std::string& m : b.table.columns) {
    if (std::find(a.table.columns.begin(), a.table.columns.end(), m) == a.table.columns.end()) continue;
    const auto tol = std::find_if(tolerances.begin(), tolerances.end(), [&](const Tolerance& t) { return t.metric == m; });
    const std::string statistic = tol == tolerances.end() ? "mean" : tol->statistic;
    const auto spec = specs.find(m);
    const double limit = spec == specs.end() ? kStatsNaN : spec->second;
    if (statistic == "p_miss" && std::isnan(limit)) continue;  // refused when the study is read
    MetricChange c = compare_metric(a.table, b.table, m, statistic, d.paired, 0.95, seed, limit);
    // With a spec, its P(miss) too (unless that is the tolerance's statistic already).
    if (tol != tolerances.end()) {
      c.tolerance = tol->describe();
      const double scale = std::abs(c.a);
      const double up = tol->increase * (tol->increase_relative ? scale : 1.0);
      const double down = tol->decrease * (tol->decrease_relative ? scale : 1.0);
      const bool rose = !std::isnan(up) && c.change > up && c.lower > 0.0;
      const bool fell = !std::isnan(down) && -c.change > down && c.upper < 0.0;
      c.regression = rose || fell;
      if (c.regression)
        d.regressions.push_back(m + ": " + describe_statistic(c) + " " + (rose ? "rose" : "fell") + " from " + num(c.a) + " to " +
                                num(c.b) + " (change " + num(c.change) + ", 95 % interval " + num(c.lower) + " to " +
                                num(c.upper) + "), beyond the tolerance (" + c.tolerance + ")");
    }
    d.metrics.push_back(c);
    // With a spec, its P(miss) too; a censored metric, its share not settled (unless those are the
    // tolerance's statistic already): a mean restricted to the horizon can fall while more runs fail to settle.
    if (!std::isnan(limit) && statistic != "p_miss")
      d.metrics.push_back(compare_metric(a.table, b.table, m, "p_miss", d.paired, 0.95, seed, limit));
    if (!std::isnan(c.horizon) && statistic != "not_settled")
      d.metrics.push_back(compare_metric(a.table, b.table, m, "not_settled", d.paired, 0.95, seed));
  }
  // Verdicts by requirement text, in b's order then a's others.
  const std::vector<Verdict> va = verdicts_of(a, requirements), vb = verdicts_of(b, requirements);
  auto find = [](const std::vector<Verdict>& v, const std::string& req) {
    const auto it = std::find_if(v.begin(), v.end(), [&](const Verdict& x) { return x.requirement == req; });
    return it == v.end() ? std::string() : it->verdict;
  };
  auto rank = [](const std::string& v) { return v == "pass" ? 2 : v == "undecided" ? 1 : v == "fail" ? 0 : -1; };
  for (const Verdict& v : vb) {
    VerdictChange c{v.requirement, find(va, v.requirement), v.verdict};
    c.worse = rank(c.a) >= 0 && rank(c.b) < rank(c.a);
    if (c.worse) d.regressions.push_back("requirement " + c.requirement + ": " + c.a + " before, " + c.b + " now");
    d.verdicts.push_back(c);
  }
  for (const Verdict& v : va)
    if (find(vb, v.requirement).empty()) d.verdicts.push_back({v.requirement, v.verdict, ""});
  const int fa = a.record.failed(), fb = b.record.failed();
  if (fb > fa)
    d.regressions.push_back("failed variants (nonfinite, solver_fail, invalid) rose from " + std::to_string(fa) + " to " +
                            std::to_string(fb));
  return d;
}

namespace {

std::string describe_counts(const RunRecord& r) {
  std::string s = std::to_string(r.variants) + (r.planned > r.variants ? " of " + std::to_string(r.planned) : "") + " (";
  bool first = true;
  for (const auto& [status, n] : r.status)
    if (n > 0) s += (first ? "" : ", ") + std::to_string(n) + " " + status, first = false;
  return s + ")";
}

std::string describe_build(const RunRecord& r) {
  return r.version.empty() ? "(not recorded)" : format_build(r.version, r.commit);
}

std::string key_table(const std::vector<KeyChange>& keys) {
  std::string md = "| key | before | now |\n|---|---|---|\n";
  for (const KeyChange& k : keys)
    md += "| " + md_cell(k.key) + " | " + (k.a.empty() ? "(absent)" : md_cell(k.a)) + " | " + (k.b.empty() ? "(absent)" : md_cell(k.b)) + " |\n";
  return md;
}

}  // namespace

std::string format_diff_md(const RunDiff& d) {
  const RunRecord &a = d.a, &b = d.b;
  std::string md = "# What changed: " + a.describe() + " -> " + b.describe() + "\n\n";
  md += "| | before | now |\n|---|---|---|\n";
  md += "| run | " + md_cell(a.describe()) + " | " + md_cell(b.describe()) + " |\n";
  md += "| directory | " + md_cell(a.out) + " | " + md_cell(b.out) + " |\n";
  md += "| flexfarm | " + md_cell(describe_build(a)) + " | " + md_cell(describe_build(b)) + " |\n";
  md += "| finished | " + md_cell(a.finished) + " | " + md_cell(b.finished) + " |\n";
  md += "| variants | " + describe_counts(a) + " | " + describe_counts(b) + " |\n\n";

  md += "## Inputs\n\n";
  auto inputs = [&](const char* what, const std::string& path, const std::string& ta, const std::string& tb,
                    const std::vector<KeyChange>& keys) {
    md += std::string(what) + (path.empty() ? "" : " (" + path + ")") + ": ";
    if (ta.empty() || tb.empty()) md += "not recorded in " + std::string(ta.empty() ? "the earlier" : "this") + " run.\n\n";
    else if (keys.empty()) md += "unchanged.\n\n";
    else md += std::to_string(keys.size()) + " key(s) changed.\n\n" + key_table(keys) + "\n";
  };
  inputs("Model", b.model_path, a.model_text, b.model_text, d.model);
  inputs("Study", b.study_path, a.study_text, b.study_text, d.study);
  const std::string va = describe_build(a), vb = describe_build(b);
  md += "flexfarm: " + (va == vb ? "the same build, " + vb : va + " before, " + vb + " now") + ".\n\n";

  md += "## Metrics\n\n";
  md += d.paired ? "Paired by variant: both runs hold the same " + std::to_string(b.variants) +
                       " variants (eval_id, seed and values), so each change is resampled variant by variant.\n\n"
                 : "Not paired (the runs hold different variants): each run is resampled on its own.\n\n";
  md += "| metric | statistic | before | now | change [95 % interval] | beyond noise | tolerance |\n"
        "|---|---|---|---|---|---|---|\n";
  int identical = 0, within = 0;
  for (const MetricChange& c : d.metrics) {
    if (c.tolerance.empty() && !c.beyond_noise) {
      (c.identical ? identical : within)++;
      continue;
    }
    md += "| " + md_cell(c.metric) + " | " + describe_statistic(c) + (std::isnan(c.horizon) ? "" : " (restricted to " + num(c.horizon, "%.3g") + " s)") +
          " | " + num(c.a) + " | " + num(c.b) + " | " + num(c.change) + " [" + num(c.lower) + ", " + num(c.upper) + "] | " +
          (c.identical ? "identical" : c.beyond_noise ? "yes" : "no") + " | " +
          (c.tolerance.empty() ? "" : md_cell(c.tolerance) + (c.regression ? ": **regression**" : ": within")) + " |\n";
  }
  md += "\n";
  if (identical || within)
    md += std::to_string(identical + within) + " other metric(s) not shown: " + std::to_string(identical) + " identical, " +
          std::to_string(within) + " moved within noise.\n\n";

  if (!d.verdicts.empty()) {
    md += "## Requirements\n\n| requirement | before | now |\n|---|---|---|\n";
    for (const VerdictChange& v : d.verdicts)
      md += "| " + md_cell(v.requirement) + " | " + (v.a.empty() ? "-" : v.a) + " | " + (v.b.empty() ? "-" : v.b) +
            (v.worse ? " (worse)" : "") + " |\n";
    md += "\n";
  }
  md += "## Result\n\n";
  if (d.regressions.empty()) return md + "Nothing got worse.\n";
  md += std::to_string(d.regressions.size()) + " regression(s):\n\n";
  for (const std::string& r : d.regressions) md += "- " + r + "\n";
  return md;
}

}  // namespace ff
