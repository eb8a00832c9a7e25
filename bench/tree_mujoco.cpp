// Side by side, in one run: flexfarm's tree lanes (multibody/lanes, lane_integrators) against MuJoCo
// (2.2) on two trees, M variants of each simulated for a fixed time from the same initial state:
//   rigid  the 6-DOF arm of tests/multibody/mujoco_test.cpp (hinges z, y, y, x, y, x, full inertias)
//          with armature, joint springs about a reference pose and dampers, and the constant torque
//          that holds the nominal arm at that pose (gravity compensation); from an offset pose at a
//          swing it oscillates in 3-D, damped. Variants: every link's mass and inertia x 0.9 .. 1.1.
//   flex   a two-link flexible arm in 3-D: aluminium strips on edge (height along z), 0.7 m 40 x 3 mm
//          and 0.6 m 30 x 2 mm, N = 8 segments each (multibody/flexible_link: bending in both planes,
//          torsion off), revolute joints about z at the shoulder and the elbow (the first link's tip)
//          with springs, dampers and armature; gravity -z. From shoulder 0.5 rad, elbow -0.8 rad
//          (springs' reference 0), straight links, at rest: the joints swing, the links vibrate in
//          the plane and sag and bounce under gravity. nv = 2 + 2 x 7 x 2 = 30. Variants: the links'
//          density x 0.9 .. 1.1 (every segment's mass and inertia).
// MuJoCo gets the same lumped model: nested bodies, one hinge per joint, a cell's two hinges in one
// body (MuJoCo composes a body's joints in order, as flexfarm's massless joint bodies do), diagonal
// inertias as written, joint stiffness/springref/damping/armature, qfrc_applied for the torque,
// contacts off, no limits; its mass matrix and bias forces are checked against flexfarm's first.
//
// Measured for each simulator setting: accuracy = the max joint-angle error over all joints at the
// end, against a reference (flexfarm RK4 at --ref-h; checked against MuJoCo RK4 at the same step
// over the first --ref-check-seconds, and over the whole run against flexfarm SDIRK2 at 1e-6 s and
// RK4 at twice the step), on the first and last variant; cost = variant-steps per
// second and wall time of the whole run (M variants, --seconds), OpenMP over batches of W lanes
// (flexfarm) or over variants, one mjData each (MuJoCo), on --threads threads; median of --reps.
// A setting whose whole run would take longer than --budget seconds is timed on a shorter window
// (all variants, fewer steps) and its whole-run wall time extrapolated (marked *).
// Run: tree_mujoco [--case rigid|flex|both] [--variants 64] [--seconds 2] [--reps 5] [--threads 2]
//                  [--ref-h H] [--ref-check-seconds 0.02] [--budget 4] [--lanes 8]
// (--ref-h: default 1e-6 s for the rigid arm, 2.5e-7 s for the flexible one, inside RK4's stability limit)
#include <mujoco/mujoco.h>
#include <omp.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/mujoco_tree.hpp"
#include "bench/tree_arm.hpp"
#include "multibody/algorithms.hpp"
#include "multibody/flexible_link.hpp"
#include "multibody/lane_integrators.hpp"
#include "multibody/lanes.hpp"

namespace {

using ff::BodySpec;
using ff::Mat3;
using ff::Vec3;
using ff::bench::check_models;
using ff::bench::load_mjcf;
using ff::bench::quiet_warning;
using ff::bench::tree_mjcf;

// ---------------------------------------------------------------- the two trees

using Case = ff::bench::TreeCase;
using ff::bench::Method;
using ff::bench::is_flexfarm;
using ff::bench::median;
using ff::bench::method_name;
using ff::bench::run_flexfarm;
using ff::bench::run_mujoco;
using ff::bench::set_option;
using ff::bench::variant_scale;

Case rigid_case() { return ff::bench::rigid_arm_case(); }

// An aluminium strip on edge: width b (along z, vertical), thickness t (along y).
ff::BeamSection strip(double b, double t, double density) {
  ff::BeamSection s;
  s.youngs_modulus = 70e9;
  s.shear_modulus = 26e9;
  s.density = density;
  s.area = b * t;
  s.second_moment_y = t * b * b * b / 12.0;  // bending about y (vertical sag): the stiff plane
  s.second_moment_z = b * t * t * t / 12.0;  // bending about z (in the plane of motion): the soft one
  s.torsion_constant = b * t * t * t / 3.0;
  return s;
}

constexpr int kFlexSegments = 8;
constexpr double kFlexBeta = 2.289e-3;  // s: the cells' dampers c = beta k (the reference rig's rule)

Case flex_case() {
  Case c;
  c.name = "two-link flexible arm (N = 8, bending y and z, no torsion)";
  c.spec = [](double scale) {
    ff::TreeSpec s;
    ff::FlexibleLinkSpec upper;
    upper.name = "upper";
    upper.length = 0.7;
    upper.section = strip(0.040, 0.003, 2700.0 * scale);
    upper.segments = kFlexSegments;
    upper.damping_time = kFlexBeta;
    upper.torsion = false;
    upper.root_joint = {ff::JointType::kRevolute, Vec3::UnitZ(), 0.05, 20.0, 0.1, 0.0};  // shoulder
    const int tip = ff::append_flexible_link(s, -1, Vec3(0, 0, 0.1), Mat3::Identity(), upper);
    ff::FlexibleLinkSpec fore = upper;
    fore.name = "fore";
    fore.length = 0.6;
    fore.section = strip(0.030, 0.002, 2700.0 * scale);
    fore.root_joint = {ff::JointType::kRevolute, Vec3::UnitZ(), 0.01, 5.0, 0.02, 0.0};  // elbow
    ff::append_flexible_link(s, tip, ff::flexible_link_tip_point(upper), Mat3::Identity(), fore);
    return s;
  };
  const int nv = ff::make_tree(c.spec(1.0)).nv();
  c.q0 = Eigen::VectorXd::Zero(nv);
  c.qd0 = Eigen::VectorXd::Zero(nv);
  c.tau = Eigen::VectorXd::Zero(nv);
  c.q0[0] = 0.5;  // shoulder
  c.q0[1 + 2 * (kFlexSegments - 1)] = -0.8;  // elbow: after the shoulder and the upper link's cell joints
  // The cells' dampers make real poles up to beta omega^2 = 5.2e6 /s (the short forearm cells'
  // stiff-plane bending, omega ~ 4.8e4 rad/s): explicit RK4 is stable below h ~ 5e-7 s only.
  c.ref_h = 2.5e-7;
  return c;
}

// Everything built once per case: the variants' trees and MuJoCo models.
struct Rig {
  const Case* c = nullptr;
  int M = 0, W = 8, nv = 0;
  std::vector<ff::TreeSpec> specs;
  std::vector<ff::TreeLanes> batches;      // M / W batches of W lanes
  std::vector<std::vector<double>> tau;    // per batch: (nv x W)
  std::vector<mjModel*> models;            // per variant
  std::vector<mjData*> data;               // per variant
  ~Rig() {
    for (auto* d : data) mj_deleteData(d);
    for (auto* m : models) mj_deleteModel(m);
  }
};

// The end state of variant v alone (flexfarm: one lane, the same bits as in any lane of a batch;
// MuJoCo: a private model and data). Empty on divergence. Seconds per step into *sec_per_step.
Eigen::VectorXd end_state(const Rig& rig, int v, Method k, double h, long steps, double* sec_per_step) {
  const Case& c = *rig.c;
  const auto t0 = std::chrono::steady_clock::now();
  Eigen::VectorXd out;
  if (is_flexfarm(k)) {
    const ff::TreeLanes tl = ff::make_tree_lanes(std::vector<ff::Tree>{ff::make_tree(rig.specs[v])});
    std::vector<double> q;
    const std::vector<double> tau(c.tau.data(), c.tau.data() + rig.nv);
    if (run_flexfarm(tl, tau.data(), c, k, h, steps, &q, 64)) out = Eigen::Map<const Eigen::VectorXd>(q.data(), rig.nv);
  } else {
    mjModel* m = mj_copyModel(nullptr, rig.models[v]);
    set_option(m, k, h);
    mjData* d = mj_makeData(m);
    if (run_mujoco(m, d, c, steps, 64)) out = Eigen::Map<const Eigen::VectorXd>(d->qpos, rig.nv);
    mj_deleteData(d);
    mj_deleteModel(m);
  }
  if (sec_per_step)
    *sec_per_step = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / steps;
  return out;
}

struct Options {
  int M = 64, reps = 5, threads = 2, W = 8;
  double seconds = 2.0, ref_h = 0.0, budget = 4.0, ref_check_seconds = 0.02;  // ref_h 0: the case's
  std::string which = "both";
};

// One (method, step) setting: accuracy from the sweep, cost from the timed whole run.
struct Setting {
  Method k;
  double h;
  long steps = 0;
  bool stable = true;
  double error = NAN;          // rad, max over joints and the checked variants
  double sec_per_step = NAN;   // one variant, one thread, from the sweep
  bool timed = false;
  long timed_steps = 0;        // steps per variant in the timed window
  int inner = 1;               // whole runs per timing (a short run is repeated to ~0.5 s)
  double rate = NAN;           // variant-steps/s, median
  double wall = NAN;           // s for the whole run (extrapolated when timed_steps < steps)
};

// The timed window: the whole run, or (when it would take longer than opt.budget by the sweep's
// cost per step) its first steps, for every variant.
void plan_timing(const Rig& rig, Setting& st, const Options& opt) {
  const double est = st.sec_per_step * st.steps * rig.M / opt.threads;
  st.timed_steps = est > opt.budget ? std::max(1L, std::lround(st.steps * opt.budget / est)) : st.steps;
  st.inner = est < 0.5 ? static_cast<int>(std::ceil(0.5 / est)) : 1;
}

// One timed run (the mean of st.inner) of the window for all M variants on opt.threads threads: OpenMP over batches of W
// lanes (flexfarm) or over variants (MuJoCo, one mjData each); seconds.
double time_once(Rig& rig, const Setting& st, const Options& opt) {
  const Case& c = *rig.c;
  const long n = st.timed_steps;
  int bad = 0;
  if (!is_flexfarm(st.k))
    for (auto* m : rig.models) set_option(m, st.k, st.h);
  const auto t0 = std::chrono::steady_clock::now();
  for (int rep = 0; rep < st.inner; ++rep) {
    if (is_flexfarm(st.k)) {
      const int nbatch = static_cast<int>(rig.batches.size());
#pragma omp parallel for num_threads(opt.threads) schedule(static) reduction(+ : bad)
      for (int b = 0; b < nbatch; ++b) bad += !run_flexfarm(rig.batches[b], rig.tau[b].data(), c, st.k, st.h, n, nullptr);
    } else {
#pragma omp parallel for num_threads(opt.threads) schedule(static) reduction(+ : bad)
      for (int v = 0; v < rig.M; ++v) bad += !run_mujoco(rig.models[v], rig.data[v], c, n);
    }
  }
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / st.inner;
  if (bad) std::printf("  (%d runs of %s h=%g diverged in the timed run)\n", bad, method_name(st.k), st.h);
  return t;
}

std::string fmt_h(double h) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", h);
  return b;
}

void run_case(const Case& c, const Options& opt) {
  Rig rig;
  rig.c = &c;
  rig.M = opt.M;
  rig.W = opt.W;
  if (rig.M % rig.W != 0) throw std::runtime_error("--variants must be a multiple of --lanes");
  for (int v = 0; v < rig.M; ++v) rig.specs.push_back(c.spec(variant_scale(v, rig.M)));
  rig.nv = ff::make_tree(rig.specs[0]).nv();
  for (int b = 0; b < rig.M / rig.W; ++b) {
    std::vector<ff::Tree> trees;
    for (int l = 0; l < rig.W; ++l) trees.push_back(ff::make_tree(rig.specs[b * rig.W + l]));
    rig.batches.push_back(ff::make_tree_lanes(trees));
    std::vector<double> tau(static_cast<std::size_t>(rig.nv) * rig.W);
    for (int j = 0; j < rig.nv; ++j)
      for (int l = 0; l < rig.W; ++l) tau[j * rig.W + l] = c.tau[j];
    rig.tau.push_back(tau);
  }
  for (int v = 0; v < rig.M; ++v) {
    rig.models.push_back(load_mjcf(tree_mjcf(rig.specs[v])));
    rig.data.push_back(mj_makeData(rig.models.back()));
  }
  std::printf("\n=== %s: nv = %d, M = %d variants (scale 0.9 .. 1.1), %g s, %d threads, W = %d, median of %d ===\n",
              c.name.c_str(), rig.nv, rig.M, opt.seconds, opt.threads, rig.W, opt.reps);

  // The two models are one: M(q) and the bias forces at the start and at a random state.
  double worst_M = 0.0, worst_bias = 0.0;
  for (int v : {0, rig.M - 1}) {
    const ff::Tree tree = ff::make_tree(rig.specs[v]);
    Eigen::VectorXd qr = c.q0, qdr = c.qd0;
    for (int j = 0; j < rig.nv; ++j) qr[j] += 0.3 * std::sin(1.0 + 7.0 * j), qdr[j] += std::cos(2.0 + 3.0 * j);
    for (int s = 0; s < 2; ++s) {
      double dM, db;
      check_models(rig.models[v], tree, s ? qr : c.q0, s ? qdr : c.qd0, dM, db);
      worst_M = std::max(worst_M, dM);
      worst_bias = std::max(worst_bias, db);
    }
  }
  std::printf("MuJoCo vs flexfarm model: M(q) max rel diff %.2e, bias forces %.2e (first and last variant, 2 states)\n",
              worst_M, worst_bias);
  if (!(worst_M < 1e-10 && worst_bias < 1e-10)) throw std::runtime_error("the MuJoCo model is not flexfarm's");

  const int checked[2] = {0, rig.M - 1};
  const double ref_h = opt.ref_h > 0 ? opt.ref_h : c.ref_h;
  const long nref = std::lround(opt.seconds / ref_h);
  const double tw = std::min(opt.seconds, opt.ref_check_seconds);
  const long nwin = std::lround(tw / ref_h);
  // Reference: flexfarm RK4 at ref_h. Checks: flexfarm SDIRK2 at 1e-6 and RK4 at 2 ref_h over the
  // whole run; MuJoCo RK4 against flexfarm RK4 at ref_h over the first tw seconds (MuJoCo's RK4 costs
  // ~10 times flexfarm's a step on the flexible arm).
  Eigen::VectorXd ref[2], sd[2], ref2[2], mjw[2], ffw[2];
  double us_mj = 0.0, us_ff = 0.0;  // s a step of MuJoCo RK4 and flexfarm RK4 (one lane) at ref_h, first variant
  {
    const auto t0 = std::chrono::steady_clock::now();
    const int nsd = std::lround(opt.seconds / 1e-6);
#pragma omp parallel for num_threads(opt.threads) schedule(dynamic)
    for (int job = 0; job < 10; ++job) {
      const int i = job % 2;
      if (job < 2) ref[i] = end_state(rig, checked[i], Method::kFfRk4, ref_h, nref, nullptr);
      else if (job < 4) sd[i] = end_state(rig, checked[i], Method::kFfSdirk2, 1e-6, nsd, nullptr);
      else if (job < 6) ref2[i] = end_state(rig, checked[i], Method::kFfRk4, 2 * ref_h, nref / 2, nullptr);
      else if (job < 8) mjw[i] = end_state(rig, checked[i], Method::kMjRk4, ref_h, nwin, i ? nullptr : &us_mj);
      else ffw[i] = end_state(rig, checked[i], Method::kFfRk4, ref_h, nwin, i ? nullptr : &us_ff);
    }
    auto diff = [](const Eigen::VectorXd* a, const Eigen::VectorXd* b) {
      double d = 0.0;
      for (int i = 0; i < 2; ++i) {
        if (a[i].size() == 0 || b[i].size() == 0) return static_cast<double>(INFINITY);
        d = std::max(d, (a[i] - b[i]).cwiseAbs().maxCoeff());
      }
      return d;
    };
    if (ref[0].size() == 0 || ref[1].size() == 0) throw std::runtime_error("the reference diverged");
    double swing = 0.0;
    for (int i = 0; i < 2; ++i) swing = std::max(swing, (ref[i] - c.q0).cwiseAbs().maxCoeff());
    const double d2 = diff(ref, ref2);
    char self[96] = "unstable (2h beyond RK4's stability limit)";
    if (d2 < 1.0) std::snprintf(self, sizeof self, "%.2e rad (its own error ~ this / 15)", d2);
    std::printf("reference: flexfarm RK4, h = %g s (%ld steps; the checks took %.0f s on %d threads); max |q(T) - q(0)| "
                "%.3g rad\n  vs MuJoCo RK4 at the same h over the first %g s: %.2e rad (a step: MuJoCo RK4 %.3g us, flexfarm "
                "RK4 one lane %.3g us)\n  vs flexfarm SDIRK2 at h = 1e-6 "
                "over the run: %.2e rad\n  vs flexfarm RK4 at 2h over the run: %s\n",
                ref_h, nref, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), opt.threads,
                swing, tw, diff(mjw, ffw), 1e6 * us_mj, 1e6 * us_ff, diff(ref, sd),
                self);
  }

  // The sweep: every method at every step, accuracy on the two checked variants.
  const std::vector<double> hs = {1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4, 5e-5, 2.5e-5, 1e-5};
  const Method methods[5] = {Method::kMjEuler, Method::kMjImplicit, Method::kMjRk4, Method::kFfRk4, Method::kFfSdirk2};
  std::vector<Setting> sweep;
  for (Method k : methods)
    for (double h : hs) {
      Setting st{k, h};
      st.steps = std::lround(opt.seconds / h);
      sweep.push_back(st);
    }
  const int njobs = static_cast<int>(sweep.size()) * 2;
  std::vector<double> errs(static_cast<std::size_t>(njobs), 0.0), sps(static_cast<std::size_t>(njobs), 0.0);
  // Costliest first so that the threads finish together.
#pragma omp parallel for num_threads(opt.threads) schedule(dynamic)
  for (int jj = 0; jj < njobs; ++jj) {
    const int job = njobs - 1 - jj;
    Setting& st = sweep[job / 2];
    const int i = job % 2;
    const Eigen::VectorXd q = end_state(rig, checked[i], st.k, st.h, st.steps, &sps[job]);
    errs[job] = q.size() == 0 ? INFINITY : (q - ref[i]).cwiseAbs().maxCoeff();
    if (!std::isfinite(errs[job])) errs[job] = INFINITY;
  }
  for (std::size_t s = 0; s < sweep.size(); ++s) {
    sweep[s].error = std::max(errs[2 * s], errs[2 * s + 1]);
    sweep[s].stable = std::isfinite(sweep[s].error) && sweep[s].error < 1.0;
    sweep[s].sec_per_step = std::min(sps[2 * s], sps[2 * s + 1]);
  }

  // Which settings to time: MuJoCo's default (Euler, 1 ms), and for each method the largest step
  // (cheapest) that reaches each target, and for flexfarm the largest step at least as accurate as
  // MuJoCo's default.
  auto find = [&](Method k, double h) -> Setting& {
    for (auto& s : sweep)
      if (s.k == k && s.h == h) return s;
    throw std::runtime_error("no such setting");
  };
  auto cheapest = [&](Method k, double target) -> Setting* {
    for (double h : hs) {  // largest first
      Setting& s = find(k, h);
      if (s.stable && s.error <= target) return &s;
    }
    return nullptr;
  };
  Setting& mj_default = find(Method::kMjEuler, 1e-3);
  const double targets[2] = {1e-4, 1e-6};
  std::vector<Setting*> to_time{&mj_default};
  for (Method k : methods) {
    for (double tgt : targets)
      if (Setting* s = cheapest(k, tgt)) to_time.push_back(s);
    if (is_flexfarm(k) && mj_default.stable)
      if (Setting* s = cheapest(k, mj_default.error)) to_time.push_back(s);
  }
  std::sort(to_time.begin(), to_time.end());
  to_time.erase(std::unique(to_time.begin(), to_time.end()), to_time.end());
  // Repetitions round-robin over the settings, so that the other work on the machine hits them alike.
  std::vector<std::vector<double>> times(to_time.size());
  for (Setting* s : to_time) plan_timing(rig, *s, opt);
  for (int r = 0; r < opt.reps; ++r)
    for (std::size_t i = 0; i < to_time.size(); ++i) times[i].push_back(time_once(rig, *to_time[i], opt));
  for (std::size_t i = 0; i < to_time.size(); ++i) {
    Setting& s = *to_time[i];
    const double t = median(times[i]);
    s.rate = static_cast<double>(s.timed_steps) * rig.M / t;
    s.wall = t * static_cast<double>(s.steps) / s.timed_steps;
    s.timed = true;
  }

  std::printf("\naccuracy: max joint-angle error at t = %g s over all %d joints (variants 0 and %d) vs the reference;"
              " cost: whole run, %d variants, %d threads\n",
              opt.seconds, rig.nv, rig.M - 1, rig.M, opt.threads);
  std::printf("%-17s %9s %8s %11s %12s %16s %12s %9s\n", "setting", "h (s)", "steps", "error (rad)", "us/step 1v1t",
              "variant-steps/s", "wall (s)", "/ MJ 1ms");
  for (Method k : methods)
    for (double h : hs) {
      const Setting& s = find(k, h);
      std::printf("%-17s %9s %8ld ", method_name(k), fmt_h(h).c_str(), s.steps);
      if (!s.stable) std::printf("%11s %12.3g", "unstable", 1e6 * s.sec_per_step);
      else std::printf("%11.2e %12.3g", s.error, 1e6 * s.sec_per_step);
      if (s.timed)
        std::printf(" %16.4g %11.3g%s %9.3g", s.rate, s.wall, s.timed_steps < s.steps ? "*" : " ",
                    mj_default.wall / s.wall);
      std::printf("\n");
    }
  std::printf("(* timed on the first %s of the run for every variant, whole-run wall time extrapolated)\n",
              "steps that fit --budget");

  // (i) MuJoCo's default against flexfarm at equal or better accuracy.
  std::printf("\n(i) MuJoCo default (Euler, h = 1 ms): error %.2e rad, %.4g variant-steps/s, %.3g s for the run\n",
              mj_default.error, mj_default.rate, mj_default.wall);
  for (Method k : {Method::kFfRk4, Method::kFfSdirk2}) {
    const Setting* s = mj_default.stable ? cheapest(k, mj_default.error) : cheapest(k, 1e-2);
    if (!s) {
      std::printf("    %-16s: no step of the sweep is as accurate\n", method_name(k));
      continue;
    }
    std::printf("    %-16s h = %-7s error %.2e rad, %.4g variant-steps/s, %.3g s: %.3g x MuJoCo's variant-steps/s, "
                "%.3g x faster run\n",
                method_name(k), fmt_h(s->h).c_str(), s->error, s->rate, s->wall, s->rate / mj_default.rate,
                mj_default.wall / s->wall);
  }
  // (ii) accuracy-matched: the cheapest setting of each side reaching the target.
  for (double tgt : targets) {
    std::printf("(ii) error <= %g rad: cheapest (wall time of the whole run)\n", tgt);
    const Setting *best_ff = nullptr, *best_mj = nullptr;
    for (Method k : methods) {
      const Setting* s = cheapest(k, tgt);
      if (!s) {
        std::printf("    %-16s: not reached at h >= %g\n", method_name(k), hs.back());
        continue;
      }
      std::printf("    %-16s h = %-7s error %.2e rad, %.4g variant-steps/s, %.3g s%s\n", method_name(k),
                  fmt_h(s->h).c_str(), s->error, s->rate, s->wall, s->timed_steps < s->steps ? " *" : "");
      const Setting*& best = is_flexfarm(k) ? best_ff : best_mj;
      if (!best || s->wall < best->wall) best = s;
    }
    if (best_ff && best_mj)
      std::printf("    => %s / %s: %.3g x faster run\n", method_name(best_ff->k), method_name(best_mj->k),
                  best_mj->wall / best_ff->wall);
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--case" && has) opt.which = argv[++i];
    else if (a == "--variants" && has) opt.M = std::atoi(argv[++i]);
    else if (a == "--seconds" && has) opt.seconds = std::atof(argv[++i]);
    else if (a == "--reps" && has) opt.reps = std::atoi(argv[++i]);
    else if (a == "--threads" && has) opt.threads = std::atoi(argv[++i]);
    else if (a == "--ref-h" && has) opt.ref_h = std::atof(argv[++i]);
    else if (a == "--ref-check-seconds" && has) opt.ref_check_seconds = std::atof(argv[++i]);
    else if (a == "--budget" && has) opt.budget = std::atof(argv[++i]);
    else if (a == "--lanes" && has) opt.W = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: %s [--case rigid|flex|both] [--variants 64] [--seconds 2] [--reps 5] [--threads 2]"
                   " [--ref-h H] [--ref-check-seconds 0.02] [--budget 4] [--lanes 8]\n", argv[0]);
      return 2;
    }
  }
  if (opt.M < 2 || opt.reps < 1 || opt.threads < 1 || opt.W < 1 || opt.W > ff::kMaxTreeLanes || !(opt.seconds > 0) ||
      !(opt.ref_h >= 0) || !(opt.ref_check_seconds > 0) || !(opt.budget > 0) || (opt.which != "rigid" && opt.which != "flex" && opt.which != "both")) {
    std::fprintf(stderr, "bad arguments\n");
    return 2;
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  mju_user_warning = quiet_warning;
  std::printf("MuJoCo %s; flexfarm tree lanes W = %d; %d threads (omp_get_num_procs %d)\n", mj_versionString(), opt.W,
              opt.threads, omp_get_num_procs());
  try {
    if (opt.which != "flex") run_case(rigid_case(), opt);
    if (opt.which != "rigid") run_case(flex_case(), opt);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
