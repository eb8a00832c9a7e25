// Counter-based random numbers and the normal CDF / quantile (see random.hpp).
#include "common/random.hpp"

#include <cmath>
#include <limits>

namespace ff {

namespace {

// High and low 64 bits of the 128-bit product a * b, from 32-bit halves (portable, no __int128).
void mul_64x64(std::uint64_t a, std::uint64_t b, std::uint64_t& hi, std::uint64_t& lo) {
  const std::uint64_t a_lo = a & 0xFFFFFFFFu, a_hi = a >> 32;
  const std::uint64_t b_lo = b & 0xFFFFFFFFu, b_hi = b >> 32;
  const std::uint64_t ll = a_lo * b_lo, lh = a_lo * b_hi, hl = a_hi * b_lo, hh = a_hi * b_hi;
  const std::uint64_t mid = (ll >> 32) + (lh & 0xFFFFFFFFu) + (hl & 0xFFFFFFFFu);
  lo = (mid << 32) | (ll & 0xFFFFFFFFu);
  hi = hh + (lh >> 32) + (hl >> 32) + (mid >> 32);
}

// Horner evaluation of c[0] + c[1] r + ... + c[7] r^7 (no FMA: the project builds with -ffp-contract=off).
double horner8(const double (&c)[8], double r) {
  double v = c[7];
  for (int i = 6; i >= 0; --i) v = v * r + c[i];
  return v;
}

}  // namespace

std::uint64_t splitmix64(std::uint64_t x) {
  // Vigna's splitmix64.c: advance the Weyl state, then the variant-13 finaliser of MurmurHash3.
  std::uint64_t z = x + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

std::uint64_t calc_variant_seed(std::uint64_t study_seed, std::uint64_t eval_id) {
  return splitmix64(splitmix64(study_seed) ^ eval_id);
}

std::array<std::uint32_t, 4> philox4x32_10(std::array<std::uint32_t, 4> c, std::array<std::uint32_t, 2> k) {
  // Random123 philox.h: multipliers M0, M1 and the Weyl key increments W0, W1; the key is bumped
  // between rounds (before rounds 2..10).
  constexpr std::uint64_t kM0 = 0xD2511F53u, kM1 = 0xCD9E8D57u;
  constexpr std::uint32_t kW0 = 0x9E3779B9u, kW1 = 0xBB67AE85u;
  for (int round = 0; round < 10; ++round) {
    if (round > 0) {
      k[0] += kW0;
      k[1] += kW1;
    }
    const std::uint64_t p0 = kM0 * c[0];
    const std::uint64_t p1 = kM1 * c[2];
    c = {static_cast<std::uint32_t>(p1 >> 32) ^ c[1] ^ k[0], static_cast<std::uint32_t>(p1),
         static_cast<std::uint32_t>(p0 >> 32) ^ c[3] ^ k[1], static_cast<std::uint32_t>(p0)};
  }
  return c;
}

double calc_open_unit(std::uint64_t bits) {
  // (2k + 1) / 2^53 for k = bits >> 12 in [0, 2^52): the centres of 2^52 equal cells of (0, 1).
  const std::uint64_t odd = ((bits >> 12) << 1) | 1u;
  return static_cast<double>(odd) * 0x1p-53;
}

CounterRng::CounterRng(std::uint64_t key, std::uint64_t counter) : key_(key), counter_(counter) {}

std::uint64_t CounterRng::next_u64() {
  const std::uint64_t block = counter_ >> 1;
  const std::array<std::uint32_t, 4> w = philox4x32_10(
      {static_cast<std::uint32_t>(block), static_cast<std::uint32_t>(block >> 32), 0u, 0u},
      {static_cast<std::uint32_t>(key_), static_cast<std::uint32_t>(key_ >> 32)});
  const bool second = (counter_ & 1u) != 0;
  ++counter_;
  return second ? (std::uint64_t{w[3]} << 32 | w[2]) : (std::uint64_t{w[1]} << 32 | w[0]);
}

double CounterRng::uniform() { return calc_open_unit(next_u64()); }

double CounterRng::normal() { return calc_normal_quantile(uniform()); }

std::uint64_t CounterRng::next_below(std::uint64_t n) {
  // Lemire 2019: the high word of x * n is uniform on [0, n) once the few low words below
  // 2^64 mod n are rejected.
  std::uint64_t hi = 0, lo = 0;
  mul_64x64(next_u64(), n, hi, lo);
  if (lo < n) {
    const std::uint64_t threshold = (0 - n) % n;
    while (lo < threshold) mul_64x64(next_u64(), n, hi, lo);
  }
  return hi;
}

double calc_normal_cdf(double x) {
  constexpr double kSqrtHalf = 0.70710678118654752440;
  return 0.5 * std::erfc(-x * kSqrtHalf);
}

double calc_normal_quantile(double p) {
  // Wichura, AS241 PPND16: rational approximations in q = p - 1/2 for |q| <= 0.425, else in
  // r = sqrt(-log(min(p, 1 - p))) for r <= 5 and r > 5. Coefficients from the paper.
  static constexpr double a[8] = {3.3871328727963666080e0,  1.3314166789178437745e+2,
                                  1.9715909503065514427e+3, 1.3731693765509461125e+4,
                                  4.5921953931549871457e+4, 6.7265770927008700853e+4,
                                  3.3430575583588128105e+4, 2.5090809287301226727e+3};
  static constexpr double b[8] = {1.0,
                                  4.2313330701600911252e+1, 6.8718700749205790830e+2,
                                  5.3941960214247511077e+3, 2.1213794301586595867e+4,
                                  3.9307895800092710610e+4, 2.8729085735721942674e+4,
                                  5.2264952788528545610e+3};
  static constexpr double c[8] = {1.42343711074968357734e0,  4.63033784615654529590e0,
                                  5.76949722146069140550e0,  3.64784832476320460504e0,
                                  1.27045825245236838258e0,  2.41780725177450611770e-1,
                                  2.27238449892691845833e-2, 7.74545014278341407640e-4};
  static constexpr double d[8] = {1.0,
                                  2.05319162663775882187e0,  1.67638483018380384940e0,
                                  6.89767334985100004550e-1, 1.48103976427480074590e-1,
                                  1.51986665636164571966e-2, 5.47593808499534494600e-4,
                                  1.05075007164441684324e-9};
  static constexpr double e[8] = {6.65790464350110377720e0,  5.46378491116411436990e0,
                                  1.78482653991729133580e0,  2.96560571828504891230e-1,
                                  2.65321895265761230930e-2, 1.24266094738807843860e-3,
                                  2.71155556874348757815e-5, 2.01033439929228813265e-7};
  static constexpr double f[8] = {1.0,
                                  5.99832206555887937690e-1, 1.36929880922735805310e-1,
                                  1.48753612908506148525e-2, 7.86869131145613259100e-4,
                                  1.84631831751005468180e-5, 1.42151175831644588870e-7,
                                  2.04426310338993978564e-15};
  if (!(p >= 0.0 && p <= 1.0)) return std::numeric_limits<double>::quiet_NaN();
  if (p == 0.0) return -std::numeric_limits<double>::infinity();
  if (p == 1.0) return std::numeric_limits<double>::infinity();

  const double q = p - 0.5;
  if (std::fabs(q) <= 0.425) {
    // Central region.
    const double r = 0.180625 - q * q;
    return q * horner8(a, r) / horner8(b, r);
  }
  // Tails: r from the smaller of p and 1 - p (1 - p is exact here by Sterbenz's lemma).
  double r = std::sqrt(-std::log(q < 0.0 ? p : 1.0 - p));
  double x;
  if (r <= 5.0) {
    r -= 1.6;
    x = horner8(c, r) / horner8(d, r);
  } else {
    r -= 5.0;
    x = horner8(e, r) / horner8(f, r);
  }
  return q < 0.0 ? -x : x;
}

}  // namespace ff
