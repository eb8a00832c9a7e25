// flexfarm view MODEL_OR_STUDY_OR_RUN --out view.html: one self-contained HTML page
// (plotting/view_html.hpp) playing a run in 3-D in the browser, among the world's obstacles; for a study
// (or a study's finished run: its output directory), one variant solid and others as ghosts (a Monte
// Carlo spread), the worst clearance pair highlighted.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include "apps/verbs.hpp"
#include "arm/arm_simulate.hpp"
#include "kernel/batch.hpp"
#include "common/files.hpp"
#include "plotting/view_arm.hpp"
#include "results/history.hpp"
#include "results/table.hpp"
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
    print_safe(stderr, "warning: %s: the run ended %s; the page shows it up to there\n", label.c_str(),
                 lane_status_name(run.status[0]));
  return make_arm_view_variant(m, run.traces[0].t(), run.q[0], label);
}

void print_written(const std::string& out, const ViewScene& s) {
  const ViewVariant& v = s.variants.front();
  print_safe(stdout, "wrote %s: %s solid%s, %zu samples, %zu capsules, %zu obstacles", out.c_str(), v.label.c_str(),
              s.variants.size() > 1 ? (" and " + std::to_string(s.variants.size() - 1) + " ghosts").c_str() : "",
              v.t.size(), s.capsules.size(), s.shapes.size());
  if (v.worst_capsule >= 0) {
    const std::string other = v.worst_shape >= 0 ? s.shapes[static_cast<std::size_t>(v.worst_shape)].name
                                                 : s.capsules[static_cast<std::size_t>(-v.worst_shape - 2)].name;
    print_safe(stdout, "; least clearance %.4g m, %s to %s at %.3f s", v.min_clearance,
                s.capsules[static_cast<std::size_t>(v.worst_capsule)].name.c_str(), other.c_str(), v.worst_time);
  }
  print_safe(stdout, "\n");
}

// Whether two arms play on one time base: the same waypoint times and duration (a trade study's other
// move times would play out of step beside the solid one: an unreadable fan).
bool same_time_base(const ArmModel& a, const ArmModel& b) {
  const auto& wa = a.trajectory.waypoints;
  const auto& wb = b.trajectory.waypoints;
  return a.duration == b.duration && wa.size() == wb.size() &&
         std::equal(wa.begin(), wa.end(), wb.begin(), [](const auto& x, const auto& y) { return x.time == y.time; });
}

// `count` of `ids` (all if fewer), evenly spaced over them, in their order.
std::vector<int> spread(const std::vector<int>& ids, int count) {
  const std::size_t m = ids.size(), k = std::min(m, static_cast<std::size_t>(std::max(count, 0)));
  std::vector<int> out;
  for (std::size_t j = 0; j < k; ++j) out.push_back(ids[j * m / k]);  // j * m / k < m, and increasing
  return out;
}

// The variants of `study` shown: `solid` (-1: of those shown, the one that comes closest) and up to
// a.ghosts others, evenly spaced over the eval_ids of the variants on the solid one's time base (without
// `solid`, eval_id 0's); the others are left out, and the count said.
void view_study(const Study& study, int solid, const ViewArgs& a) {
  if (!study.arm) throw CLI::ValidationError("input", "the viewer shows arm models; this study's model is the reference rig");
  const int n = static_cast<int>(study.variants.size());
  if (solid >= n) throw CLI::ValidationError("--eval", "the study has eval_ids 0.." + std::to_string(n - 1));
  std::vector<ArmModel> arms;
  for (const Variant& v : study.variants) arms.push_back(make_variant_arm(study, v));
  const ArmModel& base = arms[static_cast<std::size_t>(std::max(solid, 0))];
  std::vector<int> shared;  // on base's time base, solid apart
  for (int i = 0; i < n; ++i)
    if (i != solid && same_time_base(arms[static_cast<std::size_t>(i)], base)) shared.push_back(i);
  std::vector<int> ids = spread(shared, a.ghosts + (solid >= 0 ? 0 : 1));
  if (solid >= 0) ids.insert(ids.begin(), solid);
  const int others = n - 1 - static_cast<int>(shared.size()) + (solid >= 0 ? 0 : 1);
  if (others > 0)
    std::fprintf(stderr, "view: %d of the %d variants move on another time base (waypoint times, duration) than "
                         "variant %d: not ghosted\n", others, n, std::max(solid, 0));
  std::vector<ViewVariant> variants;
  ViewScene scene;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const Variant& v = study.variants[static_cast<std::size_t>(ids[i])];
    const ArmModel& m = arms[static_cast<std::size_t>(ids[i])];
    if (i == 0) scene = make_arm_view_scene(m, study.name);
    std::fprintf(stderr, "\rview: simulating %zu/%zu", i + 1, ids.size());
    variants.push_back(run_view_variant(m, "variant " + std::to_string(ids[i]) + ": " + v.label));
  }
  print_safe(stderr, "\n");
  // Without one given, the variant that comes closest is shown solid.
  if (solid < 0) {
    std::size_t worst = 0;
    for (std::size_t i = 1; i < variants.size(); ++i)
      if (variants[i].min_clearance < variants[worst].min_clearance) worst = i;
    std::swap(variants[0], variants[worst]);
  }
  scene.variants = std::move(variants);
  write_view_html(scene, a.out);
  print_written(a.out, scene);
}

// A finished run (the output directory of `flexfarm run`, read as `flexfarm diff` reads it): its study,
// as the run named it (checked against the run's fingerprint), and the variant shown solid: --eval's, or
// the one whose result has the least clearance (without a world: eval_id 0).
void view_run(const ViewArgs& a) {
  RunDir run;
  try {
    run = read_run_dir(a.input);
  } catch (const std::runtime_error& e) {
    throw ExitError(e.what(), 2);
  }
  const std::string& source = run.record.study_path;
  if (source.empty() || !std::filesystem::is_regular_file(source))
    throw ExitError(a.input + "'s study '" + source + "' (as the run named it) is not found from here: give the study file instead", 2);
  const Study study = load_study(source);
  if (study.hash != run.record.study_hash)
    throw ExitError(source + " has changed since the run in " + a.input + ": give the study file instead", 2);
  int solid = a.eval_id;
  if (solid < 0) {
    solid = 0;
    const ResultTable& t = run.table;
    const auto c = std::find(t.columns.begin(), t.columns.end(), "min_clearance_m");
    if (c != t.columns.end()) {
      const std::size_t at = static_cast<std::size_t>(c - t.columns.begin());
      double least = INFINITY;
      for (const ResultRow& r : t.rows)
        if (r.values[at] < least && r.eval_id >= 0) least = r.values[at], solid = r.eval_id;
    }
  }
  view_study(study, solid, a);
}

}  // namespace

void add_view_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("view", "Write one self-contained HTML page that plays an arm's run in 3-D in the "
                                         "browser (three.js, no server): the world's obstacles, the least clearance "
                                         "pair, a time slider, orbit, deflection exaggeration; for a study, one "
                                         "variant solid and others as ghosts");
  auto args = std::make_shared<ViewArgs>();
  cmd->add_option("input", args->input, "arm model YAML, a study YAML, or a finished run's output directory")
      ->required()
      ->check(kPath)
      ->check(CLI::ExistingPath);
  cmd->add_option("--out", args->out, "the HTML file")->required()->check(kPath);
  cmd->add_option("--set", args->sets, "override a model parameter, PATH=VALUE; repeatable (model input only)");
  cmd->add_option("--eval", args->eval_id,
                  "study or run: the variant shown solid (default: a run's least clearance; a study's closest of those shown)");
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
    if (std::filesystem::is_directory(args->input)) return view_run(*args);
    view_study(load_study(args->input), args->eval_id, *args);
  });
}

}  // namespace ff
