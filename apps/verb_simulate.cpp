// flexfarm simulate MODEL.yaml --out DIR: one closed-loop run, its trace, metrics and plots.
#include <cmath>
#include <cstdio>

#include "apps/verbs.hpp"
#include "arm/arm_metrics.hpp"
#include "arm/arm_simulate.hpp"
#include "common/files.hpp"
#include "jobs/report.hpp"
#include "kernel/trajectory.hpp"
#include "kernel/model_io.hpp"
#include "kernel/simulate.hpp"
#include "results/run_metrics.hpp"
#include "results/table.hpp"
#include "common/text.hpp"

namespace ff {

namespace {

// A run that failed numerically (status nonfinite or solver_fail) has no metrics: exit 3, as `run` does,
// once its outputs (the trace up to the failure) are written.
void check_run_status(const std::string& status, const std::string& out) {
  if (is_failed_status(status))
    throw ExitError("the run failed numerically (status " + status + "): it has no metrics; its trace is in " + out + "/trace.csv", 3);
}

// An arm model (arm/): trace.csv, metrics.csv, table.md (metric | value) and the arm plots.
void simulate_arm(const std::string& path, const std::vector<std::string>& sets, const std::vector<std::string>& plant_sets,
                  const std::string& out) {
  const ArmModel m = load_arm_with(path, sets, plant_sets);
  print_safe(stderr, "simulating %s: %d bodies, %d joints (%zu actuated), %.2f s, %s with %d substeps of %.3g ms\n",
               path.c_str(), m.tree.num_bodies(), m.tree.nv(), m.actuated.size(), m.duration,
               integrator_name(m.integrator), m.substeps, 1e3 * m.control_period / m.substeps);
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1));
  ResultTable table;
  table.columns = arm_metric_columns(m);
  ResultRow row;
  row.label = path;
  row.values = calc_arm_metrics(m, run.traces[0], run.status[0]);
  row.status = calc_arm_status(m, run.status[0], table.columns, row.values);
  table.rows.push_back(row);
  std::string md = "| metric | value |\n|---|---|\n";
  // No number: a settling time the run could not confirm (censored), or none at all (a failed run, an event
  // that did not happen).
  for (std::size_t i = 0; i < table.columns.size(); ++i)
    md += "| " + md_cell(table.columns[i]) + " | " + format_metric_cell(row.values[i], find_row_horizon(table, row, table.columns[i]), "%.6g") + " |\n";
  make_directories(out);
  write_arm_trace_csv(run.traces[0], out + "/trace.csv");
  write_file_atomic(out + "/metrics.csv", format_results_csv(table));
  write_file_atomic(out + "/table.md", md);
  const std::vector<std::string> plots =
      write_arm_plots(out, {"simulation"}, {&run.traces[0]}, m.spec.description.empty() ? "simulation" : m.spec.description, m);
  std::string files = "trace.csv, metrics.csv, table.md";
  for (const std::string& p : plots) files += ", " + p;
  print_safe(stdout, "%s\nstatus: %s\nwrote %s/{%s}\n", md.c_str(), row.status.c_str(), out.c_str(), files.c_str());
  check_run_status(row.status, out);
}

}  // namespace

void add_simulate_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("simulate", "Simulate one model: writes DIR/trace.csv, DIR/metrics.csv, "
                                             "DIR/table.md and plots of tip angle, hub angle, tip deflection, torque");
  struct Args {
    std::string model, out;
    std::vector<std::string> sets, plant_sets;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("model", args->model, "model YAML file: the reference rig's, or an arm's (docs/formats.md)")
      ->required()
      ->check(kPath)
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "output directory (created)")->required()->check(kPath);
  cmd->add_option("--set", args->sets, "override a model parameter, PATH=VALUE; repeatable");
  cmd->add_option("--plant-set", args->plant_sets, "override a plant parameter the controller's model does not know (a hidden effect, a true payload), PATH=VALUE; repeatable");
  cmd->callback([args] {
    if (is_arm_model_file(args->model)) return simulate_arm(args->model, args->sets, args->plant_sets, args->out);
    const Model m = load_model_with(args->model, args->sets, args->plant_sets);
    print_safe(stderr, "simulating %s: N = %d, %.1f s, integrator %s\n", args->model.c_str(), m.nseg, m.duration,
                 integrator_name(m.spec.simulation.integrator));
    const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
    const BatchRun run = simulate(bm);
    ResultTable table;
    table.columns = calc_metric_columns(static_cast<int>(m.spec.trajectory.moves.size()));
    ResultRow row;
    row.label = args->model;
    row.values = calc_run_metrics(m, run.traces[0]);
    row.status = calc_run_status(run.status[0], table.columns, row.values);
    table.rows.push_back(row);
    const std::vector<std::vector<std::string>> moves{describe_moves(m.spec.trajectory)};
    make_directories(args->out);
    write_trace_csv(run.traces[0], args->out + "/trace.csv");
    write_file_atomic(args->out + "/metrics.csv", format_results_csv(table));
    const std::string md = format_settling_table_md(table, moves);
    write_file_atomic(args->out + "/table.md", md);
    write_trace_plots(args->out, {"simulation"}, {&run.traces[0]}, "simulation");
    print_safe(stdout, "%s\nstatus: %s\nwrote %s/{trace.csv, metrics.csv, table.md, tip_angle.png, hub_angle.png, "
                "tip_deflection.png, hub_torque.png}\n",
                md.c_str(), row.status.c_str(), args->out.c_str());
    check_run_status(row.status, args->out);
  });
}

}  // namespace ff
