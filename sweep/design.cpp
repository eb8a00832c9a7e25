// Experimental designs: distributions' quantiles, grid / centered / Monte Carlo / Latin hypercube /
// scrambled Sobol' / Saltelli / Morris designs (see design.hpp for the row layouts).
#include "sweep/design.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>

#include "common/random.hpp"

namespace ff {

namespace {

// ---- Joe & Kuo direction numbers ------------------------------------------------------------------
// new-joe-kuo-6.21201 (S. Joe and F. Y. Kuo, "Constructing Sobol sequences with better two-dimensional
// projections", SIAM J. Sci. Comput. 30, 2635-2654, 2008; https://web.maths.unsw.edu.au/~fkuo/sobol/),
// dimensions 2..100: degree s of the primitive polynomial, its inner coefficients a, initial m_1..m_s.
// Dimension 1 is the van der Corput sequence (all m_k = 1).
struct JoeKuoRow {
  int s;
  unsigned a;
  std::array<std::uint32_t, 9> m;
};

constexpr JoeKuoRow kJoeKuo[] = {
    {1, 0, {1}},                                    // d = 2
    {2, 1, {1, 3}},                                 // d = 3
    {3, 1, {1, 3, 1}},                              // d = 4
    {3, 2, {1, 1, 1}},                              // d = 5
    {4, 1, {1, 1, 3, 3}},                           // d = 6
    {4, 4, {1, 3, 5, 13}},                          // d = 7
    {5, 2, {1, 1, 5, 5, 17}},                       // d = 8
    {5, 4, {1, 1, 5, 5, 5}},                        // d = 9
    {5, 7, {1, 1, 7, 11, 19}},                      // d = 10
    {5, 11, {1, 1, 5, 1, 1}},                       // d = 11
    {5, 13, {1, 1, 1, 3, 11}},                      // d = 12
    {5, 14, {1, 3, 5, 5, 31}},                      // d = 13
    {6, 1, {1, 3, 3, 9, 7, 49}},                    // d = 14
    {6, 13, {1, 1, 1, 15, 21, 21}},                 // d = 15
    {6, 16, {1, 3, 1, 13, 27, 49}},                 // d = 16
    {6, 19, {1, 1, 1, 15, 7, 5}},                   // d = 17
    {6, 22, {1, 3, 1, 15, 13, 25}},                 // d = 18
    {6, 25, {1, 1, 5, 5, 19, 61}},                  // d = 19
    {7, 1, {1, 3, 7, 11, 23, 15, 103}},             // d = 20
    {7, 4, {1, 3, 7, 13, 13, 15, 69}},              // d = 21
    {7, 7, {1, 1, 3, 13, 7, 35, 63}},               // d = 22
    {7, 8, {1, 3, 5, 9, 1, 25, 53}},                // d = 23
    {7, 14, {1, 3, 1, 13, 9, 35, 107}},             // d = 24
    {7, 19, {1, 3, 1, 5, 27, 61, 31}},              // d = 25
    {7, 21, {1, 1, 5, 11, 19, 41, 61}},             // d = 26
    {7, 28, {1, 3, 5, 3, 3, 13, 69}},               // d = 27
    {7, 31, {1, 1, 7, 13, 1, 19, 1}},               // d = 28
    {7, 32, {1, 3, 7, 5, 13, 19, 59}},              // d = 29
    {7, 37, {1, 1, 3, 9, 25, 29, 41}},              // d = 30
    {7, 41, {1, 3, 5, 13, 23, 1, 55}},              // d = 31
    {7, 42, {1, 3, 7, 3, 13, 59, 17}},              // d = 32
    {7, 50, {1, 3, 1, 3, 5, 53, 69}},               // d = 33
    {7, 55, {1, 1, 5, 5, 23, 33, 13}},              // d = 34
    {7, 56, {1, 1, 7, 7, 1, 61, 123}},              // d = 35
    {7, 59, {1, 1, 7, 9, 13, 61, 49}},              // d = 36
    {7, 62, {1, 3, 3, 5, 3, 55, 33}},               // d = 37
    {8, 14, {1, 3, 1, 15, 31, 13, 49, 245}},        // d = 38
    {8, 21, {1, 3, 5, 15, 31, 59, 63, 97}},         // d = 39
    {8, 22, {1, 3, 1, 11, 11, 11, 77, 249}},        // d = 40
    {8, 38, {1, 3, 1, 11, 27, 43, 71, 9}},          // d = 41
    {8, 47, {1, 1, 7, 15, 21, 11, 81, 45}},         // d = 42
    {8, 49, {1, 3, 7, 3, 25, 31, 65, 79}},          // d = 43
    {8, 50, {1, 3, 1, 1, 19, 11, 3, 205}},          // d = 44
    {8, 52, {1, 1, 5, 9, 19, 21, 29, 157}},         // d = 45
    {8, 56, {1, 3, 7, 11, 1, 33, 89, 185}},         // d = 46
    {8, 67, {1, 3, 3, 3, 15, 9, 79, 71}},           // d = 47
    {8, 70, {1, 3, 7, 11, 15, 39, 119, 27}},        // d = 48
    {8, 84, {1, 1, 3, 1, 11, 31, 97, 225}},         // d = 49
    {8, 97, {1, 1, 1, 3, 23, 43, 57, 177}},         // d = 50
    {8, 103, {1, 3, 7, 7, 17, 17, 37, 71}},         // d = 51
    {8, 115, {1, 3, 1, 5, 27, 63, 123, 213}},       // d = 52
    {8, 122, {1, 1, 3, 5, 11, 43, 53, 133}},        // d = 53
    {9, 8, {1, 3, 5, 5, 29, 17, 47, 173, 479}},     // d = 54
    {9, 13, {1, 3, 3, 11, 3, 1, 109, 9, 69}},       // d = 55
    {9, 16, {1, 1, 1, 5, 17, 39, 23, 5, 343}},      // d = 56
    {9, 22, {1, 3, 1, 5, 25, 15, 31, 103, 499}},    // d = 57
    {9, 25, {1, 1, 1, 11, 11, 17, 63, 105, 183}},   // d = 58
    {9, 44, {1, 1, 5, 11, 9, 29, 97, 231, 363}},    // d = 59
    {9, 47, {1, 1, 5, 15, 19, 45, 41, 7, 383}},     // d = 60
    {9, 52, {1, 3, 7, 7, 31, 19, 83, 137, 221}},    // d = 61
    {9, 55, {1, 1, 1, 3, 23, 15, 111, 223, 83}},    // d = 62
    {9, 59, {1, 1, 5, 13, 31, 15, 55, 25, 161}},    // d = 63
    {9, 62, {1, 1, 3, 13, 25, 47, 39, 87, 257}},    // d = 64
    {9, 67, {1, 1, 1, 11, 21, 53, 125, 249, 293}},  // d = 65
    {9, 74, {1, 1, 7, 11, 11, 7, 57, 79, 323}},     // d = 66
    {9, 81, {1, 1, 5, 5, 17, 13, 81, 3, 131}},      // d = 67
    {9, 82, {1, 1, 7, 13, 23, 7, 65, 251, 475}},    // d = 68
    {9, 87, {1, 3, 5, 1, 9, 43, 3, 149, 11}},       // d = 69
    {9, 91, {1, 1, 3, 13, 31, 13, 13, 255, 487}},   // d = 70
    {9, 94, {1, 3, 3, 1, 5, 63, 89, 91, 127}},      // d = 71
    {9, 103, {1, 1, 3, 3, 1, 19, 123, 127, 237}},   // d = 72
    {9, 104, {1, 1, 5, 7, 23, 31, 37, 243, 289}},   // d = 73
    {9, 109, {1, 1, 5, 11, 17, 53, 117, 183, 491}}, // d = 74
    {9, 122, {1, 1, 1, 5, 1, 13, 13, 209, 345}},    // d = 75
    {9, 124, {1, 1, 3, 15, 1, 57, 115, 7, 33}},     // d = 76
    {9, 137, {1, 3, 1, 11, 7, 43, 81, 207, 175}},   // d = 77
    {9, 138, {1, 3, 1, 1, 15, 27, 63, 255, 49}},    // d = 78
    {9, 143, {1, 3, 5, 3, 27, 61, 105, 171, 305}},  // d = 79
    {9, 145, {1, 1, 5, 3, 1, 3, 57, 249, 149}},     // d = 80
    {9, 152, {1, 1, 3, 5, 5, 57, 15, 13, 159}},     // d = 81
    {9, 157, {1, 1, 1, 11, 7, 11, 105, 141, 225}},  // d = 82
    {9, 167, {1, 3, 3, 5, 27, 59, 121, 101, 271}},  // d = 83
    {9, 173, {1, 3, 5, 9, 11, 49, 51, 59, 115}},    // d = 84
    {9, 176, {1, 1, 7, 1, 23, 45, 125, 71, 419}},   // d = 85
    {9, 181, {1, 1, 3, 5, 23, 5, 105, 109, 75}},    // d = 86
    {9, 182, {1, 1, 7, 15, 7, 11, 67, 121, 453}},   // d = 87
    {9, 185, {1, 3, 7, 3, 9, 13, 31, 27, 449}},     // d = 88
    {9, 191, {1, 3, 1, 15, 19, 39, 39, 89, 15}},    // d = 89
    {9, 194, {1, 1, 1, 1, 1, 33, 73, 145, 379}},    // d = 90
    {9, 199, {1, 3, 1, 15, 15, 43, 29, 13, 483}},   // d = 91
    {9, 218, {1, 1, 7, 3, 19, 27, 85, 131, 431}},   // d = 92
    {9, 220, {1, 3, 3, 3, 5, 35, 23, 195, 349}},    // d = 93
    {9, 227, {1, 3, 3, 7, 9, 27, 39, 59, 297}},     // d = 94
    {9, 229, {1, 1, 3, 9, 11, 17, 13, 241, 157}},   // d = 95
    {9, 230, {1, 3, 7, 15, 25, 57, 33, 189, 213}},  // d = 96
    {9, 234, {1, 1, 7, 1, 9, 55, 73, 83, 217}},     // d = 97
    {9, 236, {1, 3, 3, 13, 19, 27, 23, 113, 249}},  // d = 98
    {9, 241, {1, 3, 5, 3, 23, 43, 3, 253, 479}},    // d = 99
    {9, 244, {1, 1, 5, 5, 11, 5, 45, 117, 217}},    // d = 100
};
static_assert(std::size(kJoeKuo) + 1 == kSobolMaxDimension);

// Direction numbers V_1..V_32 of dimension `dim` (0-based), left-aligned in 32 bits: V_k = m_k 2^(32-k),
// and for k > s the Bratley-Fox recurrence as Joe & Kuo state it:
// V_k = V_{k-s} ^ (V_{k-s} >> s) ^ XOR_{i=1..s-1} a_i V_{k-i}, a_i = bit (s-1-i) of a.
std::array<std::uint32_t, 32> make_sobol_directions(int dim) {
  std::array<std::uint32_t, 32> v{};
  if (dim == 0) {
    for (int k = 0; k < 32; ++k) v[k] = std::uint32_t{1} << (31 - k);
    return v;
  }
  const JoeKuoRow& row = kJoeKuo[dim - 1];
  const int s = row.s;
  for (int k = 0; k < 32; ++k) {
    if (k < s) {
      v[k] = row.m[k] << (31 - k);
      continue;
    }
    std::uint32_t x = v[k - s] ^ (v[k - s] >> s);
    for (int i = 1; i < s; ++i)
      if ((row.a >> (s - 1 - i)) & 1u) x ^= v[k - i];
    v[k] = x;
  }
  return v;
}

// Sobol' integers of one dimension for indices 0..n-1 in Gray-code order (Antonov & Saleev 1979):
// x_i = x_{i-1} ^ V_{c}, c = number of trailing zeros of i.
std::vector<std::uint32_t> make_sobol_column(int n, int dim) {
  const std::array<std::uint32_t, 32> v = make_sobol_directions(dim);
  std::vector<std::uint32_t> x(static_cast<std::size_t>(n));
  std::uint32_t cur = 0;
  for (int i = 1; i < n; ++i) {
    cur ^= v[std::countr_zero(static_cast<std::uint32_t>(i))];
    x[static_cast<std::size_t>(i)] = cur;
  }
  return x;
}

// Owen's nested uniform scramble of the 32 leading binary digits of x (Owen 1995), hash-based
// (Burley 2020): digit b (b = 0 most significant) is flipped by the random bit of tree node
// (b, leading b digits of x), drawn as the top bit of splitmix64(key ^ node id) with node id
// 2^b + prefix (the heap index, unique over the tree). Returns the 32 scrambled digits in the high word
// and, in the low word, 32 random digits from the leaf's hash (the scramble of x's all-zero tail).
std::uint64_t owen_scramble(std::uint32_t x, std::uint64_t key) {
  std::uint32_t y = x;
  for (int b = 0; b < 32; ++b) {
    const std::uint64_t prefix = b == 0 ? 0 : x >> (32 - b);
    const std::uint64_t node = (std::uint64_t{1} << b) | prefix;
    if (splitmix64(key ^ node) >> 63) y ^= std::uint32_t{1} << (31 - b);
  }
  const std::uint64_t leaf = (std::uint64_t{1} << 32) | x;
  return (std::uint64_t{y} << 32) | (splitmix64(key ^ leaf) >> 32);
}

// ---- stream keys -----------------------------------------------------------------------------------
// Independent streams of one design seed: key(seed, tag, index). Monte Carlo uses calc_variant_seed
// (seed, row) directly, as the variants of a study do.
constexpr std::uint64_t kTagLhs = 0x4c48532d53545241ull;     // "LHS-STRA"
constexpr std::uint64_t kTagSobol = 0x534f424f4c2d4f57ull;   // "SOBOL-OW"
constexpr std::uint64_t kTagMorris = 0x4d4f525249532d54ull;  // "MORRIS-T"

std::uint64_t stream_key(std::uint64_t seed, std::uint64_t tag, std::uint64_t index) {
  return calc_variant_seed(splitmix64(seed ^ tag), index);
}

// ---- messages --------------------------------------------------------------------------------------
// Shortest round-trip decimal form of x.
std::string fmt(double x) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, x);
  return res.ec == std::errc() ? std::string(buf, res.ptr) : std::string("?");
}

const char* distribution_name(DistributionKind k) {
  switch (k) {
    case DistributionKind::kUniform: return "uniform";
    case DistributionKind::kNormal: return "normal";
    case DistributionKind::kTruncatedNormal: return "truncated_normal";
    case DistributionKind::kLognormal: return "lognormal";
    case DistributionKind::kChoice: return "choice";
  }
  return "unknown";
}

const char* design_name(DesignKind k) {
  switch (k) {
    case DesignKind::kGrid: return "grid";
    case DesignKind::kCentered: return "centered";
    case DesignKind::kMonteCarlo: return "monte_carlo";
    case DesignKind::kLatinHypercube: return "lhs";
    case DesignKind::kSobol: return "sobol";
    case DesignKind::kSaltelli: return "saltelli";
    case DesignKind::kMorris: return "morris";
  }
  return "unknown";
}

[[noreturn]] void fail(const std::string& msg) { throw std::invalid_argument(msg); }

// ---- truncated normal ------------------------------------------------------------------------------
// The standardised bounds a, b and the CDF values the quantile interpolates between: Phi(a), Phi(b) in
// the lower tail, or the complements Phi(-a), Phi(-b) when a >= 0 (upper tail, no cancellation).
struct TruncatedNormalCdf {
  bool upper_tail;
  double lo, hi;  // lower tail: Phi(a) <= Phi(b); upper tail: Phi(-a) >= Phi(-b)
  double mass() const { return upper_tail ? lo - hi : hi - lo; }
};

TruncatedNormalCdf calc_truncated_cdf(const Distribution& d) {
  const double a = (d.lower - d.mean) / d.std, b = (d.upper - d.mean) / d.std;
  if (a >= 0.0) return {true, calc_normal_cdf(-a), calc_normal_cdf(-b)};
  return {false, calc_normal_cdf(a), calc_normal_cdf(b)};
}

bool has_bounded_support(const Distribution& d) {
  switch (d.kind) {
    case DistributionKind::kUniform:
    case DistributionKind::kChoice: return true;
    case DistributionKind::kTruncatedNormal: return std::isfinite(d.lower) && std::isfinite(d.upper);
    default: return false;
  }
}

// ---- design helpers --------------------------------------------------------------------------------
using Matrix = std::vector<std::vector<double>>;

// Rows of a design must be addressable by an int eval_id.
int checked_rows(long double rows, const char* design) {
  if (rows > static_cast<long double>(INT_MAX))
    fail(std::string(design) + " design: " + fmt(static_cast<double>(rows)) +
         " rows exceed the limit of " + std::to_string(INT_MAX) + " evaluations");
  return static_cast<int>(rows);
}

// Distinct levels of a centered variable other than its nominal, in the order given.
std::vector<double> centered_levels(const Variable& v) {
  std::vector<double> out;
  for (double x : v.levels)
    if (x != v.nominal && std::find(out.begin(), out.end(), x) == out.end()) out.push_back(x);
  return out;
}

// Unit-cube points through the variables' quantiles.
Matrix map_unit(const Matrix& unit, const std::vector<Variable>& vars) {
  Matrix out(unit.size(), std::vector<double>(vars.size()));
  for (std::size_t i = 0; i < unit.size(); ++i)
    for (std::size_t j = 0; j < vars.size(); ++j) out[i][j] = calc_quantile(vars[j].dist, unit[i][j]);
  return out;
}

void check_unit_args(int n, int d, const char* what) {
  if (n < 1) fail(std::string(what) + ": the number of points must be >= 1 (got " + std::to_string(n) + ")");
  if (d < 1) fail(std::string(what) + ": the dimension must be >= 1 (got " + std::to_string(d) + ")");
}

void check_sobol_dimension(int d, const char* what) {
  if (d > kSobolMaxDimension)
    fail(std::string(what) + ": " + std::to_string(d) + " Sobol' dimensions requested, the embedded " +
         "Joe & Kuo table has " + std::to_string(kSobolMaxDimension));
}

void check_morris_levels(int p) {
  if (p < 2 || p % 2 != 0)
    fail("morris design: morris_levels p must be even and >= 2 (got " + std::to_string(p) + ")");
}

}  // namespace

// ---- distributions ---------------------------------------------------------------------------------

void validate_distribution(const Distribution& d) {
  const std::string name = distribution_name(d.kind);
  switch (d.kind) {
    case DistributionKind::kUniform:
      if (!std::isfinite(d.lower) || !std::isfinite(d.upper))
        fail("uniform distribution needs finite bounds (got lower = " + fmt(d.lower) + ", upper = " +
             fmt(d.upper) + ")");
      if (!(d.lower < d.upper))
        fail("uniform distribution needs lower < upper (got lower = " + fmt(d.lower) + ", upper = " +
             fmt(d.upper) + ")");
      return;
    case DistributionKind::kNormal:
    case DistributionKind::kTruncatedNormal:
      if (!std::isfinite(d.mean)) fail(name + " distribution needs a finite mean (got " + fmt(d.mean) + ")");
      if (!(d.std > 0.0) || !std::isfinite(d.std))
        fail(name + " distribution needs std > 0 (got " + fmt(d.std) + ")");
      if (d.kind == DistributionKind::kNormal) return;
      if (std::isnan(d.lower) || std::isnan(d.upper) || !(d.lower < d.upper))
        fail("truncated_normal distribution needs lower < upper (got lower = " + fmt(d.lower) +
             ", upper = " + fmt(d.upper) + ")");
      if (!(calc_truncated_cdf(d).mass() > 0.0))
        fail("truncated_normal distribution has no probability mass between lower = " + fmt(d.lower) +
             " and upper = " + fmt(d.upper) + " (mean = " + fmt(d.mean) + ", std = " + fmt(d.std) + ")");
      return;
    case DistributionKind::kLognormal:
      if (!std::isfinite(d.mu)) fail("lognormal distribution needs a finite mu (got " + fmt(d.mu) + ")");
      if (!(d.sigma > 0.0) || !std::isfinite(d.sigma))
        fail("lognormal distribution needs sigma > 0 (got " + fmt(d.sigma) + ")");
      return;
    case DistributionKind::kChoice: {
      if (d.values.empty()) fail("choice distribution needs at least one value");
      for (double v : d.values)
        if (!std::isfinite(v)) fail("choice distribution has a non-finite value (" + fmt(v) + ")");
      if (d.weights.empty()) return;
      if (d.weights.size() != d.values.size())
        fail("choice distribution has " + std::to_string(d.weights.size()) + " weights for " +
             std::to_string(d.values.size()) + " values");
      double total = 0.0;
      for (double w : d.weights) {
        if (!(w >= 0.0) || !std::isfinite(w))
          fail("choice distribution weights must be finite and >= 0 (got " + fmt(w) + ")");
        total += w;
      }
      if (!(total > 0.0) || !std::isfinite(total))
        fail("choice distribution weights must not all be zero");
      return;
    }
  }
  fail("unknown distribution kind " + std::to_string(static_cast<int>(d.kind)));
}

double calc_quantile(const Distribution& d, double u) {
  if (!(u >= 0.0 && u <= 1.0)) fail("calc_quantile: u must be in [0, 1] (got " + fmt(u) + ")");
  switch (d.kind) {
    case DistributionKind::kUniform:
      if (u == 1.0) return d.upper;
      return std::min(d.lower + u * (d.upper - d.lower), d.upper);
    case DistributionKind::kNormal:
      return d.mean + d.std * calc_normal_quantile(u);
    case DistributionKind::kTruncatedNormal: {
      // Inverse-CDF of the parent normal restricted to [lower, upper]; clamped against rounding.
      if (u == 0.0) return d.lower;
      if (u == 1.0) return d.upper;
      const TruncatedNormalCdf c = calc_truncated_cdf(d);
      const double z = c.upper_tail ? -calc_normal_quantile(c.lo - u * (c.lo - c.hi))
                                    : calc_normal_quantile(c.lo + u * (c.hi - c.lo));
      return std::clamp(d.mean + d.std * z, d.lower, d.upper);
    }
    case DistributionKind::kLognormal:
      return std::exp(d.mu + d.sigma * calc_normal_quantile(u));
    case DistributionKind::kChoice: {
      // First value whose cumulative weight exceeds u * total; zero weights are never chosen.
      const std::size_t n = d.values.size();
      if (n == 0) fail("choice distribution needs at least one value");
      const bool equal = d.weights.empty();
      if (!equal && d.weights.size() != n) fail("choice distribution needs one weight per value");
      double total = 0.0;
      for (std::size_t k = 0; k < n; ++k) total += equal ? 1.0 : d.weights[k];
      const double target = u * total;
      double cum = 0.0;
      std::size_t last = n - 1;
      for (std::size_t k = 0; k < n; ++k) {
        const double w = equal ? 1.0 : d.weights[k];
        if (!(w > 0.0)) continue;
        cum += w;
        last = k;
        if (target < cum) return d.values[k];
      }
      return d.values[last];
    }
  }
  fail("unknown distribution kind " + std::to_string(static_cast<int>(d.kind)));
}

// ---- unit-cube point sets --------------------------------------------------------------------------

std::vector<std::vector<double>> make_latin_hypercube(int n, int d, std::uint64_t seed) {
  check_unit_args(n, d, "make_latin_hypercube");
  Matrix x(static_cast<std::size_t>(n), std::vector<double>(static_cast<std::size_t>(d)));
  std::vector<int> perm(static_cast<std::size_t>(n));
  for (int j = 0; j < d; ++j) {
    // Column j: Fisher-Yates permutation of the strata, then one uniform position per row.
    CounterRng rng(stream_key(seed, kTagLhs, static_cast<std::uint64_t>(j)));
    std::iota(perm.begin(), perm.end(), 0);
    for (int i = n - 1; i > 0; --i)
      std::swap(perm[static_cast<std::size_t>(i)],
                perm[static_cast<std::size_t>(rng.next_below(static_cast<std::uint64_t>(i) + 1))]);
    for (int i = 0; i < n; ++i) {
      const int k = perm[static_cast<std::size_t>(i)];
      double v = (k + rng.uniform()) / n;
      // k + u can round up to k + 1 when u is within an ulp of 1; keep the point inside its stratum.
      if (!(v > 0.0 && v < 1.0) || static_cast<int>(std::floor(v * n)) != k) v = (k + 0.5) / n;
      x[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] = v;
    }
  }
  return x;
}

std::vector<std::vector<double>> make_sobol_points(int n, int d, std::uint64_t seed) {
  check_unit_args(n, d, "make_sobol_points");
  check_sobol_dimension(d, "make_sobol_points");
  Matrix x(static_cast<std::size_t>(n), std::vector<double>(static_cast<std::size_t>(d)));
  for (int j = 0; j < d; ++j) {
    const std::uint64_t key = stream_key(seed, kTagSobol, static_cast<std::uint64_t>(j));
    const std::vector<std::uint32_t> col = make_sobol_column(n, j);
    for (std::size_t i = 0; i < col.size(); ++i)
      x[i][static_cast<std::size_t>(j)] = calc_open_unit(owen_scramble(col[i], key));
  }
  return x;
}

std::vector<std::vector<double>> make_sobol_points_unscrambled(int n, int d) {
  check_unit_args(n, d, "make_sobol_points_unscrambled");
  check_sobol_dimension(d, "make_sobol_points_unscrambled");
  Matrix x(static_cast<std::size_t>(n), std::vector<double>(static_cast<std::size_t>(d)));
  for (int j = 0; j < d; ++j) {
    const std::vector<std::uint32_t> col = make_sobol_column(n, j);
    for (std::size_t i = 0; i < col.size(); ++i) x[i][static_cast<std::size_t>(j)] = col[i] * 0x1p-32;
  }
  return x;
}

double calc_morris_delta(int p) {
  check_morris_levels(p);
  return static_cast<double>(p) / (2.0 * (p - 1));
}

std::vector<std::vector<double>> make_morris_points(int r, int d, int p, std::uint64_t seed) {
  if (r < 1) fail("morris design: trajectories must be >= 1 (got " + std::to_string(r) + ")");
  if (d < 1) fail("morris design: needs at least one variable");
  check_morris_levels(p);
  checked_rows(static_cast<long double>(r) * (d + 1), "morris");
  // Work in integer grid levels 0..p-1 (Delta = p/2 levels), so steps are exact; u = level / (p - 1).
  const int half = p / 2;
  const auto to_unit = [p](const std::vector<int>& level) {
    std::vector<double> row(level.size());
    for (std::size_t j = 0; j < level.size(); ++j) row[j] = static_cast<double>(level[j]) / (p - 1);
    return row;
  };
  Matrix x;
  x.reserve(static_cast<std::size_t>(r) * static_cast<std::size_t>(d + 1));
  std::vector<int> level(static_cast<std::size_t>(d)), dir(static_cast<std::size_t>(d)),
      order(static_cast<std::size_t>(d));
  for (int t = 0; t < r; ++t) {
    // Trajectory t: base levels in {0..p/2-1}, a direction per variable, then the order of the steps.
    CounterRng rng(stream_key(seed, kTagMorris, static_cast<std::uint64_t>(t)));
    for (std::size_t j = 0; j < level.size(); ++j)
      level[j] = static_cast<int>(rng.next_below(static_cast<std::uint64_t>(half)));
    for (std::size_t j = 0; j < dir.size(); ++j) {
      dir[j] = (rng.next_u64() >> 63) != 0 ? 1 : -1;
      if (dir[j] < 0) level[j] += half;  // starts at x* + Delta and steps down to x*
    }
    std::iota(order.begin(), order.end(), 0);
    for (int i = d - 1; i > 0; --i)
      std::swap(order[static_cast<std::size_t>(i)],
                order[static_cast<std::size_t>(rng.next_below(static_cast<std::uint64_t>(i) + 1))]);
    x.push_back(to_unit(level));
    for (int k = 0; k < d; ++k) {
      const std::size_t j = static_cast<std::size_t>(order[static_cast<std::size_t>(k)]);
      level[j] += dir[j] * half;
      x.push_back(to_unit(level));
    }
  }
  return x;
}

// ---- designs ---------------------------------------------------------------------------------------

void validate_design(const DesignSpec& spec, const std::vector<Variable>& vars) {
  const std::string name = design_name(spec.kind);
  if (name == "unknown") fail("unknown design kind " + std::to_string(static_cast<int>(spec.kind)));
  if (vars.empty()) fail(name + " design: no variables");
  const auto where = [&](const Variable& v) { return name + " design, variable '" + v.path + "': "; };
  const int d = static_cast<int>(vars.size());

  switch (spec.kind) {
    case DesignKind::kGrid: {
      long double rows = 1;
      for (const Variable& v : vars) {
        if (v.levels.empty()) fail(where(v) + "a grid variable needs at least one level");
        for (double x : v.levels)
          if (!std::isfinite(x)) fail(where(v) + "level " + fmt(x) + " is not finite");
        rows *= static_cast<long double>(v.levels.size());
      }
      checked_rows(rows, "grid");
      return;
    }
    case DesignKind::kCentered: {
      long double rows = 1;
      for (const Variable& v : vars) {
        if (!std::isfinite(v.nominal)) fail(where(v) + "nominal " + fmt(v.nominal) + " is not finite");
        for (double x : v.levels)
          if (!std::isfinite(x)) fail(where(v) + "level " + fmt(x) + " is not finite");
        rows += static_cast<long double>(centered_levels(v).size());
      }
      checked_rows(rows, "centered");
      return;
    }
    case DesignKind::kMonteCarlo:
    case DesignKind::kLatinHypercube:
    case DesignKind::kSobol:
    case DesignKind::kSaltelli:
      if (spec.samples < 1)
        fail(name + " design: samples must be >= 1 (got " + std::to_string(spec.samples) + ")");
      if (spec.kind == DesignKind::kSobol && d > kSobolMaxDimension)
        fail("sobol design: at most " + std::to_string(kSobolMaxDimension) + " variables (got " +
             std::to_string(d) + ")");
      if (spec.kind == DesignKind::kSaltelli && 2 * d > kSobolMaxDimension)
        fail("saltelli design: at most " + std::to_string(kSobolMaxDimension / 2) +
             " variables, it draws 2 Sobol' dimensions per variable (got " + std::to_string(d) + ")");
      if (spec.kind == DesignKind::kSaltelli)
        checked_rows(static_cast<long double>(spec.samples) * (d + 2), "saltelli");
      break;
    case DesignKind::kMorris:
      if (spec.trajectories < 1)
        fail("morris design: trajectories must be >= 1 (got " + std::to_string(spec.trajectories) + ")");
      check_morris_levels(spec.morris_levels);
      checked_rows(static_cast<long double>(spec.trajectories) * (d + 1), "morris");
      break;
  }
  // Sampling designs: every variable needs a valid distribution.
  for (const Variable& v : vars) {
    try {
      validate_distribution(v.dist);
    } catch (const std::invalid_argument& e) {
      fail(where(v) + e.what());
    }
  }
}

int calc_design_size(const DesignSpec& spec, const std::vector<Variable>& vars) {
  validate_design(spec, vars);
  const int d = static_cast<int>(vars.size());
  switch (spec.kind) {
    case DesignKind::kGrid: {
      int rows = 1;
      for (const Variable& v : vars) rows *= static_cast<int>(v.levels.size());
      return rows;
    }
    case DesignKind::kCentered: {
      int rows = 1;
      for (const Variable& v : vars) rows += static_cast<int>(centered_levels(v).size());
      return rows;
    }
    case DesignKind::kMonteCarlo:
    case DesignKind::kLatinHypercube:
    case DesignKind::kSobol: return spec.samples;
    case DesignKind::kSaltelli: return spec.samples * (d + 2);
    case DesignKind::kMorris: return spec.trajectories * (d + 1);
  }
  return 0;
}

std::vector<std::vector<double>> make_design(const DesignSpec& spec, const std::vector<Variable>& vars) {
  const int rows = calc_design_size(spec, vars);  // validates
  const std::size_t d = vars.size();
  Matrix out;
  out.reserve(static_cast<std::size_t>(rows));

  switch (spec.kind) {
    case DesignKind::kGrid: {
      // Mixed-radix counter over the level indices, last variable fastest.
      std::vector<std::size_t> idx(d, 0);
      for (int r = 0; r < rows; ++r) {
        std::vector<double> row(d);
        for (std::size_t j = 0; j < d; ++j) row[j] = vars[j].levels[idx[j]];
        out.push_back(std::move(row));
        for (std::size_t j = d; j-- > 0;) {
          if (++idx[j] < vars[j].levels.size()) break;
          idx[j] = 0;
        }
      }
      return out;
    }
    case DesignKind::kCentered: {
      std::vector<double> centre(d);
      for (std::size_t j = 0; j < d; ++j) centre[j] = vars[j].nominal;
      out.push_back(centre);
      for (std::size_t j = 0; j < d; ++j) {
        for (double x : centered_levels(vars[j])) {
          out.push_back(centre);
          out.back()[j] = x;
        }
      }
      return out;
    }
    case DesignKind::kMonteCarlo: {
      // Row i from the stream of calc_variant_seed(seed, i): independent of the sample count.
      for (int i = 0; i < rows; ++i) {
        CounterRng rng(calc_variant_seed(spec.seed, static_cast<std::uint64_t>(i)));
        std::vector<double> row(d);
        for (std::size_t j = 0; j < d; ++j) row[j] = calc_quantile(vars[j].dist, rng.uniform());
        out.push_back(std::move(row));
      }
      return out;
    }
    case DesignKind::kLatinHypercube:
      return map_unit(make_latin_hypercube(spec.samples, static_cast<int>(d), spec.seed), vars);
    case DesignKind::kSobol:
      return map_unit(make_sobol_points(spec.samples, static_cast<int>(d), spec.seed), vars);
    case DesignKind::kSaltelli: {
      // A = columns [0, d), B = columns [d, 2d) of one scrambled Sobol' set; rows A, B, AB_0..AB_{d-1}.
      const std::size_t n = static_cast<std::size_t>(spec.samples);
      const Matrix ab = make_sobol_points(spec.samples, 2 * static_cast<int>(d), spec.seed);
      Matrix unit;
      unit.reserve(static_cast<std::size_t>(rows));
      const auto split = static_cast<std::ptrdiff_t>(d);
      for (std::size_t k = 0; k < n; ++k) unit.emplace_back(ab[k].begin(), ab[k].begin() + split);
      for (std::size_t k = 0; k < n; ++k) unit.emplace_back(ab[k].begin() + split, ab[k].end());
      for (std::size_t i = 0; i < d; ++i) {
        for (std::size_t k = 0; k < n; ++k) {
          unit.push_back(unit[k]);
          unit.back()[i] = unit[n + k][i];
        }
      }
      return map_unit(unit, vars);
    }
    case DesignKind::kMorris: {
      // Grid values through the quantiles; unbounded supports are clipped to [1e-12, 1 - 1e-12].
      const Matrix unit =
          make_morris_points(spec.trajectories, static_cast<int>(d), spec.morris_levels, spec.seed);
      for (const std::vector<double>& u : unit) {
        std::vector<double> row(d);
        for (std::size_t j = 0; j < d; ++j) {
          const double uj =
              has_bounded_support(vars[j].dist) ? u[j] : std::clamp(u[j], 1e-12, 1.0 - 1e-12);
          row[j] = calc_quantile(vars[j].dist, uj);
        }
        out.push_back(std::move(row));
      }
      return out;
    }
  }
  return out;
}

}  // namespace ff
