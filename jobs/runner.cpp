#include "jobs/runner.hpp"

#include <omp.h>

#include <chrono>
#include <stdexcept>

#include "jobs/batches.hpp"
#include "results/run_metrics.hpp"

namespace ff {

ResultTable make_result_table(const Study& study) {
  ResultTable t;
  t.params = study.params;
  const std::size_t nmoves = study.models[0].spec.trajectory.moves.size();
  for (const auto& m : study.models)
    if (m.spec.trajectory.moves.size() != nmoves)
      throw std::invalid_argument(study.source + ": every variant of a study needs the same number of moves");
  t.columns = calc_metric_columns(static_cast<int>(nmoves));
  return t;
}

ResultRow make_result_row(const Study& study, int i, const Trace& trace, LaneStatus status) {
  const Variant& v = study.variants[i];
  ResultRow row;
  row.eval_id = v.eval_id;
  row.seed = v.seed;
  row.label = v.label;
  row.params = v.params;
  row.values = calc_run_metrics(study.models[i], trace);
  row.status = calc_run_status(status, calc_metric_columns(static_cast<int>(study.models[i].spec.trajectory.moves.size())),
                               row.values);
  return row;
}

void evaluate_variants(const Study& study, const std::vector<int>& pending, const EvalOptions& opt,
                       const std::function<void(BatchResult&&)>& done) {
  const std::vector<Batch> batches = make_batches(study.models, pending, opt.lanes);
  const int nb = static_cast<int>(batches.size());
  const int threads = opt.threads > 0 ? opt.threads : omp_get_max_threads();
  // Nothing may leave the parallel region by exception: the first error is kept and rethrown.
  std::exception_ptr error;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int b = 0; b < nb; ++b) {
    try {
      const auto t0 = std::chrono::steady_clock::now();
      std::vector<Model> lanes;
      for (int i : batches[b].variants) lanes.push_back(study.models[i]);
      BatchRun run = simulate(make_batch(lanes));
      BatchResult res;
      for (std::size_t l = 0; l < lanes.size(); ++l) {
        res.rows.push_back(make_result_row(study, batches[b].variants[l], run.traces[l], run.status[l]));
        if (opt.keep_traces) res.traces.push_back(std::move(run.traces[l]));
      }
      res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
#pragma omp critical(ff_batch_done)
      done(std::move(res));
    } catch (...) {
#pragma omp critical(ff_batch_error)
      if (!error) error = std::current_exception();
    }
  }
  if (error) std::rethrow_exception(error);
}

StudyRun run_study(const Study& study, const EvalOptions& opt, const std::function<void(int, int)>& progress) {
  const int n = static_cast<int>(study.variants.size());
  std::vector<int> pending(n);
  for (int i = 0; i < n; ++i) pending[i] = i;
  StudyRun out;
  out.table = make_result_table(study);
  out.table.rows.resize(n);
  if (opt.keep_traces) out.traces.resize(n);
  int finished = 0;
  evaluate_variants(study, pending, opt, [&](BatchResult&& res) {
    for (std::size_t k = 0; k < res.rows.size(); ++k) {
      const int id = res.rows[k].eval_id;
      if (opt.keep_traces) out.traces[id] = std::move(res.traces[k]);
      out.table.rows[id] = std::move(res.rows[k]);
    }
    finished += static_cast<int>(res.rows.size());
    if (progress) progress(finished, n);
  });
  return out;
}

}  // namespace ff
