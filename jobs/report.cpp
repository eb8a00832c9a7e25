#include "jobs/report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>

#include "arm/arm_metrics.hpp"
#include "common/files.hpp"
#include "common/version.hpp"
#include "jobs/farm.hpp"
#include "kernel/simulate.hpp"
#include "kernel/trajectory.hpp"
#include "plotting/plot.hpp"
#include "plotting/charts.hpp"
#include "results/censoring.hpp"
#include "results/sqlite.hpp"
#include "results/statistics.hpp"
#include "results/summaries.hpp"
#include "sweep/design.hpp"
#include "common/text.hpp"

namespace ff {

void write_trace_plots(const std::string& dir, const std::vector<std::string>& labels,
                       const std::vector<const Trace*>& traces, const std::string& title) {
  struct Signal {
    const char* file;
    const char* axis;
    double scale;
    const std::vector<double> Trace::*member;
  };
  // The angles' reference (the first trace's) and the settling band about its final target: ±2 % of the
  // last move's amplitude (kernel/metrics.hpp), from where that move starts.
  const std::vector<double>& ref = traces.empty() ? std::vector<double>{} : traces.front()->ref;
  std::size_t move = ref.size();  // the last sample not at the final target, then the last move's start
  while (move > 0 && ref[move - 1] == ref.back()) --move;
  while (move > 1 && ref[move - 1] != ref[move - 2]) --move;
  const double amplitude = move > 0 ? std::abs(ref.back() - ref[move - 1]) : 0.0;  // rad
  const Signal signals[] = {
      {"tip_angle", "tip angle (rad)", 1.0, &Trace::tip_angle},
      {"hub_angle", "hub angle (rad)", 1.0, &Trace::hub_angle},
      {"tip_deflection", "tip deflection (mm)", 1e3, &Trace::tip_deflection},
      {"hub_torque", "hub torque (kN m)", 1e-3, &Trace::torque},
  };
  for (const auto& sig : signals) {
    LinePlot p;
    const std::string axis = sig.axis;
    p.title = title + ": " + axis.substr(0, axis.find(" ("));
    p.x_label = "time (s)";
    p.y_label = axis;
    for (std::size_t i = 0; i < traces.size(); ++i) {
      Series s;
      s.label = labels[i];
      s.x = traces[i]->t;
      s.y = traces[i]->*sig.member;
      for (auto& y : s.y) y *= sig.scale;
      p.series.push_back(std::move(s));
    }
    if (!traces.empty() && (sig.member == &Trace::tip_angle || sig.member == &Trace::hub_angle)) {
      Series r{.label = "reference", .x = traces.front()->t, .y = ref, .colour = 6, .width = 1.5, .dashed = true};  // black
      p.series.push_back(std::move(r));
      if (amplitude > 0)
        p.hlines = {{ref.back() + 0.02 * amplitude, "target ±2 % of the move"}, {ref.back() - 0.02 * amplitude, ""}};
    }
    render_line_plot(p, dir + "/" + sig.file + ".png");
  }
}

namespace {

// An axis over joints: "joint angle (rad)", "joint position (m)", or both, naming the prismatic joints
// ("joint angle (rad) or position (m: lift)"); `revolute` and `prismatic` name the quantity and unit.
std::string joint_axis(const ArmModel& arm, const std::vector<std::string>& joints, const std::string& revolute,
                       const std::string& prismatic) {
  std::string slides;
  std::size_t n = 0;
  for (const std::string& j : joints)
    if (is_prismatic(arm, j)) slides += (n++ ? ", " : "") + j;
  if (n == 0) return "joint " + revolute;
  if (n == joints.size()) return "joint " + prismatic;
  const std::size_t open = prismatic.find(" (");
  return "joint " + revolute + " or " + prismatic.substr(0, open) + " (" +
         prismatic.substr(open + 2, prismatic.size() - open - 3) + ": " + slides + ")";
}

}  // namespace

std::vector<std::string> write_arm_plots(const std::string& dir, const std::vector<std::string>& labels,
                                         const std::vector<const ArmTrace*>& traces, const std::string& title,
                                         const ArmModel& arm) {
  std::vector<std::string> written;
  if (traces.empty()) return written;
  const ArmTrace& first = *traces.front();
  // Which columns go on which plot: joints by their ".q" suffix, links by ".deflection_y".
  std::vector<std::string> joints, links;
  for (const std::string& n : first.names) {
    if (n.ends_with(".q")) joints.push_back(n.substr(0, n.size() - 2));
    if (n.ends_with(".deflection_y")) links.push_back(n.substr(0, n.size() - 13));
  }
  const bool many = traces.size() > 1;
  auto plot = [&](const std::string& file, const std::string& axis, auto add) {
    LinePlot p;
    p.title = title + ": " + axis.substr(0, axis.find(" ("));
    p.x_label = "time (s)";
    p.y_label = axis;
    for (std::size_t i = 0; i < traces.size(); ++i) add(p, *traces[i], labels[i]);
    render_line_plot(p, dir + "/" + file);
    written.push_back(file);
  };
  // One colour per joint for one trace; per trace (the joints dashed apart) for several.
  plot("joints.png", joint_axis(arm, joints, "angle (rad)", "position (m)"), [&](LinePlot& p, const ArmTrace& tr, const std::string& label) {
    for (std::size_t j = 0; j < joints.size(); ++j) {
      Series q{.label = many ? label + " " + joints[j] : joints[j], .x = tr.t(), .y = tr.column(joints[j] + ".q")};
      Series r{.label = many ? "" : joints[j] + " reference", .x = tr.t(), .y = tr.column(joints[j] + ".ref")};
      r.dashed = true;
      r.width = 1.0;
      r.colour = q.colour = static_cast<int>(p.series.size() / 2);
      p.series.push_back(std::move(q));
      p.series.push_back(std::move(r));
    }
  });
  plot("torques.png", joint_axis(arm, joints, "torque (N m)", "force (N)"), [&](LinePlot& p, const ArmTrace& tr, const std::string& label) {
    for (const std::string& j : joints)
      p.series.push_back({.label = many ? label + " " + j : j, .x = tr.t(), .y = tr.column(j + ".torque")});
  });
  // Each tool's error from where the rigid arm at the reference puts it (tools by their ".ref_x" columns).
  std::vector<std::string> tools;
  for (const std::string& n : first.names)
    if (n.ends_with(".ref_x")) tools.push_back(n.substr(0, n.size() - 6));
  plot("tool_error.png", tools.size() > 1 ? "tool errors (mm)" : "tool error (mm)",
       [&](LinePlot& p, const ArmTrace& tr, const std::string& label) {
         for (const std::string& tool : tools) {
           const std::string name = tools.size() > 1 ? tool : "|tool - reference|";
           Series e{.label = many ? (tools.size() > 1 ? label + " " + tool : label) : name, .x = tr.t(), .y = {}};
           for (std::size_t k = 0; k < tr.t().size(); ++k) {
             double d2 = 0.0;
             for (const char* c : {"x", "y", "z"}) {
               const double d = tr.column(tool + "." + c)[k] - tr.column(tool + ".ref_" + c)[k];
               d2 += d * d;
             }
             e.y.push_back(1e3 * std::sqrt(d2));
           }
           p.series.push_back(std::move(e));
         }
       });
  // Signed, along each link's y and z (its own frame), so a swing's overshoot shows on the other side;
  // a component that stays below 1 µm in every trace (a planar arm's z) is left out.
  const auto moves = [&](const std::string& column) {
    for (const ArmTrace* tr : traces)
      for (double v : tr->column(column))
        if (std::abs(v) > 1e-6) return true;
    return false;
  };
  if (!links.empty())
    plot("deflection.png", "link tip deflection, signed (mm)", [&](LinePlot& p, const ArmTrace& tr, const std::string& label) {
      for (const std::string& l : links)
        for (const char* axis : {"y", "z"}) {
          const std::string column = l + ".deflection_" + axis;
          if (!moves(column)) continue;
          Series d{.label = (many ? label + " " : "") + l + " " + axis, .x = tr.t(), .y = tr.column(column)};
          for (double& v : d.y) v *= 1e3;
          d.dashed = axis[0] == 'z';
          p.series.push_back(std::move(d));
        }
    });
  // With a world: the arm's least clearance to it (and between parts) over time.
  if (std::find(first.names.begin(), first.names.end(), "clearance") != first.names.end())
    plot("clearance.png", "least clearance (mm; below 0: contact)", [&](LinePlot& p, const ArmTrace& tr, const std::string& label) {
      Series c{.label = many ? label : "least clearance", .x = tr.t(), .y = tr.column("clearance")};
      for (double& v : c.y) v *= 1e3;
      p.series.push_back(std::move(c));
    });
  return written;
}

namespace {

// The responses a study's report plots and summarises: the reference rig's first move, or an arm's
// tool, first flexible link (else the tool's tracking error) and first actuated joint.
struct KeyMetrics {
  std::string settling, overshoot, deflection, residual, torque;  // result columns
  std::string what;                                               // "tip" or "tool", for titles
  std::string deflection_title;
  bool clearance = false;  // an arm with a world: min_clearance_m and contact too (arm/arm_metrics.hpp)
  std::vector<std::string> all() const { return {settling, overshoot, deflection, residual, torque}; }
};

KeyMetrics key_metrics(const ResultTable& t) {
  if (std::find(t.columns.begin(), t.columns.end(), "m1_tip_settling_s") != t.columns.end())
    return {"m1_tip_settling_s", "m1_tip_overshoot_pct", "m1_peak_tip_deflection_m", "m1_residual_vibration_m",
            "m1_peak_torque_Nm", "tip", "peak tip deflection"};
  // The first tool's (`tool:`'s is named "tool").
  const std::vector<std::string> tools = arm_tool_names(t.columns);
  const std::string tool = tools.empty() ? "tool" : tools.front();
  KeyMetrics k{tool + "_settling_s", tool + "_overshoot_pct", tool + "_peak_error_m", tool + "_final_error_m", "", "tool",
               tool == "tool" ? "peak tool tracking error" : "peak tracking error of tool " + tool};
  for (const std::string& c : t.columns) {
    if (c.ends_with("_peak_deflection_m") && k.deflection == tool + "_peak_error_m") {
      k.deflection = c;
      k.deflection_title = "peak deflection of " + c.substr(0, c.size() - 18);
    }
    if (c.ends_with("_residual_m") && k.residual == tool + "_final_error_m") k.residual = c;
    if (c.ends_with("_peak_torque_Nm") && k.torque.empty()) k.torque = c;
  }
  k.clearance = std::find(t.columns.begin(), t.columns.end(), "min_clearance_m") != t.columns.end();
  return k;
}

// What each point of a plot over the first `shown` parameters is taken over: " over a, b" naming the
// others, or "" when there are none (each point is one variant).
std::string over_others(const std::vector<std::string>& params, std::size_t shown) {
  std::string out;
  for (std::size_t i = shown; i < params.size(); ++i) out += (i > shown ? ", " : " over ") + params[i];
  return out;
}

// A heat map over parameters x and y of the table, axes with their units: each cell's value from its rows
// (NaN: none), and whether it is a lower bound (HeatMap::bounds) when `bound` is given.
template <class Cell>
HeatMap make_heat_map(const Study& study, const ResultTable& t, const std::string& x, const std::string& y, const Cell& cell,
                      const std::function<bool(const std::vector<int>&)>& bound = {}) {
  HeatMap h;
  h.x_label = parameter_axis_label(study, x);
  h.y_label = parameter_axis_label(study, y);
  const auto groups = make_groups({column_values(t, x), column_values(t, y)});
  for (const auto& g : groups) {
    if (std::find(h.x.begin(), h.x.end(), g.key[0]) == h.x.end()) h.x.push_back(g.key[0]);
    if (std::find(h.y.begin(), h.y.end(), g.key[1]) == h.y.end()) h.y.push_back(g.key[1]);
  }
  std::sort(h.x.begin(), h.x.end());
  std::sort(h.y.begin(), h.y.end());
  h.values.assign(h.x.size() * h.y.size(), NAN);
  if (bound) h.bounds.assign(h.values.size(), 0);
  for (const auto& g : groups) {
    const auto ix = std::find(h.x.begin(), h.x.end(), g.key[0]) - h.x.begin();
    const auto iy = std::find(h.y.begin(), h.y.end(), g.key[1]) - h.y.begin();
    h.values[iy * h.x.size() + ix] = cell(g.rows);
    if (bound) h.bounds[iy * h.x.size() + ix] = bound(g.rows);
  }
  return h;
}

// An arm with a world: the least clearance and contact by the first two parameters (binned as in
// report_grid), and its heat map (the least over the other parameters: the worst case of each cell).
std::string report_clearance_grid(const Study& study, const ResultTable& t, const std::string& dir) {
  const auto& p = t.params;
  std::string md = "## Least clearance and contact by " + p[0] + (p.size() > 1 ? " and " + p[1] : "") + "\n\n";
  md += format_groupby_md(t, std::vector<std::string>(p.begin(), p.begin() + std::min<std::size_t>(2, p.size())),
                          {"min_clearance_m", "contact"}, study.specs);
  if (p.size() >= 2) {
    const auto clearance = column_values(t, "min_clearance_m");
    HeatMap h = make_heat_map(study, t, p[0], p[1], [&](const std::vector<int>& rows) {
      double least = INFINITY;
      for (int r : rows) least = std::min(least, clearance[r]);
      return least;
    });
    h.title = std::string("least clearance of the arm (m; <= 0: contact)") +
              (p.size() > 2 ? ", the least" + over_others(p, 2) : "");
    h.value_label = "least clearance (m)";
    render_heat_map(h, dir + "/heatmap_clearance.png");
    md += "Heat map: heatmap_clearance.png.\n\n";
  }
  return md;
}

// Grid and centred designs: settling time over the first two parameters, and against each. The table
// bins a parameter with more than 10 values (format_groupby_md's default Binning: 10 quantile bins);
// the heat map and the band plots keep every level.
std::string report_grid(const Study& study, const ResultTable& t, const std::string& dir) {
  const KeyMetrics km = key_metrics(t);
  const auto& p = t.params;
  std::string md = "## " + std::string(km.what == "tip" ? "Tip" : "Tool") + " settling time by " + p[0] + (p.size() > 1 ? " and " + p[1] : "") + "\n\n";
  md += format_groupby_md(t, std::vector<std::string>(p.begin(), p.begin() + std::min<std::size_t>(2, p.size())),
                          {km.settling, km.overshoot}, study.specs);
  // Settling times are right-censored (not settled: known only to exceed the run's horizon), so each
  // cell and group is summarised by calc_summary(values, horizons): the restricted mean, Kaplan-Meier
  // percentiles, and a percentile above the horizon drawn at the horizon (a lower bound).
  const auto settle = column_values(t, km.settling);
  const auto horizon = horizon_values(t, km.settling);
  const auto summary_of = [&](const std::vector<int>& rows) {
    std::vector<double> v, hz;
    for (int r : rows) {
      v.push_back(settle[r]);
      if (!horizon.empty()) hz.push_back(horizon[r]);
    }
    return calc_summary(v, hz);
  };
  const auto at_most_horizon = [](double x, const Summary& s) { return std::isinf(x) ? s.horizon : x; };
  bool censored = false;
  for (std::size_t r = 0; r < settle.size() && !horizon.empty(); ++r) censored |= std::isnan(settle[r]) && !std::isnan(horizon[r]);
  if (p.size() >= 2) {
    // Heat map: mean settling over the other parameters (restricted mean where some did not settle: a lower
    // bound, marked).
    HeatMap h = make_heat_map(
        study, t, p[0], p[1],
        [&](const std::vector<int>& rows) {
          const Summary s = summary_of(rows);
          return at_most_horizon(s.mean, s);
        },
        [&](const std::vector<int>& rows) { return summary_of(rows).censored > 0; });
    const std::string over = over_others(p, 2);
    h.title = censored ? km.what + " settling time (" + (over.empty() ? "" : "restricted mean" + over + "; ") +
                             "> v: not settled in some runs, counted at the horizon: a lower bound)"
          : over.empty() ? km.what + " settling time"
                         : km.what + " settling time (mean" + over + ")";
    h.value_label = km.what + " settling time (s)";
    render_heat_map(h, dir + "/heatmap_settling.png");
  }
  // Settling against each parameter: median with the 5-95 % band over the others.
  for (const auto& name : p) {
    BandPlot b;
    b.title = km.what + " settling time against " + name;
    b.x_label = parameter_axis_label(study, name);
    b.y_label = km.what + " settling time (s)";
    std::vector<std::string> rest;  // the other parameters, the band's spread
    for (const std::string& q : p)
      if (q != name) rest.push_back(q);
    BandSeries series;
    series.label = "p50, band p5-p95" + over_others(rest, 0) + (censored ? " (Kaplan-Meier)" : "");
    series.bound_label = "above the horizon (not settled): drawn at it, a lower bound";
    for (const auto& g : make_groups({column_values(t, name)})) {
      const Summary s = summary_of(g.rows);
      series.x.push_back(g.key[0]);
      for (auto [line, x] : {std::pair{&series.mid, s.p50}, {&series.lo, s.p5}, {&series.hi, s.p95}}) {
        line->push_back(at_most_horizon(x, s));
        if (std::isinf(x)) series.bound_x.push_back(g.key[0]), series.bound_y.push_back(s.horizon);
      }
    }
    b.series.push_back(series);
    render_band_plot(b, dir + "/settling_vs_" + make_file_stem(name) + ".png");
  }
  return md;
}

// Studies with `cases:`: each case's metric against the first design variable, one table row and
// one plotted line per case (mean over any further variables; where some did not settle the restricted mean,
// marked as a lower bound; "-" / a gap where a run has no value).
std::string report_cases(const Study& study, const ResultTable& t, const std::string& dir) {
  const std::string x_name = t.params.size() > 1 ? t.params[1] : "case";
  const auto groups = make_groups({column_values(t, "case"), column_values(t, x_name)});
  std::vector<double> xs;
  for (const auto& g : groups)
    if (std::find(xs.begin(), xs.end(), g.key[1]) == xs.end()) xs.push_back(g.key[1]);
  std::sort(xs.begin(), xs.end());
  const KeyMetrics km = key_metrics(t);
  const std::pair<std::string, std::string> shown[] = {{km.settling, km.what + " settling time (s)"},
                                                       {km.overshoot, km.what + " overshoot (%)"},
                                                       {km.residual, km.what == "tip" ? "residual vibration (m)" : km.residual},
                                                       {km.torque, "peak torque (N·m)"}};
  std::string md;
  for (const auto& [metric, title] : shown) {
    if (metric.empty()) continue;
    const auto values = column_values(t, metric);
    const auto horizons = horizon_values(t, metric);
    // cell[case][x]: the mean over the group; where some did not settle the restricted mean (counted at
    // their horizon), a lower bound (bound[case][x]); NaN when a run of it has no value (diverged).
    std::vector<std::vector<double>> cell(study.case_labels.size(), std::vector<double>(xs.size(), NAN));
    std::vector<std::vector<char>> bound(study.case_labels.size(), std::vector<char>(xs.size(), 0));
    for (const auto& g : groups) {
      std::vector<double> v, h;
      for (int r : g.rows) {
        v.push_back(values[r]);
        if (!horizons.empty()) h.push_back(horizons[r]);
      }
      const Summary s = calc_summary(v, h);
      const auto ix = std::find(xs.begin(), xs.end(), g.key[1]) - xs.begin();
      const auto c = static_cast<std::size_t>(g.key[0]);
      cell[c][ix] = s.missing > 0 ? NAN : s.mean;
      bound[c][ix] = s.missing == 0 && s.censored > 0;
    }
    md += "## " + title + " by case and " + x_name + "\n\n| case |";
    for (double x : xs) {
      char buf[32];
      std::snprintf(buf, sizeof buf, " %g |", x);
      md += buf;
    }
    md += "\n|---|";
    for (std::size_t i = 0; i < xs.size(); ++i) md += "---|";
    md += "\n";
    LinePlot plot;
    plot.title = std::string(title) + " against " + x_name + (t.params.size() > 2 ? ", mean" + over_others(t.params, 2) : "");
    plot.x_label = parameter_axis_label(study, x_name);
    plot.y_label = title;
    bool any_bound = false;
    for (std::size_t c = 0; c < cell.size(); ++c) {
      md += "| " + md_cell(study.case_labels[c]) + " |";
      Series line, bounds;
      line.label = study.case_labels[c];
      line.colour = bounds.colour = static_cast<int>(c);
      line.dashed = static_cast<int>(c) >= palette_size();  // the palette repeats
      line.marker = Series::Marker::kDot;
      bounds.line = false;
      bounds.marker = Series::Marker::kBound;
      for (std::size_t i = 0; i < xs.size(); ++i) {
        char buf[32];
        const double a = std::abs(cell[c][i]);
        std::snprintf(buf, sizeof buf, a >= 100 ? "%.0f" : (a < 0.1 && a > 0 ? "%.3g" : "%.2f"), cell[c][i]);
        md += std::isnan(cell[c][i]) ? std::string(" - |") : std::string(bound[c][i] ? " > " : " ") + buf + " |";
        line.x.push_back(xs[i]);
        line.y.push_back(cell[c][i]);
        if (bound[c][i]) bounds.x.push_back(xs[i]), bounds.y.push_back(cell[c][i]);
      }
      if (!bounds.x.empty() && !any_bound) bounds.label = "not settled in some runs: a lower bound";
      any_bound = any_bound || !bounds.x.empty();
      md += "\n";
      plot.series.push_back(line);
      plot.series.push_back(bounds);
    }
    md += "\n";
    std::string file = metric;
    render_line_plot(plot, dir + "/cases_" + make_file_stem(file) + ".png");
  }
  md += "\"> v\": some runs did not settle; the restricted mean (counting them at their horizon), a lower bound. "
        "\"-\": no value (a run diverged). Plots: cases_<metric>.png.\n";
  return md;
}

// Random designs: statistics with confidence intervals, spec misses, distributions.
std::string report_monte_carlo(const Study& study, const ResultTable& t, const std::string& dir) {
  std::string md = "## Responses (95 % percentile-bootstrap intervals; P(miss): Wilson interval)\n\n";
  const KeyMetrics km = key_metrics(t);
  std::vector<std::string> shown;
  for (const std::string& c : km.all())
    if (!c.empty()) shown.push_back(c);
  if (km.clearance) shown.insert(shown.end(), {"min_clearance_m", "contact"});
  md += format_monte_carlo_md(t, shown, study.specs, study.seed);
  const auto settle = column_values(t, km.settling);
  const auto horizon = horizon_values(t, km.settling);
  const Summary s = calc_summary(settle, horizon);
  Histogram h;
  h.title = km.what + " settling time";
  h.x_label = km.what + " settling time (s)";
  // Not settled (censored at a horizon) as a bar and CDF mass of its own; runs with no value at all left out.
  for (std::size_t i = 0; i < settle.size(); ++i)
    if (horizon.empty() || !std::isnan(settle[i]) || !std::isnan(horizon[i])) h.values.push_back(settle[i]);
  h.nan_label = s.censored > 0 ? "not settled, > horizon " + horizon_range(s) + " s" : "not settled";
  h.nan_bar = true;
  // p95 from the Kaplan-Meier curve; above the horizon it has no line, only its legend entry.
  if (!std::isnan(s.p95)) {
    char above[64];
    std::snprintf(above, sizeof above, "p95: not settled (> %.3g s)", s.horizon);
    h.markers.push_back(s.p95);
    h.marker_labels.push_back(std::isfinite(s.p95) ? "p95" : above);
  }
  if (study.specs.count(km.settling)) {
    h.markers.push_back(study.specs.at(km.settling));
    h.marker_labels.push_back("spec");
  }
  render_histogram(h, dir + "/hist_settling.png");
  render_cdf(h, dir + "/cdf_settling.png");
  Histogram d;
  d.title = km.deflection_title;
  d.x_label = km.deflection_title + " (m)";
  d.values = column_values(t, km.deflection);
  render_histogram(d, dir + "/hist_peak_deflection.png");
  if (km.clearance) {
    Histogram c;
    c.title = "least clearance of the arm (<= 0: contact)";
    c.x_label = "least clearance (m)";
    c.values = column_values(t, "min_clearance_m");
    c.markers.push_back(0.0);
    c.marker_labels.push_back("contact");
    render_histogram(c, dir + "/hist_clearance.png");
  }
  return md;
}

// Sensitivity designs: Sobol' indices (Saltelli) or Morris screening, with bar charts.
std::string report_sensitivity(const Study& study, const ResultTable& t, const std::string& dir) {
  // Responses with a value for every variant: the estimators drop a base point with any NaN (not settled).
  const KeyMetrics km = key_metrics(t);
  std::vector<std::string> metrics;
  for (const std::string& c : {km.overshoot, km.deflection, km.residual, km.torque, km.settling})
    if (!c.empty()) metrics.push_back(c);
  BarChart b;
  b.names = t.params;
  std::string md;
  if (study.design.kind == DesignKind::kSaltelli) {
    const auto idx = calc_sobol_for(t, metrics, static_cast<int>(t.params.size()), study.seed);
    md = "## Sobol' indices (Saltelli design; first order: Saltelli 2010, total: Jansen 1999)\n\n" + format_sobol_md(idx, t.params);
    const auto& s = idx.at(km.deflection);
    b.title = "Sobol' indices of the " + km.deflection_title;
    b.y_label = "index";
    b.groups = {s.first, s.total};
    b.errors = {s.first_ci, s.total_ci};
    b.group_labels = {"first order", "total"};
  } else {
    const auto x = make_morris_points(study.design.trajectories, static_cast<int>(t.params.size()),
                                      study.design.morris_levels, study.design.seed);
    const auto idx = calc_morris_for(t, metrics, x);
    md = "## Morris elementary effects (per unit of the parameter range)\n\n" + format_morris_md(idx, t.params);
    const auto& m = idx.at(km.deflection);
    b.title = "Morris screening of the " + km.deflection_title;
    b.y_label = "elementary effect (m)";
    b.groups = {m.mu_star, m.sigma};
    b.group_labels = {"mu*", "sigma"};
  }
  render_bar_chart(b, dir + "/sensitivity_peak_deflection.png");
  return md;
}

}  // namespace

RunRecord make_run_record(const Study& study, const ResultTable& table, const std::string& dir, const RunContext& ctx) {
  const auto absolute = [](const std::string& p) {
    return p.empty() ? p : std::filesystem::absolute(p).lexically_normal().string();
  };
  RunRecord r;
  r.study = study.name;
  r.study_path = absolute(study.source);
  r.out = absolute(dir);
  r.study_hash = study.hash;
  r.study_text = study.text;
  r.model_path = absolute(study.model_path);
  r.model_text = study.model_text;
  r.study_sha256 = calc_sha256(study.text);
  r.model_sha256 = calc_sha256(study.model_text);
  r.version = flexfarm_version();
  r.commit = flexfarm_commit();
  r.host = host_name();
  r.started = ctx.started;
  r.finished = format_utc_now();
  r.seconds = ctx.seconds;
  r.processes = ctx.processes;
  r.threads = ctx.threads;
  r.lanes = ctx.lanes;
  r.planned = static_cast<int>(study.variants.size());
  r.variants = static_cast<int>(table.rows.size());
  r.status = count_statuses(table);
  r.summaries = calc_metric_summaries(table, study.specs);
  r.verdicts = calc_study_verdicts(study, table);
  return r;
}

std::string format_study_requirements_md(const Study& study, const ResultTable& table, const std::vector<Verdict>& verdicts) {
  if (study.requirements.statements.empty()) return "";
  std::string md = "\n## Requirements\n\n";
  if (table.rows.size() < study.variants.size())
    md += "Stopped early after " + std::to_string(table.rows.size()) + " of " + std::to_string(study.variants.size()) +
          " variants: every requirement decided.\n\n";
  char conf[64];
  std::snprintf(conf, sizeof conf, "Intervals at %g %% confidence.\n\n", study.requirements.confidence * 100.0);
  return md + conf + format_requirements_md(verdicts);
}

StudyReport write_study_report(const Study& study, const ResultTable& table, const std::string& dir, const RunRecord& record) {
  write_file_atomic(dir + "/results.csv", format_results_csv(table));
  // results.sqlite is the same bits for the same results; what differs from run to run goes in run.yaml.
  write_results_sqlite(table, {{"name", study.name}, {"study", study.source}, {"model", study.model_path}, {"hash", study.hash}},
                       dir + "/results.sqlite");
  write_file_atomic(dir + "/run.yaml", format_run_yaml(record));

  // Readable table: per run and move when the runs are few, a summary of every metric otherwise.
  StudyReport report{"# " + study.name + "\n\n" + (study.description.empty() ? "" : study.description + "\n\n"), "", ""};
  std::string& md = report.results;
  const auto& n = record.status;
  char status[256];
  std::snprintf(status, sizeof status, "%zu variants: %d ok, %d not settled, %d nonfinite, %d solver failures%s.\n\n",
                table.rows.size(), n.at("ok"), n.at("not_settled"), n.at("nonfinite"), n.at("solver_fail"),
                n.at("invalid") ? (", " + std::to_string(n.at("invalid")) + " invalid (values the model rejects)").c_str() : "");
  md += status;
  if (study.listed && study.arm) {
    // One row per run: its key responses.
    const KeyMetrics km = key_metrics(table);
    md += "| run | status |";
    std::vector<std::string> shown;
    for (const std::string& c : km.all())
      if (!c.empty()) shown.push_back(c);
    for (const std::string& c : shown) md += " " + md_cell(c) + " |";
    md += "\n|---|---|";
    for (std::size_t i = 0; i < shown.size(); ++i) md += "---|";
    md += "\n";
    for (const auto& r : table.rows) {
      md += "| " + md_cell(r.label) + " | " + r.status + " |";
      for (const std::string& c : shown) {
        const double v = r.values[static_cast<std::size_t>(std::find(table.columns.begin(), table.columns.end(), c) - table.columns.begin())];
        md += " " + format_metric_cell(v, find_row_horizon(table, r, c)) + " |";
      }
      md += "\n";
    }
    md += "\n## Every metric\n\n" + format_groupby_md(table, {}, table.columns, study.specs);
  } else if (study.listed) {
    std::vector<std::vector<std::string>> moves;
    for (const auto& v : study.variants) moves.push_back(describe_moves(make_variant_model(study, v).spec.trajectory));
    md += format_settling_table_md(table, moves);
  } else {
    if (!study.case_labels.empty()) md += report_cases(study, table, dir);
    else switch (study.design.kind) {
      case DesignKind::kGrid:
      case DesignKind::kCentered:
        md += report_grid(study, table, dir);
        if (key_metrics(table).clearance) md += report_clearance_grid(study, table, dir);
        break;
      case DesignKind::kSaltelli:
      case DesignKind::kMorris: md += report_sensitivity(study, table, dir); break;
      default: md += report_monte_carlo(study, table, dir); break;
    }
    md += "\n## Every metric\n\n" + format_groupby_md(table, {}, table.columns, study.specs);
  }
  report.requirements = format_study_requirements_md(study, table, record.verdicts);
  write_file_atomic(dir + "/table.md", report.md());

  // Time series of every variant whose trace is on disk, when they are few enough to tell apart.
  if (study.arm) {
    std::vector<ArmTrace> traces;
    std::vector<std::string> labels;
    for (const auto& r : table.rows) {
      char name[48];
      std::snprintf(name, sizeof name, "/traces/%06d.csv", r.eval_id);
      if (table.rows.size() > 12 || !std::filesystem::exists(dir + name)) break;
      traces.push_back(read_arm_trace_csv(dir + name));
      labels.push_back(r.label);
    }
    if (!traces.empty() && traces.size() == table.rows.size()) {
      std::vector<const ArmTrace*> ptrs;
      for (const auto& t : traces) ptrs.push_back(&t);
      write_arm_plots(dir, labels, ptrs, study.name, study.arm_nominal);
    }
    return report;
  }
  std::vector<Trace> traces;
  std::vector<std::string> labels;
  for (const auto& r : table.rows) {
    char name[48];
    std::snprintf(name, sizeof name, "/traces/%06d.csv", r.eval_id);
    if (table.rows.size() > 12 || !std::filesystem::exists(dir + name)) break;
    traces.push_back(read_trace_csv(dir + name));
    labels.push_back(r.label);
  }
  if (!traces.empty() && traces.size() == table.rows.size()) {
    std::vector<const Trace*> ptrs;
    for (const auto& t : traces) ptrs.push_back(&t);
    write_trace_plots(dir, labels, ptrs, study.name);
  }
  return report;
}

}  // namespace ff
