// Throughput of the tree kernels (multibody/): forward dynamics per variant by the lane-batched ABA
// (multibody/lanes) against the scalar one (multibody/algorithms), and RK4 / SDIRK2 steps over lanes,
// on a rigid 6-DOF arm and a two-link 3-D flexible arm; CVODE (multibody/tree_cvode) dense, KLU and
// preconditioned GMRES on one 3-D flexible link per second of simulated time.
// Run: build/bench/tree_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "multibody/algorithms.hpp"
#include "multibody/flexible_link.hpp"
#include "multibody/lane_integrators.hpp"
#include "multibody/lanes.hpp"
#include "multibody/tree_cvode.hpp"

namespace {

using ff::BodySpec;
using ff::Mat3;
using ff::Vec3;

ff::Mat3 box(double m, double a, double b, double c) {
  return Vec3(m * (b * b + c * c) / 12.0, m * (a * a + c * c) / 12.0, m * (a * a + b * b) / 12.0).asDiagonal();
}

// A UR5-like rigid arm: six revolute joints (z, y, y, y, z, y), link masses 3.7 ... 0.19 kg; scale
// varies the masses per variant.
ff::Tree rigid_arm(double scale) {
  ff::TreeSpec s;
  const Vec3 axes[6] = {Vec3::UnitZ(), Vec3::UnitY(), Vec3::UnitY(), Vec3::UnitY(), Vec3::UnitZ(), Vec3::UnitY()};
  const Vec3 pos[6] = {{0, 0, 0.089}, {0, 0.136, 0}, {0, -0.12, 0.425}, {0, 0, 0.392}, {0, 0.093, 0}, {0, 0, 0.095}};
  const double mass[6] = {3.7, 8.4, 2.3, 1.2, 1.2, 0.19};
  for (int i = 0; i < 6; ++i) {
    BodySpec b;
    b.parent = i - 1;
    b.axis = axes[i];
    b.position = pos[i];
    b.rotation = ff::rotx(0.1 * i);
    b.mass = mass[i] * scale;
    b.com = Vec3(0.01, 0.02, 0.1);
    b.inertia = box(b.mass, 0.1, 0.1, 0.3);
    b.armature = 0.1;
    s.bodies.push_back(b);
  }
  return ff::make_tree(s);
}

// Two revolute joints (shoulder about z, elbow about z at the first link's tip), each carrying a
// 3-D flexible aluminium link of N segments (bending in two planes and torsion), a payload.
ff::Tree flexible_arm(int N, double scale) {
  ff::TreeSpec s;
  BodySpec hub;
  hub.mass = 2.0;
  hub.inertia = box(2.0, 0.1, 0.1, 0.1);
  s.bodies.push_back(hub);
  ff::FlexibleLinkSpec link;
  link.length = 0.5;
  link.section = {70e9, 26e9, 2700.0, 2.0e-4, 1.7e-9, 6.7e-8, 6.0e-9};
  link.segments = N;
  link.damping_time = 1e-4;
  link.payload.mass = 0.5 * scale;
  const int tip1 = ff::append_flexible_link(s, 0, Vec3::Zero(), Mat3::Identity(), link);
  BodySpec elbow = hub;
  elbow.parent = tip1;
  elbow.position = Vec3(0.5 / (N > 1 ? 2 * (N - 1) : 1), 0, 0);
  s.bodies.push_back(elbow);
  link.name = "forearm";
  ff::append_flexible_link(s, static_cast<int>(s.bodies.size()) - 1, Vec3::Zero(), Mat3::Identity(), link);
  return ff::make_tree(s);
}

std::vector<ff::Tree> lanes_of(int kind, int N, int W) {
  std::vector<ff::Tree> trees;
  for (int l = 0; l < W; ++l) trees.push_back(kind == 0 ? rigid_arm(1.0 + 0.01 * l) : flexible_arm(N, 1.0 + 0.01 * l));
  return trees;
}

// A smooth state in every lane.
void fill_state(int nv, int W, std::vector<double>& q, std::vector<double>& qd) {
  q.assign(static_cast<std::size_t>(nv) * W, 0.0);
  qd.assign(q.size(), 0.0);
  for (int j = 0; j < nv; ++j)
    for (int l = 0; l < W; ++l) {
      q[static_cast<std::size_t>(j * W + l)] = 0.3 * std::sin(1.0 + j + 0.1 * l);
      qd[static_cast<std::size_t>(j * W + l)] = 0.5 * std::cos(2.0 + j);
    }
}

// args: kind (0 rigid 6-DOF, 1 two-link flexible), N, W.
void BM_LaneAba(benchmark::State& state) {
  const int W = static_cast<int>(state.range(2));
  const ff::TreeLanes tl = ff::make_tree_lanes(lanes_of(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), W));
  std::vector<double> q, qd, tau, qdd;
  fill_state(tl.nv, W, q, qd);
  tau.assign(q.size(), 0.0);
  qdd.assign(q.size(), 0.0);
  ff::TreeLanesWorkspace ws(tl);
  for (auto _ : state) {
    ff::compute_tree_forward_dynamics(tl, q.data(), qd.data(), tau.data(), nullptr, qdd.data(), ws);
    benchmark::DoNotOptimize(qdd.data());
  }
  state.counters["nv"] = tl.nv;
  state.counters["variant_calls/s"] = benchmark::Counter(W, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_LaneAba)->ArgNames({"flex", "N", "W"})
    ->Args({0, 0, 1})->Args({0, 0, 4})->Args({0, 0, 8})->Args({0, 0, 16})
    ->Args({1, 8, 1})->Args({1, 8, 8})->Args({1, 24, 8});

void BM_ScalarAba(benchmark::State& state) {
  const std::vector<ff::Tree> trees = lanes_of(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), 1);
  const ff::Tree& tree = trees[0];
  std::vector<double> q, qd;
  fill_state(tree.nv(), 1, q, qd);
  const Eigen::Map<const Eigen::VectorXd> Q(q.data(), tree.nv()), QD(qd.data(), tree.nv());
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(tree.nv());
  Eigen::VectorXd qdd(tree.nv());
  ff::TreeWorkspace ws(tree);
  for (auto _ : state) {
    ff::calc_forward_dynamics(tree, Q, QD, tau, qdd, ws);
    benchmark::DoNotOptimize(qdd.data());
  }
  state.counters["nv"] = tree.nv();
  state.counters["variant_calls/s"] = benchmark::Counter(1, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ScalarAba)->ArgNames({"flex", "N"})->Args({0, 0})->Args({1, 8})->Args({1, 24});

// Steps over lanes; args: kind, N, W, integrator (0 RK4, 1 SDIRK2).
void BM_LaneStep(benchmark::State& state) {
  const int W = static_cast<int>(state.range(2));
  const ff::TreeLanes tl = ff::make_tree_lanes(lanes_of(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), W));
  ff::TreeLanesState s = ff::make_tree_lanes_state(tl);
  fill_state(tl.nv, W, s.q, s.qd);
  ff::TreeStepWorkspace ws(tl);
  const bool sdirk = state.range(3) == 1;
  for (auto _ : state) {
    if (sdirk)
      ff::step_tree_sdirk2(tl, nullptr, s, ws, 1e-4);
    else
      ff::step_tree_rk4(tl, nullptr, s, ws, 1e-5);
    benchmark::DoNotOptimize(s.q.data());
  }
  state.counters["variant_steps/s"] = benchmark::Counter(W, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_LaneStep)->ArgNames({"flex", "N", "W", "sdirk2"})
    ->Args({0, 0, 8, 0})->Args({0, 0, 8, 1})->Args({1, 8, 8, 0})->Args({1, 8, 8, 1});

// One 3-D flexible aluminium link of N segments (bending in two planes and torsion, beta = 1e-4 s, a
// 0.5 kg payload) on a revolute hub about z, gravity along -z: nv = 3 (N - 1) + 1.
ff::Tree hub_link(int N) {
  ff::TreeSpec s;
  ff::FlexibleLinkSpec link;
  link.length = 0.5;
  link.section = {70e9, 26e9, 2700.0, 2.0e-4, 1.7e-9, 6.7e-8, 6.0e-9};
  link.segments = N;
  link.damping_time = 1e-4;
  link.payload.mass = 0.5;
  link.root_joint.type = ff::JointType::kRevolute;
  link.root_joint.armature = 0.05;
  ff::append_flexible_link(s, -1, Vec3::Zero(), Mat3::Identity(), link);
  return ff::make_tree(s);
}

// CVODE on hub_link(N), W = 1, from the straight link at rest: 0.1 s of simulated time in 1 ms
// samples with the hub torque held, constant (one BDF history) or a new value every sample (a
// restart every sample, as under a controller). args: N, solver (0 dense, 1 KLU, 2 GMRES), jump (0, 1).
void BM_TreeCvode(benchmark::State& state) {
  const int N = static_cast<int>(state.range(0));
  const ff::TreeLanes tl = ff::make_tree_lanes(std::vector<ff::Tree>{hub_link(N)});
  ff::TreeCvodeOptions opt;
  opt.solver = state.range(1) == 1   ? ff::TreeCvodeSolver::kKlu
               : state.range(1) == 2 ? ff::TreeCvodeSolver::kGmres
                                     : ff::TreeCvodeSolver::kDense;
  const bool jump = state.range(2) == 1;
  ff::TreeCvode cv(tl, opt);
  std::vector<double> tau(static_cast<std::size_t>(tl.nv), 0.0);
  std::vector<char> ok;
  const int samples = 100;
  const double h = 1e-3;
  bool all_ok = true;
  for (auto _ : state) {
    ff::TreeLanesState s = ff::make_tree_lanes_state(tl);
    for (int k = 0; k < samples; ++k) {
      tau[0] = jump ? 2.0 * std::sin(0.05 * k) + 0.1 * (k % 2) : 1.0;
      cv.advance(tl, tau.data(), s, k * h, h, ok);
      all_ok = all_ok && ok[0];
    }
    benchmark::DoNotOptimize(s.q.data());
  }
  if (!all_ok) state.SkipWithError("CVODE failed");
  state.counters["nv"] = tl.nv;
  const double sim_s = static_cast<double>(state.iterations()) * samples * h;
  state.counters["steps/sim_s"] = static_cast<double>(cv.steps(0)) / sim_s;
  state.counters["rhs/sim_s"] = static_cast<double>(cv.rhs_evals(0)) / sim_s;
  // Wall time per second of simulated time = 1 / this rate.
  state.counters["sim_s/s"] = benchmark::Counter(samples * h, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_TreeCvode)->ArgNames({"N", "klu", "jump"})->Unit(benchmark::kMillisecond)
    ->Args({24, 0, 1})->Args({24, 1, 1})->Args({24, 2, 1})->Args({24, 2, 0})->Args({8, 2, 1})->Args({8, 2, 0})->Args({48, 2, 1})->Args({48, 2, 0})->Args({24, 0, 0})->Args({24, 1, 0})
    ->Args({8, 0, 1})->Args({8, 1, 1})->Args({8, 0, 0})->Args({8, 1, 0})
    ->Args({48, 0, 1})->Args({48, 1, 1})->Args({48, 0, 0})->Args({48, 1, 0})->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
