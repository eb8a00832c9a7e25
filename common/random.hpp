// Random numbers of a study (sweep/): bit-identical on every machine, thread count and rank count.
//
// No std:: distributions (they differ between standard libraries) and no global state: every draw is a
// pure function of a 64-bit key and a counter. A variant's key derives from (study_seed, eval_id) by
// calc_variant_seed, so a run's randomness does not depend on which worker runs it or in what order.
// The uniform and normal transforms are our own (below), built only on IEEE-exact integer and
// floating-point operations plus std::erfc / std::log / std::sqrt.
#pragma once

#include <array>
#include <cstdint>

namespace ff {

// SplitMix64 (Steele, Lea & Flood 2014; Vigna's splitmix64.c): the output the generator returns when its
// state before the call is x, i.e. the finaliser applied to x + 0x9E3779B97F4A7C15. A bijection of x.
// splitmix64(0) = 0xE220A8397B1DCDAF, the generator's first published output for seed 0.
std::uint64_t splitmix64(std::uint64_t x);

// Key of variant eval_id's random stream: splitmix64(splitmix64(study_seed) ^ eval_id). A bijection in
// eval_id, so two variants of one study never share a key.
std::uint64_t calc_variant_seed(std::uint64_t study_seed, std::uint64_t eval_id);

// One block of Philox4x32-10 (Salmon, Moraes, Dror & Shaw, "Parallel random numbers: as easy as 1, 2, 3",
// SC'11): ten rounds over a 128-bit counter with a 64-bit key. Matches Random123's known-answer vectors.
std::array<std::uint32_t, 4> philox4x32_10(std::array<std::uint32_t, 4> counter,
                                           std::array<std::uint32_t, 2> key);

// 64 random bits to a double in (0, 1): (2k + 1) * 2^-53 with k the top 52 bits. Never 0 or 1, symmetric
// about 1/2, every value exact (53 significant bits).
double calc_open_unit(std::uint64_t bits);

// Counter-based stream: value i of stream `key` is a pure function of (key, i) - no hidden state beyond the
// counter, so CounterRng(key, i) continues exactly where CounterRng(key) is after i draws of next_u64().
// Value i = half (i & 1) of the Philox4x32-10 block with counter (i >> 1, 0) and key (lo32, hi32 of key):
// half 0 is word0 | word1 << 32, half 1 is word2 | word3 << 32.
class CounterRng {
 public:
  explicit CounterRng(std::uint64_t key, std::uint64_t counter = 0);

  std::uint64_t next_u64();
  double uniform();  // calc_open_unit(next_u64()): in (0, 1), never 0 or 1, 53-bit; one counter step
  double normal();   // calc_normal_quantile(uniform()): inverse CDF, one counter step, no cached pair
  // Uniform integer in [0, n), n >= 1, exactly unbiased (Lemire 2019, "Fast random integer generation in
  // an interval", multiply-shift with rejection); usually one counter step.
  std::uint64_t next_below(std::uint64_t n);

  std::uint64_t key() const { return key_; }
  std::uint64_t counter() const { return counter_; }

 private:
  std::uint64_t key_;
  std::uint64_t counter_;
};

// Standard normal CDF Phi(x) = erfc(-x / sqrt 2) / 2: relative accuracy ~1e-15 in both tails
// (calc_normal_cdf(-x) is the upper tail 1 - Phi(x) without cancellation).
double calc_normal_cdf(double x);

// Phi^-1(p) by Wichura's AS241 PPND16 (Applied Statistics 37(3), 477-484, 1988), relative accuracy ~1e-16,
// for p in (0, 1); p = 0 gives -inf, p = 1 gives +inf, p outside [0, 1] or NaN gives NaN.
double calc_normal_quantile(double p);

}  // namespace ff
