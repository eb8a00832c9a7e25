// flexfarm run STUDY.yaml --out DIR: every variant of a study, on the cores, the MPI ranks or a
// Slurm array task's shard; journalled, resumable; then the result table, database and plots.
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <regex>

#include "apps/verbs.hpp"
#include "jobs/farm.hpp"
#include "jobs/mpi.hpp"
#include "jobs/progress.hpp"
#include "jobs/report.hpp"
#include "jobs/report_html.hpp"
#include "common/files.hpp"
#include "results/diff.hpp"
#include "results/history.hpp"
#include "results/run_metrics.hpp"

namespace ff {

namespace {

// "i/N" with 0 <= i < N.
Partition parse_shard(const std::string& text) {
  std::smatch m;
  const std::regex re("^([0-9]+)/([0-9]+)$");
  if (!std::regex_match(text, m, re)) throw CLI::ValidationError("--shard", "expected I/N, e.g. 3/16, got '" + text + "'");
  Partition p{std::stoi(m[1]), std::stoi(m[2])};
  if (p.count < 1 || p.index >= p.count) throw CLI::ValidationError("--shard", "needs 0 <= I < N, got '" + text + "'");
  return p;
}

// Exit status 3 when any variant failed numerically or could not run (not_settled is a result).
std::string describe_failures(const Study& study, const ResultTable& t) {
  int failed = 0, invalid = 0, first_invalid = -1;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    failed += is_failed_status(t.rows[i].status);
    if (t.rows[i].status != "invalid") continue;
    if (!invalid++) first_invalid = static_cast<int>(i);
  }
  std::string why;
  if (failed) why = std::to_string(failed) + " variant(s) failed numerically (status nonfinite or solver_fail in results.csv)";
  if (invalid)
    why += (why.empty() ? "" : "; ") + std::to_string(invalid) +
           " variant(s) invalid (status invalid in results.csv): their values are ones the model rejects; the first, " +
           explain_invalid_variant(study, first_invalid);
  return why;
}

}  // namespace

// Where a run records itself: --history, or the default history (results/history.hpp); --no-history: nowhere.
struct HistoryArgs {
  std::string dir;
  bool off = false;
  void add(CLI::App* cmd) {
    cmd->add_option("--history", dir, "run history directory (default: $FLEXFARM_HISTORY, else "
                                      "$XDG_DATA_HOME/flexfarm, else ~/.local/share/flexfarm)");
    cmd->add_flag("--no-history", off, "do not record this run in the run history");
  }
};

// Assembles the journals of `dir` into the final outputs, records the run in the history, compares it
// with the study's previous run there (DIR/diff.md) and prints where they are.
void finish_study(const Study& study, const std::string& dir, const RunContext& ctx, const HistoryArgs& history) {
  const ResultTable table = assemble_results(study, dir);
  RunRecord record = make_run_record(study, table, dir, ctx);
  ReportPage page;
  page.description = study.description;
  page.table_md = write_study_report(study, table, dir, record);
  std::printf("%s\nwrote %s/results.csv, results.sqlite, table.md and plots\n", page.table_md.c_str(), dir.c_str());
  const std::string hist = history.off ? "" : resolve_history_dir(history.dir);
  page.diff_note = hist.empty() ? "Not recorded in a run history (--no-history, or no home directory)."
                                : "The first run of this study in the history " + hist + ".";
  if (!hist.empty()) {
    // The results stand without the history: a history that cannot be written is a warning.
    try {
      record.id = record_run(hist, record);
      std::printf("recorded as run %ld in %s/history.sqlite\n", record.id, hist.c_str());
      if (const auto previous = find_previous_run(hist, record)) {
        if (std::filesystem::exists(previous->out + "/results.sqlite")) {
          const RunDiff d = diff_runs(read_run_dir(*previous), RunDir{record, table}, study.tolerances, study.requirements, study.specs);
          page.diff_md = format_diff_md(d);
          write_file_atomic(dir + "/diff.md", page.diff_md);
          std::printf("compared with %s: %s (%s/diff.md)\n", previous->describe().c_str(),
                      d.regressions.empty() ? "nothing got worse" : (std::to_string(d.regressions.size()) + " regression(s)").c_str(),
                      dir.c_str());
        } else {
          page.diff_note = "The previous run, " + previous->describe() + ", is gone from " + previous->out + ": not compared.";
          std::printf("%s\n", page.diff_note.c_str());
        }
      }
    } catch (const std::runtime_error& e) {
      page.diff_note = std::string("The run history was not updated: ") + e.what();
      std::fprintf(stderr, "flexfarm: warning: the run history was not updated: %s\n", e.what());
    }
  }
  page.record = record;
  write_report_html(dir, page);
  std::printf("wrote %s/report.html\n", dir.c_str());
  if (!record.verdicts.empty()) {
    // The verdicts last, where they are seen (they do not change the exit code).
    const std::size_t n = table.rows.size(), total = study.variants.size();
    std::printf("\nrequirements (%zu of %zu variants%s):\n%s", n, total, n < total ? ", stopped early: every requirement decided" : "",
                format_verdict_lines(record.verdicts).c_str());
  }
  const std::string failures = describe_failures(study, table);
  if (!failures.empty()) throw ExitError(failures, 3);
}

void add_run_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "run", "Run a study: every variant on the cores (and MPI ranks under mpirun), journalled so --resume continues "
             "a killed run; writes DIR/results.csv, results.sqlite, table.md, plots (and traces/ for small studies)");
  struct Args {
    std::string study, out, shard;
    int threads = 0, lanes = 8;
    bool resume = false;
    HistoryArgs history;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("study", args->study, "study YAML file, e.g. configs/studies/fbtb_paper.yaml")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "output directory (created)")->required();
  cmd->add_flag("--resume", args->resume, "continue the run journalled in --out: compute only the missing variants");
  cmd->add_option("--threads", args->threads, "worker threads per process (default: all cores)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--lanes", args->lanes, "variants advanced together by one kernel call")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  auto* shard = cmd->add_option("--shard", args->shard,
                  "I/N: compute only the variants with eval_id % N == I (a Slurm array task: "
                  "--shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT), then `flexfarm merge`");
  args->history.add(cmd);
  cmd->callback([args, shard] {
    const auto t0 = std::chrono::steady_clock::now();
    RunContext ctx{.started = format_utc_now()};
    const bool sharded = shard->count() > 0;  // an empty --shard "$UNSET" is an error, not "no shard"
    if (sharded) parse_shard(args->shard);
    const Study study = load_study(args->study);
    const MpiSession& comm = mpi();
    FarmOptions opt;
    opt.out = args->out;
    opt.resume = args->resume;
    opt.eval.lanes = args->lanes;
    opt.eval.threads = args->threads;
    opt.eval.keep_traces = study.keep_traces;
    if (sharded) {
      if (comm.size() > 1) throw CLI::ValidationError("--shard", "use either MPI ranks or --shard, not both");
      opt.part = parse_shard(args->shard);
      opt.tag = "shard-" + std::to_string(opt.part.index) + "-of-" + std::to_string(opt.part.count);
    } else if (comm.size() > 1) {
      opt.part = {comm.rank(), comm.size()};
      opt.tag = "rank-" + std::to_string(comm.rank()) + "-of-" + std::to_string(comm.size());
    }
    if (comm.rank() == 0) make_directories(args->out + (study.keep_traces ? "/traces" : ""));
    comm.barrier();
    // One process per journal: a second run on the same --out (and share) refuses before it reads or writes.
    const FileLock lock(args->out + "/journal-" + opt.tag + ".lock",
                        args->out + ": another flexfarm run is writing it (journal-" + opt.tag +
                            ".csv is locked); wait for that run to end, or use another --out");

    opt.notice = [](const std::string& m) { std::fprintf(stderr, "flexfarm: %s\n", m.c_str()); };
    if (study.requirements.stop_when_decided && opt.part.count > 1 && comm.rank() == 0)
      opt.notice("requirements.stop_when_decided: " + std::string(sharded ? "shards" : "MPI ranks") +
                 " do not see each other's rows, so every variant runs; the results stop where one process would have");
    Progress progress(study.name + (opt.tag == "main" ? "" : " " + opt.tag), stderr_is_terminal());
    int already = -1;
    opt.progress = [&](int done, int total, double seconds) {
      if (already < 0) already = done;
      if (comm.rank() == 0) progress.update(done, total, done - already, seconds);
    };
    // Every rank runs its share; a failure on any rank stops them all after the barrier.
    std::string error;
    try {
      run_farm(study, opt);
    } catch (const std::exception& e) {
      error = e.what();
    }
    progress.finish();
    if (comm.any(!error.empty())) {
      if (!error.empty()) throw std::runtime_error(error);
      throw std::runtime_error("another rank failed");
    }
    if (sharded) {
      std::printf("shard %s of %s done in %s; when every shard is done: flexfarm merge %s --out %s\n",
                  args->shard.c_str(), study.name.c_str(), args->out.c_str(), args->study.c_str(), args->out.c_str());
      return;
    }
    comm.barrier();
    ctx.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ctx.processes = comm.size();
    ctx.threads = args->threads > 0 ? args->threads : omp_get_max_threads();
    ctx.lanes = args->lanes;
    if (comm.rank() == 0) finish_study(study, args->out, ctx, args->history);
  });
}

void add_merge_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("merge", "Assemble the journals of a sharded run (flexfarm run --shard I/N) into "
                                          "DIR/results.csv, results.sqlite, table.md and plots");
  struct Args {
    std::string study, out;
    HistoryArgs history;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("study", args->study, "the study YAML file the shards ran")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "the directory the shards wrote into")->required()->check(CLI::ExistingDirectory);
  args->history.add(cmd);
  // The shards' start and wall time are their own: the record says when the merge finished.
  cmd->callback([args] { finish_study(load_study(args->study), args->out, RunContext{}, args->history); });
}

}  // namespace ff
