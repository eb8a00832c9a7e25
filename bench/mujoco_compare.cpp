// Side by side, in one run: flexfarm's batch kernel against MuJoCo (2.2) on the reference rig
// (docs/reference-rig.md): throughput in variant-steps per second (1 ms controller steps) and
// tip-deflection accuracy of both against flexfarm's CVODE reference.
// Run: mujoco_compare [--segments 6,24,48] [--variants 16] [--reps 5]
#include <mujoco/mujoco.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "kernel/batch.hpp"
#include "kernel/model.hpp"
#include "kernel/modes.hpp"
#include "kernel/simulate.hpp"
#include "kernel/trajectory.hpp"

namespace {

// ==================== flexfarm configuration under test: edit HERE ====================
// Point the benchmark at another integrator, substep count or lane width.
struct FlexfarmConfig {
  const char* label = "flexfarm RK4";          // row name in the tables
  ff::Integrator integrator = ff::Integrator::kRk4;
  int substeps = 0;                            // per 1 ms control period; 0 = automatic
  int lanes = 8;                               // W: variants advanced in lock-step per batch
};
FlexfarmConfig flexfarm_config() { return FlexfarmConfig{}; }
// =======================================================================================

// The reference motion: 0 -> 0.5 rad in 3 s, held 17 s (20 s, 20000 controller steps).
ff::ModelSpec rig_spec(int nseg, ff::Integrator integrator, int substeps) {
  ff::ModelSpec s;
  s.segments = nseg;
  s.trajectory.moves = {{0.5, 17.0}};
  s.simulation.integrator = integrator;
  s.simulation.substeps = substeps;
  return s;
}

// ---------------------------------------------------------------- MuJoCo model

// Box inertia about the segment centre: x along the beam, z vertical. Izz is flexfarm's seg_inertia;
// Ixx, Iyy are never excited (all hinges about z) but satisfy the triangle inequality.
struct Diag {
  double x, y, z;
};

// MJCF of the rig: nested bodies, one hinge about z per segment, payload body welded at the tip.
std::string make_mjcf(const ff::Model& m, const char* integrator) {
  const auto& b = m.spec.beam;
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco model=\"fbtb\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\" balanceinertia=\"false\"/>\n"
    << "  <option gravity=\"0 0 0\" timestep=\"" << m.control_period << "\" integrator=\"" << integrator << "\">\n"
    << "    <flag contact=\"disable\"/>\n  </option>\n  <worldbody>\n";
  std::string indent = "    ";
  for (int i = 0; i < m.nseg; ++i) {
    const double li = m.seg_length[i], mi = m.seg_mass[i];
    const Diag in{mi * (b.height * b.height + b.thickness * b.thickness) / 12.0,
                  mi * (li * li + b.height * b.height) / 12.0, m.seg_inertia[i]};
    x << indent << "<body name=\"seg" << i << "\" pos=\"" << (i == 0 ? 0.0 : m.seg_length[i - 1]) << " 0 0\">\n";
    indent += "  ";
    // Hub joint: the hub inertia is its armature (a rotor inertia on the dof). Others: spring + damper.
    x << indent << "<joint name=\"j" << i << "\" type=\"hinge\" axis=\"0 0 1\" pos=\"0 0 0\" limited=\"false\"";
    if (i == 0)
      x << " armature=\"" << m.spec.hub_inertia << "\"";
    else
      x << " stiffness=\"" << m.joint_k[i] << "\" damping=\"" << m.joint_c[i] << "\" springref=\"0\"";
    x << "/>\n";
    x << indent << "<inertial pos=\"" << 0.5 * li << " 0 0\" mass=\"" << mi << "\" diaginertia=\"" << in.x << " "
      << in.y << " " << in.z << "\"/>\n";
  }
  const double ip = m.spec.payload_inertia;
  x << indent << "<body name=\"payload\" pos=\"" << m.seg_length.back() << " 0 0\">\n"
    << indent << "  <inertial pos=\"0 0 0\" mass=\"" << m.spec.payload_mass << "\" diaginertia=\"" << ip << " " << ip
    << " " << ip << "\"/>\n"
    << indent << "</body>\n";
  for (int i = m.nseg - 1; i >= 0; --i) {
    indent.resize(indent.size() - 2);
    x << indent << "</body>\n";
  }
  x << "  </worldbody>\n  <actuator>\n"
    << "    <motor name=\"hub\" joint=\"j0\" gear=\"1\" ctrllimited=\"false\"/>\n  </actuator>\n</mujoco>\n";
  return x.str();
}

// Compiles MJCF text through MuJoCo's virtual file system (no temp file).
mjModel* load_mjcf(const std::string& xml) {
  auto vfs = std::make_unique<mjVFS>();  // ~2 MB: heap, not stack
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), "rig.xml", static_cast<int>(xml.size())) != 0)
    throw std::runtime_error("mj_makeEmptyFileVFS failed");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), "rig.xml")], xml.data(), xml.size());
  char err[1000] = "";
  mjModel* mm = mj_loadXML("rig.xml", vfs.get(), err, sizeof err);
  mj_deleteVFS(vfs.get());
  if (!mm) throw std::runtime_error(std::string("mj_loadXML: ") + err);
  return mm;
}

// MuJoCo's compiled body inertias must be the ones written (no rebalancing, no axis reordering).
bool mujoco_inertia_as_written(const mjModel* mm, const ff::Model& m) {
  const auto& b = m.spec.beam;
  bool ok = true;
  for (int i = 0; i < m.nseg; ++i) {
    const int id = i + 1;  // body 0 is the world
    const double li = m.seg_length[i], mi = m.seg_mass[i];
    const double want[3] = {mi * (b.height * b.height + b.thickness * b.thickness) / 12.0,
                            mi * (li * li + b.height * b.height) / 12.0, m.seg_inertia[i]};
    for (int a = 0; a < 3; ++a) ok &= std::abs(mm->body_inertia[3 * id + a] - want[a]) <= 1e-12 * want[a];
    ok &= mm->body_iquat[4 * id] == 1.0 && std::abs(mm->body_mass[id] - mi) <= 1e-12 * mi;
  }
  return ok;
}

// Max relative difference of MuJoCo's joint-space mass matrix at q = 0 from flexfarm's.
double mass_matrix_difference(const mjModel* mm, const ff::Model& m) {
  mjData* d = mj_makeData(mm);
  mj_forward(mm, d);
  const int n = mm->nv;
  std::vector<mjtNum> full(static_cast<std::size_t>(n) * n);
  mj_fullM(mm, full.data(), d->qM);
  mj_deleteData(d);
  const Eigen::MatrixXd ref = ff::calc_mass_matrix(m, Eigen::VectorXd::Zero(m.nseg));
  const double scale = ref.cwiseAbs().maxCoeff();
  double worst = 0.0;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      worst = std::max(worst, std::abs(full[r * n + c] - ref(r, c)) / std::max(std::abs(ref(r, c)), 1e-12 * scale));
  return worst;
}

// Tip deflection sum L_i sin(q_1 + ... + q_i) from MuJoCo's relative hinge angles.
double mujoco_tip(const double* qpos, const ff::Model& m) {
  double phi = 0.0, defl = 0.0;
  for (int i = 0; i < m.nseg; ++i) {
    if (i > 0) phi += qpos[i];
    defl += m.seg_length[i] * std::sin(phi);
  }
  return defl;
}

// One variant from rest: PD sampled at t_k = k T from the state at t_k, held over one mj_step.
// tip (nsamples) receives the tip deflection at every sample, as flexfarm's traces do.
void run_mujoco(const mjModel* mm, mjData* d, const ff::Model& m, long nsamples, double* tip) {
  mj_resetData(mm, d);
  const double T = m.control_period, kp = m.spec.controller.kp, kd = m.spec.controller.kd;
  for (long k = 0; k < nsamples; ++k) {
    const double r = ff::calc_reference(m.spec.trajectory, k * T);
    d->ctrl[0] = kp * (r - d->qpos[0]) - kd * d->qvel[0];
    tip[k] = mujoco_tip(d->qpos, m);
    if (k + 1 == nsamples) break;
    mj_step(mm, d);
  }
}

// ---------------------------------------------------------------- timing and statistics

template <class F>
double median_seconds(int reps, F&& f) {
  f();  // warm-up
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return reps % 2 ? t[reps / 2] : 0.5 * (t[reps / 2 - 1] + t[reps / 2]);
}

struct Error {
  double rms, max;
};
Error compare(const std::vector<double>& a, const std::vector<double>& ref) {
  if (a.size() != ref.size()) throw std::runtime_error("trace lengths differ");
  double ss = 0.0, mx = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    const double e = a[k] - ref[k];
    ss += e * e;
    mx = std::max(mx, std::abs(e));
  }
  return {std::sqrt(ss / a.size()), mx};
}

double rms(const std::vector<double>& a) {
  double ss = 0.0;
  for (double x : a) ss += x * x;
  return std::sqrt(ss / a.size());
}

struct Summary {
  int nseg;
  double ratio, ff_rms, mj_rms;
};

// Everything for one segment count. Returns false when the two rigs differ.
bool run_case(int nseg, int M, int reps, Summary& out) {
  const FlexfarmConfig cfg = flexfarm_config();
  const ff::Model m = ff::make_model(rig_spec(nseg, cfg.integrator, cfg.substeps));
  const ff::Model mref = ff::make_model(rig_spec(nseg, ff::Integrator::kCvodeDense, 0));
  const long nsamples = std::lround(m.duration / m.control_period) + 1;
  const double steps = static_cast<double>(nsamples - 1) * M;  // variant-steps per repetition

  std::printf("\n=== N = %d segments, M = %d variants x %ld steps of %g ms (%.0f s), median of %d ===\n", nseg, M,
              nsamples - 1, 1e3 * m.control_period, m.duration, reps);

  // The MuJoCo rig must be flexfarm's rig.
  mjModel* mj_euler = load_mjcf(make_mjcf(m, "Euler"));
  mjModel* mj_rk4 = load_mjcf(make_mjcf(m, "RK4"));
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

  // Reference and flexfarm batches.
  const std::vector<double> ref = ff::simulate(ff::make_batch(std::vector<ff::Model>{mref})).traces[0].tip_deflection;
  const int W = cfg.lanes;
  if (M % W != 0) throw std::runtime_error("--variants must be a multiple of the lane width W");
  const int nbatch = M / W;
  const ff::BatchModel bm = ff::make_batch(std::vector<ff::Model>(W, m));
  std::vector<ff::BatchRun> runs(nbatch);
  auto run_ff = [&](int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int bi = 0; bi < nbatch; ++bi) runs[bi] = ff::simulate(bm);
  };

  // MuJoCo: one mjData and one trace per variant.
  std::vector<mjData*> data(M);
  std::vector<std::vector<double>> tips(M, std::vector<double>(nsamples));
  auto run_mj = [&](const mjModel* mm, int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int v = 0; v < M; ++v) run_mujoco(mm, data[v], m, nsamples, tips[v].data());
  };

  struct Row {
    std::string name;
    int substeps, threads;
    double rate;
  };
  std::vector<Row> rows;
  std::vector<double> tip_euler, tip_rk4;
  for (const mjModel* mm : {mj_euler, mj_rk4}) {
    for (auto& d : data) d = mj_makeData(mm);
    const std::string name = mm == mj_euler ? "MuJoCo Euler (semi-implicit)" : "MuJoCo RK4";
    for (int th : {1, 2}) rows.push_back({name, 1, th, steps / median_seconds(reps, [&] { run_mj(mm, th); })});
    (mm == mj_euler ? tip_euler : tip_rk4) = tips[0];
    for (auto& d : data) mj_deleteData(d);
  }
  const std::string ffname = std::string(cfg.label) + " W=" + std::to_string(W);
  for (int th : {1, 2}) rows.push_back({ffname, m.substeps, th, steps / median_seconds(reps, [&] { run_ff(th); })});
  mj_deleteModel(mj_euler);
  mj_deleteModel(mj_rk4);
  for (const auto& r : runs)
    for (auto st : r.status)
      if (st != ff::LaneStatus::kOk) throw std::runtime_error("a flexfarm lane failed");

  std::printf("\n%-34s %8s %7s %18s %12s\n", "throughput", "substeps", "threads", "variant-steps/s", "/ MuJoCo Eu");
  for (const auto& r : rows) {
    const double base = rows[r.threads == 1 ? 0 : 1].rate;  // MuJoCo Euler, same thread count
    std::printf("%-34s %8d %7d %18.4g %12.2f\n", r.name.c_str(), r.substeps, r.threads, r.rate, r.rate / base);
  }
  if (nbatch < 2) std::printf("(only one batch of W lanes: flexfarm's 2-thread row has nothing to share)\n");

  const Error e_eu = compare(tip_euler, ref), e_rk = compare(tip_rk4, ref),
              e_ff = compare(runs[0].traces[0].tip_deflection, ref);
  std::printf("\n%-34s %14s %14s   (reference: CVODE dense rtol %g; tip deflection RMS %.1f mm)\n", "accuracy vs CVODE",
              "RMS error mm", "max error mm", mref.spec.simulation.rtol, 1e3 * rms(ref));
  std::printf("%-34s %14.4g %14.4g\n", "MuJoCo Euler (semi-implicit)", 1e3 * e_eu.rms, 1e3 * e_eu.max);
  std::printf("%-34s %14.4g %14.4g\n", "MuJoCo RK4", 1e3 * e_rk.rms, 1e3 * e_rk.max);
  std::printf("%-34s %14.4g %14.4g\n", ffname.c_str(), 1e3 * e_ff.rms, 1e3 * e_ff.max);

  out = {nseg, rows[4].rate / rows[0].rate, e_ff.rms, e_eu.rms};
  std::printf("\nN=%d: flexfarm / MuJoCo(Euler) throughput = %.2f (1 thread), %.2f (2 threads)\n", nseg, out.ratio,
              rows[5].rate / rows[1].rate);
  return true;
}

std::vector<int> parse_list(const std::string& s) {
  std::vector<int> out;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, ',')) out.push_back(std::stoi(tok));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> segments = {6};
  int M = 16, reps = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--segments" && has) {
      segments = parse_list(argv[++i]);
    } else if (a == "--variants" && has) {
      M = std::atoi(argv[++i]);
    } else if (a == "--reps" && has) {
      reps = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: %s [--segments 6,24,48] [--variants 16] [--reps 5]\n", argv[0]);
      return 2;
    }
  }
  if (segments.empty() || M < 1 || reps < 1) {
    std::fprintf(stderr, "bad arguments\n");
    return 2;
  }
  std::printf("MuJoCo %s, flexfarm config: %s, substeps %d (0 = auto), W = %d\n", mj_versionString(),
              flexfarm_config().label, flexfarm_config().substeps, flexfarm_config().lanes);
  try {
    std::vector<Summary> sums;
    for (int n : segments) {
      Summary s{};
      if (!run_case(n, M, reps, s)) return 1;
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
