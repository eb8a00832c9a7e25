// The core's FP64 peak as the kernels can use it: independent vector multiplies and adds, half and
// half, no fused multiply-add (the build's -ffp-contract=off: the kernels have none either), at each
// vector width the CPU runs (common/isa.hpp). The measured rate is the "peak" of docs/performance.md's
// fraction-of-peak figures. A core with two multiply and two add pipes of 256 bits (AMD Zen 2/3)
// reaches 16 FLOPs a cycle so, the same as two fused multiply-adds a cycle.
// Run: build/bench/fp_peak --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include "bench/width_scope.hpp"
#include "common/isa.hpp"

namespace {

// Multiply chains and add chains of `double` vectors of V lanes, independent, so that the pipes are
// never waiting on a result. Returns the chains' sum so nothing is dead.
typedef double v2 __attribute__((vector_size(16)));
typedef double v4 __attribute__((vector_size(32)));
typedef double v8 __attribute__((vector_size(64)));

template <typename vec>
[[gnu::always_inline]] inline double mul_add_chains(long iterations) {
  constexpr int V = sizeof(vec) / sizeof(double);
  const vec f = vec{} + 0.9999999, c = vec{} + 1e-9;
  // Named registers, not arrays: GCC keeps arrays of vectors on the stack.
  // Six chains of each: 3-4 cycles of latency on two pipes each, and 14 of the 16 registers.
  vec m0 = f + 0.0, m1 = f + 1.0, m2 = f + 2.0, m3 = f + 3.0, m4 = f + 4.0, m5 = f + 5.0;
  vec a0 = c + 0.0, a1 = c + 1.0, a2 = c + 2.0, a3 = c + 3.0, a4 = c + 4.0, a5 = c + 5.0;
  for (long k = 0; k < iterations; ++k) {
    m0 = m0 * f, m1 = m1 * f, m2 = m2 * f, m3 = m3 * f, m4 = m4 * f, m5 = m5 * f;
    a0 = a0 + c, a1 = a1 + c, a2 = a2 + c, a3 = a3 + c, a4 = a4 + c, a5 = a5 + c;
  }
  const vec t = m0 + m1 + m2 + m3 + m4 + m5 + a0 + a1 + a2 + a3 + a4 + a5;
  double s = 0.0;
  for (int l = 0; l < V; ++l) s += t[l];
  return s;
}

}  // namespace

namespace ff {
// The widths' copies: SSE2 two doubles a vector, AVX2 four, AVX-512 eight (one copy, SSE2's width,
// where the build has no multiversioning: select_isa then never grants a wider one).
static double fp_peak_sse2_kernel(long n) { return mul_add_chains<v2>(n); }
#if FF_ISA_MULTIVERSION
[[gnu::target("avx2")]] static double fp_peak_avx2_kernel(long n) { return mul_add_chains<v4>(n); }
[[gnu::target("avx512f")]] static double fp_peak_avx512_kernel(long n) { return mul_add_chains<v8>(n); }
#else
static double fp_peak_avx2_kernel(long n) { return mul_add_chains<v2>(n); }
static double fp_peak_avx512_kernel(long n) { return mul_add_chains<v2>(n); }
#endif
}  // namespace ff

namespace {

void BM_Fp64Peak(benchmark::State& state) {
  const ff::Isa isa = static_cast<ff::Isa>(state.range(0));
  const ff::bench::WidthScope width(state, isa);
  if (!width.ok()) return;
  const long n = 1 << 22;
  const int lanes = isa == ff::Isa::avx512 ? 8 : isa == ff::Isa::avx2 ? 4 : 2;
  for (auto _ : state)
    benchmark::DoNotOptimize(isa == ff::Isa::avx512 ? ff::fp_peak_avx512_kernel(n)
                             : isa == ff::Isa::avx2 ? ff::fp_peak_avx2_kernel(n)
                                                    : ff::fp_peak_sse2_kernel(n));
  state.counters["FLOP/s"] = benchmark::Counter(12.0 * lanes * n, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Fp64Peak)->ArgNames({"isa"})->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
