#include "jobs/runner.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "jobs/batches.hpp"
#include "common/errors.hpp"
#include "arm/arm_metrics.hpp"
#include "arm/arm_online_metrics.hpp"
#include "results/run_metrics.hpp"

namespace ff {

ResultTable make_result_table(const Study& study) {
  ResultTable t;
  t.params = study.params;
  t.columns = study.arm ? arm_metric_columns(study.arm_nominal)
                        : calc_metric_columns(static_cast<int>(study.nominal.spec.trajectory.moves.size()));
  return t;
}

namespace {
// A variant that could not run: its parameters, no metrics, and why in its status.
ResultRow make_invalid_row(const Study& study, int i, std::size_t ncolumns) {
  const Variant& v = study.variants[i];
  return {v.eval_id, v.seed, v.label, "invalid", v.params, std::vector<double>(ncolumns, std::nan(""))};
}
}  // namespace

namespace {
// A simulated variant's row from its metric values.
ResultRow make_row(const Study& study, int i, const Model& model, std::vector<double> values, LaneStatus status) {
  const Variant& v = study.variants[i];
  ResultRow row;
  row.eval_id = v.eval_id;
  row.seed = v.seed;
  row.label = v.label;
  row.params = v.params;
  row.values = std::move(values);
  row.status = calc_run_status(status, calc_metric_columns(static_cast<int>(model.spec.trajectory.moves.size())), row.values);
  return row;
}
}  // namespace

ResultRow make_result_row(const Study& study, int i, const Model& model, const Trace& trace, LaneStatus status) {
  return make_row(study, i, model, calc_run_metrics(model, trace), status);
}

ResultRow make_result_row(const Study& study, int i, const Model& model, const OnlineRun& run, LaneStatus status) {
  return make_row(study, i, model, calc_run_metrics(model, run), status);
}

std::string explain_invalid_variant(const Study& study, int i) {
  const std::string who = "eval_id " + std::to_string(study.variants[i].eval_id) + ": ";
  try {
    if (study.arm) {
      const std::string mismatch = explain_columns_mismatch(study, make_variant_arm(study, study.variants[i]));
      return mismatch.empty() ? "" : who + mismatch;
    }
    const std::string mismatch = explain_moves_mismatch(study, make_variant_model(study, study.variants[i]));
    if (!mismatch.empty()) return who + mismatch;
  } catch (const ConfigError& e) {
    return who + e.what();
  }
  return "";
}

namespace {

// Arm variants of one shape (arm_simulate.hpp) W at a time, in eval_id order: each variant joins the
// first open batch of its shape, else opens one. Lanes are independent, so rows do not depend on it.
std::vector<Batch> make_arm_batches(const std::vector<ArmModel>& models, const std::vector<int>& pending, int lanes) {
  std::vector<Batch> batches;
  std::vector<std::size_t> open;
  for (int k : pending) {
    std::size_t b = batches.size();
    for (std::size_t o : open)
      if (batches[o].variants.size() < static_cast<std::size_t>(lanes) &&
          explain_arm_shape_mismatch(models[static_cast<std::size_t>(batches[o].variants[0])], models[static_cast<std::size_t>(k)]).empty()) {
        b = o;
        break;
      }
    if (b == batches.size()) {
      batches.emplace_back();
      open.push_back(b);
    }
    batches[b].variants.push_back(k);
  }
  return batches;
}

// The chunked, parallel evaluation of either model family. `Family` gives: Model (its model type),
// build(variant) (throws ConfigError for a value the model rejects), valid(model) (its columns match
// the study's), batches(models, local, lanes), and run(lanes, first rows' variants, res) (simulates a
// batch and appends its rows and traces to `res`).
template <class Family>
void evaluate_in_chunks(const Study& study, const std::vector<int>& pending, const EvalOptions& opt,
                        const std::function<void(BatchResult&&)>& done, const Family& family) {
  using Model = typename Family::Model;
  const int threads = opt.threads > 0 ? opt.threads : omp_get_max_threads();
  const std::size_t ncolumns = make_result_table(study).columns.size();
  // Models are built per chunk of variants and dropped after it: memory is bounded by the chunk, not
  // the study. A chunk holds enough batches to keep every thread busy.
  const std::size_t chunk = std::max<std::size_t>(1024, 32u * static_cast<std::size_t>(opt.lanes * threads));
  // Nothing may leave a parallel region by exception: the first error is kept and rethrown.
  std::exception_ptr error;
  auto keep_error = [&] {
#pragma omp critical(ff_batch_error)
    if (!error) error = std::current_exception();
  };
  const auto stopped = [&] { return opt.stop && opt.stop->load(); };
  for (std::size_t c0 = 0; c0 < pending.size() && !error && !stopped(); c0 += chunk) {
    const int n = static_cast<int>(std::min(chunk, pending.size() - c0));
    // Build: a variant the model rejects (a draw from a distribution's tail) is a result, `invalid`.
    std::vector<Model> models(static_cast<std::size_t>(n));
    std::vector<char> valid(static_cast<std::size_t>(n), 0);
#pragma omp parallel for schedule(dynamic, 8) num_threads(threads)
    for (int k = 0; k < n; ++k) {
      try {
        models[static_cast<std::size_t>(k)] = family.build(study.variants[static_cast<std::size_t>(pending[c0 + k])]);
        valid[static_cast<std::size_t>(k)] = family.valid(models[static_cast<std::size_t>(k)]);
      } catch (const ConfigError&) {
      } catch (...) {
        keep_error();
      }
    }
    if (error) break;
    std::vector<int> local;
    BatchResult invalid;
    for (int k = 0; k < n; ++k)
      if (valid[static_cast<std::size_t>(k)]) local.push_back(k);
      else invalid.rows.push_back(make_invalid_row(study, pending[c0 + k], ncolumns));
    if (!invalid.rows.empty()) done(std::move(invalid));

    const std::vector<Batch> batches = family.batches(models, local, opt.lanes);
    const int nb = static_cast<int>(batches.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (int b = 0; b < nb; ++b) {
      if (stopped()) continue;
      try {
        const auto t0 = std::chrono::steady_clock::now();
        std::vector<Model> lanes;
        std::vector<int> variants;
        for (int k : batches[static_cast<std::size_t>(b)].variants) {
          lanes.push_back(models[static_cast<std::size_t>(k)]);
          variants.push_back(pending[c0 + k]);
        }
        BatchResult res;
        family.run(lanes, variants, res);
        res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
#pragma omp critical(ff_batch_done)
        done(std::move(res));
      } catch (...) {
        keep_error();
      }
    }
  }
  if (error) std::rethrow_exception(error);
}

// The reference rig's family: Model, kernel/simulate.
struct RigFamily {
  using Model = ff::Model;
  const Study& study;
  bool keep_traces;
  Model build(const Variant& v) const { return make_variant_model(study, v); }
  bool valid(const Model& m) const { return explain_moves_mismatch(study, m).empty(); }
  std::vector<Batch> batches(const std::vector<Model>& m, const std::vector<int>& local, int lanes) const {
    return make_batches(m, local, lanes);
  }
  void run(const std::vector<Model>& lanes, const std::vector<int>& variants, BatchResult& res) const {
    if (keep_traces) {
      BatchRun run = simulate(make_batch(lanes));
      for (std::size_t l = 0; l < lanes.size(); ++l) {
        res.rows.push_back(make_result_row(study, variants[l], lanes[l], run.traces[l], run.status[l]));
        res.traces.push_back(std::move(run.traces[l]));
      }
      return;
    }
    // Traces not written: the metrics accumulate online, the same bits with no per-sample storage.
    std::vector<OnlineRun> metrics;
    for (const Model& m : lanes) metrics.push_back(make_online_run(m));
    const BatchRun run = simulate(make_batch(lanes), nullptr, nullptr, &metrics);
    for (std::size_t l = 0; l < lanes.size(); ++l)
      res.rows.push_back(make_result_row(study, variants[l], lanes[l], metrics[l], run.status[l]));
  }
};

// Arm models' family: ArmModel, arm/arm_simulate.
struct ArmFamily {
  using Model = ArmModel;
  const Study& study;
  bool keep_traces;
  std::vector<std::string> columns = arm_metric_columns(study.arm_nominal);
  Model build(const Variant& v) const { return make_variant_arm(study, v); }
  bool valid(const Model& m) const { return explain_columns_mismatch(study, m).empty(); }
  std::vector<Batch> batches(const std::vector<Model>& m, const std::vector<int>& local, int lanes) const {
    return make_arm_batches(m, local, lanes);
  }
  void run(const std::vector<Model>& lanes, const std::vector<int>& variants, BatchResult& res) const {
    // Traces not written: the metrics accumulate online (arm/arm_online_metrics.hpp), the same bits
    // without storing every column of every sample.
    std::vector<OnlineArmRun> online;
    if (!keep_traces)
      for (const Model& m : lanes) online.emplace_back(m);
    ArmRun run = simulate_arms(lanes, {.online = keep_traces ? nullptr : &online});
    for (std::size_t l = 0; l < lanes.size(); ++l) {
      const Variant& v = study.variants[static_cast<std::size_t>(variants[l])];
      ResultRow row{v.eval_id, v.seed, v.label, "", v.params,
                    keep_traces ? calc_arm_metrics(lanes[l], run.traces[l], run.status[l]) : online[l].result(run.status[l])};
      row.status = calc_arm_status(lanes[l], run.status[l], columns, row.values);
      res.rows.push_back(std::move(row));
      if (keep_traces) res.arm_traces.push_back(std::move(run.traces[l]));
    }
  }
};

}  // namespace

void evaluate_variants(const Study& study, const std::vector<int>& pending, const EvalOptions& opt,
                       const std::function<void(BatchResult&&)>& done) {
  if (study.arm) evaluate_in_chunks(study, pending, opt, done, ArmFamily{study, opt.keep_traces});
  else evaluate_in_chunks(study, pending, opt, done, RigFamily{study, opt.keep_traces});
}

StudyRun run_study(const Study& study, const EvalOptions& opt, const std::function<void(int, int)>& progress) {
  const int n = static_cast<int>(study.variants.size());
  std::vector<int> pending(n);
  for (int i = 0; i < n; ++i) pending[i] = i;
  StudyRun out;
  out.table = make_result_table(study);
  out.table.rows.resize(n);
  if (opt.keep_traces) (study.arm ? out.arm_traces.resize(n) : out.traces.resize(n));
  int finished = 0;
  evaluate_variants(study, pending, opt, [&](BatchResult&& res) {
    for (std::size_t k = 0; k < res.rows.size(); ++k) {
      const int id = res.rows[k].eval_id;
      if (opt.keep_traces && study.arm) out.arm_traces[id] = std::move(res.arm_traces[k]);
      else if (opt.keep_traces) out.traces[id] = std::move(res.traces[k]);
      out.table.rows[id] = std::move(res.rows[k]);
    }
    finished += static_cast<int>(res.rows.size());
    if (progress) progress(finished, n);
  });
  return out;
}

}  // namespace ff
