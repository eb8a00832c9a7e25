// flexfarm plot STUDY.yaml --eval 3,17 --out DIR: time series of chosen variants of a study,
// simulated again (every variant is a pure function of the study, so this is its run exactly).
#include <cstdio>
#include <sstream>

#include "apps/verbs.hpp"
#include "jobs/report.hpp"
#include "kernel/files.hpp"
#include "kernel/simulate.hpp"
#include "sweep/study.hpp"

namespace ff {

void add_plot_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("plot", "Plot the time series (tip angle, hub angle, tip deflection, torque) of "
                                         "chosen variants of a study, and write their traces");
  struct Args {
    std::string study, out, evals;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("study", args->study, "study YAML file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--eval", args->evals, "eval_ids, comma separated (at most 12), e.g. 0,40,80")->required();
  cmd->add_option("--out", args->out, "output directory (created)")->required();
  cmd->callback([args] {
    const Study study = load_study(args->study);
    std::vector<int> ids;
    std::stringstream ss(args->evals);
    std::string part;
    while (std::getline(ss, part, ',')) {
      int id = -1;
      try {
        id = std::stoi(part);
      } catch (const std::exception&) {
      }
      if (id < 0 || id >= static_cast<int>(study.variants.size()))
        throw CLI::ValidationError("--eval", "'" + part + "' is not an eval_id of this study (0.." +
                                                 std::to_string(study.variants.size() - 1) + ")");
      ids.push_back(id);
    }
    if (ids.empty() || ids.size() > 12) throw CLI::ValidationError("--eval", "give 1 to 12 eval_ids");
    std::vector<Trace> traces;
    std::vector<std::string> labels;
    for (int id : ids) {
      const Model m = make_variant_model(study, study.variants[id]);
      traces.push_back(std::move(simulate(make_batch(std::span<const Model>(&m, 1))).traces[0]));
      labels.push_back(std::to_string(id) + ": " + study.variants[id].label);
    }
    make_directories(args->out);
    std::vector<const Trace*> ptrs;
    for (std::size_t k = 0; k < traces.size(); ++k) {
      char name[48];
      std::snprintf(name, sizeof name, "/trace_%06d.csv", ids[k]);
      write_trace_csv(traces[k], args->out + name);
      ptrs.push_back(&traces[k]);
    }
    write_trace_plots(args->out, labels, ptrs, study.name);
    std::printf("wrote %s/{tip_angle,hub_angle,tip_deflection,hub_torque}.png and trace_NNNNNN.csv for %zu variants\n",
                args->out.c_str(), ids.size());
  });
}

}  // namespace ff
