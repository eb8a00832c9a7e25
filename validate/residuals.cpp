#include "validate/residuals.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <opencv2/core.hpp>
#include <stdexcept>

namespace ff {

namespace {

constexpr double kZ99 = 2.58;  // two-sided 99 % point of the normal distribution

double mean_of(const std::vector<double>& x) {
  return x.empty() ? 0.0 : std::accumulate(x.begin(), x.end(), 0.0) / x.size();
}

double rms_of(const std::vector<double>& x) {
  double s = 0.0;
  for (double v : x) s += v * v;
  return x.empty() ? 0.0 : std::sqrt(s / x.size());
}

void check_sizes(const char* what, std::size_t a, std::size_t b) {
  if (a != b)
    throw std::invalid_argument(std::string(what) + ": sizes differ (" + std::to_string(a) + " and " +
                                std::to_string(b) + ")");
}

// Unnormalised lagged products sum_k a_{k+tau} b_k of the centred series, tau in [-L, L].
std::vector<double> lagged_sums(const std::vector<double>& a, const std::vector<double>& b, int L) {
  const long n = static_cast<long>(a.size());
  std::vector<double> out(2 * L + 1, 0.0);
  for (int tau = -L; tau <= L; ++tau) {
    double s = 0.0;
    for (long k = std::max(0L, -static_cast<long>(tau)); k < n && k + tau < n; ++k) s += a[k + tau] * b[k];
    out[tau + L] = s;
  }
  return out;
}

std::vector<double> centred(const std::vector<double>& x) {
  const double m = mean_of(x);
  std::vector<double> c(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) c[k] = x[k] - m;
  return c;
}

// Linear-interpolated percentile p (0..100) of the values.
double percentile(std::vector<double> x, double p) {
  std::sort(x.begin(), x.end());
  const double pos = p / 100.0 * (x.size() - 1);
  const std::size_t i = static_cast<std::size_t>(std::floor(pos));
  const std::size_t j = std::min(i + 1, x.size() - 1);
  return x[i] + (pos - i) * (x[j] - x[i]);
}

void finish(Correlation& c, int first_tested) {
  int tested = 0, outside = 0;
  for (std::size_t i = 0; i < c.lag.size(); ++i) {
    if (c.lag[i] < first_tested) continue;
    ++tested;
    const double a = std::abs(c.value[i]);
    c.max_abs = std::max(c.max_abs, a);
    if (a > c.band) ++outside;
  }
  c.fraction_outside = tested > 0 ? static_cast<double>(outside) / tested : 0.0;
}

}  // namespace

Correlation calc_autocorrelation(const std::vector<double>& e, int max_lag) {
  const int n = static_cast<int>(e.size());
  const int L = std::clamp(max_lag, 0, std::max(0, n - 1));
  const auto c = centred(e);
  const auto s = lagged_sums(c, c, L);
  const double s0 = s[L];
  Correlation r;
  r.band = n > 0 ? kZ99 / std::sqrt(static_cast<double>(n)) : 0.0;
  for (int tau = 0; tau <= L; ++tau) {
    r.lag.push_back(tau);
    r.value.push_back(s0 > 0 ? s[tau + L] / s0 : 0.0);
  }
  finish(r, 1);
  return r;
}

Correlation calc_cross_correlation(const std::vector<double>& e, const std::vector<double>& u, int max_lag) {
  check_sizes("calc_cross_correlation", e.size(), u.size());
  const int n = static_cast<int>(e.size());
  const int L = std::clamp(max_lag, 0, std::max(0, n - 1));
  const auto ce = centred(e), cu = centred(u);
  const auto seu = lagged_sums(ce, cu, L), see = lagged_sums(ce, ce, L), suu = lagged_sums(cu, cu, L);
  const double ee = see[L], uu = suu[L];
  const double norm = std::sqrt(ee * uu);
  Correlation r;
  double P = 0.0;
  for (int i = 0; i <= 2 * L; ++i) P += ee > 0 && uu > 0 ? see[i] / ee * suu[i] / uu : 0.0;
  r.band = n > 0 ? kZ99 * std::sqrt(std::max(P, 1.0) / n) : 0.0;
  for (int tau = -L; tau <= L; ++tau) {
    r.lag.push_back(tau);
    r.value.push_back(norm > 0 ? seu[tau + L] / norm : 0.0);
  }
  finish(r, -L);
  return r;
}

double calc_effective_samples(const std::vector<double>& e, int max_lag) {
  const double n = static_cast<double>(e.size());
  if (e.size() < 4) return std::max(1.0, n);
  const Correlation r = calc_autocorrelation(e, max_lag);
  double tau = 1.0;
  for (std::size_t i = 1; i < r.value.size() && r.value[i] > 0.0; ++i) tau += 2.0 * r.value[i];
  return std::clamp(n / tau, 1.0, n);
}

double calc_rms(const std::vector<double>& x) {
  double s = 0.0;
  for (double v : x) s += v * v;
  return x.empty() ? 0.0 : std::sqrt(s / x.size());
}

double calc_standard_deviation(const std::vector<double>& x) {
  const double m = mean_of(x);
  double s = 0.0;
  for (double v : x) s += (v - m) * (v - m);
  return x.empty() ? 0.0 : std::sqrt(s / x.size());
}

namespace {

// The spectral floor of one window of m samples (m a power of two): its Hann periodogram |X_k|^2 /
// sum(w^2) from calc_amplitude_spectrum (line removed, Hann-weighted; A_k = 2 |X_k| / sum(w), and for
// the Hann window sum(w) = m / 2, sum(w^2) = 3 m / 8, so |X_k|^2 / sum(w^2) = A_k^2 m / 6) at the bins
// k = m/8 .. m/2 - 1 (an eighth of the sample rate up to just below Nyquist). White noise of variance
// s^2 makes each bin exponential with mean s^2, so the median over the bins is ln 2 s^2. A ring or a
// rattle fills a few bins and leaves the median.
double window_spectral_floor(const double* y, std::size_t m) {
  std::vector<double> t(m);
  for (std::size_t j = 0; j < m; ++j) t[j] = static_cast<double>(j);
  const Spectrum s = calc_amplitude_spectrum(t, std::vector<double>(y, y + m));
  std::vector<double> p;
  for (std::size_t k = m / 8; k < m / 2; ++k) p.push_back(s.amplitude[k] * s.amplitude[k] * static_cast<double>(m) / 6.0);
  std::nth_element(p.begin(), p.begin() + p.size() / 2, p.end());
  return p[p.size() / 2] / std::log(2.0);
}

}  // namespace

double calc_noise_floor(const std::vector<double>& y) {
  const std::size_t n = y.size();
  if (n < 8) return 0.0;
  // Window by window, then the median over windows: a ring or a rattle that fills a minority of the
  // record (a move's end, a drive's free play crossed) is signal, not noise.
  const std::size_t w = std::max<std::size_t>(16, std::min<std::size_t>(64, (n - 4) / 8));
  std::vector<double> v2, v4, vs;
  double s2 = 0.0, s4 = 0.0;
  std::size_t m = 0;
  for (std::size_t k = 2; k + 2 < n; ++k) {
    const double d2 = y[k + 1] - 2.0 * y[k] + y[k - 1];
    const double d4 = y[k + 2] - 4.0 * y[k + 1] + 6.0 * y[k] - 4.0 * y[k - 1] + y[k - 2];
    s2 += d2 * d2;
    s4 += d4 * d4;
    if (++m == w) {
      v2.push_back(s2 / (6.0 * m));
      v4.push_back(s4 / (70.0 * m));
      s2 = s4 = 0.0;
      m = 0;
    }
  }
  if (v2.empty()) {  // fewer differences than one window: the whole record is the window
    v2.push_back(s2 / (6.0 * m));
    v4.push_back(s4 / (70.0 * m));
  }
  // And the spectral floor, windows of 64 samples: a ring or a rattle in every window, whose samples
  // look like noise to the differences (a drive rattling at a quarter of the sample rate), stays out.
  for (std::size_t k0 = 0; k0 + 64 <= n; k0 += 64) vs.push_back(window_spectral_floor(y.data() + k0, 64));
  auto median = [](std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  double v = std::min(median(v2), median(v4));
  if (vs.size() >= 4) v = std::min(v, median(vs));
  return std::sqrt(v);
}

Spectrum calc_amplitude_spectrum(const std::vector<double>& t, const std::vector<double>& e) {
  check_sizes("calc_amplitude_spectrum", t.size(), e.size());
  Spectrum s;
  if (e.size() < 4 || !(t.back() > t.front())) return s;
  int M = 1;
  while (static_cast<std::size_t>(M) < e.size()) M *= 2;
  const double dt = (t.back() - t.front()) / (M - 1);
  // Resample (linear), then remove the least-squares line a + b j.
  std::vector<double> x(M);
  std::size_t k = 0;
  for (int j = 0; j < M; ++j) {
    const double tj = t.front() + j * dt;
    while (k + 2 < t.size() && t[k + 1] <= tj) ++k;
    const double u = std::clamp((tj - t[k]) / (t[k + 1] - t[k]), 0.0, 1.0);
    x[j] = e[k] + u * (e[k + 1] - e[k]);
  }
  const double jm = (M - 1) / 2.0;
  double sxy = 0.0, sxx = 0.0;
  const double xm = mean_of(x);
  for (int j = 0; j < M; ++j) sxy += (j - jm) * (x[j] - xm), sxx += (j - jm) * (j - jm);
  const double slope = sxy / sxx;
  cv::Mat in(1, M, CV_64F), out;
  double wsum = 0.0;
  for (int j = 0; j < M; ++j) {
    const double w = 0.5 - 0.5 * std::cos(2.0 * M_PI * j / M);
    wsum += w;
    in.at<double>(0, j) = w * (x[j] - xm - slope * (j - jm));
  }
  cv::dft(in, out, cv::DFT_COMPLEX_OUTPUT);
  s.resolution = 1.0 / (M * dt);
  for (int i = 0; i <= M / 2; ++i) {
    const cv::Vec2d X = out.at<cv::Vec2d>(0, i);
    s.frequency.push_back(i * s.resolution);
    s.amplitude.push_back((i == 0 ? 1.0 : 2.0) * std::hypot(X[0], X[1]) / wsum);
  }
  return s;
}

std::vector<SpectrumPeak> find_spectrum_peaks(const Spectrum& s, int count) {
  std::vector<SpectrumPeak> peaks;
  const auto& A = s.amplitude;
  for (std::size_t i = 1; i + 1 < A.size(); ++i)
    if (A[i] > A[i - 1] && A[i] >= A[i + 1] && A[i] > 0) peaks.push_back({s.frequency[i], A[i]});
  std::sort(peaks.begin(), peaks.end(), [](const auto& a, const auto& b) { return a.amplitude > b.amplitude; });
  if (static_cast<int>(peaks.size()) > count) peaks.resize(std::max(0, count));
  return peaks;
}

BinnedResidual calc_binned_residual(const std::vector<double>& e, const std::vector<double>& x, int bins,
                                    const std::string& state) {
  check_sizes("calc_binned_residual", e.size(), x.size());
  if (bins < 1) throw std::invalid_argument("calc_binned_residual: bins must be >= 1");
  BinnedResidual b;
  b.state = state;
  if (e.empty()) return b;
  b.lo = percentile(x, 1.0);
  b.hi = percentile(x, 99.0);
  if (!(b.hi > b.lo)) b.lo -= 0.5, b.hi += 0.5;  // a constant state: one range around it
  const double width = (b.hi - b.lo) / bins;
  std::vector<double> sum(bins, 0.0);
  b.count.assign(bins, 0);
  for (std::size_t k = 0; k < e.size(); ++k) {
    if (x[k] < b.lo || x[k] > b.hi) continue;
    const int i = std::min(bins - 1, static_cast<int>((x[k] - b.lo) / width));
    sum[i] += e[k];
    ++b.count[i];
  }
  double between = 0.0;
  int n = 0;
  for (int i = 0; i < bins; ++i) {
    b.centre.push_back(b.lo + (i + 0.5) * width);
    b.mean.push_back(b.count[i] > 0 ? sum[i] / b.count[i] : NAN);
    if (b.count[i] > 0) between += b.count[i] * b.mean[i] * b.mean[i], n += b.count[i];
  }
  const double rms = rms_of(e);
  b.departure = n > 0 && rms > 0 ? std::sqrt(between / n) / rms : 0.0;
  return b;
}

ZeroStep calc_zero_step(const std::vector<double>& e, const std::vector<double>& w, int bins) {
  check_sizes("calc_zero_step", e.size(), w.size());
  ZeroStep z;
  if (e.empty() || bins < 1) return z;
  double lo = percentile(w, 1.0), hi = percentile(w, 99.0);
  if (!(hi > lo)) return z;
  const double h = (hi - lo) / bins, d = h / 20.0;
  double above = 0.0, below = 0.0;
  for (std::size_t k = 0; k < e.size(); ++k) {
    if (w[k] > d && w[k] <= h) above += e[k], ++z.above;
    if (w[k] < -d && w[k] >= -h) below += e[k], ++z.below;
  }
  if (z.above < 5 || z.below < 5) return z;
  z.ok = true;
  z.step = above / z.above - below / z.below;
  const double rms = rms_of(e);
  z.relative = rms > 0 ? z.step / rms : 0.0;
  return z;
}

std::vector<ResidualWindow> find_worst_windows(const std::vector<double>& t, const std::vector<double>& e,
                                               double width, int count) {
  check_sizes("find_worst_windows", t.size(), e.size());
  if (!(width > 0)) throw std::invalid_argument("find_worst_windows: width must be > 0");
  std::vector<ResidualWindow> all;
  if (t.empty()) return all;
  const int n = static_cast<int>(std::floor((t.back() - t.front()) / width)) + 1;
  all.resize(n);
  std::vector<double> sq(n, 0.0);
  for (std::size_t k = 0; k < t.size(); ++k) {
    const int i = std::min(n - 1, static_cast<int>((t[k] - t.front()) / width));
    sq[i] += e[k] * e[k];
    ++all[i].count;
  }
  for (int i = 0; i < n; ++i) {
    all[i].t0 = t.front() + i * width;
    all[i].t1 = all[i].t0 + width;
    all[i].rms = all[i].count > 0 ? std::sqrt(sq[i] / all[i].count) : 0.0;
  }
  std::erase_if(all, [](const ResidualWindow& w) { return w.count == 0; });
  std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.rms > b.rms; });
  if (static_cast<int>(all.size()) > count) all.resize(std::max(0, count));
  return all;
}

ResidualAnalysis analyse_residual(const std::vector<double>& t, const std::vector<double>& e,
                                  const std::vector<double>& u,
                                  const std::vector<std::pair<std::string, std::vector<double>>>& states,
                                  const ResidualOptions& o) {
  check_sizes("analyse_residual", t.size(), e.size());
  check_sizes("analyse_residual", u.size(), e.size());
  ResidualAnalysis a;
  for (double x : e)
    if (!std::isfinite(x)) return a;
  a.valid = true;
  a.acf = calc_autocorrelation(e, o.max_lag);
  a.ccf = calc_cross_correlation(e, u, o.max_lag);
  a.spectrum = calc_amplitude_spectrum(t, e);
  FailureReport& f = a.failure;
  f.rms = rms_of(e);
  const double span = t.empty() ? 0.0 : t.back() - t.front();
  const double width = span >= 4.0 * o.window ? o.window : std::max(span / 10.0, 1e-9);
  f.worst_windows = find_worst_windows(t, e, width, o.windows);
  f.peaks = find_spectrum_peaks(a.spectrum, o.peaks);
  for (const auto& [name, x] : states) {
    check_sizes(("analyse_residual: state " + name).c_str(), x.size(), e.size());
    a.binned.push_back(calc_binned_residual(e, x, o.bins, name));
    f.states.emplace_back(name, a.binned.back().departure);
    if (name == "hub_velocity") f.velocity_step = calc_zero_step(e, x, o.bins);
  }
  std::stable_sort(f.states.begin(), f.states.end(), [](const auto& p, const auto& q) { return p.second > q.second; });
  f.friction_like = f.velocity_step.ok && std::abs(f.velocity_step.relative) >= o.friction_step;
  f.acf_outside = a.acf.fraction_outside;
  f.white = f.acf_outside <= o.white_fraction;
  f.ccf_outside = a.ccf.fraction_outside;
  f.uncorrelated = f.ccf_outside <= o.white_fraction;
  return a;
}

std::vector<std::string> describe_failure(const FailureReport& f, const ResidualOptions& o) {
  std::vector<std::string> out;
  if (!(f.rms > 0)) return {"the residual is zero: the model reproduces the record exactly"};
  char buf[256];
  if (!f.worst_windows.empty()) {
    const auto& w = f.worst_windows.front();
    std::snprintf(buf, sizeof buf, "the model fails most in t = %.1f-%.1f s (residual RMS %.3g, %.1fx that of the whole record)",
                  w.t0, w.t1, w.rms, w.rms / f.rms);
    out.emplace_back(buf);
  }
  if (!f.peaks.empty()) {
    std::string s = "the residual peaks at ";
    for (std::size_t i = 0; i < f.peaks.size(); ++i) {
      std::snprintf(buf, sizeof buf, "%s%.2f Hz (amplitude %.3g)", i == 0 ? "" : (i + 1 == f.peaks.size() ? " and " : ", "),
                    f.peaks[i].frequency, f.peaks[i].amplitude);
      s += buf;
    }
    out.push_back(s);
  }
  if (f.velocity_step.ok) {
    std::snprintf(buf, sizeof buf, "the residual steps by %.0f %% of its RMS across zero hub velocity",
                  100.0 * std::abs(f.velocity_step.relative));
    out.push_back(std::string(buf) + (f.friction_like ? ": a friction-like effect is missing" : ""));
  }
  std::string named;
  for (const auto& [state, d] : f.states)
    if (d >= o.state_departure) {
      std::snprintf(buf, sizeof buf, "%s%s (%.2f)", named.empty() ? "" : ", ", state.c_str(), d);
      named += buf;
    }
  if (!named.empty()) out.push_back("the mean residual depends on " + named + " (departure = binned mean RMS / residual RMS)");
  std::snprintf(buf, sizeof buf, "the residual is %s (%.0f %% of autocorrelation lags outside the 99 %% band)",
                f.white ? "white" : "not white", 100.0 * f.acf_outside);
  out.emplace_back(buf);
  std::snprintf(buf, sizeof buf, "it is %s with the input (%.0f %% of cross-correlation lags outside the 99 %% band)",
                f.uncorrelated ? "uncorrelated" : "correlated", 100.0 * f.ccf_outside);
  out.emplace_back(buf);
  return out;
}

}  // namespace ff
