// Side by side, in one run: flexfarm's batch kernel against MuJoCo (2.2) on the reference rig
// (docs/reference-rig.md): throughput in variant-steps per second (1 ms controller steps) and
// tip-deflection accuracy of both against flexfarm's CVODE reference.
// The controller is sampled every 1 ms and held in between. MuJoCo's timestep is 1 ms / K with
// K = ff::calc_auto_substeps of the rig with RK4 (h omega_max <= 1; K = 1 at N = 6, i.e. 1 ms) unless
// --mujoco-substeps K.
// Larger N needs many substeps (N = 24: 29, N = 48: 496), so --seconds can shorten the simulated
// window per N (throughput and accuracy then refer to that window).
// Run: mujoco_compare [--segments 6,24,48 --seconds 20,0.5,0.02] [--variants 16] [--reps 7] [--mujoco-substeps K]
#include <mujoco/mujoco.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/mujoco_rig.hpp"
#include "bench/mujoco_util.hpp"
#include "kernel/batch.hpp"
#include "kernel/model.hpp"
#include "kernel/modes.hpp"
#include "kernel/simulate.hpp"
#include "kernel/trajectory.hpp"

namespace {

using ff::bench::load_mjcf;
using ff::bench::mass_matrix_difference;
using ff::bench::median;
using ff::bench::parse_list;
using ff::bench::mujoco_inertia_as_written;
using ff::bench::quiet_warning;
using ff::bench::rig_spec;
using ff::bench::rms;
using ff::bench::time_it;
using Error = ff::bench::TipError;

// ==================== flexfarm configurations under test: edit HERE ====================
// Point the benchmark at another integrator, substep count or lane width. The first is "flexfarm"
// in the summary lines; the others are extra rows.
struct FlexfarmConfig {
  const char* label;            // row name in the tables
  ff::Integrator integrator;
  int substeps = 0;             // per 1 ms control period; 0 = automatic (1 here at N = 6)
  int lanes = 8;                // W: variants advanced in lock-step per batch (M = 16: two batches)
};
std::vector<FlexfarmConfig> flexfarm_configs() {
  return {{"flexfarm midpoint", ff::Integrator::kMidpoint},  // one ABA pass per step (short chains)
          {"flexfarm SDIRK2", ff::Integrator::kSdirk2}};     // two passes, L-stable (any N)
}
// =======================================================================================

// The rig in MuJoCo, its checks and the tip error: bench/mujoco_rig.hpp.

struct Summary {
  double ratio, ff_rms, mj_rms;
};

// One timed configuration: a full run of all M variants.
struct Row {
  std::string name;
  int substeps = 0, threads = 1;
  std::function<void()> run;
  bool stable = true;
  std::vector<double> times;
  double rate = NAN;  // variant-steps/s, median
};

// Everything for one segment count. Returns false when the two rigs differ.
bool run_case(int nseg, double seconds, int M, int reps, int mj_sub_override, Summary& out) {
  const std::vector<FlexfarmConfig> cfgs = flexfarm_configs();
  // The rig; its RK4 step rule (h omega_n <= 1) sets MuJoCo's substeps.
  const ff::Model m = ff::make_model(rig_spec(nseg, ff::Integrator::kRk4, 0, seconds));
  const ff::Model mref = ff::make_model(rig_spec(nseg, ff::Integrator::kCvodeDense, 0, seconds));
  const long nsamples = std::lround(m.duration / m.control_period) + 1;
  const double steps = static_cast<double>(nsamples - 1) * M;  // variant-steps per run
  const int mj_sub = mj_sub_override > 0 ? mj_sub_override : m.substeps;

  std::printf("\n=== N = %d segments: M = %d variants x %ld controller steps of %g ms (%g s), median of %d ===\n",
              nseg, M, nsamples - 1, 1e3 * m.control_period, m.duration, reps);

  // The MuJoCo rig must be flexfarm's rig.
  mjModel* mj_euler = load_mjcf(ff::bench::rig_mjcf(m, "Euler", mj_sub));
  mjModel* mj_rk4 = load_mjcf(ff::bench::rig_mjcf(m, "RK4", mj_sub));
  const double dM = mass_matrix_difference(mj_euler, m);
  const bool inertia_ok = mujoco_inertia_as_written(mj_euler, m);
  std::printf("mass matrix M(0), MuJoCo vs ff::calc_mass_matrix: max rel diff %.2e; body inertias %s\n", dM,
              inertia_ok ? "kept as written" : "CHANGED by MuJoCo");
  if (!(dM <= 1e-6) || !inertia_ok) {
    std::printf("ERROR: the MuJoCo rig differs from flexfarm's; the comparison would be meaningless\n");
    mj_deleteModel(mj_euler);
    mj_deleteModel(mj_rk4);
    return false;
  }

  // flexfarm: M / W batches of W identical lanes per configuration; each thread simulates whole batches.
  struct FfSide {
    std::string name;
    ff::BatchModel bm;
    std::vector<ff::BatchRun> runs;
  };
  std::vector<FfSide> ffs;
  for (const auto& cfg : cfgs) {
    const int W = cfg.lanes;
    if (M % W != 0) throw std::runtime_error("--variants must be a multiple of the lane width W");
    const ff::Model mf = ff::make_model(rig_spec(nseg, cfg.integrator, cfg.substeps, seconds));
    ffs.push_back({std::string(cfg.label) + " W=" + std::to_string(W), ff::make_batch(std::vector<ff::Model>(W, mf)),
                   std::vector<ff::BatchRun>(M / W)});
  }
  auto run_ff = [&](FfSide& sd, int threads) {
    const int nbatch = static_cast<int>(sd.runs.size());
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int bi = 0; bi < nbatch; ++bi) sd.runs[bi] = ff::simulate(sd.bm);
  };

  // MuJoCo: one mjData and one trace per variant and integrator; each thread runs whole variants.
  struct MjSide {
    const mjModel* mm;
    std::vector<mjData*> data;
    std::vector<std::vector<double>> tips;
    int diverged = 0;
  };
  MjSide sides[2] = {{mj_euler, {}, {}, 0}, {mj_rk4, {}, {}, 0}};
  for (auto& sd : sides) {
    for (int v = 0; v < M; ++v) sd.data.push_back(mj_makeData(sd.mm));
    sd.tips.assign(M, std::vector<double>(nsamples));
  }
  auto run_mj = [&](MjSide& sd, int threads) {
    int bad = 0;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(+ : bad)
    for (int v = 0; v < M; ++v) bad += !ff::bench::run_rig_mujoco(sd.mm, sd.data[v], m, mj_sub, nsamples, sd.tips[v].data());
    sd.diverged = bad;
  };

  std::vector<Row> rows;
  auto add = [&](std::string name, int sub, int th, std::function<void()> f) {
    Row r;
    r.name = std::move(name);
    r.substeps = sub;
    r.threads = th;
    r.run = std::move(f);
    rows.push_back(std::move(r));
  };
  for (int th : {1, 2}) add("MuJoCo Euler (semi-implicit)", mj_sub, th, [&, th] { run_mj(sides[0], th); });
  for (int th : {1, 2}) add("MuJoCo RK4", mj_sub, th, [&, th] { run_mj(sides[1], th); });
  for (auto& sd : ffs)
    for (int th : {1, 2}) add(sd.name, sd.bm.substeps, th, [&, th] { run_ff(sd, th); });

  // Warm-up (and divergence check), then the repetitions round-robin so load drift hits every row alike.
  for (std::size_t r = 0; r < rows.size(); ++r) {
    rows[r].run();
    if (r < 4) rows[r].stable = sides[r / 2].diverged == 0;
  }
  for (int rep = 0; rep < reps; ++rep)
    for (auto& row : rows)
      if (row.stable) row.times.push_back(time_it(row.run));
  for (auto& row : rows)
    if (row.stable) row.rate = steps / median(row.times);
  for (const auto& sd : ffs)
    for (const auto& r : sd.runs)
      for (auto st : r.status)
        if (st != ff::LaneStatus::kOk) throw std::runtime_error("a flexfarm lane failed (" + sd.name + ")");

  std::printf("\n%-34s %8s %7s %18s %12s\n", "throughput", "substeps", "threads", "variant-steps/s", "/ MuJoCo Eu");
  for (const auto& r : rows) {
    const double base = rows[r.threads == 1 ? 0 : 1].rate;  // MuJoCo Euler, same thread count
    if (r.stable)
      std::printf("%-34s %8d %7d %18.4g %12.2f\n", r.name.c_str(), r.substeps, r.threads, r.rate, r.rate / base);
    else
      std::printf("%-34s %8d %7d %18s %12s\n", r.name.c_str(), r.substeps, r.threads, "diverged", "-");
  }
  for (const auto& sd : ffs)
    if (sd.runs.size() < 2) std::printf("(%s: only one batch of W lanes, its 2-thread row has nothing to share)\n", sd.name.c_str());

  const std::vector<double> ref = ff::simulate(ff::make_batch(std::vector<ff::Model>{mref})).traces[0].tip_deflection;
  std::printf("\n%-34s %14s %14s   (reference: CVODE dense, rtol %g; tip deflection RMS %.4g mm)\n",
              "accuracy vs reference", "RMS error mm", "max error mm", mref.spec.simulation.rtol, 1e3 * rms(ref));
  // err: MuJoCo Euler, MuJoCo RK4, then each flexfarm configuration.
  std::vector<Error> err;
  std::vector<std::string> names = {"MuJoCo Euler (semi-implicit)", "MuJoCo RK4"};
  for (const auto& sd : ffs) names.push_back(sd.name);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i < 2 && sides[i].diverged) {
      err.push_back({NAN, NAN});
      std::printf("%-34s %14s %14s\n", names[i].c_str(), "diverged", "diverged");
      continue;
    }
    err.push_back(ff::bench::compare_tips(i < 2 ? sides[i].tips[0] : ffs[i - 2].runs[0].traces[0].tip_deflection, ref));
    std::printf("%-34s %14.4g %14.4g\n", names[i].c_str(), 1e3 * err[i].rms, 1e3 * err[i].max);
  }
  for (auto& sd : sides)
    for (auto* d : sd.data) mj_deleteData(d);
  mj_deleteModel(mj_euler);
  mj_deleteModel(mj_rk4);

  out = {rows[4].rate / rows[0].rate, err[2].rms, err[0].rms};
  for (std::size_t f = 0; f < ffs.size(); ++f)
    std::printf("%sN=%d: %s / MuJoCo(Euler) throughput = %.3g (1 thread), %.3g (2 threads)\n", f ? "" : "\n", nseg,
                ffs[f].name.c_str(), rows[4 + 2 * f].rate / rows[0].rate, rows[5 + 2 * f].rate / rows[1].rate);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> segments = {6}, secs = {20.0};
  int M = 16, reps = 7, mj_sub = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--segments" && has) {
      segments = parse_list(argv[++i]);
    } else if (a == "--seconds" && has) {
      secs = parse_list(argv[++i]);
    } else if (a == "--variants" && has) {
      M = std::atoi(argv[++i]);
    } else if (a == "--reps" && has) {
      reps = std::atoi(argv[++i]);
    } else if (a == "--mujoco-substeps" && has) {
      mj_sub = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: %s [--segments 6,24,48] [--seconds 20,0.5,0.02] [--variants 16] [--reps 7]"
                   " [--mujoco-substeps K]\n", argv[0]);
      return 2;
    }
  }
  if (secs.size() == 1) secs.resize(segments.size(), secs[0]);  // one value for every N
  for (double x : secs)
    if (!(x > 0)) secs.clear();
  if (segments.empty() || secs.size() != segments.size() || M < 1 || reps < 1 || mj_sub < 0) {
    std::fprintf(stderr, "bad arguments\n");
    return 2;
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // progress visible through pipes
  mju_user_warning = quiet_warning;
  std::printf("MuJoCo %s; flexfarm configs:", mj_versionString());
  for (const auto& c : flexfarm_configs())
    std::printf(" [%s, substeps %d (0 = auto), W = %d]", c.label, c.substeps, c.lanes);
  std::printf("\n");
  try {
    std::vector<Summary> sums;
    for (std::size_t i = 0; i < segments.size(); ++i) {
      Summary s{};
      if (!run_case(static_cast<int>(segments[i]), secs[i], M, reps, mj_sub, s)) return 1;
      sums.push_back(s);
    }
    // One line for the docs: the first segment count asked for (default N = 6), single thread.
    std::printf("\nratio_vs_mujoco_euler=%.3g accuracy_flexfarm_rms_m=%.3g accuracy_mujoco_rms_m=%.3g\n", sums[0].ratio,
                sums[0].ff_rms, sums[0].mj_rms);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
