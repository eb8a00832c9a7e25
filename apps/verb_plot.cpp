// flexfarm plot STUDY.yaml --eval 3,17 --out DIR: time series of chosen variants of a study,
// simulated again (every variant is a pure function of the study, so this is its run exactly).
#include <cstdio>
#include <sstream>

#include "apps/verbs.hpp"
#include "arm/arm_simulate.hpp"
#include "jobs/report.hpp"
#include "common/files.hpp"
#include "common/text.hpp"
#include "kernel/simulate.hpp"
#include "sweep/study.hpp"

namespace ff {

void add_plot_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("plot", "Plot the time series of chosen variants of a study (the rig: tip angle, hub "
                                         "angle, tip deflection, torque; an arm: joints, torques, tool error, link "
                                         "deflection), and write their traces");
  struct Args {
    std::string study, out, evals;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("study", args->study, "study YAML file")->required()->check(kPath)->check(CLI::ExistingFile);
  cmd->add_option("--eval", args->evals, "eval_ids, comma separated (at most 12), e.g. 0,40,80")->required();
  cmd->add_option("--out", args->out, "output directory (created)")->required()->check(kPath);
  cmd->callback([args] {
    const Study study = load_study(args->study);
    std::vector<int> ids;
    std::stringstream ss(args->evals);
    std::string part;
    while (std::getline(ss, part, ',')) {
      const auto id = parse_integer(part, 0, static_cast<long long>(study.variants.size()) - 1);
      if (!id)
        throw CLI::ValidationError("--eval", "'" + part + "' is not an eval_id of this study (0.." +
                                                 std::to_string(study.variants.size() - 1) + ")");
      ids.push_back(static_cast<int>(*id));
    }
    if (ids.empty() || ids.size() > 12) throw CLI::ValidationError("--eval", "give 1 to 12 eval_ids");
    make_directories(args->out);
    std::vector<std::string> labels = calc_legend_labels(study, ids);
    for (std::size_t k = 0; k < ids.size(); ++k) labels[k] = std::to_string(ids[k]) + ": " + labels[k];
    // Each variant alone (a variant's bits are the same in any lane), its trace written as `write` does.
    auto run_each = [&](auto simulate_one, auto write) {
      std::vector<decltype(simulate_one(0))> traces;
      for (int id : ids) traces.push_back(simulate_one(id));
      std::vector<const typename decltype(traces)::value_type*> ptrs;
      for (std::size_t k = 0; k < traces.size(); ++k) {
        char name[48];
        std::snprintf(name, sizeof name, "/trace_%06d.csv", ids[k]);
        write(traces[k], args->out + name);
        ptrs.push_back(&traces[k]);
      }
      return std::make_pair(std::move(traces), ptrs);
    };
    std::string files;
    if (study.arm) {
      const auto [traces, ptrs] = run_each(
          [&](int id) {
            const ArmModel m = make_variant_arm(study, study.variants[id]);
            return std::move(simulate_arms(std::span<const ArmModel>(&m, 1)).traces[0]);
          },
          write_arm_trace_csv);
      for (const std::string& f : write_arm_plots(args->out, labels, ptrs, study.name, study.arm_nominal)) files += (files.empty() ? "" : ",") + f;
    } else {
      const auto [traces, ptrs] = run_each(
          [&](int id) {
            const Model m = make_variant_model(study, study.variants[id]);
            return std::move(simulate(make_batch(std::span<const Model>(&m, 1))).traces[0]);
          },
          write_trace_csv);
      write_trace_plots(args->out, labels, ptrs, study.name);
      files = "tip_angle.png,hub_angle.png,tip_deflection.png,hub_torque.png";
    }
    print_safe(stdout, "wrote %s/{%s} and trace_NNNNNN.csv for %zu variants\n", args->out.c_str(), files.c_str(), ids.size());
  });
}

}  // namespace ff
