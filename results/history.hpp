// A run's record and the run history: what a finished `flexfarm run` was (study, inputs and their
// hashes, version, machine, times, variant counts, per-metric summaries, requirement verdicts), kept
// in its output directory (results.sqlite, table `study`) and appended to a history database
// (SQLite, DIR/history.sqlite) that `flexfarm history` lists and `flexfarm diff` reads.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "results/requirements.hpp"
#include "results/statistics.hpp"
#include "results/table.hpp"

namespace ff {

// One metric of a run summarised (censored metrics as calc_summary(values, horizons): the mean is the
// restricted mean, percentiles above the horizon +inf). mean_lower/upper: mean ± z se, se from the
// restricted values (calc_restricted_values), 95 %. With a spec: P(miss) and its Wilson interval.
struct MetricSummary {
  std::string metric;
  int count = 0, censored = 0, missing = 0;
  double mean = kStatsNaN, mean_lower = kStatsNaN, mean_upper = kStatsNaN;
  double min = kStatsNaN, p5 = kStatsNaN, p50 = kStatsNaN, p95 = kStatsNaN, max = kStatsNaN;
  double spec = kStatsNaN, p_miss = kStatsNaN, p_miss_lower = kStatsNaN, p_miss_upper = kStatsNaN;
};
std::vector<MetricSummary> calc_metric_summaries(const ResultTable& t, const std::map<std::string, double>& specs);

struct RunRecord {
  long id = 0;                       // in the history (0: not recorded there)
  std::string study;                 // the study's name
  std::string study_path, out;       // absolute: the study file and the output directory
  std::string study_hash;            // Study::hash (the study and model texts)
  std::string study_text, model_path, model_text;  // the inputs as they were read
  std::string study_sha256, model_sha256;          // of those texts (what sha256sum prints for the files)
  std::string version, commit, host;
  std::string started, finished;     // UTC, ISO 8601 ("2026-12-05T02:00:13Z"); started "" when not known
  double seconds = kStatsNaN;        // wall time, start to finish
  int processes = 1, threads = 0, lanes = 0;
  int planned = 0;                   // the study's variants
  int variants = 0;                  // rows in the results (fewer than planned when stopped early)
  std::map<std::string, int> status;  // rows by status: ok, not_settled, nonfinite, solver_fail, invalid
  std::vector<MetricSummary> summaries;
  std::vector<Verdict> verdicts;   // of the study's requirements (results/requirements.hpp)

  int failed() const;                // rows whose status is nonfinite, solver_fail or invalid
  std::string describe() const;      // "run 12 (fbtb_mc, 2026-12-05T02:00:13Z)" or the directory
};

// The row counts by status of a result table.
std::map<std::string, int> count_statuses(const ResultTable& t);

// SHA-256 of `bytes` in hex (OpenSSL).
std::string calc_sha256(const std::string& bytes);

// Now, as ISO 8601 UTC.
std::string format_utc_now();
// This machine's host name ("" when unknown).
std::string host_name();

// The run record's key-value form, and back (unknown keys ignored, absent ones left default).
std::map<std::string, std::string> format_run_info(const RunRecord& r);
RunRecord parse_run_info(const std::map<std::string, std::string>& info);

// DIR/run.yaml: the record, its key-value form as a YAML map with the verdicts as a list (results.csv and
// results.sqlite stay byte-identical from run to run; this file holds what differs: times, host, paths).
std::string format_run_yaml(const RunRecord& r);

// A finished run's directory: its record (run.yaml; for a run from before run.yaml, results.sqlite's
// table `study`) and its result table (results.csv).
// Throws std::runtime_error naming what is missing or malformed.
struct RunDir {
  RunRecord record;
  ResultTable table;
};
RunDir read_run_dir(const std::string& dir);
// The directory of a run in the history, with the run's id; throws std::runtime_error naming the run
// when its directory is gone.
RunDir read_run_dir(const RunRecord& recorded);

// The history directory: `option` when given, else $FLEXFARM_HISTORY, else $XDG_DATA_HOME/flexfarm,
// else $HOME/.local/share/flexfarm; "" when none can be found. A variable set to "" counts as unset; one
// set blank ("  ") throws std::runtime_error naming it.
std::string resolve_history_dir(const std::string& option);

// Appends `r` (with its summaries and verdicts) to DIR/history.sqlite, creating it; returns its id.
// Waits for another process that is writing it (up to 30 s). Throws std::runtime_error naming the
// file when it cannot, or when the file is no flexfarm history. `finish(id)`, when given, runs inside
// the transaction, before it commits (flexfarm run writes report.html there, naming the id): a run is
// recorded only once it has finished; when finish throws, nothing is recorded and the exception passes on.
long record_run(const std::string& history_dir, const RunRecord& r, const std::function<void(long)>& finish = {});

// The runs in the history, oldest first: all, or those whose study is `study` (a name, or a study
// file's absolute path). Summaries and verdicts are read too when `full`. An absent history: none.
std::vector<RunRecord> list_runs(const std::string& history_dir, const std::string& study = "", bool full = false);
// One run by id, with its summaries and verdicts; throws std::runtime_error when there is none.
RunRecord read_history_run(const std::string& history_dir, long id);
// The latest run of the same study file recorded before `r` (by id; r.id = 0: the latest of all).
std::optional<RunRecord> find_previous_run(const std::string& history_dir, const RunRecord& r);

}  // namespace ff
