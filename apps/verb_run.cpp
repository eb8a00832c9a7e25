// flexfarm run STUDY.yaml --out DIR: every run of a study, its result table and plots.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "apps/verbs.hpp"
#include "jobs/runner.hpp"
#include "kernel/files.hpp"
#include "kernel/trajectory.hpp"
#include "results/table.hpp"

namespace ff {

void add_run_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("run", "Run a study: writes DIR/results.csv (one row per run), DIR/table.md "
                                        "(settling and overshoot), DIR/traces/*.csv and plots of all runs");
  struct Args {
    std::string study, out;
    int threads = 0;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("study", args->study, "study YAML file, e.g. configs/studies/fbtb_paper.yaml")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "output directory (created)")->required();
  cmd->add_option("--threads", args->threads, "worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
  cmd->callback([args] {
    const Study study = load_study(args->study);
    const auto t0 = std::chrono::steady_clock::now();
    const bool tty = isatty(fileno(stderr));
    RunOptions opt;
    opt.threads = args->threads;
    opt.progress = [&](int done, int total) {
      const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::fprintf(stderr, tty ? "\r%s: %d/%d runs, %.1f s elapsed   " : "%s: %d/%d runs, %.1f s elapsed\n",
                   study.name.c_str(), done, total, el);
      if (tty && done == total) std::fprintf(stderr, "\n");
    };
    const StudyRun run = run_study(study, opt);

    // Outputs, each written whole (temporary file + rename).
    make_directories(args->out + "/traces");
    std::vector<std::string> labels;
    std::vector<const Trace*> traces;
    for (std::size_t i = 0; i < run.traces.size(); ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "/traces/%06d.csv", run.table.rows[i].eval_id);
      write_trace_csv(run.traces[i], args->out + name);
      labels.push_back(run.table.rows[i].label);
      traces.push_back(&run.traces[i]);
    }
    write_file_atomic(args->out + "/results.csv", format_results_csv(run.table));
    std::vector<std::vector<std::string>> moves;
    for (const auto& m : run.models) moves.push_back(describe_moves(m.spec.trajectory));
    const std::string md = format_settling_table_md(run.table, moves);
    write_file_atomic(args->out + "/table.md", "# " + study.name + "\n\n" + study.description + "\n\n" + md);
    write_trace_plots(args->out, labels, traces, study.name);
    int failed = 0;
    for (const auto& r : run.table.rows) failed += r.status == "nonfinite" || r.status == "solver_fail";
    std::printf("%s\nwrote %s/results.csv, %s/table.md, %s/traces/, plots %s/{tip_angle,hub_angle,tip_deflection,"
                "hub_torque}.png\n",
                md.c_str(), args->out.c_str(), args->out.c_str(), args->out.c_str(), args->out.c_str());
    if (failed) throw std::runtime_error(std::to_string(failed) + " run(s) failed numerically; see results.csv");
  });
}

}  // namespace ff
