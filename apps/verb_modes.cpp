// flexfarm modes MODEL.yaml: natural frequencies and damping, clamped and in the closed loop.
#include <cstdio>

#include "apps/verbs.hpp"
#include "kernel/modes.hpp"

namespace ff {

namespace {

void print_modes(const char* title, const std::vector<Mode>& modes, int count) {
  std::printf("%s\n  %-4s %12s %12s %10s\n", title, "mode", "f (Hz)", "omega (rad/s)", "zeta");
  int shown = 0;
  for (const auto& m : modes) {
    if (shown++ == count) break;
    if (m.oscillatory)
      std::printf("  %-4d %12.4f %12.4f %10.4f\n", shown, m.frequency_hz(), m.omega_n, m.zeta);
    else
      std::printf("  %-4d %12s %12.4f %10s   real pole, time constant %.4g s\n", shown, "-", m.omega_n, "-",
                  1.0 / m.omega_n);
  }
}

}  // namespace

void add_modes_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("modes", "Print clamped-hub and closed-loop natural frequencies, damping ratios "
                                          "and the equivalent cantilever stiffness 3EI/L");
  struct Args {
    std::string model;
    std::vector<std::string> sets;
    int count = 6;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("model", args->model, "model YAML file, e.g. configs/fbtb.yaml")->required()->check(CLI::ExistingFile);
  cmd->add_option("--set", args->sets, "override a model parameter, PATH=VALUE (e.g. segments=24); repeatable");
  cmd->add_option("--count", args->count, "modes to list per table")->check(CLI::PositiveNumber);
  cmd->callback([args] {
    const Model m = load_model_with(args->model, args->sets);
    const auto& b = m.spec.beam;
    if (m.nseg > 1)
      std::printf("model %s: N = %d segments, cell l = %.5f m, joint k = %.5g N m/rad, c = %.5g N m s/rad\n",
                  args->model.c_str(), m.nseg, m.cell, m.joint_k[1], m.joint_c[1]);
    else
      std::printf("model %s: N = 1, one rigid arm (no joints)\n", args->model.c_str());
    std::printf("beam mass %.2f kg, EI = %.5g N m^2\n", calc_beam_mass(b), b.youngs_modulus * calc_area_moment(b));
    std::printf("equivalent cantilever stiffness 3EI/L (seed eq. 5):\n");
    std::printf("  one cell   (L = %.5f m): %10.2f kN m/rad\n", m.cell, 1e-3 * calc_cantilever_stiffness(b, m.cell));
    std::printf("  whole beam (L = %.5f m): %10.2f kN m/rad\n", b.length, 1e-3 * calc_cantilever_stiffness(b, b.length));
    print_modes("clamped hub:", calc_clamped_modes(m), args->count);
    print_modes("closed loop (continuous-time PD on the hub):", calc_closed_loop_modes(m), args->count);
    const auto res = calc_closed_loop_resonances(m);
    if (res.size() >= 2)
      std::printf("closed-loop resonances for the notch filter: omega_z1 = %.4f rad/s (%.4f Hz), omega_z2 = %.4f rad/s (%.4f Hz)\n",
                  res[0], res[0] / (2 * 3.141592653589793), res[1], res[1] / (2 * 3.141592653589793));
    std::printf("fixed-step substeps per control period: %d (h = %.3g ms)\n", m.substeps,
                1e3 * m.control_period / m.substeps);
  });
}

}  // namespace ff
