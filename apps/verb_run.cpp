// flexfarm run STUDY.yaml --out DIR: every variant of a study, on the cores, the MPI ranks or a
// Slurm array task's shard; journalled, resumable; then the result table, database and plots.
#include <omp.h>

#include <chrono>
#include <climits>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <regex>

#include "apps/verbs.hpp"
#include "jobs/farm.hpp"
#include "jobs/mpi.hpp"
#include "jobs/progress.hpp"
#include "jobs/report.hpp"
#include "jobs/report_html.hpp"
#include "common/files.hpp"
#include "common/text.hpp"
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
  const auto index = parse_integer(m.str(1), 0, INT_MAX), count = parse_integer(m.str(2), 1, INT_MAX);
  if (!index || !count || *index >= *count)
    throw CLI::ValidationError("--shard", "needs 0 <= I < N <= " + std::to_string(INT_MAX) + ", got '" + text + "'");
  return {static_cast<int>(*index), static_cast<int>(*count)};
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
                                      "$XDG_DATA_HOME/flexfarm, else ~/.local/share/flexfarm)")
        ->check(kPath);
    cmd->add_flag("--no-history", off, "do not record this run in the run history");
  }
  // The history directory ("": none), resolved before the run starts: a blank $FLEXFARM_HISTORY is a usage error.
  std::string resolve() const {
    try {
      return off ? "" : resolve_history_dir(dir);
    } catch (const std::runtime_error& e) {
      throw ExitError(e.what(), 2);
    }
  }
};

// Assembles the journals of `dir` into the final outputs, compares the run with the study's previous
// run in the history `hist` ("": none) into DIR/diff.md, writes DIR/report.html and records the run in
// the history once that is written (a run that fails before its end is not recorded), and prints where
// they are.
void finish_study(const Study& study, const std::string& dir, const RunContext& ctx, const std::string& hist) {
  const ResultTable table = assemble_results(study, dir);
  RunRecord record = make_run_record(study, table, dir, ctx);
  ReportPage page;
  page.description = study.description;
  const StudyReport report = write_study_report(study, table, dir, record);
  page.results_md = report.results;
  print_safe(stdout, "%s\nwrote %s/results.csv, results.sqlite, table.md and plots\n", report.md().c_str(), dir.c_str());
  page.diff_note = hist.empty() ? "Not recorded in a run history (--no-history, or no home directory)."
                                : "The first run of this study in the history " + hist + ".";
  // The results stand without the history: a history that cannot be read or written is a warning.
  std::string history_error;
  if (!hist.empty()) {
    try {
      if (const auto previous = find_previous_run(hist, record)) {
        if (std::filesystem::exists(previous->out + "/results.sqlite")) {
          const RunDiff d = diff_runs(read_run_dir(*previous), RunDir{record, table}, study.tolerances, study.requirements, study.specs);
          page.diff_md = format_diff_md(d);
          page.regressions = d.regressions;
          print_safe(stdout, "compared with %s: %s (%s/diff.md)\n", previous->describe().c_str(),
                     d.regressions.empty() ? "nothing got worse" : (std::to_string(d.regressions.size()) + " regression(s)").c_str(),
                     dir.c_str());
        } else {
          page.diff_note = "The previous run, " + previous->describe() + ", is gone from " + previous->out + ": not compared.";
          print_safe(stdout, "%s\n", page.diff_note.c_str());
        }
      }
    } catch (const std::runtime_error& e) {
      history_error = e.what();
    }
  }
  if (!page.diff_md.empty()) write_file_atomic(dir + "/diff.md", page.diff_md);
  // A --resume of a run already finished and recorded (a requeued job): the same run, recorded once.
  if (!hist.empty() && history_error.empty() && !record.started.empty()) {
    try {
      for (const RunRecord& r : list_runs(hist, record.study_path))
        if (r.out == record.out && r.started == record.started && r.study_hash == record.study_hash) record.id = r.id;
    } catch (const std::runtime_error& e) {
      history_error = e.what();
    }
    if (record.id > 0) print_safe(stdout, "already recorded as run %ld in %s/history.sqlite\n", record.id, hist.c_str());
  }
  bool reported = false;  // report.html written with the record, in its transaction
  if (!hist.empty() && history_error.empty() && record.id == 0) {
    bool reporting = false;  // report.html failing (a full disk) is the run's error: nothing is recorded
    try {
      page.record = record;
      record.id = record_run(hist, record, [&](long id) {
        page.record.id = id;
        reporting = true;
        write_report_html(dir, page);
        reporting = false;
      });
      reported = true;
      print_safe(stdout, "recorded as run %ld in %s/history.sqlite\n", record.id, hist.c_str());
    } catch (const std::runtime_error& e) {
      if (reporting) throw;
      history_error = e.what();
    }
  }
  if (!reported) {
    if (!history_error.empty()) {
      page.diff_note = "The run history was not updated: " + history_error;
      print_safe(stderr, "flexfarm: warning: the run history was not updated: %s\n", history_error.c_str());
    }
    page.record = record;
    write_report_html(dir, page);
  }
  print_safe(stdout, "wrote %s/report.html\n", dir.c_str());
  if (!record.verdicts.empty()) {
    // The verdicts last, where they are seen (they do not change the exit code).
    const std::size_t n = table.rows.size(), total = study.variants.size();
    print_safe(stdout, "\nrequirements (%zu of %zu variants%s):\n%s", n, total, n < total ? ", stopped early: every requirement decided" : "",
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
      ->check(kPath)
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "output directory (created)")->required()->check(kPath);
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
    const std::string hist = args->history.resolve();
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
    if (comm.rank() == 0) {
      make_directories(args->out);
      if (study.keep_traces) make_own_directory(args->out + "/traces");  // never a link planted in a shared --out
    }
    comm.barrier();
    // One process per journal: a second run on the same --out (and share) refuses before it reads or writes.
    const FileLock lock(args->out + "/journal-" + opt.tag + ".lock",
                        args->out + ": another flexfarm run is writing it (journal-" + opt.tag +
                            ".csv is locked); wait for that run to end, or use another --out");

    opt.notice = [](const std::string& m) { print_safe(stderr, "flexfarm: %s\n", m.c_str()); };
    if (study.requirements.stop_when_decided && opt.part.count > 1 && comm.rank() == 0)
      opt.notice("requirements.stop_when_decided: " + std::string(sharded ? "shards" : "MPI ranks") +
                 " do not see each other's rows, so every variant runs; the results stop where one process would have");
    Progress progress(study.name + (opt.tag == "main" ? "" : " " + opt.tag), stderr_is_terminal());
    int already = -1;
    // This attempt's wall time, kept after each batch and at its end however it ends (a throw, not a kill),
    // so the run is recorded with every attempt's (jobs/farm.hpp). Rank 0's, from its first batch on:
    // run_farm has refused a journal that is not to be resumed by then.
    std::optional<AttemptLog> attempts;
    const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    struct NoteAtEnd {
      std::optional<AttemptLog>& log;
      std::function<double()> seconds;
      ~NoteAtEnd() {
        try {
          if (log) log->note(seconds());
        } catch (const std::exception&) {  // a full disk: the run's own error says so
        }
      }
    } note_at_end{attempts, elapsed};
    opt.progress = [&](int done, int total, double seconds) {
      if (already < 0) already = done;
      if (comm.rank() != 0) return;
      progress.update(done, total, done - already, seconds);
      if (!attempts) attempts.emplace(args->out, opt.tag, ctx.started, args->resume);
      attempts->note(elapsed());
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
      print_safe(stdout, "shard %s of %s done in %s; when every shard is done: flexfarm merge %s --out %s\n",
                  args->shard.c_str(), study.name.c_str(), args->out.c_str(), args->study.c_str(), args->out.c_str());
      return;
    }
    comm.barrier();
    ctx.seconds = elapsed();
    if (attempts) {  // with --resume, every attempt's: the run's first start, the sum of their wall times
      ctx.started = attempts->first_started();
      ctx.seconds = attempts->total_seconds(ctx.seconds);
    }
    ctx.processes = comm.size();
    ctx.threads = args->threads > 0 ? args->threads : omp_get_max_threads();
    ctx.lanes = args->lanes;
    if (comm.rank() == 0) finish_study(study, args->out, ctx, hist);
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
  cmd->add_option("study", args->study, "the study YAML file the shards ran")->required()->check(kPath)->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "the directory the shards wrote into")->required()->check(kPath)->check(CLI::ExistingDirectory);
  args->history.add(cmd);
  // The shards' start and wall time are their own: the record says when the merge finished.
  cmd->callback([args] { finish_study(load_study(args->study), args->out, RunContext{}, args->history.resolve()); });
}

}  // namespace ff
