#include "jobs/report.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "kernel/files.hpp"
#include "kernel/simulate.hpp"
#include "kernel/trajectory.hpp"
#include "plotting/plot.hpp"
#include "results/sqlite.hpp"

namespace ff {

void write_trace_plots(const std::string& dir, const std::vector<std::string>& labels,
                       const std::vector<const Trace*>& traces, const std::string& title) {
  struct Signal {
    const char* file;
    const char* axis;
    double scale;
    const std::vector<double> Trace::*member;
  };
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
    render_line_plot(p, dir + "/" + sig.file + ".png");
  }
}

namespace {

// Summary of each metric over all variants: how many have a number, mean, min, max.
std::string format_summary_md(const ResultTable& t) {
  std::string out = "| metric | runs with a value | mean | min | max |\n|---|---|---|---|---|\n";
  for (std::size_t c = 0; c < t.columns.size(); ++c) {
    int n = 0;
    double sum = 0, lo = INFINITY, hi = -INFINITY;
    for (const auto& r : t.rows) {
      const double x = r.values[c];
      if (std::isnan(x)) continue;
      ++n;
      sum += x;
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    char buf[256];
    if (n) std::snprintf(buf, sizeof buf, "| %s | %d of %zu | %.4g | %.4g | %.4g |\n", t.columns[c].c_str(), n, t.rows.size(), sum / n, lo, hi);
    else std::snprintf(buf, sizeof buf, "| %s | 0 of %zu | | | |\n", t.columns[c].c_str(), t.rows.size());
    out += buf;
  }
  return out;
}

}  // namespace

std::string write_study_report(const Study& study, const ResultTable& table, const std::string& dir) {
  write_file_atomic(dir + "/results.csv", format_results_csv(table));
  write_results_sqlite(table, {{"name", study.name}, {"study", study.source}, {"model", study.model_path}, {"hash", study.hash}},
                       dir + "/results.sqlite");

  // Readable table: per run and move when the runs are few, a summary of every metric otherwise.
  std::string md = "# " + study.name + "\n\n" + (study.description.empty() ? "" : study.description + "\n\n");
  int counts[4] = {0, 0, 0, 0};
  for (const auto& r : table.rows)
    counts[r.status == "ok" ? 0 : r.status == "not_settled" ? 1 : r.status == "nonfinite" ? 2 : 3]++;
  char status[256];
  std::snprintf(status, sizeof status, "%zu variants: %d ok, %d not settled, %d nonfinite, %d solver failures.\n\n",
                table.rows.size(), counts[0], counts[1], counts[2], counts[3]);
  md += status;
  if (table.rows.size() <= 24) {
    std::vector<std::vector<std::string>> moves;
    for (const auto& m : study.models) moves.push_back(describe_moves(m.spec.trajectory));
    md += format_settling_table_md(table, moves);
  } else {
    md += format_summary_md(table);
  }
  write_file_atomic(dir + "/table.md", md);

  // Time series of every variant whose trace is on disk, when they are few enough to tell apart.
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
  return md;
}

}  // namespace ff
