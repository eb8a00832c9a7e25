#include "validate/diagnose.hpp"

#include <ceres/ceres.h>
#include <glog/logging.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "kernel/errors.hpp"
#include "kernel/yaml_reader.hpp"

namespace ff {

ModelSource load_model_source(const std::string& path, const std::vector<std::string>& sets) {
  ModelSource src;
  src.doc = load_yaml_file(path);
  src.path = path;
  for (const auto& s : sets) src.set.push_back(parse_assignment(s));
  build_model(src);  // a bad model or override fails here, before any fitting
  return src;
}

Model build_model(const ModelSource& src, const std::vector<Assignment>& extra) {
  std::vector<Assignment> all = src.set;
  all.insert(all.end(), extra.begin(), extra.end());
  return make_model_with(YAML::Clone(src.doc), src.path, all);
}

namespace {

Assignment assign(const std::string& path, const YAML::Node& value) {
  Assignment a;
  a.path = path;
  a.value = value;
  a.source = "diagnose";
  a.key = path;
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

// The record's scored channels, decimated and normalised: residual = (y - yhat) / sd(y).
struct Scorer {
  const ModelSource* src = nullptr;
  const Record* rec = nullptr;
  ReplayMode mode = ReplayMode::kClosedLoop;
  std::vector<std::string> channels;
  std::vector<std::size_t> index;  // decimated sample indices
  std::vector<double> scale;       // 1 / sd per channel

  int size() const { return static_cast<int>(channels.size() * index.size()); }

  // Residuals of each model (empty vector for a failed lane).
  std::vector<std::vector<double>> residuals(const std::vector<Model>& models) const {
    // One batch when the models share a shape; one at a time when (e.g.) their substeps differ.
    std::vector<Prediction> p;
    try {
      p = replay(models, *rec, mode);
    } catch (const std::invalid_argument&) {
      p.clear();
      for (const auto& m : models) p.push_back(replay(std::span<const Model>(&m, 1), *rec, mode)[0]);
    }
    std::vector<std::vector<double>> out(models.size());
    for (std::size_t i = 0; i < models.size(); ++i) {
      if (!p[i].ok) continue;
      auto& r = out[i];
      for (std::size_t c = 0; c < channels.size(); ++c) {
        const auto& y = rec->at(channels[c]);
        const auto& yh = p[i].channels.at(channels[c]);
        for (std::size_t k : index) r.push_back((y[k] - yh[k]) * scale[c]);
      }
      for (double x : r)
        if (!std::isfinite(x)) {
          r.clear();
          break;
        }
    }
    return out;
  }

  std::map<std::string, double> fit_percent(const Model& m) const {
    std::map<std::string, double> out;
    const auto p = replay(std::span<const Model>(&m, 1), *rec, mode)[0];
    for (const auto& c : channels) out[c] = p.ok ? calc_fit(rec->at(c), p.channels.at(c)).percent : -INFINITY;
    return out;
  }
};

double sum_squares(const std::vector<double>& r) {
  double s = 0.0;
  for (double x : r) s += x * x;
  return s;
}

// A parameter's value from its fitted coordinate theta, and back: log(value) for a positive
// parameter, value / scale for a signed (linear) one.
double param_value(const EffectParam& p, double theta) { return p.linear ? theta * p.scale : std::exp(theta); }
double param_theta(const EffectParam& p, double value) { return p.linear ? value / p.scale : std::log(value); }

// The effect's model for fitted coordinates theta (and the grid value, if any).
std::vector<Assignment> effect_assignments(const Effect& e, const double* theta, double grid_value) {
  std::vector<Assignment> a;
  for (const auto& [path, value] : e.set) a.push_back(assign(path, YAML::Load(value)));
  if (!e.grid_path.empty()) a.push_back(assign(e.grid_path, number_node(e.grid_path, grid_value)));
  for (std::size_t i = 0; i < e.params.size(); ++i)
    a.push_back(assign(e.params[i].path, YAML::Node(param_value(e.params[i], theta[i]))));
  return a;
}

// Ceres cost: the normalised residuals of the model with the effect at log-parameters theta. The
// forward-difference Jacobian's columns run as lanes of the same batch as the point itself.
class ReplayCost : public ceres::CostFunction {
 public:
  ReplayCost(const Scorer& sc, const Effect& e, double grid_value) : sc_(sc), e_(e), grid_(grid_value) {
    set_num_residuals(sc.size());
    mutable_parameter_block_sizes()->push_back(static_cast<int>(e.params.size()));
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const int p = static_cast<int>(e_.params.size());
    std::vector<double> theta(parameters[0], parameters[0] + p);
    const double step = 1e-5;
    std::vector<Model> models;
    try {
      models.push_back(build_model(*sc_.src, effect_assignments(e_, theta.data(), grid_)));
      if (models[0].substeps > kMaxFitSubsteps) return false;  // too stiff to be worth a trial
      if (jacobians && jacobians[0])
        for (int j = 0; j < p; ++j) {
          auto t = theta;
          t[j] += step;
          models.push_back(build_model(*sc_.src, effect_assignments(e_, t.data(), grid_)));
        }
    } catch (const std::exception&) {
      return false;  // outside the model's valid range: Ceres shortens the step
    }
    const auto r = sc_.residuals(models);
    for (const auto& ri : r)
      if (ri.empty()) return false;
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

// Least-squares fit of one effect: the grid (if any) first, then the continuous parameters.
// `shared`: the last parameters of e are re-fits of existing ones, counted in the baseline's k too.
EffectFit fit_one(const Scorer& sc, const Effect& e, double base_rss, const std::map<std::string, double>& base_fit, int n,
                  int max_iterations, int shared = 0) {
  EffectFit f;
  f.effect = e.name;
  f.physics = e.physics;
  f.switches = e.set;
  double grid_value = 0.0;
  std::vector<double> theta;
  for (const auto& p : e.params) theta.push_back(param_theta(p, p.initial));
  for (std::size_t j = e.params.size() - shared; j < e.params.size(); ++j) f.refit.push_back(e.params[j].path);
  try {
    if (!e.grid_path.empty()) {
      std::vector<Model> models;
      for (double g : e.grid) models.push_back(build_model(*sc.src, effect_assignments(e, theta.data(), g)));
      const auto r = sc.residuals(models);
      double best = INFINITY;
      for (std::size_t i = 0; i < r.size(); ++i)
        if (!r[i].empty() && sum_squares(r[i]) < best) {
          best = sum_squares(r[i]);
          grid_value = e.grid[i];
        }
      if (!std::isfinite(best)) throw std::runtime_error("every grid value failed");
      f.params[e.grid_path] = grid_value;
      f.stderr_[e.grid_path] = NAN;
      f.rss = best;
    }
    if (!e.params.empty()) {
      // Multi-start: every positive starting value scaled together by 1/30 .. 30, run as lanes; the best starts.
      std::vector<double> factors;
      for (int i = -6; i <= 6; ++i) factors.push_back(std::pow(30.0, i / 6.0));
      std::vector<Model> starts;
      std::vector<double> used;
      for (double fct : factors) {
        std::vector<double> t = theta;
        for (std::size_t j = 0; j < t.size(); ++j)
          if (!e.params[j].linear) t[j] += std::log(fct);
        try {
          starts.push_back(build_model(*sc.src, effect_assignments(e, t.data(), grid_value)));
          used.push_back(fct);
        } catch (const std::exception&) {
        }
      }
      if (!starts.empty()) {
        const auto r = sc.residuals(starts);
        double best = INFINITY, pick = 1.0;
        for (std::size_t i = 0; i < r.size(); ++i)
          if (!r[i].empty() && sum_squares(r[i]) < best) {
            best = sum_squares(r[i]);
            pick = used[i];
          }
        for (std::size_t j = 0; j < theta.size(); ++j)
          if (!e.params[j].linear) theta[j] += std::log(pick);
      }
      ceres::Problem problem;
      auto* cost = new ReplayCost(sc, e, grid_value);
      problem.AddResidualBlock(cost, nullptr, theta.data());
      // Within a factor 1000 of the start either way: far enough for any plausible value, and a
      // bound on the stiffness (and so the substeps) a trial step can ask for. Signed: within ±scale.
      for (std::size_t j = 0; j < theta.size(); ++j) {
        const auto& pj = e.params[j];
        const double lo = pj.linear ? -1.0 : std::log(pj.initial) - std::log(1e3);
        const double hi = pj.linear ? 1.0 : std::log(pj.initial) + std::log(1e3);
        problem.SetParameterLowerBound(theta.data(), static_cast<int>(j), lo);
        problem.SetParameterUpperBound(theta.data(), static_cast<int>(j), hi);
        theta[j] = std::clamp(theta[j], lo, hi);
      }
      ceres::Solver::Options o;
      o.linear_solver_type = ceres::DENSE_QR;
      o.max_num_iterations = max_iterations;
      o.num_threads = 1;
      o.logging_type = ceres::SILENT;
      o.function_tolerance = 1e-8;
      ceres::Solver::Summary summary;
      ceres::Solve(o, &problem, &summary);
      // Standard errors from the Jacobian at the optimum: cov = s^2 (J^T J)^+, s^2 = RSS / (n - k), by
      // the SVD J = U S V^T. A parameter with weight in a (near-)null direction is not identifiable:
      // the record cannot tell it from the others; its standard error is NaN.
      const int p = static_cast<int>(theta.size());
      std::vector<double> res(sc.size()), jac(static_cast<std::size_t>(sc.size()) * p);
      const double* params[] = {theta.data()};
      double* jacs[] = {jac.data()};
      if (!cost->Evaluate(params, res.data(), jacs)) throw std::runtime_error("the fitted model failed to run");
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
      cov *= f.rss / std::max(1, n - p);
      for (int j = 0; j < p; ++j) {
        const auto& pj = e.params[j];
        const double value = param_value(pj, theta[j]);
        const double unit = pj.linear ? pj.scale : value;  // d value / d theta
        f.params[pj.path] = value;
        f.stderr_[pj.path] = null[j] ? NAN : std::abs(unit) * std::sqrt(std::max(cov(j, j), 0.0));
        if (null[j]) f.unidentifiable.push_back(pj.path);
      }
    }
    f.k = static_cast<int>(e.params.size()) - shared + (e.grid_path.empty() ? 0 : 1);
    f.delta_bic = n * std::log(f.rss / base_rss) + f.k * std::log(static_cast<double>(n));
    f.fit_percent = sc.fit_percent(build_model(*sc.src, f.assignments()));
    double gain = -INFINITY;
    for (const auto& [c, v] : f.fit_percent) gain = std::max(gain, v - base_fit.at(c));
    f.significant = f.delta_bic < kSignificantDeltaBic && gain >= kMinFitGain;
    f.ok = true;
  } catch (const std::exception& ex) {
    f.ok = false;
    f.note = ex.what();
  }
  return f;
}

Scorer make_scorer(const ModelSource& src, const Record& r, const DiagnoseOptions& opt) {
  Scorer sc;
  sc.src = &src;
  sc.rec = &r;
  sc.mode = opt.mode;
  sc.channels = scored_channels(opt.mode, r);
  const std::size_t stride = std::max<std::size_t>(1, r.size() / std::max(1, opt.max_samples));
  for (std::size_t k = 0; k < r.size(); k += stride) sc.index.push_back(k);
  for (const auto& c : sc.channels) {
    const auto& y = r.at(c);
    double mean = 0.0, var = 0.0;
    for (double x : y) mean += x;
    mean /= y.size();
    for (double x : y) var += (x - mean) * (x - mean);
    const double sd = std::sqrt(var / y.size());
    sc.scale.push_back(sd > 0 ? 1.0 / sd : 1.0);
  }
  return sc;
}

EffectScales make_scales(const Model& base, const Record& r, ReplayMode mode) {
  EffectScales s;
  const auto p = replay(std::span<const Model>(&base, 1), r, mode)[0];
  const auto& tau = mode == ReplayMode::kClosedLoop || !r.has("hub_torque") ? p.channels.at("hub_torque") : r.at("hub_torque");
  const auto& w = p.channels.count("hub_rate") ? p.channels.at("hub_rate") : std::vector<double>{1.0};
  auto rms = [](const std::vector<double>& x) {
    double s2 = 0.0;
    for (double v : x) s2 += v * v;
    return std::sqrt(s2 / x.size());
  };
  s.torque_rms = rms(tau);
  s.rate_rms = r.has("hub_rate") ? rms(r.at("hub_rate")) : rms(w);
  for (double x : tau) s.torque_max = std::max(s.torque_max, std::abs(x));
  return s;
}

// `--refit auto`: the model's existing parameters that are plausible calibration targets (nonzero),
// most sensitive first: those whose 1 % change moves the normalised residual by more than a tenth of
// what the most sensitive one's does. One batch of lanes.
std::vector<std::string> rank_sensitive(const Scorer& sc, const ModelSource& src, const Model& base) {
  const auto& s = base.spec;
  const bool beam = base.nseg > 1;
  const std::pair<const char*, double> targets[] = {
      {"hub.inertia", s.hub_inertia},           {"payload.mass", s.payload_mass},
      {"payload.inertia", s.payload_inertia},   {"friction.viscous", s.friction.viscous},
      {"friction.coulomb", s.friction.coulomb}, {"joints.stiffness", beam ? s.joints.stiffness : 0.0},
      {"joints.damping", beam ? s.joints.damping : 0.0}, {"hub.torque_offset", s.hub_torque_offset}};
  std::vector<std::string> paths, out;
  std::vector<Model> models = {base};
  for (const auto& [p, x] : targets) {
    if (x == 0.0) continue;
    try {
      models.push_back(build_model(src, {assign(p, YAML::Node(1.01 * x))}));
      paths.push_back(p);
    } catch (const std::exception&) {  // e.g. stiction below a raised Coulomb level: not a target
    }
  }
  if (paths.empty()) return out;
  const auto r = sc.residuals(models);
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

// Does the effect fit (or search) this path itself?
bool fits_path(const Effect& e, const std::string& path) {
  if (e.grid_path == path) return true;
  for (const auto& p : e.params)
    if (p.path == path) return true;
  return false;
}

}  // namespace

std::vector<Assignment> EffectFit::assignments() const {
  std::vector<Assignment> a;
  for (const auto& [path, value] : switches) a.push_back(assign(path, YAML::Load(value)));
  for (const auto& [path, value] : params) a.push_back(assign(path, number_node(path, value)));
  return a;
}

EffectFit fit_effect(const ModelSource& src, const Record& r, const DiagnoseOptions& opt, const std::string& name) {
  DiagnoseOptions o = opt;
  o.only = {name};
  const Diagnosis d = diagnose(src, r, o);
  if (d.ranking.empty()) throw std::invalid_argument("effect '" + name + "' does not apply in " + replay_mode_name(opt.mode) + " mode");
  return d.ranking[0];
}

Diagnosis diagnose(const ModelSource& src, const Record& r, const DiagnoseOptions& opt) {
  // Ceres reports failed steps through glog; they are results here, not news.
  static const bool quiet = [] {
    FLAGS_minloglevel = google::GLOG_FATAL;
    return true;
  }();
  (void)quiet;
  for (const auto& c : replay_inputs(opt.mode))
    if (!r.has(c)) throw ConfigError(r.source, 1, c, std::string("missing column '") + c + "', needed in " + replay_mode_name(opt.mode) + " mode");
  const Model base = build_model(src);
  Diagnosis d;
  d.mode = opt.mode;
  const Scorer sc = make_scorer(src, r, opt);
  d.channels = sc.channels;
  d.n = sc.size();
  const auto r0 = sc.residuals({base});
  if (r0[0].empty()) throw std::runtime_error("the base model fails to run on the record");
  d.base_rss = sum_squares(r0[0]);
  d.base_fit = sc.fit_percent(base);
  const EffectScales scales = make_scales(base, r, opt.mode);
  auto effects = make_candidate_effects(base, opt.mode, scales);
  for (const auto& name : opt.only) {
    bool known = false;
    for (const auto& n : effect_names()) known |= n == name;
    if (!known) throw std::invalid_argument("unknown effect '" + name + "'");
  }
  if (!opt.only.empty())
    effects.erase(std::remove_if(effects.begin(), effects.end(),
                                 [&](const Effect& e) {
                                   return std::find(opt.only.begin(), opt.only.end(), e.name) == opt.only.end();
                                 }),
                  effects.end());
  // Re-fitted existing parameters. Named (--refit a,b): the same for the baseline and every effect,
  // which then drops them from its own. `auto`: for each effect the (at most two) most sensitive
  // existing parameters it does not fit itself, its Delta BIC taken against the baseline re-fitted
  // with the same ones. "none" (or nothing): no re-fit.
  const bool automatic = opt.refit == std::vector<std::string>{"auto"};
  const bool named = !automatic && !opt.refit.empty() && opt.refit != std::vector<std::string>{"none"};
  YAML::Node doc = YAML::Clone(src.doc);
  for (const auto& a : src.set) set_path(doc, a.path, a.value, "--set");
  auto refit_param = [&](const std::string& path) {
    const YAML::Node v = get_path(doc, path);
    if (!v) throw std::invalid_argument("--refit: the model does not set '" + path + "'");
    try {
      return make_effect_param(path, v.as<double>(), scales);
    } catch (const YAML::Exception&) {
      throw std::invalid_argument("--refit: '" + path + "' is not a number in the model");
    }
  };
  const std::vector<std::string> pool = automatic ? rank_sensitive(sc, src, base) : named ? opt.refit : std::vector<std::string>{};
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
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t i = 0; i < sets.size(); ++i) {
    if (sets[i].empty()) {
      fitted[i].ok = true;
      fitted[i].rss = d.base_rss;
      fitted[i].fit_percent = d.base_fit;
      continue;
    }
    Effect baseline{"baseline", "the model as it is, its re-fitted parameters fitted", {}, {}, "", {}, ""};
    try {
      for (const auto& p : sets[i]) baseline.params.push_back(refit_param(p));
    } catch (const std::exception& ex) {
      fitted[i].note = ex.what();
      continue;
    }
    fitted[i] = fit_one(sc, baseline, d.base_rss, d.base_fit, d.n, opt.max_iterations);
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
  // Each effect: its own parameters, then its re-fitted ones starting where its baseline put them.
  std::vector<std::vector<std::string>> refits;
  for (auto& e : effects) refits.push_back(refit_of(e));
  for (std::size_t i = 0; i < effects.size(); ++i)
    for (const auto& p : refits[i]) {
      EffectParam q = refit_param(p);
      q.initial = baselines.at(refits[i]).params.at(p);
      effects[i].params.push_back(q);
    }
  d.ranking.resize(effects.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t i = 0; i < effects.size(); ++i) {
    const EffectFit& b = baselines.at(refits[i]);
    d.ranking[i] = fit_one(sc, effects[i], b.rss, b.fit_percent, d.n, opt.max_iterations, static_cast<int>(refits[i].size()));
  }
  std::stable_sort(d.ranking.begin(), d.ranking.end(), [](const EffectFit& a, const EffectFit& b) {
    if (a.ok != b.ok) return a.ok;
    return a.delta_bic < b.delta_bic;
  });
  // Occam: an effect ranked above the simpler one it extends must fit visibly better, else the simpler goes first.
  for (std::size_t i = 0; i < effects.size(); ++i) {
    if (effects[i].extends.empty()) continue;
    auto rich = std::find_if(d.ranking.begin(), d.ranking.end(), [&](const EffectFit& f) { return f.effect == effects[i].name; });
    auto simple = std::find_if(d.ranking.begin(), d.ranking.end(), [&](const EffectFit& f) { return f.effect == effects[i].extends; });
    if (rich == d.ranking.end() || simple == d.ranking.end() || simple < rich || !simple->ok) continue;
    double gain = -INFINITY;
    for (const auto& [c, v] : rich->fit_percent) gain = std::max(gain, v - simple->fit_percent.at(c));
    if (gain < kNestedFitMargin) std::rotate(rich, simple, simple + 1);
  }
  if (!d.ranking.empty() && d.ranking[0].ok && d.ranking[0].significant) d.verdict = d.ranking[0].effect;
  return d;
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
}  // namespace

std::string format_diagnosis_json(const Diagnosis& d) {
  std::string out = "{\n  \"mode\": \"" + std::string(replay_mode_name(d.mode)) + "\",\n";
  out += "  \"samples\": " + std::to_string(d.n) + ",\n";
  out += "  \"baseline\": {\"fit_percent\": " + json_map(d.base_fit) + ", \"params\": " + json_map(d.base_params) +
         ", \"refit\": " + json_list(d.refit) + ", \"rss\": " + json_number(d.base_rss) + "},\n";
  out += "  \"ranking\": [\n";
  for (std::size_t i = 0; i < d.ranking.size(); ++i) {
    const auto& f = d.ranking[i];
    out += "    {\"effect\": " + json_string(f.effect) + ", \"params\": " + json_map(f.params) + ", \"stderr\": " +
           json_map(f.stderr_) + ", \"unidentifiable\": " + json_list(f.unidentifiable) + ", \"refit\": " +
           json_list(f.refit) + ", \"fit_percent\": " + json_map(f.fit_percent) + ", \"delta_bic\": " +
           json_number(f.delta_bic) + ", \"significant\": " + (f.significant ? "true" : "false") +
           ", \"ok\": " + (f.ok ? "true" : "false") + (f.note.empty() ? "" : ", \"note\": " + json_string(f.note)) + "}" +
           (i + 1 < d.ranking.size() ? "," : "") + "\n";
  }
  out += "  ],\n  \"verdict\": " + json_string(d.verdict) + "\n}\n";
  return out;
}

std::string format_diagnosis_text(const Diagnosis& d) {
  std::string out = "baseline fit (" + std::string(replay_mode_name(d.mode)) + "):";
  char buf[256];
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
      std::snprintf(buf, sizeof buf, unid ? "%s%s = %.4g (unidentifiable)" : std::isfinite(se) ? "%s%s = %.4g ± %.2g" : "%s%s = %.4g",
                    params.empty() ? "" : ", ", p.c_str(), v, se);
      params += buf;
    }
    std::snprintf(buf, sizeof buf, "  %4d  %-26s %10.1f%s  %-15s  %s\n", ++rank, f.effect.c_str(), f.delta_bic,
                  f.significant ? "*" : " ", f.ok ? fits.c_str() : "failed", f.ok ? params.c_str() : f.note.c_str());
    out += buf;
  }
  out += "\n  * significant: delta BIC < " + json_number(kSignificantDeltaBic) + "\n";
  out += "verdict: " + (d.verdict == "none" ? std::string("none of the candidates is missing") : d.verdict + " is missing") + "\n";
  return out;
}

}  // namespace ff
