// A study run on disk: a share of the variants (all of them, an MPI rank's or a Slurm array
// task's) is evaluated batch by batch and journalled, so a killed run resumes where it stopped;
// the final results are assembled from the journals, in eval_id order, byte-identical whatever
// the thread count, lane width, rank count, sharding or interruptions.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "jobs/runner.hpp"

namespace ff {

// This process evaluates the variants with eval_id % count == index.
struct Partition {
  int index = 0;
  int count = 1;
};

struct FarmOptions {
  std::string out;               // output directory (exists)
  bool resume = false;           // continue the journals found in `out`
  EvalOptions eval;
  Partition part;
  std::string tag = "main";      // this process's journal: out/journal-<tag>.csv
  // After each batch: (variants of this share done, of this share in total, seconds so far).
  std::function<void(int, int, double)> progress;
  // What the user should be told, once (a journal repaired on resume).
  std::function<void(const std::string&)> notice;
};

struct FarmStatus {
  int total = 0;                 // variants of this share
  int already = 0;               // found in the journals (resume)
  int computed = 0;              // evaluated now
  int stop = -1;                 // requirements.stop_when_decided: the variants the study stopped at, else -1
};

// Evaluates this process's share. Throws std::runtime_error when `out` already holds this tag's
// journal and resume is off, or a journal of another study. A study with requirements.stop_when_decided
// run whole (no partition) stops once its stop point is known (find_study_stop_point): no new batch
// starts; rows of batches already running are journalled too. Partitioned, it runs its whole share.
FarmStatus run_farm(const Study& study, const FarmOptions& opt);

// Reads every journal in `out` and returns the complete result table; throws std::runtime_error
// naming how many variants are missing when the journals do not cover the study. A study that stops
// early (find_study_stop_point) is complete with its first K rows, and its table is exactly those.
ResultTable assemble_results(const Study& study, const std::string& out);

// Where a study with requirements.stop_when_decided stops, from its rows by eval_id (as journalled):
// find_stop_point (results/requirements.hpp) on them, -1 while not known. The study's size otherwise.
int find_study_stop_point(const Study& study, const std::map<int, std::string>& rows);

// DIR/attempts-<tag>.csv: the wall time of every attempt at the run in DIR (a run killed or failed,
// then each --resume), so that the run, once finished, is recorded with its whole wall time. Lines
// "attempt,started,seconds": the attempt's number, its start (UTC) and its seconds so far, appended
// after each batch and when it ends (a killed attempt's time counts up to its last batch). Bookkeeping,
// as the timings: a line that cannot be written (a full disk) is lost, not an error.
class AttemptLog {
 public:
  // Reads the earlier attempts (none unless `resume`: a fresh run starts the file afresh).
  AttemptLog(const std::string& out, const std::string& tag, const std::string& started, bool resume);
  void note(double seconds);  // this attempt's seconds so far
  const std::string& first_started() const { return first_started_; }      // the first attempt's start
  double total_seconds(double seconds) const { return earlier_ + seconds; }  // every attempt's, this one's at `seconds`

 private:
  std::string path_, started_, first_started_;
  int attempt_ = 1;
  double earlier_ = 0.0;
};

// The verdicts of a study's requirements on its result table (the whole study, or the rows it
// stopped at). Empty without requirements.
std::vector<Verdict> calc_study_verdicts(const Study& study, const ResultTable& table);

}  // namespace ff
