// Evaluates the variants of a study: lane batches on OpenMP threads, one result row per variant.
// Rows are a pure function of the variant: the same bits for any thread count, lane width,
// rank count or resume.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "arm/arm_simulate.hpp"
#include "kernel/simulate.hpp"
#include "results/table.hpp"
#include "sweep/study.hpp"

namespace ff {

struct EvalOptions {
  int lanes = 8;                 // W: variants advanced together by one kernel call
  int threads = 0;               // 0 = OpenMP default
  bool keep_traces = false;      // keep each variant's trace; without, its metrics accumulate online (rig and arms)
  // Set (by `done`) to stop early: no new chunk and no new batch starts; those running finish.
  const std::atomic<bool>* stop = nullptr;
};

// A finished batch: its rows (ascending eval_id), their traces when kept, and its wall time.
struct BatchResult {
  std::vector<ResultRow> rows;
  std::vector<Trace> traces;
  std::vector<ArmTrace> arm_traces;  // an arm study's traces (instead of `traces`)
  double seconds = 0.0;
};

// The result row of one simulated variant (`model` is its model), from its trace or, the same bits,
// from its online metrics (simulate's `metrics`).
ResultRow make_result_row(const Study& study, int variant, const Model& model, const Trace& trace, LaneStatus status);
ResultRow make_result_row(const Study& study, int variant, const Model& model, const OnlineRun& run, LaneStatus status);

// Why variant `variant` has the status `invalid`: the error its model gives (file, line, key), or
// its number of moves; empty if it is valid.
std::string explain_invalid_variant(const Study& study, int variant);

// Simulates the variants `pending` (indices into study.variants) in batches on the threads, building
// their models chunk by chunk; a variant whose model cannot be built gets a row with the status
// `invalid` and no metrics. `done` is called once per batch (and once per chunk for its invalid
// rows), from one thread at a time, in completion order.
void evaluate_variants(const Study& study, const std::vector<int>& pending, const EvalOptions& opt,
                       const std::function<void(BatchResult&&)>& done);

// The empty result table of a study: its parameter and metric columns.
ResultTable make_result_table(const Study& study);

// In memory: every variant of the study, rows in eval_id order (traces when asked for).
struct StudyRun {
  ResultTable table;
  std::vector<Trace> traces;     // (variants) when opt.keep_traces
  std::vector<ArmTrace> arm_traces;  // (variants) an arm study's, when opt.keep_traces
};
StudyRun run_study(const Study& study, const EvalOptions& opt,
                   const std::function<void(int, int)>& progress = nullptr);

}  // namespace ff
