#include "validate/diagnose.hpp"

#include <ceres/ceres.h>
#include <glog/logging.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>

#include "kernel/batch.hpp"
#include "common/errors.hpp"
#include "common/random.hpp"
#include "common/yaml_reader.hpp"
#include "sweep/design.hpp"
#include "validate/residuals.hpp"

namespace ff {

namespace {

Assignment assign(const std::string& path, const YAML::Node& value) {
  Assignment a;
  a.path = path;
  a.value = value;
  a.source = "diagnose";
  a.key = path;
  a.plant_only = true;  // a candidate effect is the plant's: the controller keeps its model
  return a;
}

// A path's value node: whole numbers stay integers (delays, segment counts).
YAML::Node number_node(const std::string& path, double x) {
  if (path == "segments" || path.find(".delay") != std::string::npos) return YAML::Node(static_cast<int>(std::lround(x)));
  return YAML::Node(x);
}

// A singular value of the Jacobian below this fraction of the largest is a null direction.
constexpr double kIdentifiableSv = 1e-6;

// A trial model needing more fixed steps per control period than this is refused (too stiff).
constexpr int kMaxFitSubsteps = 64;

// Residual tests: lags of the autocorrelation and cross-correlation; a channel is white (uncorrelated)
// when at most this fraction of them is outside the 99 % band.
constexpr int kTestLags = 25;
constexpr double kTestFraction = 0.05;
// The effective sample size sums the residual's autocorrelation over at most this many lags.
constexpr int kEffectiveLags = 100;

double sum_squares(const std::vector<double>& r) {
  double s = 0.0;
  for (double x : r) s += x * x;
  return s;
}

// The hub torque's band power, the scored channel `hub_torque.power` (closed loop): what a drive rattling
// in its free play, or a loop chattering on its encoder, does on average. No replay follows such a limit
// cycle's phase (the record's noise sets it off at other instants), so its samples leave every model, the
// true one included, far from the record; the power of the torque's first differences, window by window,
// does not depend on the phase. Window w of W record samples: P_w(y) = mean (y_k - y_{k-1})^2; the
// record's white noise of variance s^2 adds 2 s^2 (the variance of its differences) to it, the model's
// noise-free prediction does not. Scored: ln(P_w(y) + c) against ln(P_w(yhat) + 2 s^2 + c), c = 2 s_f^2
// from the channel's noise floor s_f (at least kRelevantError of its sd: a noise-free record's windows of
// constant torque stay finite). White noise alone gives var(P_w) = (2 / W) sum_j gamma_j^2 = 12 s^4 / W
// (gamma the autocovariance of the differenced noise: 2 s^2, -s^2), so with s = s_f the residual
// sqrt(W / 0.75) (ln(P_w(y) + c) - ln(P_w(yhat) + 2 s^2 + c)) has unit variance where the model explains
// the torque's power.
constexpr const char* kPowerChannel = "hub_torque.power";
constexpr double kPowerWindow = 0.032;  // s (at least 16 record samples)

// A torque whose band power the base model misses by this factor of the power's noise (RMS of the
// normalised residual) has a high band no replay follows: its samples are then scored low-passed.
constexpr double kPowerMisfit = 3.0;

// Three passes of a centred moving average of `window` samples (shorter at the ends): a low-pass whose
// gain is 0.707 at 0.264 / window of the sample rate and below 1 % (the sidelobes cubed) above 2 / window.
std::vector<double> calc_low_pass(std::vector<double> y, std::size_t window) {
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(y.size()), h = static_cast<std::ptrdiff_t>(window / 2);
  std::vector<double> sum(y.size() + 1);
  for (int pass = 0; pass < 3; ++pass) {
    sum[0] = 0.0;
    for (std::ptrdiff_t k = 0; k < n; ++k) sum[k + 1] = sum[k] + y[k];
    for (std::ptrdiff_t k = 0; k < n; ++k) {
      const std::ptrdiff_t lo = std::max<std::ptrdiff_t>(0, k - h), hi = std::min(n, k + h + 1);
      y[k] = (sum[hi] - sum[lo]) / static_cast<double>(hi - lo);
    }
  }
  return y;
}

std::vector<double> calc_log_band_power(const std::vector<double>& y, std::size_t window, double offset) {
  std::vector<double> out;
  for (std::size_t k0 = 1; k0 + window <= y.size(); k0 += window) {
    double s2 = 0.0;
    for (std::size_t k = k0; k < k0 + window; ++k) s2 += (y[k] - y[k - 1]) * (y[k] - y[k - 1]);
    out.push_back(std::log(s2 / window + offset));
  }
  return out;
}

// The record's scored channels, decimated and weighted by their noise: residual = (y - yhat) / sigma_c,
// sigma_c the channel's noise floor, channel-major (channel c's samples at [c n_idx, (c + 1) n_idx)).
// Weighted least squares with each channel's own noise is the maximum-likelihood fit of channels whose
// noise differs (a torque that rattles in a drive's free play against a tip sensor at 3 %): one
// channel's misfit counts by its signal-to-noise ratio, not by its share of the record's variance.
struct Scorer {
  const FitFamily* family = nullptr;
  const Record* rec = nullptr;
  std::vector<std::string> channels;
  std::vector<std::size_t> index;  // decimated sample indices
  std::vector<double> scale;       // 1 / sigma_c per channel: the residual's weight
  std::vector<double> noise;       // the record's noise floor per channel, as a fraction of sd(y) (reports)
  std::vector<double> sigma;       // the record's noise floor per channel, in its unit (not clamped)
  std::vector<std::vector<double>> input;  // per channel the loop's external input at the decimated samples (CCF)
  std::vector<std::pair<std::string, std::vector<double>>> states;  // at the decimated samples (misfit binning)
  struct BandPower {               // kPowerChannel, scored after the samples (closed loop, with a torque)
    bool on = false;
    std::size_t window = 0;        // record samples per window
    double offset = 0.0;           // c = 2 s_f^2, N^2 m^2
    double noise_power = 0.0;      // 2 s^2 (the record's own noise, unclamped)
    double scale = 0.0;            // sqrt(W / 0.75): 1 / the noise's sd of ln(P_w + c)
    std::vector<double> measured;  // ln(P_w(y) + c) of the record
    std::vector<double> input;     // the input at each window's start (for the CCF)
  } power;
  // The torque's samples low-passed (the record's and each prediction's, calc_low_pass over the band
  // power's window) when the record's torque has high-band power the base model lacks (kPowerMisfit):
  // its high band is then scored by its power alone.
  bool split = false;
  std::size_t low_pass = 0;        // samples of calc_low_pass: kPowerWindow, at least 3
  std::vector<double> torque_low;  // the record's torque, low-passed (when split)

  // The record's and the prediction's samples of channel c as scored.
  std::vector<double> predicted(const Prediction& p, std::size_t c) const {
    const auto& yh = p.channels.at(channels[c]);
    return split && channels[c] == "hub_torque" ? calc_low_pass(yh, low_pass) : yh;
  }
  const std::vector<double>& measured(std::size_t c) const {
    return split && channels[c] == "hub_torque" ? torque_low : rec->at(channels[c]);
  }
  double cutoff_hz() const {
    return split ? 0.264 / (low_pass * (rec->t[1] - rec->t[0])) : NAN;
  }

  std::size_t samples() const { return channels.size() * index.size(); }
  int size() const { return static_cast<int>(samples() + (power.on ? power.measured.size() : 0)); }

  // The effects selected so far (forward selection): every model is the source with these, then its own set.
  std::vector<Assignment> prefix;

  // What each model (the source with the prefix and an assignment set) predicts for the record.
  std::vector<Prediction> predict(const std::vector<std::vector<Assignment>>& sets) const {
    if (prefix.empty()) return family->predict(sets);
    std::vector<std::vector<Assignment>> full(sets.size(), prefix);
    for (std::size_t i = 0; i < sets.size(); ++i) full[i].insert(full[i].end(), sets[i].begin(), sets[i].end());
    return family->predict(full);
  }

  // Residuals of each model (empty vector for one that failed to build or run).
  std::vector<std::vector<double>> residuals(const std::vector<std::vector<Assignment>>& sets) const {
    const std::vector<Prediction> p = predict(sets);
    std::vector<std::vector<double>> out(sets.size());
    for (std::size_t i = 0; i < sets.size(); ++i) {
      if (!p[i].ok) continue;
      auto& r = out[i];
      for (std::size_t c = 0; c < channels.size(); ++c) {
        const auto& y = measured(c);
        const auto yh = predicted(p[i], c);
        for (std::size_t k : index) r.push_back((y[k] - yh[k]) * scale[c]);
      }
      if (power.on) {
        const auto lp = calc_log_band_power(p[i].channels.at("hub_torque"), power.window, power.noise_power + power.offset);
        for (std::size_t w = 0; w < power.measured.size(); ++w) r.push_back((power.measured[w] - lp[w]) * power.scale);
      }
      for (double x : r)
        if (!std::isfinite(x)) {
          r.clear();
          break;
        }
    }
    return out;
  }

  // The residual of a model's prediction against a record simulated by the same model with other noise
  // (`sim`), each channel given the record's own measurement noise (stream `key`): what the record's
  // residual would be if that model were the truth (the bootstrap).
  std::vector<double> simulated_residual(const Prediction& model, const Prediction& sim, std::uint64_t key) const {
    CounterRng rng(key);
    std::vector<double> r;
    std::vector<double> torque;
    for (std::size_t c = 0; c < channels.size(); ++c) {
      std::vector<double> y = sim.channels.at(channels[c]);
      for (double& x : y) x += sigma[c] * rng.normal();
      if (channels[c] == "hub_torque") torque = y;
      if (split && channels[c] == "hub_torque") y = calc_low_pass(y, low_pass);
      const auto yh = predicted(model, c);
      for (std::size_t k : index) r.push_back((y[k] - yh[k]) * scale[c]);
    }
    if (power.on) {
      const auto measured = calc_log_band_power(torque, power.window, power.offset);
      const auto lp = calc_log_band_power(model.channels.at("hub_torque"), power.window, power.noise_power + power.offset);
      for (std::size_t w = 0; w < measured.size(); ++w) r.push_back((measured[w] - lp[w]) * power.scale);
    }
    return r;
  }

  // Channel c's residual (c = channels.size(): the band power's).
  std::vector<double> channel_of(const std::vector<double>& r, std::size_t c) const {
    const std::size_t n = index.size();
    if (c == channels.size()) return std::vector<double>(r.begin() + samples(), r.end());
    return std::vector<double>(r.begin() + c * n, r.begin() + (c + 1) * n);
  }

  // Residual tests per channel and the effective sample size of a residual.
  std::map<std::string, ChannelTest> tests(const std::vector<double>& r, double* n_eff) const {
    std::map<std::string, ChannelTest> out;
    double ne = 0.0;
    for (std::size_t c = 0; c < channels.size() + power.on; ++c) {
      const bool band = c == channels.size();
      const auto e = channel_of(r, c);
      ChannelTest t;
      t.noise = band ? 1.0 / power.scale : noise[c];               // as a fraction of sd(y); ln P_w's own sd
      t.rms = std::sqrt(sum_squares(e) / e.size()) * t.noise;
      const Correlation acf = calc_autocorrelation(e, kTestLags);
      const Correlation ccf = calc_cross_correlation(e, band ? power.input : input[c], kTestLags);
      t.acf_outside = acf.fraction_outside;
      t.ccf_outside = ccf.fraction_outside;
      t.white = t.acf_outside <= kTestFraction;
      t.uncorrelated = t.ccf_outside <= kTestFraction;
      t.at_floor = t.rms * t.rms <= kFloorFactor * t.noise * t.noise;
      t.rss = sum_squares(e);
      t.n_eff = calc_effective_samples(e, kEffectiveLags);
      double mean = 0.0;
      for (double x : e) mean += x / e.size();
      t.mean = mean;
      t.unbiased = std::abs(mean) <= 2.58 * std::sqrt(std::max(t.rss / e.size() - mean * mean, 0.0) / std::max(t.n_eff, 1.0));
      out[band ? kPowerChannel : channels[c]] = t;
      ne += t.n_eff;
    }
    if (n_eff) *n_eff = ne;
    return out;
  }

  // The residual sum of squares of noise alone (each channel's weighted noise has unit variance).
  double floor_rss() const { return static_cast<double>(size()); }

  std::map<std::string, double> fit_percent(const std::vector<Assignment>& set) const {
    std::map<std::string, double> out;
    const auto p = predict({set})[0];
    for (std::size_t c = 0; c < channels.size(); ++c)
      out[channels[c]] = p.ok ? calc_fit(measured(c), predicted(p, c)).percent : -INFINITY;
    if (power.on)
      out[kPowerChannel] = p.ok ? calc_fit(power.measured, calc_log_band_power(p.channels.at("hub_torque"), power.window,
                                                                               power.noise_power + power.offset)).percent
                                : -INFINITY;
    return out;
  }
};

bool all_explained(const std::map<std::string, ChannelTest>& tests) {
  for (const auto& [c, t] : tests)
    if (!t.explained()) return false;
  return !tests.empty();
}

// A parameter's fitted coordinate theta and its value (ParamScale).
double param_value(const EffectParam& p, double theta) {
  switch (p.scale) {
    case ParamScale::kLog: return std::exp(theta);
    case ParamScale::kLinear: return theta * std::max(std::abs(p.lo), std::abs(p.hi));
    case ParamScale::kShare: return theta;
  }
  return theta;
}
double param_theta(const EffectParam& p, double value) {
  switch (p.scale) {
    case ParamScale::kLog: return std::log(value);
    case ParamScale::kLinear: return value / std::max(std::abs(p.lo), std::abs(p.hi));
    case ParamScale::kShare: return value;
  }
  return value;
}
// d value / d theta at theta.
double param_unit(const EffectParam& p, double theta) {
  return p.scale == ParamScale::kLog ? std::exp(theta) : param_value(p, 1.0);
}

// What a parameter at coordinate theta sets in the model (path -> value).
std::vector<std::pair<std::string, double>> param_settings(const EffectParam& p, double theta) {
  const double v = param_value(p, theta);
  if (p.scale == ParamScale::kShare) return {{p.path, v * p.total / p.divisor}, {p.partner, (1.0 - v) * p.total}};
  return {{p.path, v}};
}

// The effect's model for fitted coordinates theta (and the grid value, if any).
std::vector<Assignment> effect_assignments(const Effect& e, const double* theta, double grid_value) {
  std::vector<Assignment> a;
  for (const auto& [path, value] : e.set) a.push_back(assign(path, YAML::Load(value)));
  if (!e.grid_path.empty()) a.push_back(assign(e.grid_path, number_node(e.grid_path, grid_value)));
  for (std::size_t i = 0; i < e.params.size(); ++i)
    for (const auto& [path, value] : param_settings(e.params[i], theta[i])) a.push_back(assign(path, YAML::Node(value)));
  return a;
}

// The trial models of coordinate sets, as assignments on the source.
std::vector<std::vector<Assignment>> make_trials(const Effect& e, const std::vector<std::vector<double>>& thetas,
                                                 double grid_value) {
  std::vector<std::vector<Assignment>> out;
  for (const auto& theta : thetas) out.push_back(effect_assignments(e, theta.data(), grid_value));
  return out;
}

// Sums of squares of trial models (INFINITY where the model failed to build or run), kMaxLanes at a time.
std::vector<double> trial_rss(const Scorer& sc, const std::vector<std::vector<Assignment>>& trials) {
  std::vector<double> out(trials.size(), INFINITY);
  for (std::size_t lo = 0; lo < trials.size(); lo += kMaxLanes) {
    const std::size_t hi = std::min(trials.size(), lo + kMaxLanes);
    const auto r = sc.residuals(std::vector<std::vector<Assignment>>(trials.begin() + lo, trials.begin() + hi));
    for (std::size_t j = 0; j < r.size(); ++j)
      if (!r[j].empty()) out[lo + j] = sum_squares(r[j]);
  }
  return out;
}

// Ceres cost: the normalised residuals of the model with the effect at coordinates theta. The
// forward-difference Jacobian's columns run as lanes of the same batch as the point itself.
class ReplayCost : public ceres::CostFunction {
 public:
  ReplayCost(const Scorer& sc, const Effect& e, double grid_value) : sc_(sc), e_(e), grid_(grid_value) {
    set_num_residuals(sc.size());
    mutable_parameter_block_sizes()->push_back(static_cast<int>(e.params.size()));
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const int p = static_cast<int>(e_.params.size());
    const std::vector<double> theta(parameters[0], parameters[0] + p);
    const double step = 1e-5;
    std::vector<std::vector<double>> points = {theta};
    if (jacobians && jacobians[0])
      for (int j = 0; j < p; ++j) {
        points.push_back(theta);
        points.back()[j] += step;
      }
    const auto r = sc_.residuals(make_trials(e_, points, grid_));
    for (const auto& ri : r)
      if (ri.empty()) return false;  // outside the model's valid range (or its run failed): Ceres shortens the step
    std::copy(r[0].begin(), r[0].end(), residuals);
    if (jacobians && jacobians[0]) {
      const int n = num_residuals();
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < p; ++j) jacobians[0][i * p + j] = (r[j + 1][i] - r[0][i]) / step;
    }
    return true;
  }

 private:
  const Scorer& sc_;
  const Effect& e_;
  double grid_;
};

// The grid search of a discrete parameter: every value as lanes; whole numbers (delays) refined
// between the best value's neighbours, up to 8 new values a round, until they are adjacent.
double search_grid(const Scorer& sc, const Effect& e, const std::vector<double>& theta, double* best_rss) {
  std::map<double, double> seen;  // value -> rss
  auto evaluate = [&](const std::vector<double>& values) {
    std::vector<std::vector<Assignment>> trials;
    for (double g : values) trials.push_back(effect_assignments(e, theta.data(), g));
    const auto rss = trial_rss(sc, trials);
    for (std::size_t i = 0; i < values.size(); ++i) seen[values[i]] = rss[i];
  };
  auto best = [&] {
    return std::min_element(seen.begin(), seen.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  };
  evaluate(e.grid);
  if (!std::isfinite(best()->second)) throw std::runtime_error("every grid value failed");
  while (e.grid_integer) {
    const auto b = best();
    const double lo = b == seen.begin() ? b->first : std::prev(b)->first;
    const double hi = std::next(b) == seen.end() ? b->first : std::next(b)->first;
    std::vector<double> fresh;
    for (int i = 1; i <= 8; ++i) {
      const double left = std::round(lo + (b->first - lo) * i / 9.0), right = std::round(b->first + (hi - b->first) * i / 9.0);
      for (double v : {left, right})
        if (!seen.count(v) && std::find(fresh.begin(), fresh.end(), v) == fresh.end()) fresh.push_back(v);
    }
    if (fresh.empty()) break;
    evaluate(fresh);
  }
  *best_rss = best()->second;
  return best()->first;
}

// The global scan's points in the box of coordinates: 16 evenly spaced for one parameter, an 8 x 8
// grid for two, 64 Sobol' points for three, 128 for more, or the effect's own starts; the starting point
// first. `coarse`: a quarter as many (4, a 4 x 4 grid, the first 16 or 32 Sobol' points; no starts).
std::vector<std::vector<double>> scan_points(const Effect& e, const std::vector<double>& start, bool coarse = false) {
  const std::size_t p = e.params.size();
  if (!e.starts.empty()) {
    std::vector<std::vector<double>> out = {start};
    if (coarse) return out;
    for (const auto& values : e.starts) {
      std::vector<double> t = start;
      for (std::size_t j = 0; j < p; ++j)
        if (const auto v = values.find(e.params[j].path); v != values.end())
          t[j] = param_theta(e.params[j], std::clamp(v->second, e.params[j].lo, e.params[j].hi));
      out.push_back(t);
    }
    return out;
  }
  std::vector<double> lo(p), hi(p);
  for (std::size_t j = 0; j < p; ++j) {
    lo[j] = param_theta(e.params[j], e.params[j].lo);
    hi[j] = param_theta(e.params[j], e.params[j].hi);
  }
  std::vector<std::vector<double>> u;  // unit-cube points
  const int side = coarse ? 4 : p == 1 ? 16 : 8;
  if (p == 1) {
    for (int i = 0; i < side; ++i) u.push_back({i / (side - 1.0)});
  } else if (p == 2) {
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j) u.push_back({i / (side - 1.0), j / (side - 1.0)});
  } else {
    const auto s = make_sobol_points_unscrambled((p == 3 ? 64 : 128) / (coarse ? 4 : 1) + 1, static_cast<int>(p));
    for (std::size_t i = 1; i < s.size(); ++i) u.push_back(s[i]);  // row 0 is the origin, a corner
  }
  std::vector<std::vector<double>> out = {start};
  for (const auto& x : u) {
    std::vector<double> t(p);
    for (std::size_t j = 0; j < p; ++j) t[j] = lo[j] + x[j] * (hi[j] - lo[j]);
    out.push_back(t);
  }
  return out;
}

// One Ceres run from theta (in place) within the coordinate bounds.
void run_ceres(ceres::CostFunction* cost, const Effect& e, std::vector<double>& theta, int max_iterations) {
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  problem.AddResidualBlock(cost, nullptr, theta.data());
  for (std::size_t j = 0; j < theta.size(); ++j) {
    const double lo = param_theta(e.params[j], e.params[j].lo), hi = param_theta(e.params[j], e.params[j].hi);
    problem.SetParameterLowerBound(theta.data(), static_cast<int>(j), lo);
    problem.SetParameterUpperBound(theta.data(), static_cast<int>(j), hi);
    theta[j] = std::clamp(theta[j], lo, hi);
  }
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = max_iterations;
  o.num_threads = 1;
  o.logging_type = ceres::SILENT;
  // The fit need not be finer than the noise: a relative change of the RSS below 1e-4 moves Delta BIC
  // by less than n_eff 1e-4 (0.5 at the 4500 samples of three channels; significance is at -10).
  o.function_tolerance = 1e-4;
  o.parameter_tolerance = 1e-6;
  // Steps that leave the box are projected onto it, without Ceres's projected line search: that search
  // evaluates the Jacobian (1 + p replays) at each of its trial points, several per iteration, and took
  // three quarters of a fit's replays (the two-link arm's fits: 55 s of 130, 12 s without it).
  o.max_num_line_search_step_size_iterations = 0;
  ceres::Solver::Summary summary;
  ceres::Solve(o, &problem, &summary);
}

// What a fit needs besides the effect: the baseline it is measured against.
struct Against {
  double rss = NAN;
  std::map<std::string, double> fit;
  std::map<std::string, ChannelTest> tests;
};

// Delta BIC of a fit against its baseline, channel by channel: sum_c n_c ln(RSS_c / RSS_c,base) + k ln n,
// n_c the effective samples of the fit's residual on channel c and n their sum. Each channel keeps its
// own noise variance (the likelihood of channels whose noise differs), and the count is what the
// residual's autocorrelation leaves of the samples, so correlated residuals at 1 kHz do not inflate it.
double calc_delta_bic(const std::map<std::string, ChannelTest>& fit, const std::map<std::string, ChannelTest>& base, int k) {
  double d = 0.0, n = 0.0;
  for (const auto& [c, t] : fit) {
    d += t.n_eff * std::log(std::max(t.rss, 1e-300) / std::max(base.at(c).rss, 1e-300));
    n += t.n_eff;
  }
  return d + k * std::log(std::max(n, 1.0));
}

// Where an effect's fit starts: its grid's best value (if any), then the global scan's points of its
// parameters, best (lowest RSS) first.
struct Scanned {
  double grid_value = 0.0;
  double grid_rss = INFINITY;
  std::vector<std::vector<double>> points;  // coordinates, best first (failed points dropped)
  std::vector<double> rss;                  // theirs
  std::string error;                        // non-empty: the scan failed
  bool gained = false;                      // its best point's Delta BIC is below 0 (it paid for its parameters)
};

// A later round's points (`first`: the effect's scan in round 1, on the base model): its starting point
// and a coarse scan (a quarter of the points), then, when the first scan paid for its parameters, the best quarter
// (at least kRescanPoints) of its points, its own parameters' coordinates (round 1 may have fitted re-fits
// beside them, last). The valleys the effects selected since have not moved are among the first scan's
// best; the coarse scan finds one the first effect's misfit hid. (A scan that did not has as its best the
// points nearest the base model: the stiffest drives, the costliest to run.) The whole scan
// again each round cost three quarters of a two-effect diagnosis.
constexpr std::size_t kRescanPoints = 8;
std::vector<std::vector<double>> rescan_points(const Effect& e, const std::vector<double>& start, const Scanned& first) {
  std::vector<std::vector<double>> out = scan_points(e, start, true);
  if (!first.gained) return out;
  const std::size_t keep = std::min(first.points.size(), std::max(kRescanPoints, (first.points.size() + 3) / 4));
  for (std::size_t i = 0; i < keep; ++i) {
    if (first.points[i].size() < start.size()) continue;
    std::vector<double> t(first.points[i].begin(), first.points[i].begin() + static_cast<std::ptrdiff_t>(start.size()));
    if (std::find(out.begin(), out.end(), t) == out.end()) out.push_back(std::move(t));
  }
  return out;
}

// The effect's scan: its grid searched, then its parameters' global scan (or, given `first`, the
// later round's points: rescan_points).
Scanned scan_effect(const Scorer& sc, const Effect& e, const Scanned* first = nullptr) {
  Scanned s;
  std::vector<double> theta;
  for (const auto& p : e.params) theta.push_back(param_theta(p, std::clamp(p.initial, p.lo, p.hi)));
  try {
    if (!e.grid_path.empty()) s.grid_value = search_grid(sc, e, theta, &s.grid_rss);
    if (e.params.empty()) return s;
    const auto points = first && !first->points.empty() ? rescan_points(e, theta, *first) : scan_points(e, theta);
    const auto rss = trial_rss(sc, make_trials(e, points, s.grid_value));
    std::vector<std::size_t> order(points.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return rss[a] < rss[b]; });
    for (std::size_t i : order)
      if (std::isfinite(rss[i])) {
        s.points.push_back(points[i]);
        s.rss.push_back(rss[i]);
      }
    if (s.points.empty()) s.error = "every point of the scan failed";
  } catch (const std::exception& ex) {
    s.error = ex.what();
  }
  return s;
}

// The scan's RSS of an effect (its best point, or its grid's best value): what the screening ranks by.
double scanned_rss(const Scanned& s) { return s.rss.empty() ? s.grid_rss : s.rss[0]; }

// Least-squares fit of one effect from its scan: full, Ceres from the scan's best starts (a race: a few
// iterations from each, then the leader runs on to max_iterations), else the scan's best point as it is
// (screened). `shared`: the last parameters of e are re-fits of existing ones, counted in the baseline's k too.
EffectFit fit_one(const Scorer& sc, const Effect& e, const Against& base, const DiagnoseOptions& opt, int shared,
                  const Scanned& scan, bool full) {
  EffectFit f;
  f.effect = e.name;
  f.physics = e.physics;
  f.switches = e.set;
  for (std::size_t j = e.params.size() - shared; j < e.params.size(); ++j) f.refit.push_back(e.params[j].path);
  try {
    if (!scan.error.empty()) throw std::runtime_error(scan.error);
    const double grid_value = scan.grid_value;
    if (!e.grid_path.empty()) {
      f.params[e.grid_path] = grid_value;
      f.stderr_[e.grid_path] = NAN;
    }
    std::vector<double> res(sc.size());
    const int p = static_cast<int>(e.params.size());
    std::vector<double> jac(static_cast<std::size_t>(sc.size()) * std::max(p, 1));
    ReplayCost cost(sc, e, grid_value);
    std::vector<double> theta = p > 0 ? scan.points[0] : std::vector<double>{};
    f.screened = p > 0 && !full;
    if (p > 0 && full) {
      const int race = opt.starts > 1 ? std::max(3, opt.max_iterations / 4) : opt.max_iterations;
      double best = INFINITY;
      for (int s = 0; s < std::min<int>(opt.starts, static_cast<int>(scan.points.size())); ++s) {
        std::vector<double> t = scan.points[s];
        run_ceres(&cost, e, t, race);
        const double* params[] = {t.data()};
        if (!cost.Evaluate(params, res.data(), nullptr)) continue;
        const double r2 = sum_squares(res);
        if (r2 < best) {
          best = r2;
          theta = t;
        }
      }
      if (race < opt.max_iterations) run_ceres(&cost, e, theta, opt.max_iterations - race);
    }
    const double* params[] = {theta.data()};
    if (p > 0 && full) {
      // Standard errors from the Jacobian at the optimum: cov = s^2 (J^T J)^+, s^2 = RSS / (n - k), by
      // the SVD J = U S V^T. A parameter with weight in a (near-)null direction is not identifiable:
      // the record cannot tell it from the others; its standard error is NaN.
      double* jacs[] = {jac.data()};
      if (!cost.Evaluate(params, res.data(), jacs)) throw std::runtime_error("the fitted model failed to run");
      f.rss = sum_squares(res);
      const Eigen::MatrixXd J =
          Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jac.data(), sc.size(), p);
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeThinV);
      const Eigen::VectorXd& sv = svd.singularValues();
      const Eigen::MatrixXd& V = svd.matrixV();
      Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(p, p);
      std::vector<bool> null(p, false);
      for (int k = 0; k < sv.size(); ++k) {
        if (sv(k) > kIdentifiableSv * sv(0)) {
          cov += V.col(k) * V.col(k).transpose() / (sv(k) * sv(k));
        } else {
          for (int j = 0; j < p; ++j) null[j] = null[j] || std::abs(V(j, k)) > 0.1;
        }
      }
      cov *= f.rss / std::max(1, sc.size() - p);
      for (int j = 0; j < p; ++j) {
        const auto& pj = e.params[j];
        const double unit = param_unit(pj, theta[j]) * (pj.scale == ParamScale::kShare ? pj.total / pj.divisor : 1.0);
        f.stderr_[pj.path] = null[j] ? NAN : std::abs(unit) * std::sqrt(std::max(cov(j, j), 0.0));
        if (null[j]) f.unidentifiable.push_back(pj.path);
      }
    } else {
      if (!cost.Evaluate(params, res.data(), nullptr)) throw std::runtime_error("the fitted model failed to run");
      f.rss = sum_squares(res);
      for (int j = 0; j < p; ++j) f.stderr_[e.params[j].path] = NAN;
    }
    for (int j = 0; j < p; ++j) {
      const auto& pj = e.params[j];
      for (const auto& [path, value] : param_settings(pj, theta[j])) f.params[path] = value;
      const double lo = param_theta(pj, pj.lo), hi = param_theta(pj, pj.hi), tol = 1e-3 * (hi - lo);
      if (theta[j] <= lo + tol || theta[j] >= hi - tol) f.at_bound.push_back(pj.path);
    }
    f.tests = sc.tests(res, &f.n_eff);
    f.explained = all_explained(f.tests);
    f.k = p - shared + (e.grid_path.empty() ? 0 : 1);
    f.delta_bic = calc_delta_bic(f.tests, base.tests, f.k);
    const double floor = sc.floor_rss();
    f.explains = base.rss > floor ? std::clamp((base.rss - f.rss) / (base.rss - floor), 0.0, 1.0) : 0.0;
    f.fit_percent = sc.fit_percent(f.assignments());
    double gain = -INFINITY;
    for (const auto& [c, v] : f.fit_percent) gain = std::max(gain, v - base.fit.at(c));
    f.significant = f.delta_bic < kSignificantDeltaBic && gain >= kMinFitGain;
    f.ok = true;
  } catch (const std::exception& ex) {
    f.ok = false;
    f.note = ex.what();
  }
  return f;
}

// A full fit of one effect (its scan, then Ceres).
EffectFit fit_one(const Scorer& sc, const Effect& e, const Against& base, const DiagnoseOptions& opt, int shared = 0) {
  return fit_one(sc, e, base, opt, shared, scan_effect(sc, e), true);
}

// The record as scored: its channels decimated to at most opt.max_samples, each weighted by its noise
// floor, with the loop inputs and the states of the problem at the decimated samples.
Scorer make_scorer(const DiagnoseProblem& p, const DiagnoseOptions& opt) {
  const Record& r = *p.record;
  Scorer sc;
  sc.family = p.family;
  sc.rec = &r;
  sc.channels = p.channels;
  const std::size_t stride = std::max<std::size_t>(1, r.size() / std::max(1, opt.max_samples));
  for (std::size_t k = 0; k < r.size(); k += stride) sc.index.push_back(k);
  for (const auto& c : sc.channels) {
    const auto& y = r.at(c);
    const double sd = calc_standard_deviation(y);
    const double unit = sd > 0 ? sd : 1.0;
    sc.sigma.push_back(calc_noise_floor(y));
    sc.noise.push_back(std::max(sc.sigma.back() / unit, kRelevantError));
    sc.scale.push_back(1.0 / (sc.noise.back() * unit));
  }
  auto decimate = [&](const std::vector<double>& x) {
    std::vector<double> out;
    for (std::size_t k : sc.index) out.push_back(x[k]);
    return out;
  };
  for (const auto& u : p.inputs) sc.input.push_back(decimate(u));
  for (const auto& [name, x] : p.states) sc.states.emplace_back(name, decimate(x));
  return sc;
}

// The rig's hub torque scored by its band power too (kPowerChannel), with `u` the loop's input.
void add_band_power(Scorer& sc, const std::vector<double>& u) {
  const Record& r = *sc.rec;
  const auto torque = std::find(sc.channels.begin(), sc.channels.end(), "hub_torque");
  const double dt = r.size() > 1 ? r.t[1] - r.t[0] : 0.0;
  if (torque == sc.channels.end() || dt <= 0) return;
  auto& bp = sc.power;
  bp.window = std::max<std::size_t>(16, static_cast<std::size_t>(std::lround(kPowerWindow / dt)));
  sc.low_pass = std::max<std::size_t>(3, static_cast<std::size_t>(std::lround(kPowerWindow / dt)));
  const std::size_t c = static_cast<std::size_t>(torque - sc.channels.begin());
  const double sf = 1.0 / sc.scale[c], s = calc_noise_floor(r.at("hub_torque"));  // N m
  bp.offset = 2.0 * sf * sf;
  bp.noise_power = 2.0 * s * s;
  bp.scale = std::sqrt(bp.window / 0.75);
  bp.measured = calc_log_band_power(r.at("hub_torque"), bp.window, bp.offset);
  for (std::size_t k0 = 1; k0 + bp.window <= r.size(); k0 += bp.window) bp.input.push_back(u[k0]);
  bp.on = bp.measured.size() >= 8;
}

// Where the baseline's residual misfits, channel by channel.
std::vector<Misfit> locate_misfit(const Scorer& sc, const std::vector<double>& r0, const std::map<std::string, ChannelTest>& tests,
                                  const std::map<std::string, double>& fit) {
  std::vector<double> t;
  for (std::size_t k : sc.index) t.push_back(sc.rec->t[k]);
  std::vector<Misfit> out;
  for (std::size_t c = 0; c < sc.channels.size(); ++c) {
    Misfit m;
    m.channel = sc.channels[c];
    m.fit_percent = fit.at(m.channel);
    m.test = tests.at(m.channel);
    const auto e = sc.channel_of(r0, c);
    const ResidualAnalysis a = analyse_residual(t, e, sc.input[c], sc.states);
    if (a.valid) {
      if (!a.failure.worst_windows.empty() && a.failure.rms > 0) {
        m.worst_t0 = a.failure.worst_windows[0].t0;
        m.worst_t1 = a.failure.worst_windows[0].t1;
        m.worst_ratio = a.failure.worst_windows[0].rms / a.failure.rms;
      }
      if (!a.failure.peaks.empty()) m.peak_hz = a.failure.peaks[0].frequency;
      if (!a.failure.states.empty()) {
        m.state = a.failure.states[0].first;
        m.departure = a.failure.states[0].second;
      }
    }
    out.push_back(m);
  }
  return out;
}

EffectScales make_scales(const Model& base, const Record& r, ReplayMode mode) {
  EffectScales s;
  const auto p = replay(std::span<const Model>(&base, 1), r, mode)[0];
  const auto& tau = mode == ReplayMode::kClosedLoop || !r.has("hub_torque") ? p.channels.at("hub_torque") : r.at("hub_torque");
  const auto& w = p.channels.count("hub_rate") ? p.channels.at("hub_rate") : std::vector<double>{1.0};
  s.torque_rms = calc_rms(tau);
  s.rate_rms = r.has("hub_rate") ? calc_rms(r.at("hub_rate")) : calc_rms(w);
  for (double x : tau) s.torque_max = std::max(s.torque_max, std::abs(x));
  return s;
}

// `--refit auto`: of the candidates (path, value), those that are plausible calibration targets (nonzero),
// most sensitive first: those whose 1 % change moves the normalised residual by more than a tenth of
// what the most sensitive one's does. One batch of lanes; a target whose change does not build (e.g.
// stiction below a raised Coulomb level) is none.
std::vector<std::string> rank_sensitive(const Scorer& sc, const std::vector<std::pair<std::string, double>>& targets) {
  std::vector<std::string> paths, out;
  std::vector<std::vector<Assignment>> sets = {{}};
  for (const auto& [p, x] : targets) {
    if (x == 0.0) continue;
    sets.push_back({assign(p, YAML::Node(1.01 * x))});
    paths.push_back(p);
  }
  if (paths.empty()) return out;
  const auto r = sc.residuals(sets);
  std::vector<std::pair<double, std::string>> sens;
  for (std::size_t j = 0; j < paths.size(); ++j) {
    if (r[j + 1].empty() || r[0].empty()) continue;
    double s2 = 0.0;
    for (std::size_t i = 0; i < r[0].size(); ++i) s2 += (r[j + 1][i] - r[0][i]) * (r[j + 1][i] - r[0][i]);
    sens.emplace_back(std::sqrt(s2), paths[j]);
  }
  std::sort(sens.rbegin(), sens.rend());
  for (const auto& [v, p] : sens)
    if (v > 0.1 * sens[0].first) out.push_back(p);
  return out;
}

// Does the effect fit (or search, or set through a share) this path itself?
bool fits_path(const Effect& e, const std::string& path) {
  const auto paths = effect_paths(e);
  return std::find(paths.begin(), paths.end(), path) != paths.end();
}

// Ceres reports failed steps through glog; they are results here, not news.
void quiet_ceres() {
  static const bool quiet = [] {
    FLAGS_minloglevel = google::GLOG_FATAL;
    return true;
  }();
  (void)quiet;
}

// `e` started from `values` (a fit's, by path) where it has the same paths, clamped to their ranges.
Effect start_from(Effect e, const std::map<std::string, double>& values) {
  for (auto& q : e.params)
    if (const auto v = values.find(q.path); v != values.end()) q.initial = std::clamp(v->second, q.lo, q.hi);
  return e;
}

// The Delta BIC an effect would have on top of a model with residual `rss` (n_eff effective samples) if it
// took off `gain` of it, as it did alone: n_eff ln((rss - gain) / rss) + k ln n_eff (additive signatures).
double calc_added_delta_bic(double rss, double gain, double n_eff, int k) {
  const double left = std::max(rss - gain, 1e-12 * rss);
  return std::max(n_eff, 1.0) * std::log(std::max(left, 1e-300) / std::max(rss, 1e-300)) + k * std::log(std::max(n_eff, 1.0));
}

// The forms `e` extends, simplest last: its Effect::extends, what that extends in turn, and so on through `all`.
std::vector<std::string> simpler_forms(const std::vector<Effect>& all, const Effect& e) {
  std::vector<std::string> chain;
  for (const Effect* at = &e; at && !at->extends.empty() && chain.size() < all.size();) {
    chain.push_back(at->extends);
    const auto next = std::find_if(all.begin(), all.end(), [&](const Effect& x) { return x.name == chain.back(); });
    at = next == all.end() ? nullptr : &*next;
  }
  return chain;
}

// Whether `e` extends the effect `name`, directly or through the chain.
bool extends_effect(const std::vector<Effect>& all, const Effect& e, const std::string& name) {
  const auto chain = simpler_forms(all, e);
  return std::find(chain.begin(), chain.end(), name) != chain.end();
}

// The simplest form `e` extends (the end of its chain; itself when it extends none).
std::string root_effect(const std::vector<Effect>& all, const Effect& e) {
  const auto chain = simpler_forms(all, e);
  return chain.empty() ? e.name : chain.back();
}

// Whether `e` may take the selected effect `name`'s place: it extends it, or it is another form of the same
// root that is not one of `name`'s simpler forms.
bool replaces_effect(const std::vector<Effect>& all, const Effect& e, const std::string& name) {
  if (e.name == name) return false;
  if (extends_effect(all, e, name)) return true;
  const auto other = std::find_if(all.begin(), all.end(), [&](const Effect& x) { return x.name == name; });
  if (other == all.end() || extends_effect(all, *other, e.name)) return false;
  return root_effect(all, e) == root_effect(all, *other);
}

// Whether the record determines what an extension adds to the form it extends: none of its own parameters
// (those the simpler form does not fit) unidentifiable or on a bound of its range. One that is not
// determined is a flexible curve, not evidence (a worn gear's ripple at its largest amplitude imitating
// viscous friction and an offset on the EMPS record): it is not significant, nor ranked above the simpler form.
bool is_extension_determined(const EffectFit& f, const std::vector<Effect>& effects) {
  const auto e = std::find_if(effects.begin(), effects.end(), [&](const Effect& x) { return x.name == f.effect; });
  if (e == effects.end() || e->extends.empty()) return true;
  const auto simple = std::find_if(effects.begin(), effects.end(), [&](const Effect& x) { return x.name == e->extends; });
  const auto inherited = simple == effects.end() ? std::vector<std::string>{} : effect_paths(*simple);
  for (const auto& p : e->params) {
    if (std::find(inherited.begin(), inherited.end(), p.path) != inherited.end()) continue;
    for (const auto* list : {&f.unidentifiable, &f.at_bound})
      if (std::find(list->begin(), list->end(), p.path) != list->end()) return false;
  }
  return true;
}

// Occam: an effect ranked above the simpler one it extends must fit visibly better, and be determined by the
// record, else the simpler goes first.
void order_nested(std::vector<EffectFit>& ranking, const std::vector<Effect>& effects) {
  for (const Effect& e : effects) {
    if (e.extends.empty()) continue;
    auto rich = std::find_if(ranking.begin(), ranking.end(), [&](const EffectFit& f) { return f.effect == e.name; });
    auto simple = std::find_if(ranking.begin(), ranking.end(), [&](const EffectFit& f) { return f.effect == e.extends; });
    if (rich == ranking.end() || simple == ranking.end() || simple < rich || !simple->ok) continue;
    double gain = -INFINITY;
    for (const auto& [c, v] : rich->fit_percent) gain = std::max(gain, v - simple->fit_percent.at(c));
    if (gain < kNestedFitMargin || !is_extension_determined(*rich, effects)) std::rotate(rich, simple, simple + 1);
  }
}

// A richer form does at least as well as the form it extends at its optimum (it contains it, or comes as near
// as its bounds allow), so one fitted to a larger RSS is stuck in a valley of its own: fitted again in full from
// the simpler fit's values (its own parameters at their initial values) when that start is already below the
// stuck fit's RSS, and kept if better. A form with starts of its own is always scanned again so, at them:
// starts scanned at the initial values are only as good as those are (a worn gear's waves, scanned at a
// guessed Coulomb level, fit the level instead).
// Simplest first (by the length of the extends chain, each length's refits in parallel), so a chain
// (Coulomb, Stribeck, LuGre) is carried up; only forms fitted in full.
void refit_stuck_forms(const Scorer& sc, const std::vector<Effect>& effects, const std::vector<Against>& against,
                       const std::vector<int>& shared, const DiagnoseOptions& opt, const std::vector<Scanned>& scans,
                       const std::vector<bool>& full, std::vector<EffectFit>& fits) {
  const std::size_t n = effects.size();
  std::vector<std::size_t> depth(n), simpler(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    depth[i] = simpler_forms(effects, effects[i]).size();
    for (std::size_t j = 0; j < n; ++j)
      if (effects[j].name == effects[i].extends) simpler[i] = j;
  }
  const std::size_t deepest = n ? *std::max_element(depth.begin(), depth.end()) : 0;
  for (std::size_t d = 1; d <= deepest; ++d) {
    std::vector<std::size_t> stuck;
    for (std::size_t i = 0; i < n; ++i)
      if (depth[i] == d && full[i] && simpler[i] < n && fits[simpler[i]].ok && fits[i].ok &&
          (fits[i].rss > fits[simpler[i]].rss || !effects[i].starts.empty()))
        stuck.push_back(i);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::size_t k = 0; k < stuck.size(); ++k) {
      const std::size_t i = stuck[k];
      const Effect seeded = start_from(effects[i], fits[simpler[i]].params);
      Scanned start;
      if (seeded.starts.empty()) {  // the seeded point alone, the grid where the first scan found it
        start.grid_value = scans[i].grid_value;
        start.points.emplace_back();
        for (const auto& q : seeded.params) start.points[0].push_back(param_theta(q, q.initial));
        start.rss = trial_rss(sc, make_trials(seeded, start.points, start.grid_value));
      } else {
        start = scan_effect(sc, seeded);
      }
      if (start.rss.empty() || !(start.rss[0] < fits[i].rss)) continue;  // no better start: the first fit stands
      EffectFit again = fit_one(sc, seeded, against[i], opt, shared[i], start, true);
      if (again.ok && again.rss < fits[i].rss) fits[i] = std::move(again);
    }
  }
}

// One round of the search: every candidate scanned (its grid, its global scan), the `keep` best of those
// with parameters by the scan's Delta BIC (n_eff ln(RSS_scan / RSS_base) + k ln n_eff, the baseline's
// n_eff) fitted in full, the others as the scan left them (screened); ranked best first. against[i],
// shared[i]: effect i's baseline and how many of its parameters are re-fits (as fit_one). `first`: each
// effect's first scan (filled by round 1), from which a later round's scan starts (rescan_points).
std::vector<EffectFit> rank_round(const Scorer& sc, const std::vector<Effect>& effects, const std::vector<Against>& against,
                                  const std::vector<int>& shared, int keep, const DiagnoseOptions& opt,
                                  std::map<std::string, Scanned>& first, const std::vector<bool>& always = {}) {
  const std::size_t n = effects.size();
  std::vector<Scanned> scans(n);
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t i = 0; i < n; ++i) {
    const auto seen = first.find(effects[i].name);
    scans[i] = scan_effect(sc, effects[i], seen == first.end() ? nullptr : &seen->second);
  }
  std::vector<std::pair<double, std::size_t>> screen;
  for (std::size_t i = 0; i < n; ++i) {
    if (effects[i].params.empty() || !scans[i].error.empty()) continue;
    double n_eff = 0.0;
    for (const auto& [c, t] : against[i].tests) n_eff += t.n_eff;
    const int k = static_cast<int>(effects[i].params.size()) - shared[i] + (effects[i].grid_path.empty() ? 0 : 1);
    screen.emplace_back(n_eff * std::log(std::max(scanned_rss(scans[i]), 1e-300) / std::max(against[i].rss, 1e-300)) +
                            k * std::log(std::max(n_eff, 1.0)),
                        i);
  }
  std::stable_sort(screen.begin(), screen.end());
  for (const auto& [delta_bic, i] : screen) scans[i].gained = delta_bic < 0.0;
  for (std::size_t i = 0; i < n; ++i) first.try_emplace(effects[i].name, scans[i]);
  std::vector<bool> full(n, true);
  for (std::size_t j = static_cast<std::size_t>(std::max(keep, 0)); j < screen.size(); ++j)
    full[screen[j].second] = screen[j].second < always.size() && always[screen[j].second];
  // The costliest fits (full ones with most parameters) first, so that the threads finish together.
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (full[a] != full[b]) return static_cast<bool>(full[a]);
    return effects[a].params.size() > effects[b].params.size();
  });
  std::vector<EffectFit> ranking(n);
  int done = 0;
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t o = 0; o < n; ++o) {
    const std::size_t i = order[o];
    ranking[i] = fit_one(sc, effects[i], against[i], opt, shared[i], scans[i], full[i]);
    if (opt.on_fitted) {
#pragma omp critical(diagnose_progress)
      opt.on_fitted(++done, static_cast<int>(n), ranking[i]);
    }
  }
  refit_stuck_forms(sc, effects, against, shared, opt, scans, full, ranking);
  for (std::size_t i = 0; i < n; ++i)  // ranking[i] is still effects[i]'s
    if (ranking[i].ok && ranking[i].significant && !ranking[i].screened && !is_extension_determined(ranking[i], effects)) {
      ranking[i].significant = false;
      ranking[i].note = "what it adds to " + effects[i].extends + " is not determined by the record (unidentifiable or on a bound)";
    }
  std::stable_sort(ranking.begin(), ranking.end(), [](const EffectFit& a, const EffectFit& b) {
    if (a.ok != b.ok) return a.ok;
    return a.delta_bic < b.delta_bic;
  });
  order_nested(ranking, effects);
  return ranking;
}

// Judges a fitted model's residual tests (`tests`, of the record against the model: the scorer's prefix and
// `fitted`) against what that model leaves of records it made itself: `lanes` runs of it with other noise
// in its loop (its sensors' noise drawn, p.seed_path, where the prediction has their expected readings:
// with_expected_readings), each given the record's measurement noise, scored against the model's own
// prediction. A channel is within the bootstrap when its mean is unbiased (below) and its RMS
// is at most kBootstrapLevel times the largest over the lanes, or at most kBootstrapMargin times it with
// its fractions of correlation lags outside the band at most the lanes' largest plus kTestFraction (a
// residual a little above the lanes' must be as white as theirs: a noise channel's ACF alone is not
// judged). Its mean is unbiased when unbiased, at most the largest |mean|, or below kRelevantError of the channel's
// standard deviation (a fit converged to 10^-4 of its RSS leaves such a bias); or its RMS is itself below
// kRelevantError of the channel's standard deviation (what no rig's sensor resolves). A limit cycle the model makes with
// its quantised encoder, whose phase no replay follows, is judged against the misfit it really produces.
constexpr double kBootstrapLevel = 1.05, kBootstrapMargin = 1.2;
void judge_by_bootstrap(const Scorer& sc, const std::vector<Assignment>& fitted, const DiagnoseProblem& p, int lanes,
                        std::map<std::string, ChannelTest>& tests) {
  if (lanes <= 0) return;
  std::vector<std::vector<Assignment>> sets(lanes + 1, fitted);
  for (int b = 1; b <= lanes; ++b) {
    sets[b].push_back(assign(p.seed_path, YAML::Node(1000 + b)));
    sets[b].push_back(assign("simulation.expected_readings", YAML::Node(false)));
  }
  const auto pred = sc.predict(sets);
  if (!pred[0].ok) return;
  std::map<std::string, ChannelTest> worst;
  int ran = 0;
  for (int b = 1; b <= lanes; ++b) {
    if (!pred[b].ok) continue;
    ++ran;
    const auto r = sc.simulated_residual(pred[0], pred[b], 0x62006f6f74ull + b);  // "boot" + b
    for (const auto& [c, t] : sc.tests(r, nullptr)) {
      auto& w = worst[c];
      w.rms = ran == 1 ? t.rms : std::max(w.rms, t.rms);
      w.acf_outside = ran == 1 ? t.acf_outside : std::max(w.acf_outside, t.acf_outside);
      w.ccf_outside = ran == 1 ? t.ccf_outside : std::max(w.ccf_outside, t.ccf_outside);
      w.mean = ran == 1 ? std::abs(t.mean) : std::max(w.mean, std::abs(t.mean));
    }
  }
  if (2 * ran < lanes) return;  // most noise realisations failed to run: no judgement
  for (auto& [c, t] : tests) {
    if (!worst.count(c)) continue;
    const auto& w = worst.at(c);
    t.boot_rms = w.rms;
    t.boot_acf = w.acf_outside;
    t.boot_ccf = w.ccf_outside;
    t.boot_mean = w.mean;
    t.bootstrapped = true;
    const bool mean_ok = t.unbiased || std::abs(t.mean) <= w.mean || std::abs(t.mean) * t.noise <= kRelevantError;
    const bool white_ok = t.acf_outside <= w.acf_outside + kTestFraction && t.ccf_outside <= w.ccf_outside + kTestFraction;
    t.within_bootstrap = t.rms <= kRelevantError ||
                         (mean_ok && (t.rms <= kBootstrapLevel * w.rms || (t.rms <= kBootstrapMargin * w.rms && white_ok)));
  }
}

// The scorer of the model with the selected effects but the one at `skip` (its re-fitted existing
// parameters kept): what that effect is refitted on.
Scorer without_effect(const Scorer& sc, const std::vector<EffectFit>& sel, std::size_t skip) {
  Scorer s = sc;
  for (std::size_t k = 0; k < sel.size(); ++k) {
    if (k == skip) continue;
    const auto a = sel[k].assignments();
    s.prefix.insert(s.prefix.end(), a.begin(), a.end());
  }
  for (const auto& path : sel[skip].refit) s.prefix.push_back(assign(path, number_node(path, sel[skip].params.at(path))));
  return s;
}

// One pass of backfitting over the selected effects: each (the one at `last` last) refitted on top of the
// others as they now are, from its values (its scan's first point; a grid searched again), and kept when
// the whole model's RSS falls. An effect fitted before a later one was found took some of its signature
// (a Stribeck curve fitted beside a torque delay not yet found); this gives it back. `rss`: the whole
// model's, updated. Only the values change: each keeps the Delta BIC and the tests it was selected with
// (of the model with the effects up to it).
void backfit(const Scorer& sc, const std::vector<Effect>& plain, std::vector<EffectFit>& sel, std::size_t last, double& rss,
             const DiagnoseOptions& opt) {
  std::vector<std::size_t> order;
  for (std::size_t j = 0; j < sel.size(); ++j)
    if (j != last) order.push_back(j);
  order.push_back(last);
  for (std::size_t j : order) {
    const auto e0 = std::find_if(plain.begin(), plain.end(), [&](const Effect& e) { return e.name == sel[j].effect; });
    if (e0 == plain.end() || e0->params.empty()) continue;
    const Effect e = start_from(*e0, sel[j].params);
    const Scorer s = without_effect(sc, sel, j);
    const auto r = s.residuals({{}})[0];
    if (r.empty()) continue;
    EffectFit f = fit_one(s, e, {sum_squares(r), s.fit_percent({}), s.tests(r, nullptr)}, opt, 0, scan_effect(s, e), true);
    if (!f.ok || !(f.rss < rss)) continue;
    rss = f.rss;
    for (const auto& [path, v] : f.params) {
      sel[j].params[path] = v;
      sel[j].stderr_[path] = f.stderr_.count(path) ? f.stderr_.at(path) : NAN;
    }
    sel[j].at_bound = f.at_bound;
    sel[j].unidentifiable = f.unidentifiable;
  }
}

// Whether an effect writes a path another already selected writes (they cannot both be added).
bool overlaps(const Effect& e, const std::vector<EffectFit>& selected) {
  const auto paths = effect_paths(e);
  for (const auto& f : selected) {
    for (const auto& [path, v] : f.switches)
      if (std::find(paths.begin(), paths.end(), path) != paths.end()) return true;
    for (const auto& [path, v] : f.params)
      if (std::find(paths.begin(), paths.end(), path) != paths.end()) return true;
  }
  return false;
}

std::string join_effects(const std::vector<EffectFit>& fits) {
  std::string out;
  for (const auto& f : fits) out += (out.empty() ? "" : " + ") + f.effect;
  return out;
}

// The diagnosis of a scored record whose base residual is r0: every candidate of p fitted and ranked.
Diagnosis diagnose_scored(const Scorer& sc, const std::vector<double>& r0, const DiagnoseProblem& p,
                          const DiagnoseOptions& opt) {
  Diagnosis d;
  d.mode = p.mode;
  d.channels = sc.channels;
  d.n = sc.size();
  d.torque_cutoff_hz = sc.cutoff_hz();
  d.base_rss = sum_squares(r0);
  d.base_fit = sc.fit_percent({});
  const EffectScales& scales = p.scales;
  auto effects = p.effects;
  // --effects (opt.only) or calibrate's --add: only those, each a name the model offers.
  const std::vector<std::string>& named_effects = opt.add.empty() ? opt.only : opt.add;
  for (const auto& name : named_effects)
    if (std::find(p.names.begin(), p.names.end(), name) == p.names.end()) {
      std::string offered;
      for (const auto& n : p.names) offered += (offered.empty() ? "" : ", ") + n;
      throw std::invalid_argument("unknown effect '" + name + "' (this model offers: " + offered + ")");
    }
  for (std::size_t i = 0; i < opt.add.size(); ++i)
    if (std::find(opt.add.begin(), opt.add.begin() + i, opt.add[i]) != opt.add.begin() + i)
      throw std::invalid_argument("effect '" + opt.add[i] + "' is named twice");
  if (!named_effects.empty())
    effects.erase(std::remove_if(effects.begin(), effects.end(),
                                 [&](const Effect& e) {
                                   return std::find(named_effects.begin(), named_effects.end(), e.name) == named_effects.end();
                                 }),
                  effects.end());
  for (const auto& name : opt.add)
    if (std::none_of(effects.begin(), effects.end(), [&](const Effect& e) { return e.name == name; }))
      throw std::invalid_argument("effect '" + name + "' does not apply in " + replay_mode_name(p.mode) + " mode");
  for (const Effect& a : effects)
    for (const Effect& b : effects)
      if (!opt.add.empty() && a.name < b.name)
        for (const auto& path : effect_paths(a))
          if (fits_path(b, path))
            throw std::invalid_argument("effects '" + a.name + "' and '" + b.name + "' both write " + path + ": add one of them");
  // Re-fitted existing parameters. Named (--refit a,b): the same for the baseline and every effect,
  // which then drops them from its own. `auto`: for each effect the (at most two) most sensitive
  // existing parameters it does not fit itself, its Delta BIC taken against the baseline re-fitted
  // with the same ones. "none" (or nothing): no re-fit.
  const bool automatic = opt.refit == std::vector<std::string>{"auto"};
  const bool named = !automatic && !opt.refit.empty() && opt.refit != std::vector<std::string>{"none"};
  const YAML::Node& doc = p.doc;
  auto refit_param = [&](const std::string& path) {
    const YAML::Node v = get_path(doc, path);
    if (!v) throw std::invalid_argument("--refit: the model does not set '" + path + "'");
    try {
      return make_effect_param(path, v.as<double>(), scales);
    } catch (const YAML::Exception&) {
      throw std::invalid_argument("--refit: '" + path + "' is not a number in the model");
    }
  };
  const std::vector<std::string> pool = automatic ? rank_sensitive(sc, p.sensitive) : named ? opt.refit : std::vector<std::string>{};
  auto refit_of = [&](const Effect& e) {
    std::vector<std::string> out;
    for (const auto& p : pool)
      if (named || (out.size() < 2 && !fits_path(e, p))) out.push_back(p);
    return out;
  };
  if (named)
    for (auto& e : effects)
      e.params.erase(std::remove_if(e.params.begin(), e.params.end(),
                                    [&](const EffectParam& p) {
                                      return std::find(pool.begin(), pool.end(), p.path) != pool.end();
                                    }),
                     e.params.end());
  effects.erase(std::remove_if(effects.begin(), effects.end(),
                               [](const Effect& e) { return e.params.empty() && e.grid_path.empty(); }),
                effects.end());
  // One baseline fit per distinct re-fit set: the reported one (d.refit) and those effects need.
  std::map<std::vector<std::string>, EffectFit> baselines;
  d.refit = refit_of(Effect{});
  baselines[d.refit];
  for (const auto& e : effects) baselines[refit_of(e)];
  std::vector<std::vector<std::string>> sets;
  for (const auto& [set, fit] : baselines) sets.push_back(set);
  std::vector<EffectFit> fitted(sets.size());
  double r0_n_eff = NAN;
  const auto r0_tests = sc.tests(r0, &r0_n_eff);  // the base model's, once: every re-fit is against it
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t i = 0; i < sets.size(); ++i) {
    if (sets[i].empty()) {
      fitted[i].ok = true;
      fitted[i].rss = d.base_rss;
      fitted[i].fit_percent = d.base_fit;
      fitted[i].tests = r0_tests;
      fitted[i].n_eff = r0_n_eff;
      fitted[i].explained = all_explained(fitted[i].tests);
      continue;
    }
    Effect baseline{"baseline", "the model as it is, its re-fitted parameters fitted", {}, {}, "", {}, false, ""};
    try {
      for (const auto& p : sets[i]) baseline.params.push_back(refit_param(p));
    } catch (const std::exception& ex) {
      fitted[i].note = ex.what();
      continue;
    }
    fitted[i] = fit_one(sc, baseline, {d.base_rss, d.base_fit, r0_tests}, opt);
  }
  for (std::size_t i = 0; i < sets.size(); ++i) {
    if (!fitted[i].ok) {
      if (fitted[i].effect.empty()) throw std::invalid_argument(fitted[i].note);
      throw std::runtime_error("the baseline re-fit failed: " + fitted[i].note);
    }
    baselines[sets[i]] = fitted[i];
  }
  const EffectFit& reported = baselines.at(d.refit);
  d.base_rss = reported.rss;
  d.base_fit = reported.fit_percent;
  d.base_params = reported.params;
  d.base_tests = reported.tests;
  d.base_explained = reported.explained;
  d.base_n_eff = reported.n_eff;
  d.misfit = locate_misfit(sc, r0, d.base_tests, d.base_fit);
  // Each effect: its own parameters, then its re-fitted ones starting where its baseline put them.
  std::vector<std::vector<std::string>> refits;
  // The later rounds' candidates: the effects as they are (no re-fits); round 1 (calibrate: its first effect).
  const std::vector<Effect> plain = effects;
  if (!opt.add.empty())
    effects.erase(std::remove_if(effects.begin(), effects.end(), [&](const Effect& e) { return e.name != opt.add[0]; }),
                  effects.end());
  for (auto& e : effects) refits.push_back(refit_of(e));
  for (std::size_t i = 0; i < effects.size(); ++i)
    for (const auto& p : refits[i]) {
      EffectParam q = refit_param(p);
      q.initial = baselines.at(refits[i]).params.at(p);
      effects[i].params.push_back(q);
    }
  // Round 1: every candidate against its baseline (screened, the best fitted in full).
  std::vector<Against> against;
  std::vector<int> shared;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    const EffectFit& b = baselines.at(refits[i]);
    against.push_back({b.rss, b.fit_percent, b.tests});
    shared.push_back(static_cast<int>(refits[i].size()));
  }
  const bool all_full = !opt.only.empty() || !opt.add.empty();
  std::map<std::string, Scanned> first_scans;  // each effect's round-1 scan: where the later rounds look
  d.ranking = rank_round(sc, effects, against, shared, all_full ? static_cast<int>(effects.size()) : kFullFits, opt,
                         first_scans);
  // What each effect took off the residual in round 1 (RSS against its baseline's; scan-only fits a lower bound).
  std::map<std::string, double> gain1;
  for (std::size_t i = 0; i < effects.size(); ++i)
    for (const EffectFit& f : d.ranking)
      if (f.effect == effects[i].name && f.ok) gain1[f.effect] = std::max(0.0, against[i].rss - f.rss);
  // The base model judged by the bootstrap.
  judge_by_bootstrap(sc, reported.assignments(), p, opt.bootstrap_lanes, d.base_tests);
  d.base_explained = all_explained(d.base_tests);
  // Forward selection: the best significant effect is added (its tests judged by the bootstrap); while the
  // model with it is not explained, every candidate that does not write what a selected one does is tried
  // again on top of it (screened, the kFullFitsLater best fitted in full): an effect whose signature the
  // first one masked is found now. So is the richer form of a selected effect (Stribeck for Coulomb,
  // Effect::extends), which replaces it when chosen: the simpler one went first by Occam (order_nested)
  // on a record where alone it fitted as well. calibrate (opt.add): its effects in its order.
  Scorer current = sc;
  std::vector<EffectFit> ranked = d.ranking;
  for (std::size_t round = 0;; ++round) {
    const bool forced = !opt.add.empty();
    if (ranked.empty() || !ranked[0].ok || (!forced && !ranked[0].significant)) break;
    // The selected effect `e` may replace: one it is a richer form of (LuGre for Coulomb, through Stribeck), or
    // another form of the same root (free play for a hardening mesh: both drive compliance).
    auto simpler = [&](const Effect& e) {
      return std::find_if(d.selected.begin(), d.selected.end(), [&](const EffectFit& f) { return replaces_effect(plain, e, f.effect); });
    };
    const Effect* rich = nullptr;
    for (const Effect& e : plain)
      if (e.name == ranked[0].effect) rich = &e;
    std::size_t at = d.selected.size();
    if (auto s = rich ? simpler(*rich) : d.selected.end(); s != d.selected.end()) at = static_cast<std::size_t>(s - d.selected.begin());
    if (at == d.selected.size()) d.selected.push_back(ranked[0]);
    else d.selected[at] = ranked[0];
    // The earlier effects refitted beside the new one; the whole model judged by the bootstrap.
    double rss = ranked[0].rss;
    if (!forced && d.selected.size() > 1) backfit(sc, plain, d.selected, at, rss, opt);
    EffectFit& chosen = d.selected[at];
    {
      const Scorer others = without_effect(sc, d.selected, at);
      if (rss < ranked[0].rss) {  // backfitting moved the others: the whole model's residual again
        const auto r = others.residuals({chosen.assignments()})[0];
        if (!r.empty()) chosen.tests = others.tests(r, &chosen.n_eff);
        chosen.fit_percent = others.fit_percent(chosen.assignments());
        chosen.rss = rss;
      }
      judge_by_bootstrap(others, chosen.assignments(), p, opt.bootstrap_lanes, chosen.tests);
    }
    chosen.explained = all_explained(chosen.tests);
    if (at + 1 != d.selected.size()) std::rotate(d.selected.begin() + at, d.selected.begin() + at + 1, d.selected.end());
    // (Replacements do not add: the rounds are bounded too, so two forms cannot take each other's place forever.)
    if (forced ? d.selected.size() == opt.add.size()
               : d.selected.back().explained || d.selected.size() >= kMaxEffects || round + 1 >= 2 * kMaxEffects)
      break;
    const EffectFit& last = d.selected.back();
    current.prefix = sc.prefix;
    for (const EffectFit& f : d.selected) {
      const auto mine = f.assignments();
      current.prefix.insert(current.prefix.end(), mine.begin(), mine.end());
    }
    const Against now{rss, last.fit_percent, last.tests};
    double n_eff_now = 0.0;
    for (const auto& [c, t] : last.tests) n_eff_now += t.n_eff;
    std::vector<Effect> next;
    std::vector<bool> replacing;  // fitted in full whatever its scan: a richer or other form of a selected effect
    for (const Effect& e : plain) {
      if (forced ? e.name != opt.add[d.selected.size()] : false) continue;
      std::vector<EffectFit> others = d.selected;
      const auto s = forced ? d.selected.end() : simpler(e);
      if (s != d.selected.end()) others.erase(others.begin() + (s - d.selected.begin()));
      if (overlaps(e, others)) continue;
      // Round 1's evidence: an effect that would not pay for its parameters on top of the selected even
      // if it took off what it took alone is not tried again (a richer form of a selected effect is).
      const auto g = gain1.find(e.name);
      const int k = static_cast<int>(e.params.size()) + (e.grid_path.empty() ? 0 : 1);
      if (!forced && s == d.selected.end() && g != gain1.end() &&
          calc_added_delta_bic(rss, g->second, n_eff_now, k) >= kLaterRoundScreen)
        continue;
      // A richer form starts where the simpler selected one left what they share (LuGre's Coulomb level).
      next.push_back(s != d.selected.end() ? start_from(e, s->params) : e);
      replacing.push_back(s != d.selected.end());
    }
    if (forced && next.empty())
      throw std::invalid_argument("effect '" + opt.add[d.selected.size()] + "' writes what an effect before it does");
    if (next.empty()) break;
    ranked = rank_round(current, next, std::vector<Against>(next.size(), now), std::vector<int>(next.size(), 0),
                        forced ? 1 : kFullFitsLater, opt, first_scans, replacing);
    d.rounds.push_back(ranked);
  }
  // The verdict: the selected effects when with them the record is explained; else "none" when the model
  // already explains it and no effect is significant; else "unexplained".
  if (!d.selected.empty())
    d.verdict = d.selected.back().explained ? join_effects(d.selected) : "unexplained";
  else
    d.verdict = d.base_explained ? "none" : "unexplained";
  return d;
}

// The reference rig's models as diagnose fits them: each assignment set built on the source (one needing
// more than kMaxFitSubsteps fixed steps per control period refused as too stiff, except the base), then
// replayed as lanes of one batch per group of equal substeps (one at a time when they differ in more:
// segments, the drive's parts).
class RigFamily : public FitFamily {
 public:
  RigFamily(const ModelSource& src, const Record& r, ReplayMode mode) : src_(src), rec_(r), mode_(mode) {}
  std::vector<Prediction> predict(const std::vector<std::vector<Assignment>>& sets) const override {
    std::vector<Prediction> p(sets.size());
    std::vector<std::optional<Model>> models(sets.size());
    std::map<int, std::vector<std::size_t>> groups;
    for (std::size_t i = 0; i < sets.size(); ++i) {
      try {
        Model m = build_model(src_, sets[i]);
        if (sets[i].empty() || m.substeps <= kMaxFitSubsteps) models[i] = std::move(m);
      } catch (const std::exception&) {  // outside the model's valid range
      }
      if (models[i]) groups[models[i]->substeps].push_back(i);
      else p[i].ok = false;
    }
    for (const auto& [substeps, members] : groups) {
      std::vector<Model> group;
      for (std::size_t i : members) group.push_back(*models[i]);
      try {
        const auto q = replay(group, rec_, mode_);
        for (std::size_t j = 0; j < members.size(); ++j) p[members[j]] = q[j];
      } catch (const std::invalid_argument&) {
        for (std::size_t i : members) p[i] = replay(std::span<const Model>(&*models[i], 1), rec_, mode_)[0];
      }
    }
    return p;
  }

 private:
  const ModelSource& src_;
  const Record& rec_;
  ReplayMode mode_;
};

}  // namespace

std::vector<Assignment> EffectFit::assignments() const {
  std::vector<Assignment> a;
  for (const auto& [path, value] : switches) a.push_back(assign(path, YAML::Load(value)));
  for (const auto& [path, value] : params) a.push_back(assign(path, number_node(path, value)));
  return a;
}

std::pair<double, double> calc_loop_noise(double s_angle, double s_rate, double s_torque, double kp, double kd) {
  const double driven = std::hypot(kp * s_angle, kd * s_rate);
  const double f = std::isfinite(s_torque) && driven > s_torque ? s_torque / driven : 1.0;
  return {f * s_angle, f * s_rate};
}

ModelSource with_expected_readings(ModelSource src, const std::vector<std::pair<std::string, double>>& loop_noise) {
  src.set.push_back(assign("simulation.expected_readings", YAML::Node(true)));
  for (const auto& [path, sd] : loop_noise)
    if (sd > 0) src.set.push_back(assign(path, YAML::Node(sd)));
  return src;
}

EffectFit combine_effects(const std::vector<EffectFit>& fits) {
  if (fits.empty()) throw std::invalid_argument("no effect to combine");
  EffectFit out = fits.back();
  out.effect = join_effects(fits);
  out.physics.clear();
  out.switches.clear();
  out.params.clear();
  out.stderr_.clear();
  out.unidentifiable.clear();
  out.refit.clear();
  out.at_bound.clear();
  out.k = 0;
  out.delta_bic = 0.0;
  for (const auto& f : fits) {
    out.physics += (out.physics.empty() ? "" : "; ") + f.physics;
    out.switches.insert(out.switches.end(), f.switches.begin(), f.switches.end());
    for (const auto& [path, v] : f.params) out.params[path] = v;
    for (const auto& [path, v] : f.stderr_) out.stderr_[path] = v;
    out.unidentifiable.insert(out.unidentifiable.end(), f.unidentifiable.begin(), f.unidentifiable.end());
    out.refit.insert(out.refit.end(), f.refit.begin(), f.refit.end());
    out.at_bound.insert(out.at_bound.end(), f.at_bound.begin(), f.at_bound.end());
    out.k += f.k;
    out.delta_bic += f.delta_bic;
    out.significant = out.significant && f.significant;
    out.screened = out.screened || f.screened;
    out.ok = out.ok && f.ok;
  }
  return out;
}

EffectFit fit_effects(const ModelSource& src, const Record& r, const DiagnoseOptions& opt, const std::vector<std::string>& names) {
  DiagnoseOptions o = opt;
  o.only.clear();
  o.add = names;
  return combine_effects(diagnose(src, r, o).selected);
}

Diagnosis diagnose_problem(const DiagnoseProblem& p, const DiagnoseOptions& opt) {
  quiet_ceres();
  const Scorer sc = make_scorer(p, opt);
  const auto r0 = sc.residuals({{}});
  if (r0[0].empty()) throw std::runtime_error("the base model fails to run on the record");
  return diagnose_scored(sc, r0[0], p, opt);
}

Diagnosis diagnose(const ModelSource& src, const Record& r, const DiagnoseOptions& opt) {
  quiet_ceres();
  for (const auto& c : replay_inputs(opt.mode))
    if (!r.has(c)) throw ConfigError(r.source, 1, c, std::string("missing column '") + c + "', needed in " + replay_mode_name(opt.mode) + " mode");
  // The fits integrate an explicit (RK4) model with the linearly implicit midpoint rule: one
  // articulated-body pass per step and the drive's states implicit, half the cost or less, within
  // 1e-4 of the RK4 response on the reference rig (docs/validation.md). The written model keeps its own.
  // The predictions read the sensors' expected values, the encoder and tachometer with the noise the
  // controller read (with_expected_readings).
  const ModelSource fit_src = [&] {
    ModelSource f = src;
    const auto& s = build_model(src).spec;
    if (s.simulation.integrator == Integrator::kRk4)
      f.set.push_back(assign("simulation.integrator", YAML::Node("midpoint")));
    const auto [sa, sr] = calc_loop_noise(calc_noise_floor(r.at("hub_angle")),
                                          r.has("hub_rate") ? calc_noise_floor(r.at("hub_rate")) : 0.0,
                                          r.has("hub_torque") ? calc_noise_floor(r.at("hub_torque")) : NAN,
                                          s.controller.kp, s.controller.kd);
    std::vector<std::pair<std::string, double>> noise;
    if (s.sensors.hub_angle.noise == 0.0) noise.emplace_back("sensors.hub_angle.noise", sa);
    if (s.sensors.hub_rate.noise == 0.0) noise.emplace_back("sensors.hub_rate.noise", sr);
    return with_expected_readings(f, noise);
  }();
  const Model base = build_model(fit_src);
  const RigFamily family(fit_src, r, opt.mode);
  DiagnoseProblem p;
  p.family = &family;
  p.record = &r;
  p.mode = opt.mode;
  p.channels = scored_channels(opt.mode, r);
  // The loop's external input: the reference in closed loop, the torque in open loop, the hub angle
  // in inverse dynamics. Residuals are binned against the hub's velocity and angle.
  const auto& u = r.at(opt.mode == ReplayMode::kClosedLoop ? "ref" : opt.mode == ReplayMode::kOpenLoop ? "hub_torque" : "hub_angle");
  p.inputs.assign(p.channels.size(), u);
  const auto& angle = r.at("hub_angle");
  p.states = {{"hub_velocity", r.has("hub_rate") ? r.at("hub_rate") : time_derivative(r.t, angle)}, {"hub_angle", angle}};
  Scorer scorer = make_scorer(p, opt);
  if (opt.mode == ReplayMode::kClosedLoop) add_band_power(scorer, u);
  auto r0 = scorer.residuals({{}});
  if (r0[0].empty()) throw std::runtime_error("the base model fails to run on the record");
  // The torque's samples are scored low-passed, its high band by its power, when the base lacks that
  // band (kPowerMisfit) or when its own loop chatters on a quantised hub angle (an encoder's limit cycle,
  // whose phase no replay follows either).
  if (scorer.power.on) {
    const ChannelTest t = scorer.tests(r0[0], nullptr).at(kPowerChannel);
    if (t.rms >= kPowerMisfit * t.noise || base.spec.sensors.hub_angle.resolution > 0) {
      scorer.split = true;
      scorer.torque_low = calc_low_pass(r.at("hub_torque"), scorer.low_pass);
      r0 = scorer.residuals({{}});
    }
  }
  p.doc = apply_overrides(src);
  p.scales = make_scales(base, r, opt.mode);
  p.effects = make_candidate_effects(base, opt.mode, p.scales, scorer.channels);
  p.names = effect_names();
  const auto& s = base.spec;
  const bool beam = base.nseg > 1;
  p.sensitive = {{"hub.inertia", s.hub_inertia},           {"payload.mass", s.payload_mass},
                 {"payload.inertia", s.payload_inertia},   {"friction.viscous", s.friction.viscous},
                 {"friction.coulomb", s.friction.coulomb}, {"joints.stiffness", beam ? s.joints.stiffness : 0.0},
                 {"joints.damping", beam ? s.joints.damping : 0.0}, {"hub.torque_offset", s.hub_torque_offset}};
  return diagnose_scored(scorer, r0[0], p, opt);
}

}  // namespace ff

namespace ff {

namespace {
std::string json_number(double x) {
  if (!std::isfinite(x)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", x);
  return buf;
}
// A JSON string literal: quotes, backslashes and control characters escaped.
std::string json_string(const std::string& x) {
  std::string out = "\"";
  for (unsigned char c : x) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}
std::string json_map(const std::map<std::string, double>& m) {
  std::string out = "{";
  for (const auto& [k, v] : m) out += (out.size() > 1 ? ", " : "") + (json_string(k) + ": " + json_number(v));
  return out + "}";
}
std::string json_list(const std::vector<std::string>& v) {
  std::string out = "[";
  for (const auto& x : v) out += (out.size() > 1 ? ", " : "") + json_string(x);
  return out + "]";
}

std::string json_bool(bool b) { return b ? "true" : "false"; }

std::string json_tests(const std::map<std::string, ChannelTest>& tests) {
  std::string out = "{";
  for (const auto& [c, t] : tests)
    out += (out.size() > 1 ? ", " : "") + json_string(c) + ": {\"rms\": " + json_number(t.rms) + ", \"noise\": " +
           json_number(t.noise) + ", \"acf_outside\": " + json_number(t.acf_outside) + ", \"ccf_outside\": " +
           json_number(t.ccf_outside) + ", \"mean\": " + json_number(t.mean) + ", \"white\": " + json_bool(t.white) +
           ", \"uncorrelated\": " + json_bool(t.uncorrelated) + ", \"unbiased\": " + json_bool(t.unbiased) +
           ", \"at_floor\": " + json_bool(t.at_floor) + ", \"rss\": " + json_number(t.rss) + ", \"n_eff\": " +
           json_number(t.n_eff) + ", \"bootstrap\": {\"rms\": " + json_number(t.boot_rms) + ", \"acf_outside\": " +
           json_number(t.boot_acf) + ", \"ccf_outside\": " + json_number(t.boot_ccf) + ", \"mean\": " +
           json_number(t.boot_mean) + ", \"within\": " + json_bool(t.within_bootstrap) + "}}";
  return out + "}";
}

// A list of effect fits, one per line at `indent`.
std::string json_effects(const std::vector<EffectFit>& fits, const std::string& indent) {
  std::string out = "[\n";
  for (std::size_t i = 0; i < fits.size(); ++i) {
    const auto& f = fits[i];
    out += indent + "{\"effect\": " + json_string(f.effect) + ", \"params\": " + json_map(f.params) + ", \"stderr\": " +
           json_map(f.stderr_) + ", \"unidentifiable\": " + json_list(f.unidentifiable) + ", \"at_bound\": " +
           json_list(f.at_bound) + ", \"refit\": " + json_list(f.refit) + ", \"fit_percent\": " +
           json_map(f.fit_percent) + ", \"delta_bic\": " + json_number(f.delta_bic) + ", \"n_eff\": " +
           json_number(f.n_eff) + ", \"significant\": " + json_bool(f.significant) + ", \"screened\": " +
           json_bool(f.screened) + ", \"explained\": " + json_bool(f.explained) + ", \"explains\": " +
           json_number(f.explains) + ", \"tests\": " + json_tests(f.tests) + ", \"ok\": " + json_bool(f.ok) +
           (f.note.empty() ? "" : ", \"note\": " + json_string(f.note)) + "}" + (i + 1 < fits.size() ? "," : "") + "\n";
  }
  return out + indent.substr(0, indent.size() >= 2 ? indent.size() - 2 : 0) + "]";
}

// The best partial candidates of an unexplained record: significant ones by the share of the misfit they explain.
std::vector<const EffectFit*> partial_candidates(const Diagnosis& d, std::size_t count = 3) {
  std::vector<const EffectFit*> out;
  for (const auto& f : d.ranking)
    if (f.ok && f.significant) out.push_back(&f);
  std::stable_sort(out.begin(), out.end(), [](const EffectFit* a, const EffectFit* b) { return a->explains > b->explains; });
  if (out.size() > count) out.resize(count);
  return out;
}

}  // namespace

std::string format_diagnosis_json(const Diagnosis& d) {
  std::string out = "{\n  \"mode\": \"" + std::string(replay_mode_name(d.mode)) + "\",\n";
  out += "  \"samples\": " + std::to_string(d.n) + ",\n";
  out += "  \"torque_cutoff_hz\": " + json_number(d.torque_cutoff_hz) + ",\n";
  out += "  \"baseline\": {\"fit_percent\": " + json_map(d.base_fit) + ", \"params\": " + json_map(d.base_params) +
         ", \"refit\": " + json_list(d.refit) + ", \"rss\": " + json_number(d.base_rss) + ", \"n_eff\": " +
         json_number(d.base_n_eff) + ", \"explained\": " + json_bool(d.base_explained) + ", \"tests\": " +
         json_tests(d.base_tests) + "},\n";
  out += "  \"misfit\": [";
  for (std::size_t i = 0; i < d.misfit.size(); ++i) {
    const auto& m = d.misfit[i];
    out += std::string(i ? ", " : "") + "{\"channel\": " + json_string(m.channel) + ", \"fit_percent\": " +
           json_number(m.fit_percent) + ", \"rms\": " + json_number(m.test.rms) + ", \"noise\": " +
           json_number(m.test.noise) + ", \"worst_window\": [" + json_number(m.worst_t0) + ", " + json_number(m.worst_t1) +
           "], \"worst_ratio\": " + json_number(m.worst_ratio) + ", \"peak_hz\": " + json_number(m.peak_hz) +
           ", \"state\": " + json_string(m.state) + ", \"departure\": " + json_number(m.departure) + "}";
  }
  out += "],\n  \"ranking\": " + json_effects(d.ranking, "    ") + ",\n";
  out += "  \"selected\": " + json_effects(d.selected, "    ") + ",\n  \"rounds\": [";
  for (std::size_t i = 0; i < d.rounds.size(); ++i) out += (i ? ", " : "") + json_effects(d.rounds[i], "      ");
  out += "],\n  \"verdict\": " + json_string(d.verdict) + "\n}\n";
  return out;
}

std::string format_diagnosis_text(const Diagnosis& d) {
  std::string out = "baseline fit (" + std::string(replay_mode_name(d.mode)) + "):";
  char buf[512];
  for (const auto& [c, v] : d.base_fit) {
    std::snprintf(buf, sizeof buf, " %s %.2f %%", c.c_str(), v);
    out += buf;
  }
  if (!d.refit.empty()) {
    out += "\n  re-fitted:";
    for (const auto& [p, v] : d.base_params) {
      std::snprintf(buf, sizeof buf, " %s = %.4g", p.c_str(), v);
      out += buf;
    }
  }
  if (std::isfinite(d.torque_cutoff_hz)) {
    std::snprintf(buf, sizeof buf,
                  "\n  hub_torque has high-band power the model lacks: its samples scored below %.3g Hz, its band by its power",
                  d.torque_cutoff_hz);
    out += buf;
  }
  out += "\n  residual (RMS / noise floor, white, uncorrelated with the input):";
  for (const auto& [c, t] : d.base_tests) {
    std::snprintf(buf, sizeof buf, " %s %.3g/%.3g %s %s;", c.c_str(), t.rms, t.noise, t.white ? "white" : "NOT white",
                  t.uncorrelated ? "uncorr." : "CORRELATED");
    out += buf;
  }
  out += "\n\n  rank  effect                      delta BIC   fit % after      parameters\n";
  int rank = 0;
  for (const auto& f : d.ranking) {
    std::string fits, params;
    for (const auto& [c, v] : f.fit_percent) {
      std::snprintf(buf, sizeof buf, "%s%.2f", fits.empty() ? "" : "/", v);
      fits += buf;
    }
    for (const auto& [p, v] : f.params) {
      const double se = f.stderr_.count(p) ? f.stderr_.at(p) : NAN;
      const bool unid = std::find(f.unidentifiable.begin(), f.unidentifiable.end(), p) != f.unidentifiable.end();
      const bool bound = std::find(f.at_bound.begin(), f.at_bound.end(), p) != f.at_bound.end();
      std::snprintf(buf, sizeof buf, unid ? "%s%s = %.4g (unidentifiable)" : std::isfinite(se) ? "%s%s = %.4g ± %.2g" : "%s%s = %.4g",
                    params.empty() ? "" : ", ", p.c_str(), v, se);
      params += buf;
      if (bound) params += " (at its bound)";
    }
    std::snprintf(buf, sizeof buf, "  %4d  %-26s %10.1f%s%s%s %-15s  %s\n", ++rank, f.effect.c_str(), f.delta_bic,
                  f.significant ? "*" : " ", f.ok && f.explained ? "=" : " ", f.screened ? "~" : " ",
                  f.ok ? fits.c_str() : "failed", f.ok ? params.c_str() : f.note.c_str());
    out += buf;
  }
  out += "\n  * significant: delta BIC < " + json_number(kSignificantDeltaBic) +
         " (in effective samples); = after it every channel's residual is noise; ~ screened: the global scan's best "
         "point, not fitted further (its delta BIC an upper bound)\n";
  if (!d.selected.empty()) {
    out += "  selected in turn (each fitted on top of those before it):\n";
    int i = 0;
    for (const auto& f : d.selected) {
      std::string params;
      for (const auto& [p, v] : f.params) {
        std::snprintf(buf, sizeof buf, "%s%s = %.4g", params.empty() ? "" : ", ", p.c_str(), v);
        params += buf;
      }
      std::snprintf(buf, sizeof buf, "    %d. %s: delta BIC %.1f, %s; %s\n", ++i, f.effect.c_str(), f.delta_bic,
                    f.explained ? "with it the record is explained" : "not yet explained", params.c_str());
      out += buf;
    }
    // Each later round's best three, on top of the effects selected before it.
    for (std::size_t r = 0; r < d.rounds.size(); ++r) {
      std::string best;
      for (std::size_t j = 0; j < std::min<std::size_t>(3, d.rounds[r].size()); ++j) {
        const EffectFit& f = d.rounds[r][j];
        std::snprintf(buf, sizeof buf, "%s%s %.1f%s", best.empty() ? "" : ", ", f.effect.c_str(), f.delta_bic,
                      f.ok ? (f.screened ? "~" : "") : " (failed)");
        best += buf;
      }
      std::snprintf(buf, sizeof buf, "    round %zu (%zu tried): %s\n", r + 2, d.rounds[r].size(), best.empty() ? "-" : best.c_str());
      out += buf;
    }
  }
  if (d.verdict == "none") {
    out += "verdict: none - the model explains the record down to its noise\n";
  } else if (d.verdict != "unexplained") {
    out += "verdict: " + d.verdict + (d.selected.size() > 1 ? " are missing\n" : " is missing\n");
  } else {
    out += d.selected.empty() ? "verdict: unexplained - the model misfits the record and no candidate explains it\n"
                              : "verdict: unexplained - with " + join_effects(d.selected) +
                                    " the model still misfits the record and no further candidate is significant\n";
    for (const auto* f : partial_candidates(d)) {
      std::snprintf(buf, sizeof buf, "  %s explains %.0f %% of the misfit above the noise\n", f->effect.c_str(),
                    100.0 * f->explains);
      out += buf;
    }
    for (const auto& m : d.misfit) {
      if (m.test.explained()) continue;
      std::snprintf(buf, sizeof buf, "  %s: fit %.2f %%, residual %.2gx its noise", m.channel.c_str(), m.fit_percent,
                    m.test.noise > 0 ? m.test.rms / m.test.noise : INFINITY);
      out += buf;
      if (std::isfinite(m.worst_t0)) {
        std::snprintf(buf, sizeof buf, ", worst in t = %.1f-%.1f s (%.1fx)", m.worst_t0, m.worst_t1, m.worst_ratio);
        out += buf;
      }
      if (std::isfinite(m.peak_hz)) {
        std::snprintf(buf, sizeof buf, ", peaks at %.2f Hz", m.peak_hz);
        out += buf;
      }
      if (!m.state.empty()) {
        std::snprintf(buf, sizeof buf, ", depends on %s (%.2f)", m.state.c_str(), m.departure);
        out += buf;
      }
      out += "\n";
    }
  }
  return out;
}

}  // namespace ff
