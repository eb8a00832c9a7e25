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

// The reference motion: 0 -> 0.5 rad in 3 s, held 17 s (20 s, 20000 controller steps);
// seconds < 20 simulates only the start of it.
ff::ModelSpec rig_spec(int nseg, ff::Integrator integrator, int substeps, double seconds) {
  ff::ModelSpec s;
  s.simulation.duration = seconds;
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
std::string make_mjcf(const ff::Model& m, const char* integrator, int substeps) {
  const auto& b = m.spec.beam;
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco model=\"fbtb\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\" balanceinertia=\"false\"/>\n"
    << "  <option gravity=\"0 0 0\" timestep=\"" << m.control_period / substeps << "\" integrator=\"" << integrator << "\">\n"
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

// MuJoCo's warnings are checked per run in mjData::warning instead of printed.
void quiet_warning(const char*) {}

bool mujoco_diverged(const mjData* d) {
  for (int w : {mjWARN_BADQPOS, mjWARN_BADQVEL, mjWARN_BADQACC, mjWARN_BADCTRL})
    if (d->warning[w].number > 0) return true;
  return false;
}

// One variant from rest: PD sampled at t_k = k T from the state at t_k, held over the substeps of the
// period. tip (nsamples) receives the tip deflection at every sample, as flexfarm's traces do.
// Returns false (early) when MuJoCo diverged.
bool run_mujoco(const mjModel* mm, mjData* d, const ff::Model& m, int substeps, long nsamples, double* tip) {
  mj_resetData(mm, d);
  const double T = m.control_period, kp = m.spec.controller.kp, kd = m.spec.controller.kd;
  for (long k = 0; k < nsamples; ++k) {
    const double r = ff::calc_reference(m.spec.trajectory, k * T);
    d->ctrl[0] = kp * (r - d->qpos[0]) - kd * d->qvel[0];
    tip[k] = mujoco_tip(d->qpos, m);
    if (k + 1 == nsamples) break;
    for (int j = 0; j < substeps; ++j) mj_step(mm, d);
    if (mujoco_diverged(d)) return false;
  }
  return true;
}

// ---------------------------------------------------------------- timing and statistics

double time_it(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double median(std::vector<double> x) {
  std::sort(x.begin(), x.end());
  const std::size_t n = x.size();
  return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
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
  mjModel* mj_euler = load_mjcf(make_mjcf(m, "Euler", mj_sub));
  mjModel* mj_rk4 = load_mjcf(make_mjcf(m, "RK4", mj_sub));
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
    for (int v = 0; v < M; ++v) bad += !run_mujoco(sd.mm, sd.data[v], m, mj_sub, nsamples, sd.tips[v].data());
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
    err.push_back(compare(i < 2 ? sides[i].tips[0] : ffs[i - 2].runs[0].traces[0].tip_deflection, ref));
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

std::vector<double> parse_list(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, ',')) out.push_back(std::stod(tok));
  return out;
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
