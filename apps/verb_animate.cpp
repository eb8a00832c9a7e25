// flexfarm animate MODEL.yaml --out arm.avi: the seed's "graphical preview of proposed motions",
// the arm seen from above as a video.
#include <cmath>
#include <cstdio>

#include "apps/verbs.hpp"
#include "kernel/batch.hpp"
#include "kernel/simulate.hpp"
#include "plotting/animate.hpp"
#include "sweep/study.hpp"

namespace ff {

void add_animate_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("animate", "Render one run as a video of the arm seen from above (hub, segments, "
                                            "payload, tip trace; optional deflection exaggeration)");
  struct Args {
    std::string input, out;
    std::vector<std::string> sets;
    int eval_id = -1;
    double exaggeration = 1.0, fps = 30.0, speed = 1.0;
    int size = 960;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("input", args->input, "model YAML, or a study YAML with --eval")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "video file: .avi (Motion-JPEG) or .mp4")->required();
  cmd->add_option("--eval", args->eval_id, "the variant of a study to animate (its eval_id)");
  cmd->add_option("--set", args->sets, "override a model parameter, PATH=VALUE; repeatable (model input only)");
  cmd->add_option("--exaggerate", args->exaggeration, "scale the beam's deflection by this factor")
      ->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--fps", args->fps, "video frames per second")->check(CLI::Range(1.0, 240.0))->capture_default_str();
  cmd->add_option("--speed", args->speed, "simulated seconds per video second")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--size", args->size, "video width and height, px")->check(CLI::Range(240, 4096))->capture_default_str();
  cmd->callback([args] {
    // The model: a file with overrides, or one variant of a study.
    Model m;
    std::string title = args->input;
    if (args->eval_id >= 0) {
      const Study study = load_study(args->input);
      if (args->eval_id >= static_cast<int>(study.variants.size()))
        throw CLI::ValidationError("--eval", "the study has eval_ids 0.." + std::to_string(study.variants.size() - 1));
      m = make_variant_model(study, study.variants[args->eval_id]);
      title = study.name + ": " + study.variants[args->eval_id].label;
    } else {
      m = load_model_with(args->input, args->sets);
    }
    // Arm points in the world frame at every video frame: hub at the origin, joints, tip.
    Animation a;
    a.title = title;
    a.fps = args->fps;
    a.exaggeration = args->exaggeration;
    a.width = a.height = args->size;
    const double frame_dt = args->speed / args->fps;
    double next = 0.0;
    const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
    simulate(bm, [&](const BatchState& s) {
      if (s.t + 1e-9 < next) return;
      next += frame_dt;
      ArmFrame f;
      f.t = s.t;
      f.hub_angle = s.q[0];
      double x = 0, y = 0, theta = 0;
      f.x.push_back(0);
      f.y.push_back(0);
      for (int i = 0; i < m.nseg; ++i) {
        theta += s.q[i];
        x += m.seg_length[i] * std::cos(theta);
        y += m.seg_length[i] * std::sin(theta);
        f.x.push_back(x);
        f.y.push_back(y);
      }
      a.frames.push_back(std::move(f));
    });
    render_animation(a, args->out);
    std::printf("wrote %s: %zu frames, %.1f s of motion at %gx, deflection x%g\n", args->out.c_str(), a.frames.size(),
                m.duration, args->speed, args->exaggeration);
  });
}

}  // namespace ff
