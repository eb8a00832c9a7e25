#include "jobs/runner.hpp"

#include <omp.h>

#include <stdexcept>

#include "results/run_metrics.hpp"

namespace ff {

StudyRun run_study(const Study& study, const RunOptions& opt) {
  const int n = static_cast<int>(study.variants.size());
  StudyRun out;
  for (const auto& v : study.variants) out.models.push_back(make_variant_model(study, v));
  const int nmoves = static_cast<int>(out.models[0].spec.trajectory.moves.size());
  for (const auto& m : out.models)
    if (static_cast<int>(m.spec.trajectory.moves.size()) != nmoves)
      throw std::invalid_argument(study.source + ": every run of a study needs the same number of moves");
  out.table.columns = calc_metric_columns(nmoves);
  out.table.rows.resize(n);
  out.traces.resize(n);

  int done = 0;
  const int threads = opt.threads > 0 ? opt.threads : omp_get_max_threads();
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int i = 0; i < n; ++i) {
    // One variant: simulate, measure, keep the row in its eval_id slot.
    const Model& m = out.models[i];
    const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
    BatchRun run = simulate(bm);
    ResultRow row;
    row.eval_id = study.variants[i].eval_id;
    row.label = study.variants[i].label;
    row.values = calc_run_metrics(m, run.traces[0]);
    row.status = calc_run_status(run.status[0], out.table.columns, row.values);
    out.table.rows[i] = std::move(row);
    if (opt.keep_traces) out.traces[i] = std::move(run.traces[0]);
#pragma omp critical(ff_progress)
    {
      ++done;
      if (opt.progress) opt.progress(done, n);
    }
  }
  return out;
}

}  // namespace ff
