// Work-precision, side by side in one run: error against CVODE at rtol 1e-10 versus cost, for every
// integrator of flexfarm and of MuJoCo (2.2) at several steps, on three cases:
//   rig6, rig24  the reference rig (docs/reference-rig.md, bench/mujoco_rig.hpp) with N = 6 and 24
//                segments, the reference motion (0 -> 0.5 rad in 3 s, then held) with the PD at 1 kHz
//                and the same zero-order hold in both simulators; h = 1 ms / K with K substeps.
//                Error: the tip deflection's RMS over the run against the reference (mujoco_compare's
//                definition), one variant (the rig's variants are copies); its scale is the
//                reference's tip-deflection RMS.
//   arm          the rigid 6-DOF arm of bench/tree_arm.hpp (tree_mujoco's rigid case): from an
//                offset pose at a swing, a constant torque, springs and dampers. Error: the largest
//                joint-angle error at the end (t = --arm-seconds) over all joints, variants 0 and
//                M - 1 (tree_mujoco's definition); its scale is 1 rad.
// The reference of each case is flexfarm's CVODE (BDF, dense) at rtol 1e-10, atol 1e-13 (rig; the
// kernel's CVODE, restarted at every controller sample) or 1e-12 (arm; multibody/tree_cvode, one
// advance over the run), checked against flexfarm RK4 at its smallest step.
// Methods: flexfarm midpoint, SDIRK2 and RK4 at several h, and CVODE at several rtol (atol = rtol /
// 1000) as its own curve; MuJoCo Euler (its default; semi-implicit in the joint damping), implicit
// and RK4 at several h. A setting whose run leaves the finite numbers (MuJoCo's divergence warnings,
// a flexfarm lane's status) or whose error exceeds 10 times the scale is "unstable", not a number.
// Cost: wall seconds per variant-second simulated, M variants on --threads threads (OpenMP over
// batches of W = 8 lanes for flexfarm, over variants with one mjData each for MuJoCo), the median of
// --reps repetitions taken round-robin over the settings; a setting whose timed run would take more
// than --budget seconds is timed on the first part of the run (rig: whole controller periods; arm:
// whole steps), all variants.
// Output: the tables, the reading (MuJoCo's default against flexfarm at equal or better error, and
// the cheapest of each side at matched errors), and with --csv FILE one row per setting.
// Run: work_precision [--case rig6|rig24|arm|all] [--quick] [--csv FILE] [--threads 2] [--reps 3]
//                     [--budget 1] [--rig6-seconds 5] [--rig24-seconds 1] [--arm-seconds 2]
#include <mujoco/mujoco.h>
#include <omp.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/mujoco_rig.hpp"
#include "bench/mujoco_tree.hpp"
#include "bench/mujoco_util.hpp"
#include "bench/tree_arm.hpp"
#include "kernel/batch.hpp"
#include "kernel/model.hpp"
#include "kernel/simulate.hpp"
#include "multibody/tree_cvode.hpp"

namespace {

using ff::bench::Method;

struct Options {
  std::string which = "all", csv;
  bool quick = false;
  int threads = 2, reps = 3;
  double budget = 1.0;  // s a timed run may take
  double rig6_seconds = 5.0, rig24_seconds = 1.0, arm_seconds = 2.0;
};

constexpr int kLanes = 8;

// One (method, step) setting of one simulator.
struct Point {
  std::string sim, method, setting;  // "flexfarm" | "MuJoCo"; "RK4", ...; "h=1ms" or "rtol=1e-06"
  double h = NAN;                    // s; NAN for CVODE
  std::function<double()> error_run; // the error (NAN or inf: unstable); run once
  // The timed run over `window` s of simulated time for all variants (made once, then repeated).
  std::function<std::function<void()>(double window)> make_timed;
  bool stable = false;
  double error = NAN, sec_per_sim_s = NAN;  // sec_per_sim_s: the error run's wall s per simulated s
  double window = NAN, cost = NAN;          // cost: wall s per variant-second, M variants, all threads
  int inner = 1;
};

struct CaseResult {
  std::string name, unit;
  double scale = 1.0, seconds = 0.0, control_period = 0.0;  // control_period: the window's grain
  int M = 0;
  std::vector<Point> points;
};

std::string fmt(const char* f, double x) {
  char b[64];
  std::snprintf(b, sizeof b, f, x);
  return b;
}

std::string h_label(double h) {
  return h >= 1e-3 ? fmt("%gms", h * 1e3) : fmt("%gus", h * 1e6);
}

Point fixed_step_point(const char* sim, const char* method, double h) {
  Point p;
  p.sim = sim;
  p.method = method;
  p.h = h;
  p.setting = "h=" + h_label(h);
  return p;
}

Point cvode_point(double rtol) {
  Point p;
  p.sim = "flexfarm";
  p.method = "CVODE";
  p.setting = fmt("rtol=%g", rtol);
  return p;
}

// An integrator of a sweep: its name in the tables, its key, and a guess of its cost a step (the
// dearest error runs start first).
template <class Key>
struct Integrators {
  const char* name;
  Key k;
  double w;
};

// Runs every error run (in parallel, dearest first as guessed by `weight`), then times the stable
// settings: each timed run planned to at most opt.budget s from its error run's speed, repeated to
// ~0.2 s when shorter, the repetitions round-robin.
void measure(CaseResult& cr, const Options& opt, const std::vector<double>& weight) {
  const int n = static_cast<int>(cr.points.size());
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return weight[a] > weight[b]; });
  const auto t0 = std::chrono::steady_clock::now();
#pragma omp parallel for num_threads(opt.threads) schedule(dynamic)
  for (int j = 0; j < n; ++j) {
    Point& p = cr.points[order[j]];
    const double t = ff::bench::time_it([&] { p.error = p.error_run(); });
    p.stable = std::isfinite(p.error) && p.error <= 10.0 * cr.scale;
    p.sec_per_sim_s = t / cr.seconds;
  }
  std::printf("errors: %d settings in %.0f s\n", n, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  std::vector<std::function<void()>> runs(n);
  std::vector<std::vector<double>> times(n);
  for (int i = 0; i < n; ++i) {
    Point& p = cr.points[i];
    if (!p.stable) continue;
    // One variant on one thread took sec_per_sim_s; M variants on the threads, a window of w s:
    const double est_per_s = p.sec_per_sim_s * cr.M / opt.threads;
    double w = std::min(cr.seconds, opt.budget / est_per_s);
    const double grain = std::isnan(p.h) ? cr.control_period : std::max(cr.control_period, p.h);
    w = std::max(grain, std::floor(w / grain + 1e-9) * grain);
    p.window = std::min(w, cr.seconds);
    const double est = est_per_s * p.window;
    p.inner = est < 0.2 ? static_cast<int>(std::ceil(0.2 / std::max(est, 1e-4))) : 1;
    runs[i] = p.make_timed(p.window);
  }
  const auto t1 = std::chrono::steady_clock::now();
  for (int r = 0; r < opt.reps; ++r)
    for (int i = 0; i < n; ++i) {
      Point& p = cr.points[i];
      if (!p.stable) continue;
      times[i].push_back(ff::bench::time_it([&] {
                           for (int k = 0; k < p.inner; ++k) runs[i]();
                         }) / p.inner);
    }
  for (int i = 0; i < n; ++i) {
    Point& p = cr.points[i];
    if (p.stable) p.cost = ff::bench::median(times[i]) / (cr.M * p.window);
  }
  std::printf("timing: %d reps in %.0f s\n", opt.reps, std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count());
}

// ---------------------------------------------------------------- the rig

CaseResult rig_case(int nseg, double seconds, const Options& opt) {
  CaseResult cr;
  cr.name = "rig" + std::to_string(nseg);
  cr.unit = "m";
  cr.seconds = seconds;
  cr.M = 16;
  auto spec = [&](ff::Integrator k, int sub, double secs, double rtol) {
    ff::ModelSpec s = ff::bench::rig_spec(nseg, k, sub, secs);
    if (rtol > 0) s.simulation.rtol = rtol, s.simulation.atol = rtol * 1e-3;
    return s;
  };
  const auto mp = std::make_shared<const ff::Model>(ff::make_model(ff::bench::rig_spec(nseg, ff::Integrator::kRk4, 0, seconds)));
  const ff::Model& m = *mp;
  cr.control_period = m.control_period;
  const long nsamples = std::lround(m.duration / m.control_period) + 1;
  std::printf("\n=== reference rig, N = %d: %g s, M = %d variants, %d threads, median of %d ===\n", nseg, seconds, cr.M,
              opt.threads, opt.reps);

  // The MuJoCo rig must be flexfarm's rig (as mujoco_compare checks).
  mjModel* base = ff::bench::load_mjcf(ff::bench::rig_mjcf(m, "Euler", 1));
  const double dM = ff::bench::mass_matrix_difference(base, m);
  if (!(dM <= 1e-6) || !ff::bench::mujoco_inertia_as_written(base, m))
    throw std::runtime_error("the MuJoCo rig differs from flexfarm's");
  std::shared_ptr<mjModel> keep(base, mj_deleteModel);

  // Reference: CVODE dense at rtol 1e-10, atol 1e-13.
  ff::ModelSpec rs = spec(ff::Integrator::kCvodeDense, 0, seconds, 0);
  rs.simulation.rtol = 1e-10;
  rs.simulation.atol = 1e-13;
  std::vector<double> ref;
  const double tref = ff::bench::time_it([&] {
    const ff::BatchRun r = ff::simulate(ff::make_batch(std::vector<ff::Model>{ff::make_model(rs)}));
    if (r.status[0] != ff::LaneStatus::kOk) throw std::runtime_error("the reference failed");
    ref = r.traces[0].tip_deflection;
  });
  cr.scale = ff::bench::rms(ref);
  std::printf("reference: CVODE dense rtol 1e-10 atol 1e-13, %.1f s; tip deflection RMS %.4g mm (the scale)\n", tref,
              1e3 * cr.scale);
  auto ff_error = [=](ff::ModelSpec s) -> double {
    const ff::BatchRun r = ff::simulate(ff::make_batch(std::vector<ff::Model>{ff::make_model(s)}));
    if (r.status[0] != ff::LaneStatus::kOk) return INFINITY;
    return ff::bench::compare_tips(r.traces[0].tip_deflection, ref).rms;
  };
  auto ff_timed = [=, M = cr.M, threads = opt.threads](ff::ModelSpec s) {
    return [=](double window) -> std::function<void()> {
      ff::ModelSpec sw = s;
      sw.simulation.duration = window;
      auto bm = std::make_shared<ff::BatchModel>(ff::make_batch(std::vector<ff::Model>(kLanes, ff::make_model(sw))));
      return [bm, M, threads] {
        const int nb = M / kLanes;
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int b = 0; b < nb; ++b) ff::simulate(*bm);
      };
    };
  };

  const std::vector<int> ff_subs = opt.quick ? std::vector<int>{1, 4, 16, 64} : std::vector<int>{1, 2, 4, 8, 16, 32, 64};
  const std::vector<int> mj_subs =
      opt.quick ? std::vector<int>{1, 4, 16, 64, 256} : std::vector<int>{1, 2, 4, 8, 16, 32, 64, 128, 256};
  const std::vector<double> rtols =
      opt.quick ? std::vector<double>{1e-4, 1e-6, 1e-8} : std::vector<double>{1e-4, 1e-5, 1e-6, 1e-7, 1e-8};
  std::vector<double> weight;
  const Integrators<ff::Integrator> ffm[3] = {
      {"midpoint", ff::Integrator::kMidpoint, 1}, {"SDIRK2", ff::Integrator::kSdirk2, 2}, {"RK4", ff::Integrator::kRk4, 4}};
  for (const auto& f : ffm)
    for (int K : ff_subs) {
      Point p = fixed_step_point("flexfarm", f.name, m.control_period / K);
      const ff::ModelSpec s = spec(f.k, K, seconds, 0);
      p.error_run = [=] { return ff_error(s); };
      p.make_timed = ff_timed(s);
      cr.points.push_back(p);
      weight.push_back(f.w * K * nseg);
    }
  for (double rtol : rtols) {
    Point p = cvode_point(rtol);
    const ff::ModelSpec s = spec(ff::Integrator::kCvodeDense, 0, seconds, rtol);
    p.error_run = [=] { return ff_error(s); };
    p.make_timed = ff_timed(s);
    cr.points.push_back(p);
    weight.push_back(1e9);  // unknown: first
  }
  const Integrators<int> mjm[3] = {{"Euler", mjINT_EULER, 1}, {"implicit", mjINT_IMPLICIT, 2}, {"RK4", mjINT_RK4, 4}};
  for (const auto& f : mjm)
    for (int K : mj_subs) {
      Point p = fixed_step_point("MuJoCo", f.name, m.control_period / K);
      // A private copy of the model with this integrator and step.
      std::shared_ptr<mjModel> mm(mj_copyModel(nullptr, base), mj_deleteModel);
      mm->opt.integrator = f.k;
      mm->opt.timestep = m.control_period / K;
      p.error_run = [=] {
        mjData* d = mj_makeData(mm.get());
        std::vector<double> tip(nsamples);
        const bool ok = ff::bench::run_rig_mujoco(mm.get(), d, *mp, K, nsamples, tip.data());
        mj_deleteData(d);
        return ok ? ff::bench::compare_tips(tip, ref).rms : INFINITY;
      };
      p.make_timed = [=, M = cr.M, threads = opt.threads](double window) -> std::function<void()> {
        const long ns = std::lround(window / mp->control_period) + 1;
        auto data = std::make_shared<std::vector<std::shared_ptr<mjData>>>();
        for (int v = 0; v < M; ++v) data->emplace_back(mj_makeData(mm.get()), mj_deleteData);
        auto tips = std::make_shared<std::vector<std::vector<double>>>(M, std::vector<double>(ns));
        return [=] {
#pragma omp parallel for num_threads(threads) schedule(static)
          for (int v = 0; v < M; ++v) ff::bench::run_rig_mujoco(mm.get(), (*data)[v].get(), *mp, K, ns, (*tips)[v].data());
        };
      };
      cr.points.push_back(p);
      weight.push_back(3.0 * f.w * K * nseg);
    }
  measure(cr, opt, weight);
  // Check: flexfarm RK4 at its smallest step against the reference.
  for (const Point& p : cr.points)
    if (p.method == "RK4" && p.sim == "flexfarm" && p.h == m.control_period / ff_subs.back())
      std::printf("check: flexfarm RK4 at h = %s differs from the reference by %.3g mm RMS (%.2g of the scale)\n",
                  h_label(p.h).c_str(), 1e3 * p.error, p.error / cr.scale);
  return cr;
}

// ---------------------------------------------------------------- the rigid 6-DOF arm

CaseResult arm_case(double seconds, const Options& opt) {
  CaseResult cr;
  cr.name = "arm";
  cr.unit = "rad";
  cr.scale = 1.0;
  cr.seconds = seconds;
  cr.M = 64;
  cr.control_period = 1e-3;  // the timed windows: whole milliseconds (or whole steps when longer)
  const ff::bench::TreeCase c = ff::bench::rigid_arm_case();
  auto cp = std::make_shared<const ff::bench::TreeCase>(c);
  const int M = cr.M;
  std::vector<ff::TreeSpec> specs;
  for (int v = 0; v < M; ++v) specs.push_back(c.spec(ff::bench::variant_scale(v, M)));
  const int nv = ff::make_tree(specs[0]).nv();
  // flexfarm: M / W batches of W lanes with the torque; MuJoCo: one model per variant.
  auto batches = std::make_shared<std::vector<ff::TreeLanes>>();
  auto taus = std::make_shared<std::vector<std::vector<double>>>();
  for (int b = 0; b < M / kLanes; ++b) {
    std::vector<ff::Tree> trees;
    for (int l = 0; l < kLanes; ++l) trees.push_back(ff::make_tree(specs[b * kLanes + l]));
    batches->push_back(ff::make_tree_lanes(trees));
    std::vector<double> tau(static_cast<std::size_t>(nv) * kLanes);
    for (int j = 0; j < nv; ++j)
      for (int l = 0; l < kLanes; ++l) tau[j * kLanes + l] = c.tau[j];
    taus->push_back(tau);
  }
  std::vector<std::shared_ptr<mjModel>> models;
  for (int v = 0; v < M; ++v) models.emplace_back(ff::bench::load_mjcf(ff::bench::tree_mjcf(specs[v])), mj_deleteModel);
  double dM = 0.0, db = 0.0;
  ff::bench::check_models(models[0].get(), ff::make_tree(specs[0]), c.q0, c.qd0, dM, db);
  if (!(dM < 1e-10 && db < 1e-10)) throw std::runtime_error("the MuJoCo arm is not flexfarm's");
  std::printf("\n=== rigid 6-DOF arm: nv = %d, %g s, M = %d variants (scale 0.9 .. 1.1), %d threads, W = %d, median of %d ===\n",
              nv, seconds, M, opt.threads, kLanes, opt.reps);

  const int checked[2] = {0, M - 1};
  std::vector<ff::TreeLanes> one;  // one-lane trees of the checked variants
  for (int v : checked) one.push_back(ff::make_tree_lanes(std::vector<ff::Tree>{ff::make_tree(specs[v])}));
  auto lanes1 = std::make_shared<std::vector<ff::TreeLanes>>(one);
  auto set_state = [cp, nv](ff::TreeLanesState& s, int W) {
    for (int j = 0; j < nv; ++j)
      for (int l = 0; l < W; ++l) s.q[j * W + l] = cp->q0[j], s.qd[j * W + l] = cp->qd0[j];
  };
  // CVODE over the run in one advance (the torque is constant); q at the end, empty on failure.
  auto cvode_run = [=](const ff::TreeLanes& tl, const double* tau, double rtol, double atol, double secs) {
    ff::TreeCvodeOptions o;
    o.rtol = rtol;
    o.atol = atol;
    o.max_steps = 10000000;
    ff::TreeCvode cv(tl, o);
    ff::TreeLanesState s = ff::make_tree_lanes_state(tl);
    set_state(s, tl.W);
    std::vector<char> ok;
    cv.advance(tl, tau, s, 0.0, secs, ok);
    for (char k : ok)
      if (!k) return std::vector<double>{};
    return s.q;
  };
  const std::vector<double> tau1(c.tau.data(), c.tau.data() + nv);
  std::vector<double> ref[2];
  const double tref = ff::bench::time_it([&] {
#pragma omp parallel for num_threads(opt.threads)
    for (int i = 0; i < 2; ++i) ref[i] = cvode_run(one[i], tau1.data(), 1e-10, 1e-12, seconds);
  });
  if (ref[0].empty() || ref[1].empty()) throw std::runtime_error("the arm's reference failed");
  std::printf("reference: CVODE dense rtol 1e-10 atol 1e-12 (one advance over the run), %.1f s\n", tref);
  auto end_error = [](const std::vector<double>& q, const std::vector<double>& r) {
    if (q.size() != r.size()) return static_cast<double>(INFINITY);
    double e = 0.0;
    for (std::size_t j = 0; j < q.size(); ++j) e = std::max(e, std::abs(q[j] - r[j]));
    return std::isfinite(e) ? e : static_cast<double>(INFINITY);
  };
  auto refs = std::make_shared<std::vector<std::vector<double>>>(std::vector<std::vector<double>>{ref[0], ref[1]});

  const std::vector<double> hs = opt.quick ? std::vector<double>{1e-2, 2e-3, 1e-3, 1e-4, 2.5e-5}
                                           : std::vector<double>{1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4, 5e-5, 2.5e-5, 1e-5};
  const std::vector<double> rtols =
      opt.quick ? std::vector<double>{1e-4, 1e-6, 1e-8} : std::vector<double>{1e-4, 1e-5, 1e-6, 1e-7, 1e-8};
  std::vector<double> weight;
  const Integrators<Method> all[6] = {
      {"midpoint", Method::kFfMidpoint, 1}, {"SDIRK2", Method::kFfSdirk2, 2}, {"RK4", Method::kFfRk4, 4},
      {"Euler", Method::kMjEuler, 4},       {"implicit", Method::kMjImplicit, 8}, {"RK4", Method::kMjRk4, 16}};
  for (const auto& f : all)
    for (double h : hs) {
      const bool isff = ff::bench::is_flexfarm(f.k);
      Point p = fixed_step_point(isff ? "flexfarm" : "MuJoCo", f.name, h);
      const long steps = std::lround(seconds / h);
      const Method k = f.k;
      if (isff) {
        p.error_run = [=] {
          double e = 0.0;
          for (int i = 0; i < 2; ++i) {
            std::vector<double> q;
            if (!ff::bench::run_flexfarm((*lanes1)[i], tau1.data(), *cp, k, h, steps, &q, 64)) return static_cast<double>(INFINITY);
            e = std::max(e, end_error(q, (*refs)[i]));
          }
          return e;
        };
        p.make_timed = [=, threads = opt.threads](double window) -> std::function<void()> {
          const long n = std::max(1L, std::lround(window / h));
          return [=] {
            const int nb = static_cast<int>(batches->size());
#pragma omp parallel for num_threads(threads) schedule(static)
            for (int b = 0; b < nb; ++b) ff::bench::run_flexfarm((*batches)[b], (*taus)[b].data(), *cp, k, h, n, nullptr);
          };
        };
      } else {
        p.error_run = [=] {
          double e = 0.0;
          for (int i = 0; i < 2; ++i) {
            mjModel* m = mj_copyModel(nullptr, models[checked[i]].get());
            ff::bench::set_option(m, k, h);
            mjData* d = mj_makeData(m);
            const bool ok = ff::bench::run_mujoco(m, d, *cp, steps, 64);
            const std::vector<double> q(d->qpos, d->qpos + nv);
            mj_deleteData(d);
            mj_deleteModel(m);
            if (!ok) return static_cast<double>(INFINITY);
            e = std::max(e, end_error(q, (*refs)[i]));
          }
          return e;
        };
        p.make_timed = [=, threads = opt.threads](double window) -> std::function<void()> {
          const long n = std::max(1L, std::lround(window / h));
          auto mine = std::make_shared<std::vector<std::shared_ptr<mjModel>>>();
          auto data = std::make_shared<std::vector<std::shared_ptr<mjData>>>();
          for (int v = 0; v < M; ++v) {
            mine->emplace_back(mj_copyModel(nullptr, models[v].get()), mj_deleteModel);
            ff::bench::set_option(mine->back().get(), k, h);
            data->emplace_back(mj_makeData(mine->back().get()), mj_deleteData);
          }
          return [=] {
#pragma omp parallel for num_threads(threads) schedule(static)
            for (int v = 0; v < M; ++v) ff::bench::run_mujoco((*mine)[v].get(), (*data)[v].get(), *cp, n);
          };
        };
      }
      cr.points.push_back(p);
      weight.push_back(f.w / h);
    }
  for (double rtol : rtols) {
    Point p = cvode_point(rtol);
    p.error_run = [=] {
      double e = 0.0;
      for (int i = 0; i < 2; ++i) e = std::max(e, end_error(cvode_run((*lanes1)[i], tau1.data(), rtol, rtol * 1e-3, seconds), (*refs)[i]));
      return e;
    };
    p.make_timed = [=, threads = opt.threads](double window) -> std::function<void()> {
      return [=] {
        const int nb = static_cast<int>(batches->size());
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int b = 0; b < nb; ++b) cvode_run((*batches)[b], (*taus)[b].data(), rtol, rtol * 1e-3, window);
      };
    };
    cr.points.push_back(p);
    weight.push_back(1e9);
  }
  measure(cr, opt, weight);
  for (const Point& p : cr.points)
    if (p.method == "RK4" && p.sim == "flexfarm" && p.h == hs.back())
      std::printf("check: flexfarm RK4 at h = %s differs from the reference by %.3g rad\n", h_label(p.h).c_str(), p.error);
  return cr;
}

// ---------------------------------------------------------------- the reading

const Point* cheapest(const CaseResult& cr, const std::string& sim, double max_error) {
  const Point* best = nullptr;
  for (const Point& p : cr.points)
    if (p.sim == sim && p.stable && p.error <= max_error && (!best || p.cost < best->cost)) best = &p;
  return best;
}

void report(const CaseResult& cr) {
  const bool rig = cr.unit == "m";
  const double u = rig ? 1e3 : 1.0;  // print mm for the rig
  std::printf("\n%-9s %-9s %-12s %12s %10s %16s %14s %10s\n", "simulator", "method", "setting",
              rig ? "RMS err mm" : "err rad", "/ scale", "cost s/var-s", "var-steps/s", "window s");
  for (const Point& p : cr.points) {
    std::printf("%-9s %-9s %-12s ", p.sim.c_str(), p.method.c_str(), p.setting.c_str());
    if (!p.stable) {
      std::printf("%12s\n", "unstable");
      continue;
    }
    std::printf("%12.4g %10.2e %16.4g %14s %10g\n", u * p.error, p.error / cr.scale, p.cost,
                std::isnan(p.h) ? "-" : fmt("%.4g", 1.0 / (p.h * p.cost)).c_str(), p.window);
  }
  const Point* def = nullptr;
  for (const Point& p : cr.points)
    if (p.sim == "MuJoCo" && p.method == "Euler" && std::abs(p.h - 1e-3) < 1e-12) def = &p;
  auto line = [&](const char* what, const Point* p) {
    if (!p) return std::printf("    %-22s none of the settings\n", what), void();
    std::printf("    %-22s %s %s %s: error %.3g %s (%.2e of the scale), cost %.4g s/variant-s\n", what, p->sim.c_str(),
                p->method.c_str(), p->setting.c_str(), u * p->error, rig ? "mm" : "rad", p->error / cr.scale, p->cost);
  };
  std::printf("\nreading, %s (scale %.4g %s):\n", cr.name.c_str(), u * cr.scale, rig ? "mm" : "rad");
  if (!def || !def->stable) {
    std::printf("  (i) MuJoCo's default (Euler, 1 ms) is unstable here\n");
  } else {
    line("(i) MuJoCo default", def);
    const Point* f = cheapest(cr, "flexfarm", def->error);
    line("flexfarm cheapest <=", f);
    if (f) std::printf("    => MuJoCo default / flexfarm cost: %.3g\n", def->cost / f->cost);
  }
  for (double rel : {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8}) {
    const double tgt = rel * cr.scale;
    std::printf("  (ii) error <= %g of the scale (%.3g %s):\n", rel, u * tgt, rig ? "mm" : "rad");
    const Point* f = cheapest(cr, "flexfarm", tgt);
    const Point* m = cheapest(cr, "MuJoCo", tgt);
    line("flexfarm cheapest", f);
    line("MuJoCo cheapest", m);
    if (f && m) std::printf("    => MuJoCo / flexfarm cost: %.3g\n", m->cost / f->cost);
  }
}

void write_csv(const std::vector<CaseResult>& all, const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + path);
  std::fprintf(f, "case,simulator,method,setting,h_s,error,error_unit,rel_error,cost_s_per_variant_s,stable,window_s,variants\n");
  for (const CaseResult& cr : all)
    for (const Point& p : cr.points) {
      std::fprintf(f, "%s,%s,%s,%s,%s,", cr.name.c_str(), p.sim.c_str(), p.method.c_str(), p.setting.c_str(),
                   std::isnan(p.h) ? "" : fmt("%.6g", p.h).c_str());
      if (p.stable)
        std::fprintf(f, "%.6g,%s,%.6g,%.6g,1,%g,%d\n", p.error, cr.unit.c_str(), p.error / cr.scale, p.cost, p.window, cr.M);
      else
        std::fprintf(f, ",%s,,,0,,%d\n", cr.unit.c_str(), cr.M);
    }
  std::fclose(f);
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--case" && has) opt.which = argv[++i];
    else if (a == "--quick") opt.quick = true;
    else if (a == "--csv" && has) opt.csv = argv[++i];
    else if (a == "--threads" && has) opt.threads = std::atoi(argv[++i]);
    else if (a == "--reps" && has) opt.reps = std::atoi(argv[++i]);
    else if (a == "--budget" && has) opt.budget = std::atof(argv[++i]);
    else if (a == "--rig6-seconds" && has) opt.rig6_seconds = std::atof(argv[++i]);
    else if (a == "--rig24-seconds" && has) opt.rig24_seconds = std::atof(argv[++i]);
    else if (a == "--arm-seconds" && has) opt.arm_seconds = std::atof(argv[++i]);
    else {
      std::fprintf(stderr, "usage: %s [--case rig6|rig24|arm|all] [--quick] [--csv FILE] [--threads 2] [--reps 3]"
                   " [--budget 1] [--rig6-seconds 5] [--rig24-seconds 1] [--arm-seconds 2]\n", argv[0]);
      return 2;
    }
  }
  if (opt.which != "all" && opt.which != "rig6" && opt.which != "rig24" && opt.which != "arm") {
    std::fprintf(stderr, "bad --case\n");
    return 2;
  }
  if (opt.quick) {
    opt.reps = std::min(opt.reps, 1);
    opt.rig6_seconds = std::min(opt.rig6_seconds, 2.0);
    opt.rig24_seconds = std::min(opt.rig24_seconds, 0.3);
    opt.arm_seconds = std::min(opt.arm_seconds, 1.0);
  }
  if (opt.threads < 1 || opt.reps < 1 || !(opt.budget > 0) || !(opt.rig6_seconds > 0) || !(opt.rig24_seconds > 0) ||
      !(opt.arm_seconds > 0)) {
    std::fprintf(stderr, "bad arguments\n");
    return 2;
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  mju_user_warning = ff::bench::quiet_warning;
  std::printf("MuJoCo %s; flexfarm W = %d; %d threads (omp_get_num_procs %d)%s\n", mj_versionString(), kLanes,
              opt.threads, omp_get_num_procs(), opt.quick ? "; --quick" : "");
  try {
    std::vector<CaseResult> all;
    if (opt.which == "all" || opt.which == "rig6") all.push_back(rig_case(6, opt.rig6_seconds, opt)), report(all.back());
    if (opt.which == "all" || opt.which == "rig24") all.push_back(rig_case(24, opt.rig24_seconds, opt)), report(all.back());
    if (opt.which == "all" || opt.which == "arm") all.push_back(arm_case(opt.arm_seconds, opt)), report(all.back());
    if (!opt.csv.empty()) write_csv(all, opt.csv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
