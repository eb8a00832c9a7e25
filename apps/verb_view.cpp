// flexfarm view MODEL_OR_STUDY --out view.html: one self-contained HTML page (plotting/view_html.hpp)
// playing a run in 3-D in the browser, among the world's obstacles; for a study, one variant solid and
// others as ghosts (a Monte Carlo spread), the worst clearance pair highlighted.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "apps/verbs.hpp"
#include "arm/arm_simulate.hpp"
#include "kernel/batch.hpp"
#include "plotting/view_arm.hpp"
#include "sweep/study.hpp"

namespace ff {

namespace {

struct ViewArgs {
  std::string input, out;
  std::vector<std::string> sets;
  int eval_id = -1;
  int ghosts = 20;
};

// The run of one arm, as a variant of the page.
ViewVariant run_view_variant(const ArmModel& m, const std::string& label) {
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1), {.keep_q = true});
  if (run.status[0] != LaneStatus::kOk)
    std::fprintf(stderr, "warning: %s: the run ended %s; the page shows it up to there\n", label.c_str(),
                 lane_status_name(run.status[0]));
  return make_arm_view_variant(m, run.traces[0].t(), run.q[0], label);
}

void print_written(const std::string& out, const ViewScene& s) {
  const ViewVariant& v = s.variants.front();
  std::printf("wrote %s: %s solid%s, %zu samples, %zu capsules, %zu obstacles", out.c_str(), v.label.c_str(),
              s.variants.size() > 1 ? (" and " + std::to_string(s.variants.size() - 1) + " ghosts").c_str() : "",
              v.t.size(), s.capsules.size(), s.shapes.size());
  if (v.worst_capsule >= 0) {
    const std::string other = v.worst_shape >= 0 ? s.shapes[static_cast<std::size_t>(v.worst_shape)].name
                                                 : s.capsules[static_cast<std::size_t>(-v.worst_shape - 2)].name;
    std::printf("; least clearance %.4g m, %s to %s at %.3f s", v.min_clearance,
                s.capsules[static_cast<std::size_t>(v.worst_capsule)].name.c_str(), other.c_str(), v.worst_time);
  }
  std::printf("\n");
}

void view_study(const ViewArgs& a) {
  const Study study = load_study(a.input);
  if (!study.arm) throw CLI::ValidationError("input", "the viewer shows arm models; this study's model is the reference rig");
  const int n = static_cast<int>(study.variants.size());
  if (a.eval_id >= n) throw CLI::ValidationError("--eval", "the study has eval_ids 0.." + std::to_string(n - 1));
  // The variants shown: --eval's (if given) and up to --ghosts others, evenly spaced over the eval_ids.
  std::vector<int> ids;
  if (a.eval_id >= 0) ids.push_back(a.eval_id);
  const int others = std::min(a.ghosts + (a.eval_id >= 0 ? 0 : 1), n - (a.eval_id >= 0 ? 1 : 0));
  for (int i = 0, k = 0; k < others && i < n; ++i) {
    const int id = static_cast<int>(std::floor(static_cast<double>(i) * n / std::max(others, 1)));
    if (id == a.eval_id || std::find(ids.begin(), ids.end(), id) != ids.end()) continue;
    ids.push_back(id);
    ++k;
  }
  std::vector<ViewVariant> variants;
  ViewScene scene;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const Variant& v = study.variants[static_cast<std::size_t>(ids[i])];
    const ArmModel m = make_variant_arm(study, v);
    if (i == 0) scene = make_arm_view_scene(m, study.name);
    std::fprintf(stderr, "\rview: simulating %zu/%zu", i + 1, ids.size());
    variants.push_back(run_view_variant(m, "variant " + std::to_string(ids[i]) + ": " + v.label));
  }
  std::fprintf(stderr, "\n");
  // Without --eval, the variant that comes closest is shown solid.
  if (a.eval_id < 0) {
    std::size_t worst = 0;
    for (std::size_t i = 1; i < variants.size(); ++i)
      if (variants[i].min_clearance < variants[worst].min_clearance) worst = i;
    std::swap(variants[0], variants[worst]);
  }
  scene.variants = std::move(variants);
  write_view_html(scene, a.out);
  print_written(a.out, scene);
}

}  // namespace

void add_view_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("view", "Write one self-contained HTML page that plays an arm's run in 3-D in the "
                                         "browser (three.js, no server): the world's obstacles, the least clearance "
                                         "pair, a time slider, orbit, deflection exaggeration; for a study, one "
                                         "variant solid and others as ghosts");
  auto args = std::make_shared<ViewArgs>();
  cmd->add_option("input", args->input, "arm model YAML, or a study YAML")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "the HTML file")->required();
  cmd->add_option("--set", args->sets, "override a model parameter, PATH=VALUE; repeatable (model input only)");
  cmd->add_option("--eval", args->eval_id, "study: the variant shown solid (default: the one that comes closest)");
  cmd->add_option("--ghosts", args->ghosts, "study: how many other variants to overlay, evenly spaced over the eval_ids")
      ->check(CLI::Range(0, 1000))->capture_default_str();
  cmd->callback([args] {
    if (is_arm_model_file(args->input)) {
      if (args->eval_id >= 0) throw CLI::ValidationError("--eval", "is for a study");
      const ArmModel m = load_arm_with(args->input, args->sets);
      ViewScene scene = make_arm_view_scene(m, m.spec.description.empty() ? args->input : m.spec.description);
      scene.variants.push_back(run_view_variant(m, args->input));
      write_view_html(scene, args->out);
      return print_written(args->out, scene);
    }
    if (!args->sets.empty()) throw CLI::ValidationError("--set", "is for a model file (a study sets its own)");
    view_study(*args);
  });
}

}  // namespace ff
