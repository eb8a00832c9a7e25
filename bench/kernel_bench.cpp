// Throughput of the batch kernel: variant-steps per second of the closed loop (controller at 1 kHz,
// plant between samples) against lane width, segment count and integrator.
// Run: build/kernel_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <vector>

#include "bench/width_scope.hpp"
#include "kernel/model.hpp"
#include "kernel/simulate.hpp"

namespace {

// The reference rig: 0.5 rad cubic move over a 2 s run, W lanes with slightly different payloads.
ff::BatchModel rig_batch(int nseg, int W, ff::Integrator integ, int substeps) {
  std::vector<ff::Model> models;
  for (int l = 0; l < W; ++l) {
    ff::ModelSpec s;
    s.segments = nseg;
    s.payload_mass = 328.7 * (1.0 + 0.01 * l);
    s.trajectory.moves = {{0.5, 0.0}};
    s.simulation.duration = 2.0;
    s.simulation.integrator = integ;
    s.simulation.substeps = substeps;
    models.push_back(ff::make_model(s));
  }
  return ff::make_batch(models);
}

// Runs the batch's closed loop as the benchmark's iterations and counts its rates. `online`: keep only
// the run's metrics (kernel/online_metrics.hpp, as `flexfarm run` without traces), no trace.
void closed_loop(benchmark::State& state, const ff::BatchModel& bm, bool online = false) {
  const double samples = bm.duration / bm.control_period;
  for (auto _ : state) {
    if (!online) {
      benchmark::DoNotOptimize(ff::simulate(bm));
      continue;
    }
    std::vector<ff::OnlineRun> metrics;
    for (const ff::Model& m : bm.models) metrics.push_back(ff::make_online_run(m));
    benchmark::DoNotOptimize(ff::simulate(bm, nullptr, nullptr, &metrics));
    benchmark::DoNotOptimize(metrics.data());
  }
  state.counters["substeps"] = bm.substeps;
  state.counters["variant_samples/s"] = benchmark::Counter(samples * bm.W, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["x_realtime/core"] = benchmark::Counter(bm.duration * bm.W, benchmark::Counter::kIsIterationInvariantRate);
}

// One fixed-step benchmark; args: segments, lanes, substeps (0 = automatic).
void fixed_step(benchmark::State& state, ff::Integrator integrator, bool online = false) {
  closed_loop(state,
              rig_batch(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), integrator,
                        static_cast<int>(state.range(2))),
              online);
}

// The same closed loop at each vector width (common/isa.hpp: 0 SSE2, 1 AVX2, 2 AVX-512), side by
// side in one run; args: segments, lanes, width. A width the CPU lacks is skipped.
void at_width(benchmark::State& state, ff::Integrator integrator) {
  const ff::bench::WidthScope width(state, static_cast<ff::Isa>(state.range(2)));
  if (!width.ok()) return;
  closed_loop(state, rig_batch(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), integrator, 0));
}
void BM_MidpointWidth(benchmark::State& state) { at_width(state, ff::Integrator::kMidpoint); }
BENCHMARK(BM_MidpointWidth)
    ->ArgNames({"N", "W", "isa"})
    ->ArgsProduct({{6, 24}, {8}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond);
void BM_Sdirk2Width(benchmark::State& state) { at_width(state, ff::Integrator::kSdirk2); }
BENCHMARK(BM_Sdirk2Width)
    ->ArgNames({"N", "W", "isa"})
    ->ArgsProduct({{6, 48}, {8}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond);

void BM_Rk4ClosedLoop(benchmark::State& state) { fixed_step(state, ff::Integrator::kRk4); }
BENCHMARK(BM_Rk4ClosedLoop)
    ->ArgNames({"N", "W", "sub"})
    ->Args({6, 1, 1})->Args({6, 4, 1})->Args({6, 8, 1})->Args({6, 16, 1})
    ->Args({24, 8, 0})
    ->Unit(benchmark::kMillisecond);

// SDIRK2 at its automatic step: one step per 1 ms sample for all these N.
void BM_Sdirk2ClosedLoop(benchmark::State& state) { fixed_step(state, ff::Integrator::kSdirk2); }
BENCHMARK(BM_Sdirk2ClosedLoop)
    ->ArgNames({"N", "W", "sub"})
    ->Args({6, 1, 0})->Args({6, 4, 0})->Args({6, 8, 0})->Args({6, 16, 0})
    ->Args({24, 8, 0})->Args({48, 1, 0})->Args({48, 8, 0})->Args({96, 8, 0})
    ->Unit(benchmark::kMillisecond);

// Midpoint (one articulated-body pass per step) at its automatic step: 1 per 1 ms sample at N = 6.
void BM_MidpointClosedLoop(benchmark::State& state) { fixed_step(state, ff::Integrator::kMidpoint); }
BENCHMARK(BM_MidpointClosedLoop)
    ->ArgNames({"N", "W", "sub"})
    ->Args({6, 1, 0})->Args({6, 4, 0})->Args({6, 8, 0})->Args({6, 16, 0})->Args({24, 8, 0})
    ->Unit(benchmark::kMillisecond);

// The same, keeping only the metrics.
void BM_MidpointMetricsOnly(benchmark::State& state) { fixed_step(state, ff::Integrator::kMidpoint, true); }
BENCHMARK(BM_MidpointMetricsOnly)
    ->ArgNames({"N", "W", "sub"})
    ->Args({6, 1, 0})->Args({6, 4, 0})->Args({6, 8, 0})->Args({6, 16, 0})->Args({24, 8, 0})
    ->Unit(benchmark::kMillisecond);

// Thread scaling: 8 batches of W = 8 lanes (N = 6, SDIRK2) on T OpenMP threads, one batch per task.
void BM_Sdirk2Threads(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const auto bm = rig_batch(6, 8, ff::Integrator::kSdirk2, 0);
  const int batches = 8;
  for (auto _ : state) {
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (int b = 0; b < batches; ++b) benchmark::DoNotOptimize(ff::simulate(bm));
  }
  const double samples = bm.duration / bm.control_period * bm.W * batches;
  state.counters["variant_samples/s"] = benchmark::Counter(samples, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Sdirk2Threads)->ArgNames({"threads"})->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// One closed loop of T simulated seconds, run once (midpoint or SDIRK2, W = 8): the runs that
// bench/count_flops.py counts. The step loop's operations per variant-step are the difference of
// the counts at T = 2 and T = 1, over the 1000 x 8 variant-steps between (setup cancels out).
void BM_FlopCount(benchmark::State& state) {
  const auto integ = state.range(2) == 0 ? ff::Integrator::kMidpoint : ff::Integrator::kSdirk2;
  ff::BatchModel bm = rig_batch(static_cast<int>(state.range(0)), 8, integ, 0);
  bm.duration = static_cast<double>(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(ff::simulate(bm));
}
BENCHMARK(BM_FlopCount)
    ->ArgNames({"N", "T", "sdirk2"})
    ->ArgsProduct({{6, 48}, {1, 2}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

void BM_CvodeClosedLoop(benchmark::State& state) {
  const auto integ = state.range(1) == 0 ? ff::Integrator::kCvodeDense : ff::Integrator::kCvodeKlu;
  const auto bm = rig_batch(static_cast<int>(state.range(0)), 1, integ, 1);
  for (auto _ : state) benchmark::DoNotOptimize(ff::simulate(bm));
  state.counters["x_realtime/core"] = benchmark::Counter(bm.duration, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_CvodeClosedLoop)->ArgNames({"N", "klu"})->Args({6, 0})->Args({6, 1})->Args({24, 0})->Args({24, 1})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
