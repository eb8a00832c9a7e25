// Response metrics of sampled signals (definitions in metrics.hpp).
#include "kernel/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>

namespace ff {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// t and y must be equally long, non-empty, and t strictly increasing (this also rejects NaN times).
void check_signal(std::span<const double> t, std::span<const double> y, const char* where) {
  if (t.empty() || t.size() != y.size())
    throw std::invalid_argument(std::string(where) + ": t and y must be non-empty and of equal length");
  for (std::size_t i = 1; i < t.size(); ++i)
    if (!(t[i] > t[i - 1])) throw std::invalid_argument(std::string(where) + ": t must be strictly increasing");
}

// Half-open index range [lo, hi) of the samples with t in [t_from, t_to]; throws when empty.
struct Range {
  std::size_t lo, hi;
};
Range samples_in(std::span<const double> t, double t_from, double t_to, const char* where) {
  const auto lo = std::lower_bound(t.begin(), t.end(), t_from);
  const auto hi = std::upper_bound(t.begin(), t.end(), t_to);
  if (!(lo < hi)) throw std::invalid_argument(std::string(where) + ": no sample in the time range");
  return {static_cast<std::size_t>(lo - t.begin()), static_cast<std::size_t>(hi - t.begin())};
}

// Last exit from the band |e| <= tol over samples [lo, hi), e = y − ref.
// Returns the interpolated time the response last enters the band, NaN if the sample hi − 1 is
// still outside, and no value (has_exit = false) when no sample of the range is outside.
struct Exit {
  bool has_exit;
  double time;
};
Exit last_band_entry(std::span<const double> t, std::span<const double> y, double ref, double tol,
                     std::size_t lo, std::size_t hi) {
  for (std::size_t k = hi; k-- > lo;) {
    const double e = y[k] - ref;
    if (!(std::abs(e) > tol)) continue;
    if (k + 1 == hi) return {true, kNaN};
    const double level = e > 0.0 ? tol : -tol;  // the band edge on the side the response comes from
    return {true, calc_crossing_time(t[k], t[k + 1], e, y[k + 1] - ref, level)};
  }
  return {false, 0.0};
}

// First time ynorm = (y − y_init)/amp reaches `level`, interpolated; NaN if never. Also returns the
// index of the first sample at or above the level (size() if none).
struct Reach {
  double time;
  std::size_t index;
};
Reach first_reach(std::span<const double> t, std::span<const double> y, double y_init, double amp, double level) {
  double prev = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    const double yn = (y[k] - y_init) / amp;
    if (yn >= level) return {k == 0 ? t[0] : calc_crossing_time(t[k - 1], t[k], prev, yn, level), k};
    prev = yn;
  }
  return {kNaN, t.size()};
}

}  // namespace

double calc_move_amplitude(const MoveWindow& w, const char* who) {
  const double amplitude = w.target - w.start;
  if (amplitude == 0.0 || !std::isfinite(amplitude))
    throw std::invalid_argument(std::string(who) + ": move amplitude must be finite and non-zero");
  return amplitude;
}

double calc_settling_time(std::span<const double> t, std::span<const double> y, const MoveWindow& w, double band) {
  check_signal(t, y, "calc_settling_time");
  const double amplitude = calc_move_amplitude(w, "calc_settling_time");
  if (!(band > 0.0)) throw std::invalid_argument("calc_settling_time: band must be positive");

  // Samples of the window, plus the one just before the move end to interpolate an early crossing.
  const Range r = samples_in(t, w.t_move_end, w.t_window_end, "calc_settling_time");
  const std::size_t lo = (r.lo > 0 && t[r.lo] > w.t_move_end) ? r.lo - 1 : r.lo;

  const Exit exit = last_band_entry(t, y, w.target, band * std::abs(amplitude), lo, r.hi);
  if (!exit.has_exit) return 0.0;
  if (std::isnan(exit.time)) return kNaN;  // still outside the band at the window end: not settled
  return std::max(0.0, exit.time - w.t_move_end);
}

double calc_overshoot(std::span<const double> t, std::span<const double> y, double t_from, const MoveWindow& w) {
  check_signal(t, y, "calc_overshoot");
  const double amplitude = calc_move_amplitude(w, "calc_overshoot");

  // Largest excursion past the target in the direction of the move.
  const Range r = samples_in(t, t_from, w.t_window_end, "calc_overshoot");
  const double dir = amplitude > 0.0 ? 1.0 : -1.0;
  double past = 0.0;
  for (std::size_t k = r.lo; k < r.hi; ++k) past = std::max(past, dir * (y[k] - w.target));
  return 100.0 * past / std::abs(amplitude);
}

double calc_peak_abs(std::span<const double> t, std::span<const double> y, double t_from, double t_to) {
  check_signal(t, y, "calc_peak_abs");
  const Range r = samples_in(t, t_from, t_to, "calc_peak_abs");
  double peak = 0.0;
  for (std::size_t k = r.lo; k < r.hi; ++k) peak = std::max(peak, std::abs(y[k]));
  return peak;
}

double calc_residual_amplitude(std::span<const double> t, std::span<const double> y, double t_from, double t_to) {
  check_signal(t, y, "calc_residual_amplitude");
  const Range r = samples_in(t, t_from, t_to, "calc_residual_amplitude");
  const auto [lo, hi] = std::minmax_element(y.begin() + static_cast<std::ptrdiff_t>(r.lo),
                                            y.begin() + static_cast<std::ptrdiff_t>(r.hi));
  return 0.5 * (*hi - *lo);
}

StepInfo calc_stepinfo(std::span<const double> t, std::span<const double> y, double y_final, double y_init,
                       double settling_threshold, double rise_lo, double rise_hi) {
  check_signal(t, y, "calc_stepinfo");
  const double amp = y_final - y_init;
  if (amp == 0.0 || !std::isfinite(amp))
    throw std::invalid_argument("calc_stepinfo: y_final - y_init must be finite and non-zero");
  if (!(settling_threshold > 0.0 && settling_threshold < 1.0))
    throw std::invalid_argument("calc_stepinfo: settling_threshold must lie in (0, 1)");
  if (!(rise_lo >= 0.0 && rise_lo < rise_hi && rise_hi <= 1.0))
    throw std::invalid_argument("calc_stepinfo: need 0 <= rise_lo < rise_hi <= 1");
  const std::size_t n = t.size();
  StepInfo s{};

  // Rise time: first reaching rise_lo to first reaching rise_hi of the way from y_init to y_final.
  const Reach lo = first_reach(t, y, y_init, amp, rise_lo);
  const Reach hi = first_reach(t, y, y_init, amp, rise_hi);
  s.rise_time = hi.time - lo.time;  // NaN when rise_hi is never reached

  // Settling time: band ST·|y_final − y_init|; transient time: band ST·(peak error).
  double emax = 0.0;
  for (std::size_t k = 0; k < n; ++k) emax = std::max(emax, std::abs(y[k] - y_final));
  const Exit settle = last_band_entry(t, y, y_final, settling_threshold * std::abs(amp), 0, n);
  const Exit transient = last_band_entry(t, y, y_final, settling_threshold * emax, 0, n);
  s.settling_time = settle.has_exit ? settle.time : t[0];
  s.transient_time = transient.has_exit ? transient.time : t[0];

  // Settling min/max: extremes of y once the response has risen (from the first sample >= rise_hi).
  s.settling_min = kNaN;
  s.settling_max = kNaN;
  if (hi.index < n) {
    const auto [mn, mx] = std::minmax_element(y.begin() + static_cast<std::ptrdiff_t>(hi.index), y.end());
    s.settling_min = *mn;
    s.settling_max = *mx;
  }

  // Overshoot / undershoot on the normalised response; peak of |y − y_init| and its time.
  double yn_max = -std::numeric_limits<double>::infinity();
  double yn_min = std::numeric_limits<double>::infinity();
  std::size_t k_peak = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double yn = (y[k] - y_init) / amp;
    yn_max = std::max(yn_max, yn);
    yn_min = std::min(yn_min, yn);
    if (std::abs(y[k] - y_init) > std::abs(y[k_peak] - y_init)) k_peak = k;
  }
  s.overshoot = std::max(0.0, 100.0 * (yn_max - 1.0));
  s.undershoot = std::max(0.0, -100.0 * yn_min);
  s.peak = std::abs(y[k_peak] - y_init);
  s.peak_time = t[k_peak];
  return s;
}

}  // namespace ff
