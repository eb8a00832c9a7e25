#include "results/statistics.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <functional>
#include <numbers>
#include <stdexcept>

namespace ff {

namespace {

// Drops NaNs, keeping the order of the rest.
std::vector<double> without_nan(const std::vector<double>& values) {
  std::vector<double> out;
  out.reserve(values.size());
  for (double v : values)
    if (!std::isnan(v)) out.push_back(v);
  return out;
}

// Type-7 percentile of values already sorted ascending, NaN-free and non-empty.
double sorted_percentile(const std::vector<double>& x, double p) {
  const std::size_t n = x.size();
  const double h = static_cast<double>(n - 1) * p / 100.0;
  const std::size_t lo = std::min(static_cast<std::size_t>(std::floor(h)), n - 1);
  const std::size_t hi = std::min(lo + 1, n - 1);
  const double t = h - static_cast<double>(lo);
  if (t == 0.0 || x[lo] == x[hi]) return x[lo];  // also keeps +-inf from turning into inf - inf = NaN
  return x[lo] + t * (x[hi] - x[lo]);
}

// The same type-7 percentile of unsorted values (reordered): the two order statistics it needs by
// selection, O(n) rather than a sort.
double select_percentile(std::vector<double>& x, double p) {
  const std::size_t n = x.size();
  const double h = static_cast<double>(n - 1) * p / 100.0;
  const std::size_t lo = std::min(static_cast<std::size_t>(std::floor(h)), n - 1);
  std::nth_element(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(lo), x.end());
  const double a = x[lo];
  const double t = h - static_cast<double>(lo);
  if (t == 0.0 || lo + 1 == n) return a;
  const double b = *std::min_element(x.begin() + static_cast<std::ptrdiff_t>(lo) + 1, x.end());
  if (a == b) return a;  // also keeps +-inf from turning into inf - inf = NaN
  return a + t * (b - a);
}

void check_percentile(double p) {
  if (!(p >= 0.0 && p <= 100.0)) throw std::invalid_argument("percentile p must be in [0, 100]");
}

// Sum in index order, then divide: the fixed-order mean used everywhere here.
double mean_of(const std::vector<double>& x) {
  double s = 0.0;
  for (double v : x) s += v;
  return s / static_cast<double>(x.size());
}

// SplitMix64 finaliser (Steele, Lea & Flood 2014; constants from Vigna's splitmix64.c).
std::uint64_t splitmix64_mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}
constexpr std::uint64_t kGolden = 0x9E3779B97F4A7C15ULL;

// High 64 bits of the 128-bit product a b, in portable 32-bit pieces.
std::uint64_t mulhi64(std::uint64_t a, std::uint64_t b) {
  const std::uint64_t a_lo = a & 0xFFFFFFFFULL, a_hi = a >> 32, b_lo = b & 0xFFFFFFFFULL, b_hi = b >> 32;
  const std::uint64_t p0 = a_lo * b_lo, p1 = a_lo * b_hi, p2 = a_hi * b_lo, p3 = a_hi * b_hi;
  const std::uint64_t mid = (p0 >> 32) + (p1 & 0xFFFFFFFFULL) + (p2 & 0xFFFFFFFFULL);
  return p3 + (p1 >> 32) + (p2 >> 32) + (mid >> 32);
}

// Percentile bootstrap of `statistic` over the NaN-free sample (Efron & Tibshirani 1993, ch. 13).
Interval bootstrap(const std::vector<double>& values, int resamples, double confidence, std::uint64_t seed,
                   const std::function<double(std::vector<double>&)>& statistic) {
  if (resamples < 1) throw std::invalid_argument("bootstrap needs at least one resample");
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must be in (0, 1)");
  std::vector<double> x = without_nan(values);
  if (x.empty()) return {};
  const std::size_t n = x.size();
  Interval out;
  {
    std::vector<double> copy = x;
    out.estimate = statistic(copy);
  }
  // Resample b, draw j takes x[draw_index(seed, b n + j, n)]: any resample can be rebuilt on its own.
  std::vector<double> stats(static_cast<std::size_t>(resamples));
  std::vector<double> sample(n);
  for (std::size_t b = 0; b < stats.size(); ++b) {
    for (std::size_t j = 0; j < n; ++j) sample[j] = x[draw_index(seed, b * n + j, n)];
    stats[b] = statistic(sample);
  }
  std::sort(stats.begin(), stats.end());
  out.lower = sorted_percentile(stats, 50.0 * (1.0 - confidence));
  out.upper = sorted_percentile(stats, 50.0 * (1.0 + confidence));
  return out;
}

// Rounds to 12 significant digits through the 12-digit decimal form (std::to_chars rounds exactly and is
// locale-independent), so the result is the same double on every machine; -0 becomes +0, NaN stays NaN.
double round_key(double v) {
  if (std::isnan(v)) return kStatsNaN;
  if (!std::isfinite(v)) return v;
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific, 11);
  double r = v;
  std::from_chars(buf, res.ptr, r, std::chars_format::scientific);
  return r == 0.0 ? 0.0 : r;
}

// Strict weak order on keys: numbers ascending, NaN after every number, NaN equal to NaN.
bool key_less(double a, double b) { return !std::isnan(a) && (std::isnan(b) || a < b); }
bool key_equal(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

// Standard normal quantile Phi^-1(p) for p in (0, 1/2]; the upper half by symmetry.
double normal_quantile(double p) {
  if (p > 0.5) return -normal_quantile(1.0 - p);  // 1 - p is exact for p >= 1/2; Phi(x) - p never cancels
  // Acklam's rational approximation (relative error < 1.15e-9): lower tail and central region.
  static constexpr double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                                 1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                                 6.680131188771972e+01, -1.328068155288572e+01};
  static constexpr double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                                 -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static constexpr double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                                 3.754408661907416e+00};
  constexpr double p_low = 0.02425;
  double x;
  if (p < p_low) {
    const double q = std::sqrt(-2.0 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  } else {
    const double q = p - 0.5;
    const double r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  }
  // One Halley step on Phi(x) - p, with Phi(x) = erfc(-x / sqrt 2) / 2, to full double precision.
  const double e = 0.5 * std::erfc(-x / std::numbers::sqrt2) - p;
  const double u = e * std::sqrt(2.0 * std::numbers::pi) * std::exp(0.5 * x * x);
  return x - u / (1.0 + 0.5 * x * u);
}

}  // namespace

double calc_percentile(std::vector<double> values, double p) {
  check_percentile(p);
  std::erase_if(values, [](double v) { return std::isnan(v); });
  if (values.empty()) return kStatsNaN;
  std::sort(values.begin(), values.end());
  return sorted_percentile(values, p);
}

Summary calc_summary(const std::vector<double>& values) {
  Summary s;
  std::vector<double> x = without_nan(values);
  s.count = static_cast<int>(x.size());
  s.missing = static_cast<int>(values.size() - x.size());
  if (x.empty()) return s;
  // Two-pass mean and sample variance, in index order.
  s.mean = mean_of(x);
  if (x.size() >= 2) {
    double ss = 0.0;
    for (double v : x) ss += (v - s.mean) * (v - s.mean);
    s.std = std::sqrt(ss / static_cast<double>(x.size() - 1));
  }
  std::sort(x.begin(), x.end());
  s.min = x.front();
  s.max = x.back();
  s.p5 = sorted_percentile(x, 5.0);
  s.p50 = sorted_percentile(x, 50.0);
  s.p95 = sorted_percentile(x, 95.0);
  return s;
}

Interval calc_bootstrap_mean(const std::vector<double>& values, int resamples, double confidence, std::uint64_t seed) {
  return bootstrap(values, resamples, confidence, seed, [](std::vector<double>& x) { return mean_of(x); });
}

Interval calc_bootstrap_percentile(const std::vector<double>& values, double p, int resamples, double confidence,
                                   std::uint64_t seed) {
  check_percentile(p);
  return bootstrap(values, resamples, confidence, seed, [p](std::vector<double>& x) { return select_percentile(x, p); });
}

Interval calc_wilson_interval(std::size_t k, std::size_t n_rows, double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must be in (0, 1)");
  if (n_rows == 0) return {};
  const double n = static_cast<double>(n_rows);
  const double ph = static_cast<double>(k) / n;
  // Wilson score interval: (ph + z^2/2n -+ z sqrt(ph (1-ph)/n + z^2/4n^2)) / (1 + z^2/n).
  const double z = calc_two_sided_z(confidence);
  const double z2 = z * z;
  const double denom = 1.0 + z2 / n;
  const double centre = (ph + z2 / (2.0 * n)) / denom;
  const double half = z / denom * std::sqrt(ph * (1.0 - ph) / n + z2 / (4.0 * n * n));
  Interval out;
  out.estimate = ph;
  out.lower = k == 0 ? 0.0 : std::max(0.0, centre - half);
  out.upper = k >= n_rows ? 1.0 : std::min(1.0, centre + half);
  return out;
}

Interval calc_miss_probability(const std::vector<double>& values, double limit, double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must be in (0, 1)");
  if (values.empty()) return {};
  // Count the misses: above the limit, or NaN (did not meet the spec at all).
  std::size_t k = 0;
  for (double v : values)
    if (std::isnan(v) || v > limit) ++k;
  return calc_wilson_interval(k, values.size(), confidence);
}

std::vector<Group> make_groups(const std::vector<std::vector<double>>& key_columns) {
  if (key_columns.empty()) return {};
  const std::size_t nrows = key_columns[0].size();
  for (const auto& c : key_columns)
    if (c.size() != nrows) throw std::invalid_argument("make_groups: key columns differ in length");
  // Round every key once; rounded[row] is the row's key tuple.
  std::vector<std::vector<double>> rounded(nrows, std::vector<double>(key_columns.size()));
  for (std::size_t k = 0; k < key_columns.size(); ++k)
    for (std::size_t r = 0; r < nrows; ++r) rounded[r][k] = round_key(key_columns[k][r]);
  // Stable sort of the rows by key tuple keeps each group's rows ascending.
  std::vector<int> order(nrows);
  for (std::size_t r = 0; r < nrows; ++r) order[r] = static_cast<int>(r);
  const auto tuple_less = [&](int a, int b) {
    return std::lexicographical_compare(rounded[a].begin(), rounded[a].end(), rounded[b].begin(), rounded[b].end(),
                                        key_less);
  };
  std::stable_sort(order.begin(), order.end(), tuple_less);
  // Sweep: a new group starts wherever the key tuple changes.
  std::vector<Group> groups;
  for (int r : order) {
    if (groups.empty() || !std::equal(groups.back().key.begin(), groups.back().key.end(), rounded[r].begin(), key_equal))
      groups.push_back({rounded[r], {}});
    groups.back().rows.push_back(r);
  }
  return groups;
}

std::vector<double> calc_bin_edges(const std::vector<double>& column, const Binning& binning) {
  if (binning.bins <= 0) return {};
  std::vector<double> x;  // the finite keys, rounded, ascending
  for (double v : column)
    if (std::isfinite(v)) x.push_back(round_key(v));
  std::sort(x.begin(), x.end());
  std::size_t levels = x.empty() ? 0 : 1;
  for (std::size_t i = 1; i < x.size(); ++i) levels += x[i] != x[i - 1];
  if (levels <= static_cast<std::size_t>(binning.bins)) return {};
  const double lo = x.front(), hi = x.back();
  std::vector<double> edges = {lo};
  for (int k = 1; k < binning.bins; ++k) {
    const double e = binning.kind == Binning::kQuantile
                         ? sorted_percentile(x, 100.0 * k / binning.bins)
                         : lo + (hi - lo) * static_cast<double>(k) / static_cast<double>(binning.bins);
    // Rounded like the keys; clamped so the edges never decrease or pass the largest key.
    edges.push_back(std::clamp(round_key(e), edges.back(), hi));
  }
  edges.push_back(hi);
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  if (binning.kind == Binning::kQuantile) {
    // Drop the upper edge of a bin [a, b) that holds no key: it merges with the next one. The last bin,
    // closed, holds the largest key.
    std::vector<double> kept = {edges.front()};
    for (std::size_t i = 1; i + 1 < edges.size(); ++i)
      if (std::lower_bound(x.begin(), x.end(), kept.back()) != std::lower_bound(x.begin(), x.end(), edges[i]))
        kept.push_back(edges[i]);
    kept.push_back(edges.back());
    edges = std::move(kept);
  }
  return edges;
}

double calc_bin_key(const std::vector<double>& edges, double value) {
  if (!std::isfinite(value) || edges.size() < 2) return value;
  const double v = round_key(value);
  if (v < edges.front() || v > edges.back()) throw std::invalid_argument("calc_bin_key: value outside the bins");
  const auto above = std::upper_bound(edges.begin(), edges.end(), v) - edges.begin();  // first edge > v
  return static_cast<double>(std::min<std::ptrdiff_t>(above - 1, static_cast<std::ptrdiff_t>(edges.size()) - 2));
}

std::size_t draw_index(std::uint64_t seed, std::uint64_t counter, std::size_t n) {
  // Output number `counter` of the SplitMix64 stream whose state starts at mix(seed): mix(state + (counter+1) g).
  const std::uint64_t key = splitmix64_mix(seed + kGolden);
  const std::uint64_t r = splitmix64_mix(key + (counter + 1) * kGolden);
  return static_cast<std::size_t>(mulhi64(r, static_cast<std::uint64_t>(n)));
}

double calc_two_sided_z(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must be in (0, 1)");
  return -normal_quantile(0.5 * (1.0 - confidence));
}

}  // namespace ff
