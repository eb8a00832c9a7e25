// Residual analysis: where and how a model fails to reproduce a measurement. For one channel's
// residual e_k = y_k - yhat_k (k = 0..N-1, at the record's times t_k) and an input u_k:
//   - autocorrelation of e (whiteness) and cross-correlation of e with u (independence of the input),
//     each with its 99 % band (Ljung 1999, "System Identification", sec. 16.6);
//   - the one-sided amplitude spectrum of e and its largest peaks;
//   - e binned against a state (mean per bin), and the step of e across zero hub velocity (Coulomb
//     friction shows itself as e ~ Fc sign(w));
//   - the time windows where e is largest;
// and a FailureReport that puts these in a few findings. Sizes that disagree are programming errors
// (std::invalid_argument); a residual that is not finite is the caller's to skip (compare.cpp does).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace ff {

// Normalised correlation at integer lags (in samples) with a symmetric 99 % band.
struct Correlation {
  std::vector<int> lag;
  std::vector<double> value;      // r(lag), dimensionless, |r| <= 1
  double band = 0.0;              // r is significant outside ±band
  double fraction_outside = 0.0;  // of the lags tested (ACF: 1..L; CCF: -L..L) with |r| > band
  double max_abs = 0.0;           // largest |r| over the lags tested
};

// Autocorrelation for lags 0..L (L clamped to N-1):
//   r_e(tau) = sum_{k=0}^{N-1-tau} (e_k - m)(e_{k+tau} - m) / sum_k (e_k - m)^2,  m = mean(e).
// 99 % band for a white residual: ±2.58 / sqrt(N). A zero residual gives r = 0 at every lag.
Correlation calc_autocorrelation(const std::vector<double>& e, int max_lag);

// Cross-correlation of e with u for lags -L..L (e lags u by tau):
//   r_eu(tau) = sum_k (e_{k+tau} - m_e)(u_k - m_u) / sqrt(sum (e - m_e)^2 sum (u - m_u)^2).
// 99 % band: ±2.58 sqrt(P / N) with P = sum_{|k|<=L} r_e(k) r_u(k) (Ljung eq. 16.65: the variance of
// sqrt(N) r_eu when e and u are independent); P is not taken below 1, the white-residual value.
Correlation calc_cross_correlation(const std::vector<double>& e, const std::vector<double>& u, int max_lag);

// Effective sample size of a residual: n / (1 + 2 sum_{k=1}^{K} r_e(k)), summed over lags 1..max_lag
// while r_e stays positive (Geyer's initial positive sequence, Geyer 1992, "Practical Markov chain
// Monte Carlo"), within [1, n]: n for a white residual, about n / 10 for an AR(1) with rho = 0.82.
double calc_effective_samples(const std::vector<double>& e, int max_lag = 100);

// The root mean square of x: sqrt(mean(x^2)); 0 when x is empty.
double calc_rms(const std::vector<double>& x);

// The (population) standard deviation of x: sqrt(mean((x - mean x)^2)); 0 when x is empty.
double calc_standard_deviation(const std::vector<double>& x);

// The standard deviation of the white noise on a smooth signal y, the least of three estimates, each
// the median over windows of 64 samples (so a ring in a minority of the record is signal): from its
// second and fourth differences, var(d2 y) = 6 sigma^2 and var(d4 y) = 70 sigma^2 for white noise (the
// signal's share falling as h^4 and h^8 with the sample spacing h); and from its spectrum, the median
// of each window's Hann periodogram over the upper three quarters of its band, over ln 2 (a ring or
// a rattle in every window fills a few bins, not the median). 0 for fewer than 8 samples.
double calc_noise_floor(const std::vector<double>& y);

// One-sided amplitude spectrum. e(t) is resampled linearly onto M equally spaced times over
// [t_0, t_{N-1}] (M = the power of two >= N, spacing dt = (t_{N-1} - t_0)/(M-1)), detrended (its
// least-squares line removed), Hann-windowed (w_j = 0.5 - 0.5 cos(2 pi j / M)) and transformed with
// cv::dft. A_0 = |X_0| / sum(w), A_k = 2 |X_k| / sum(w) for 0 < k <= M/2, at f_k = k / (M dt):
// a sinusoid a sin(2 pi f t) on a bin shows A = a there (coherent gain of the window divided out).
struct Spectrum {
  std::vector<double> frequency;  // Hz
  std::vector<double> amplitude;  // unit of e
  double resolution = 0.0;        // Hz, 1 / (M dt)
};
Spectrum calc_amplitude_spectrum(const std::vector<double>& t, const std::vector<double>& e);

struct SpectrumPeak {
  double frequency = 0.0;  // Hz, of the bin
  double amplitude = 0.0;  // unit of e
};
// The `count` largest local maxima (A_k > A_{k-1}, A_k >= A_{k+1}) above DC, largest first.
std::vector<SpectrumPeak> find_spectrum_peaks(const Spectrum& s, int count = 3);

// e binned against a state x: `bins` equal-width bins over [p1, p99] of x (the 1st and 99th
// percentiles, so that a few outliers do not stretch the bins); samples outside are left out.
// departure = sqrt(sum_i n_i mean_i^2 / sum_i n_i) / rms(e): 0 when e does not depend on x, 1 when
// e is a function of x alone (a correlation ratio about zero, 0..1).
struct BinnedResidual {
  std::string state;               // e.g. "hub_velocity"
  std::vector<double> centre;      // state unit
  std::vector<double> mean;        // unit of e; NaN in an empty bin
  std::vector<int> count;
  double lo = 0.0, hi = 0.0;       // the binned range, state unit
  double departure = 0.0;
};
BinnedResidual calc_binned_residual(const std::vector<double>& e, const std::vector<double>& x, int bins = 15,
                                    const std::string& state = "");

// The step of e across zero velocity w:
//   step = mean(e | d < w <= h) - mean(e | -h <= w < -d),  relative = step / rms(e),
// with h the width of one bin of calc_binned_residual(e, w, bins) and d = h / 20 (samples at rest,
// whose sign the noise decides, are left out). A missing Coulomb torque Fc in a torque channel gives
// step ~ 2 Fc. `ok` is false with fewer than 5 samples on either side.
struct ZeroStep {
  double step = 0.0;       // unit of e
  double relative = 0.0;   // step / rms(e)
  int below = 0, above = 0;
  bool ok = false;
};
ZeroStep calc_zero_step(const std::vector<double>& e, const std::vector<double>& w, int bins = 15);

// Consecutive windows [t_0 + i width, t_0 + (i+1) width) and the residual's RMS in each.
struct ResidualWindow {
  double t0 = 0.0, t1 = 0.0;  // s
  double rms = 0.0;           // unit of e
  int count = 0;
};
// The `count` windows with the largest RMS, largest first (windows without samples are skipped).
std::vector<ResidualWindow> find_worst_windows(const std::vector<double>& t, const std::vector<double>& e,
                                               double width = 1.0, int count = 3);

struct ResidualOptions {
  int max_lag = 50;              // L, samples
  int bins = 15;                 // state binning
  double window = 1.0;           // s; shorter records use a tenth of their length
  int windows = 3;               // worst windows reported
  int peaks = 3;                 // spectrum peaks reported
  double white_fraction = 0.05;  // white when at most this fraction of ACF lags 1..L is outside the band
  double friction_step = 0.25;   // a relative step at zero velocity at least this large is "friction-like"
  double state_departure = 0.3;  // a state is named when its departure is at least this
};

// Where the model fails, in a few numbers.
struct FailureReport {
  double rms = 0.0;                            // of the whole residual, unit of e
  std::vector<ResidualWindow> worst_windows;   // largest RMS first
  std::vector<SpectrumPeak> peaks;             // largest first
  std::vector<std::pair<std::string, double>> states;  // (state, departure), largest first
  ZeroStep velocity_step;                      // across zero hub velocity (ok = false: no velocity state)
  bool friction_like = false;                  // |velocity_step.relative| >= friction_step
  double acf_outside = 0.0;                    // fraction of ACF lags 1..L outside the band
  bool white = false;                          // acf_outside <= white_fraction
  double ccf_outside = 0.0;                    // fraction of CCF lags outside the band
  bool uncorrelated = false;                   // ccf_outside <= white_fraction
};

// Everything above for one residual. `states` are (name, values at the record's times); the one
// named "hub_velocity" (rad/s) also gives the step at zero.
struct ResidualAnalysis {
  bool valid = false;                  // false: the residual was not finite; nothing else is set
  Correlation acf, ccf;
  Spectrum spectrum;
  std::vector<BinnedResidual> binned;  // one per state, in the order given
  FailureReport failure;
};
ResidualAnalysis analyse_residual(const std::vector<double>& t, const std::vector<double>& e,
                                  const std::vector<double>& u,
                                  const std::vector<std::pair<std::string, std::vector<double>>>& states,
                                  const ResidualOptions& options = {});

// The findings in words, one sentence each, e.g. "the model fails most in t = 3.0-4.0 s (RMS 2.1x
// the whole record's)", "the residual peaks at 2.30 Hz", "the residual steps by 40 % of its RMS across
// zero hub velocity: a friction-like effect is missing".
std::vector<std::string> describe_failure(const FailureReport& f, const ResidualOptions& options = {});

}  // namespace ff
