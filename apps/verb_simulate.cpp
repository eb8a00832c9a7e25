// flexfarm simulate MODEL.yaml --out DIR: one closed-loop run, its trace, metrics and plots.
#include <cstdio>

#include "apps/verbs.hpp"
#include "kernel/files.hpp"
#include "jobs/report.hpp"
#include "kernel/trajectory.hpp"
#include "kernel/model_io.hpp"
#include "kernel/simulate.hpp"
#include "results/run_metrics.hpp"
#include "results/table.hpp"

namespace ff {

void add_simulate_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("simulate", "Simulate one model: writes DIR/trace.csv, DIR/metrics.csv, "
                                             "DIR/table.md and plots of tip angle, hub angle, tip deflection, torque");
  struct Args {
    std::string model, out;
    std::vector<std::string> sets;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("model", args->model, "model YAML file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "output directory (created)")->required();
  cmd->add_option("--set", args->sets, "override a model parameter, PATH=VALUE; repeatable");
  cmd->callback([args] {
    const Model m = load_model_with(args->model, args->sets);
    std::fprintf(stderr, "simulating %s: N = %d, %.1f s, integrator %s\n", args->model.c_str(), m.nseg, m.duration,
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
    std::printf("%s\nstatus: %s\nwrote %s/{trace.csv, metrics.csv, table.md, tip_angle.png, hub_angle.png, "
                "tip_deflection.png, hub_torque.png}\n",
                md.c_str(), row.status.c_str(), args->out.c_str());
  });
}

}  // namespace ff
