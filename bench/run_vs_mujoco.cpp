// End to end, side by side in one run: `flexfarm run` of a study of V variants of the reference rig
// (N = 6, PD at 1 kHz, the 0.5 rad move held to 20 s; a grid of payload x joint stiffness) against
// MuJoCo's bare stepping loop over the same variants on the same cores (OpenMP, one mjData a
// variant, the models compiled before the clock starts), at MuJoCo's default step (Euler, 1 ms) and
// at the substeps that match flexfarm's accuracy. flexfarm's time is the whole process: reading the
// study, the variants, results.csv, results.sqlite, table.md and the plots.
// Accuracy: the nominal variant's tip deflection against CVODE (rtol 1e-10), RMS over the run.
// Run: build/bench/run_vs_mujoco [--variants 512] [--reps 3] [--substeps 1,12] [--mujoco-variants 512]
// (MuJoCo at K substeps is timed on the first --mujoco-variants variants and scaled to all of them.)
#include <mujoco/mujoco.h>
#include <omp.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bench/mujoco_rig.hpp"
#include "bench/mujoco_util.hpp"
#include "common/isa.hpp"
#include "kernel/batch.hpp"
#include "kernel/model_io.hpp"
#include "kernel/simulate.hpp"

namespace {

namespace fs = std::filesystem;
using ff::bench::compare_tips;
using ff::bench::load_mjcf;
using ff::bench::median;
using ff::bench::time_it;

// The study's grid: 32 payloads x V/32 joint stiffnesses around the reference rig's.
std::vector<double> levels(double nominal, double spread, int n) {
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(nominal * (1.0 - spread + 2.0 * spread * (n > 1 ? i / (n - 1.0) : 0.5)));
  return v;
}

std::string list(const std::vector<double>& v) {
  std::ostringstream s;
  s.precision(17);
  for (std::size_t i = 0; i < v.size(); ++i) s << (i ? ", " : "") << v[i];
  return "[" + s.str() + "]";
}

}  // namespace

int main(int argc, char** argv) {
  int variants = 512, reps = 3, mj_variants = 512;
  std::vector<int> substeps = {1, 12};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--variants" && has) variants = std::atoi(argv[++i]);
    else if (a == "--reps" && has) reps = std::atoi(argv[++i]);
    else if (a == "--substeps" && has) {
      substeps.clear();
      for (double k : ff::bench::parse_list(argv[++i])) substeps.push_back(static_cast<int>(k));
    }
    else if (a == "--mujoco-variants" && has) mj_variants = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: %s [--variants 512] [--reps 3] [--substeps 1,12] [--mujoco-variants 512]\n", argv[0]);
      return 2;
    }
  }
  if (variants % 32 != 0 || variants < 32) {
    std::fprintf(stderr, "--variants must be a multiple of 32\n");
    return 2;
  }
  mju_user_warning = ff::bench::quiet_warning;
  const std::string source = FLEXFARM_SOURCE_DIR, binary = FLEXFARM_BINARY;
  const fs::path dir = fs::temp_directory_path() / ("ff_run_vs_mujoco_" + std::to_string(::getpid()));
  fs::create_directories(dir);

  // The study and, for MuJoCo, the same variants as models.
  const ff::Model base = ff::load_model(source + "/configs/fbtb.yaml");
  const std::vector<double> payloads = levels(base.spec.payload_mass, 0.3, 32);
  const std::vector<double> stiffness = levels(base.spec.joints.stiffness, 0.2, variants / 32);
  {
    std::ofstream st(dir / "study.yaml");
    st << "name: run_vs_mujoco\nseed: 1\nmodel: " << source << "/configs/fbtb.yaml\n"
       << "set:\n  trajectory.moves: [{target: 0.5, hold: 17.0}]\n  simulation.integrator: midpoint\n"
       << "variables:\n  - path: payload.mass\n    levels: " << list(payloads) << "\n"
       << "  - path: joints.stiffness\n    levels: " << list(stiffness) << "\ndesign: {type: grid}\n";
  }
  auto spec_of = [&](double payload, double k) {
    ff::ModelSpec s = base.spec;
    s.trajectory.moves = {{0.5, 17.0}};
    s.simulation.integrator = ff::Integrator::kMidpoint;
    s.payload_mass = payload;
    s.joints.stiffness = k;
    return s;
  };
  std::vector<ff::Model> models;
  for (double p : payloads)
    for (double k : stiffness) models.push_back(ff::make_model(spec_of(p, k)));
  const long samples = std::lround(models[0].duration / models[0].control_period) + 1;

  // Accuracy on the nominal variant: flexfarm's midpoint (as `run` steps it), MuJoCo at each K.
  const ff::Model nominal = ff::make_model(spec_of(base.spec.payload_mass, base.spec.joints.stiffness));
  ff::ModelSpec ref_spec = nominal.spec;
  ref_spec.simulation.integrator = ff::Integrator::kCvodeDense;
  ref_spec.simulation.rtol = 1e-10;
  const ff::Model ref_model = ff::make_model(ref_spec);
  const std::vector<double> ref = ff::simulate(ff::make_batch(std::vector<ff::Model>{ref_model})).traces[0].tip_deflection;
  const std::vector<double> ff_tip =
      ff::simulate(ff::make_batch(std::vector<ff::Model>{nominal})).traces[0].tip_deflection;
  const double ff_err = compare_tips(ff_tip, ref).rms;

  // flexfarm run, the whole process, median of reps.
  std::vector<double> ff_times;
  for (int r = 0; r < reps; ++r) {
    fs::remove_all(dir / "out");
    const std::string cmd = "'" + binary + "' run '" + (dir / "study.yaml").string() + "' --out '" +
                            (dir / "out").string() + "' > '" + (dir / "log.txt").string() + "' 2>&1";
    int rc = 0;
    ff_times.push_back(time_it([&] { rc = std::system(cmd.c_str()); }));
    if (rc != 0) {
      std::fprintf(stderr, "flexfarm run failed (%d); see %s\n", rc, (dir / "log.txt").c_str());
      return 1;
    }
  }
  const double ff_wall = median(ff_times);
  const int threads = omp_get_max_threads();
  std::printf("run_vs_mujoco: %d variants of the reference rig (N = 6), %.0f s each, PD at 1 kHz; %d threads; "
              "flexfarm kernels %s\n\n",
              variants, models[0].duration, threads, ff::describe_isa().c_str());
  std::printf("%-34s %12s %14s %14s %10s\n", "setting", "wall s", "variant-steps/s", "tip RMS err m", "ratio");
  const double steps = static_cast<double>(variants) * (samples - 1);
  std::printf("%-34s %12.3f %14.4g %14.3g %10s\n", "flexfarm run (midpoint, 1 ms)", ff_wall, steps / ff_wall, ff_err,
              "1");

  // MuJoCo: the variants' models compiled first, then the stepping loop timed.
  for (int K : substeps) {
    const int M = std::min(mj_variants, variants);
    std::vector<mjModel*> mm(M);
    std::vector<mjData*> md(M);
    for (int v = 0; v < M; ++v) {
      mm[v] = load_mjcf(ff::bench::rig_mjcf(models[v], "Euler", K));
      md[v] = mj_makeData(mm[v]);
    }
    std::vector<double> tip(static_cast<std::size_t>(samples) * M);
    std::vector<double> times;
    for (int r = 0; r < reps; ++r)
      times.push_back(time_it([&] {
#pragma omp parallel for schedule(dynamic, 1)
        for (int v = 0; v < M; ++v) ff::bench::run_rig_mujoco(mm[v], md[v], models[v], K, samples, &tip[v * samples]);
      }));
    // Accuracy on the nominal variant's own MuJoCo model.
    mjModel* nm = load_mjcf(ff::bench::rig_mjcf(nominal, "Euler", K));
    mjData* nd = mj_makeData(nm);
    std::vector<double> ntip(samples);
    const bool ok = ff::bench::run_rig_mujoco(nm, nd, nominal, K, samples, ntip.data());
    const double err = ok ? compare_tips(ntip, ref).rms : NAN;
    mj_deleteData(nd);
    mj_deleteModel(nm);
    for (int v = 0; v < M; ++v) mj_deleteData(md[v]), mj_deleteModel(mm[v]);
    const double wall = median(times) * variants / M;
    char label[64];
    std::snprintf(label, sizeof label, "MuJoCo Euler, %g ms%s", 1.0 / K, M < variants ? " (scaled)" : "");
    std::printf("%-34s %12.3f %14.4g %14.3g %9.1fx\n", label, wall, steps / wall, err, wall / ff_wall);
  }
  std::printf("\nratio: MuJoCo's stepping loop's wall time / flexfarm run's; flexfarm is at least as accurate "
              "where its error is the smaller.\n");
  fs::remove_all(dir);
  return 0;
}
