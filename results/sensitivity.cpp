#include "results/sensitivity.hpp"

#include <cmath>
#include <cstddef>
#include <stdexcept>

#include "results/statistics.hpp"

namespace ff {

namespace {

// The Saltelli blocks of the kept base indices: fa[k], fb[k], fab[i][k].
struct SaltelliBlocks {
  std::vector<double> fa, fb;
  std::vector<std::vector<double>> fab;
};

// S_i and ST_i (appended to first / total) over the base indices `idx` of the blocks, in index order:
// V = population variance of [fA, fB] (two-pass), V_i = mean (fB - f0) (fAB_i - fA) (Saltelli et al. 2010,
// Table 2 b, with the output centred on its mean f0: the same expectation, since E[fAB_i - fA] = 0, but
// without the variance a large mean adds), E_i = mean (fA - fAB_i)^2 / 2 (Jansen 1999).
void sobol_of(const SaltelliBlocks& s, const std::vector<std::size_t>& idx, std::vector<double>& first,
              std::vector<double>& total) {
  const double n = static_cast<double>(idx.size());
  double sum = 0.0;
  for (std::size_t k : idx) sum += s.fa[k];
  for (std::size_t k : idx) sum += s.fb[k];
  const double mean = sum / (2.0 * n);
  double ss = 0.0;
  for (std::size_t k : idx) ss += (s.fa[k] - mean) * (s.fa[k] - mean);
  for (std::size_t k : idx) ss += (s.fb[k] - mean) * (s.fb[k] - mean);
  const double var = ss / (2.0 * n);
  for (const auto& fab : s.fab) {
    double vi = 0.0, ei = 0.0;
    for (std::size_t k : idx) {
      vi += (s.fb[k] - mean) * (fab[k] - s.fa[k]);
      ei += (s.fa[k] - fab[k]) * (s.fa[k] - fab[k]);
    }
    first.push_back(var > 0.0 ? vi / n / var : kStatsNaN);
    total.push_back(var > 0.0 ? ei / (2.0 * n) / var : kStatsNaN);
  }
}

// Sample standard deviation (divisor m - 1) of column i of the m x d row-major matrix v.
double column_std(const std::vector<double>& v, std::size_t m, std::size_t d, std::size_t i) {
  double sum = 0.0;
  for (std::size_t b = 0; b < m; ++b) sum += v[b * d + i];
  const double mean = sum / static_cast<double>(m);
  double ss = 0.0;
  for (std::size_t b = 0; b < m; ++b) ss += (v[b * d + i] - mean) * (v[b * d + i] - mean);
  return std::sqrt(ss / static_cast<double>(m - 1));
}

}  // namespace

SobolIndices calc_sobol_indices(const std::vector<double>& y, int d, int resamples, std::uint64_t seed) {
  if (d < 1) throw std::invalid_argument("calc_sobol_indices: d must be >= 1");
  if (resamples < 0) throw std::invalid_argument("calc_sobol_indices: resamples must be >= 0");
  const std::size_t nd = static_cast<std::size_t>(d);
  if (y.empty() || y.size() % (nd + 2) != 0)
    throw std::invalid_argument("calc_sobol_indices: y must hold N (d + 2) evaluations");
  const std::size_t N = y.size() / (nd + 2);

  // Keep the base indices k with no NaN in any block; copy the blocks of the kept k.
  SaltelliBlocks s;
  s.fab.resize(nd);
  for (std::size_t k = 0; k < N; ++k) {
    bool ok = true;
    for (std::size_t blk = 0; blk < nd + 2 && ok; ++blk) ok = !std::isnan(y[blk * N + k]);
    if (!ok) continue;
    s.fa.push_back(y[k]);
    s.fb.push_back(y[N + k]);
    for (std::size_t i = 0; i < nd; ++i) s.fab[i].push_back(y[(2 + i) * N + k]);
  }
  const std::size_t n = s.fa.size();

  SobolIndices out;
  if (n < 2) {
    out.first.assign(nd, kStatsNaN);
    out.total.assign(nd, kStatsNaN);
    out.first_ci.assign(nd, kStatsNaN);
    out.total_ci.assign(nd, kStatsNaN);
    return out;
  }
  // Point estimates over every kept base index.
  std::vector<std::size_t> idx(n);
  for (std::size_t k = 0; k < n; ++k) idx[k] = k;
  sobol_of(s, idx, out.first, out.total);

  // Bootstrap: resample b draws base index j as draw_index(seed, b n + j, n), shared by all blocks and inputs
  // (as SALib); the 95 % half-width is z_0.975 times the standard deviation over the resamples.
  const std::size_t m = static_cast<std::size_t>(resamples);
  if (m < 2) {
    out.first_ci.assign(nd, kStatsNaN);
    out.total_ci.assign(nd, kStatsNaN);
    return out;
  }
  std::vector<double> boot_first, boot_total;  // m x d, row-major
  boot_first.reserve(m * nd);
  boot_total.reserve(m * nd);
  for (std::size_t b = 0; b < m; ++b) {
    for (std::size_t j = 0; j < n; ++j) idx[j] = draw_index(seed, b * n + j, n);
    sobol_of(s, idx, boot_first, boot_total);
  }
  const double z = calc_two_sided_z(0.95);
  for (std::size_t i = 0; i < nd; ++i) {
    out.first_ci.push_back(z * column_std(boot_first, m, nd, i));
    out.total_ci.push_back(z * column_std(boot_total, m, nd, i));
  }
  return out;
}

MorrisIndices calc_morris_indices(const std::vector<std::vector<double>>& x_unit, const std::vector<double>& y, int d) {
  if (d < 1) throw std::invalid_argument("calc_morris_indices: d must be >= 1");
  const std::size_t nd = static_cast<std::size_t>(d);
  const std::size_t rows = x_unit.size();
  if (y.size() != rows || rows == 0 || rows % (nd + 1) != 0)
    throw std::invalid_argument("calc_morris_indices: need r (d + 1) rows of x and y");
  for (const auto& row : x_unit)
    if (row.size() != nd) throw std::invalid_argument("calc_morris_indices: every row of x must have d values");
  constexpr double kStepTol = 1e-9;  // smaller coordinate differences count as "unchanged"

  // Elementary effects per input, in trajectory and step order.
  std::vector<std::vector<double>> ee(nd);
  for (std::size_t t0 = 0; t0 < rows; t0 += nd + 1) {
    std::vector<bool> changed(nd, false);
    for (std::size_t j = t0; j < t0 + nd; ++j) {
      // The one variable that changes from row j to row j+1.
      std::size_t which = nd;
      for (std::size_t i = 0; i < nd; ++i) {
        if (std::fabs(x_unit[j + 1][i] - x_unit[j][i]) <= kStepTol) continue;
        if (which != nd) throw std::invalid_argument("calc_morris_indices: consecutive rows differ in two variables");
        which = i;
      }
      if (which == nd) throw std::invalid_argument("calc_morris_indices: consecutive rows do not differ");
      if (changed[which])
        throw std::invalid_argument("calc_morris_indices: a variable changes twice in one trajectory");
      changed[which] = true;
      // EE = (y(x + delta e_i) - y(x)) / delta with the signed step (Morris 1991); NaN ends drop it.
      if (std::isnan(y[j]) || std::isnan(y[j + 1])) continue;
      ee[which].push_back((y[j + 1] - y[j]) / (x_unit[j + 1][which] - x_unit[j][which]));
    }
  }

  // mu, mu* (Campolongo et al. 2007) and sigma (sample standard deviation) per input.
  MorrisIndices out;
  for (std::size_t i = 0; i < nd; ++i) {
    const auto& e = ee[i];
    double mu = kStatsNaN, mu_star = kStatsNaN, sigma = kStatsNaN;
    if (!e.empty()) {
      double sum = 0.0, sum_abs = 0.0;
      for (double v : e) {
        sum += v;
        sum_abs += std::fabs(v);
      }
      const double cnt = static_cast<double>(e.size());
      mu = sum / cnt;
      mu_star = sum_abs / cnt;
      if (e.size() >= 2) {
        double ss = 0.0;
        for (double v : e) ss += (v - mu) * (v - mu);
        sigma = std::sqrt(ss / (cnt - 1.0));
      }
    }
    out.mu.push_back(mu);
    out.mu_star.push_back(mu_star);
    out.sigma.push_back(sigma);
  }
  return out;
}

}  // namespace ff
