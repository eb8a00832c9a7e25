#include "results/censoring.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

namespace ff {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// One entry that is not missing: settled at `time`, or censored there (known only to be > time).
struct Obs {
  double time;
  bool settled;
};

// The non-missing entries in index order; `missing` counts the rest.
std::vector<Obs> observations(const std::vector<double>& values, const std::vector<double>& horizons, int& missing) {
  if (!horizons.empty() && horizons.size() != values.size())
    throw std::invalid_argument("censored sample: " + std::to_string(horizons.size()) + " horizons for " +
                                std::to_string(values.size()) + " values");
  std::vector<Obs> out;
  missing = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isnan(values[i])) out.push_back({values[i], true});
    else if (!horizons.empty() && !std::isnan(horizons[i])) out.push_back({horizons[i], false});
    else ++missing;
  }
  return out;
}

bool any_censored(const std::vector<Obs>& obs) {
  return std::any_of(obs.begin(), obs.end(), [](const Obs& o) { return !o.settled; });
}

// Indices of `obs` by ascending time, settled before censored at equal times (stable: ties keep index order).
std::vector<std::size_t> time_order(const std::vector<Obs>& obs) {
  std::vector<std::size_t> order(obs.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return obs[a].time < obs[b].time || (obs[a].time == obs[b].time && obs[a].settled && !obs[b].settled);
  });
  return order;
}

// Product-limit estimate (Kaplan & Meier 1958) over `obs` taken in time order, entry k counted weight[k]
// times: 1 for the sample, its multiplicity in a bootstrap resample.
KaplanMeier product_limit(const std::vector<Obs>& obs, const std::vector<std::size_t>& order,
                          const std::vector<int>& weight) {
  KaplanMeier km;
  int at_risk = 0;
  for (std::size_t k : order) at_risk += weight[k];
  double s = 1.0;
  for (std::size_t i = 0; i < order.size();) {
    // The run of entries at one time: d settled there, c censored there.
    const double t = obs[order[i]].time;
    int d = 0, c = 0;
    for (; i < order.size() && obs[order[i]].time == t; ++i) (obs[order[i]].settled ? d : c) += weight[order[i]];
    if (d + c == 0) continue;
    km.end = t;
    if (c > 0) {  // times ascend: the first censored time is the smallest horizon, the last the largest
      if (std::isnan(km.horizon_min)) km.horizon_min = t;
      km.horizon = t;
    }
    if (d > 0) {
      // S(t) = S(t-) (1 - d / n): the settled fraction of those still at risk.
      s *= 1.0 - static_cast<double>(d) / static_cast<double>(at_risk);
      km.time.push_back(t);
      km.survival.push_back(s);
      km.at_risk.push_back(at_risk);
      km.events.push_back(d);
    }
    km.count += d;
    km.censored += c;
    at_risk -= d + c;
  }
  return km;
}

KaplanMeier product_limit(const std::vector<Obs>& obs) {
  return product_limit(obs, time_order(obs), std::vector<int>(obs.size(), 1));
}

// Percentile bootstrap (Efron & Tibshirani 1993, ch. 13) of a Kaplan–Meier statistic, resampling the
// (time, settled) pairs (Efron 1981): resample b counts entry draw_index(seed, b n + j, n) once per draw j.
Interval bootstrap_km(const std::vector<Obs>& obs, int resamples, double confidence, std::uint64_t seed,
                      const std::function<double(const KaplanMeier&)>& statistic) {
  if (resamples < 1) throw std::invalid_argument("bootstrap needs at least one resample");
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must be in (0, 1)");
  if (obs.empty()) return {};
  const std::size_t n = obs.size();
  const std::vector<std::size_t> order = time_order(obs);
  Interval out;
  out.estimate = statistic(product_limit(obs, order, std::vector<int>(n, 1)));
  std::vector<double> stats(static_cast<std::size_t>(resamples));
  std::vector<int> weight(n);
  for (std::size_t b = 0; b < stats.size(); ++b) {
    std::fill(weight.begin(), weight.end(), 0);
    for (std::size_t j = 0; j < n; ++j) ++weight[draw_index(seed, b * n + j, n)];
    stats[b] = statistic(product_limit(obs, order, weight));
  }
  // Type-7 percentiles of the resampled statistics; +inf (above the horizon) sorts last.
  out.lower = calc_percentile(stats, 50.0 * (1.0 - confidence));
  out.upper = calc_percentile(stats, 50.0 * (1.0 + confidence));
  return out;
}

void check_p(double p) {
  if (!(p >= 0.0 && p <= 100.0)) throw std::invalid_argument("percentile p must be in [0, 100]");
}

}  // namespace

KaplanMeier calc_kaplan_meier(const std::vector<double>& values, const std::vector<double>& horizons) {
  int missing = 0;
  KaplanMeier km = product_limit(observations(values, horizons, missing));
  km.missing = missing;
  return km;
}

double calc_km_survival(const KaplanMeier& km, double t) {
  if (km.count + km.censored == 0) return kStatsNaN;
  const auto i = std::upper_bound(km.time.begin(), km.time.end(), t) - km.time.begin();
  return i == 0 ? 1.0 : km.survival[static_cast<std::size_t>(i - 1)];
}

double calc_km_percentile(const KaplanMeier& km, double p) {
  check_p(p);
  if (km.count + km.censored == 0) return kStatsNaN;
  // First settled time where the settled fraction 1 - S reaches p (a 1e-12 slack absorbs the rounding of
  // the product, so that k of n settled reads exactly k/n).
  for (std::size_t i = 0; i < km.time.size(); ++i)
    if (1.0 - km.survival[i] >= p / 100.0 - 1e-12) return km.time[i];
  return kInf;
}

double calc_km_restricted_mean(const KaplanMeier& km, double tau) {
  if (km.count + km.censored == 0) return kStatsNaN;
  // E[min(T, tau)]: each jump of the curve up to tau at its time, the mass left at tau.
  double sum = 0.0, before = 1.0;
  for (std::size_t i = 0; i < km.time.size() && km.time[i] <= tau; ++i) {
    sum += km.time[i] * (before - km.survival[i]);
    before = km.survival[i];
  }
  return sum + tau * before;
}

Summary calc_summary(const std::vector<double>& values, const std::vector<double>& horizons) {
  int missing = 0;
  const std::vector<Obs> obs = observations(values, horizons, missing);
  if (!any_censored(obs)) return calc_summary(values);
  const KaplanMeier km = product_limit(obs);
  Summary s;
  s.count = km.count;
  s.censored = km.censored;
  s.missing = missing;
  s.horizon = km.horizon;
  s.horizon_min = km.horizon_min;
  s.mean = calc_km_restricted_mean(km, km.horizon);
  s.min = km.time.empty() ? kInf : km.time.front();
  s.p5 = calc_km_percentile(km, 5.0);
  s.p50 = calc_km_percentile(km, 50.0);
  s.p95 = calc_km_percentile(km, 95.0);
  s.max = kInf;
  return s;
}

Interval calc_bootstrap_mean(const std::vector<double>& values, const std::vector<double>& horizons, int resamples,
                             double confidence, std::uint64_t seed) {
  int missing = 0;
  const std::vector<Obs> obs = observations(values, horizons, missing);
  if (!any_censored(obs)) return calc_bootstrap_mean(values, resamples, confidence, seed);
  const double tau = product_limit(obs).horizon;
  return bootstrap_km(obs, resamples, confidence, seed,
                      [tau](const KaplanMeier& km) { return calc_km_restricted_mean(km, tau); });
}

Interval calc_bootstrap_percentile(const std::vector<double>& values, const std::vector<double>& horizons, double p,
                                   int resamples, double confidence, std::uint64_t seed) {
  check_p(p);
  int missing = 0;
  const std::vector<Obs> obs = observations(values, horizons, missing);
  if (!any_censored(obs)) return calc_bootstrap_percentile(values, p, resamples, confidence, seed);
  return bootstrap_km(obs, resamples, confidence, seed,
                      [p](const KaplanMeier& km) { return calc_km_percentile(km, p); });
}

}  // namespace ff
