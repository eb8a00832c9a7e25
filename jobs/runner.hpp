// Runs the variants of a study on the cores and collects one result row per variant.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "kernel/simulate.hpp"
#include "results/table.hpp"
#include "sweep/study.hpp"

namespace ff {

struct StudyRun {
  ResultTable table;             // one row per variant, ascending eval_id
  std::vector<Trace> traces;     // (variants), kept when asked for
  std::vector<Model> models;     // (variants)
};

struct RunOptions {
  bool keep_traces = true;
  int threads = 0;               // 0 = OpenMP default
  // Called after each finished variant with (done, total); from one thread at a time.
  std::function<void(int, int)> progress;
};

// Simulates every variant (each its own one-lane batch) and evaluates its metrics. The rows do
// not depend on the thread count.
StudyRun run_study(const Study& study, const RunOptions& opt);

}  // namespace ff
