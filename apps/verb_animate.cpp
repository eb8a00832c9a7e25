// flexfarm animate MODEL.yaml --out arm.avi: the seed's "graphical preview of proposed motions",
// the arm seen from above as a video.
#include <cmath>
#include <cstdio>

#include "apps/verbs.hpp"
#include "arm/arm_simulate.hpp"
#include "plotting/animate3d_arm.hpp"
#include "kernel/batch.hpp"
#include "kernel/simulate.hpp"
#include "plotting/animate.hpp"
#include "sweep/study.hpp"

namespace ff {

namespace {

struct AnimateArgs {
  std::string input, out, frame_png;
  std::vector<std::string> sets;
  int eval_id = -1;
  double exaggeration = 1.0, fps = 30.0, speed = 1.0, frame_time = 0.0, azimuth = -55.0, elevation = 25.0;
  int size = 960;
};

// An arm model in 3-D (plotting/animate3d.hpp): a perspective view of every body, the flexible links'
// deflection exaggerated, the tool's path.
void animate_arm(const ArmModel& m, const std::string& title, const AnimateArgs& a) {
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1), {.keep_q = true});
  ArmAnimationOptions o;
  o.fps = a.fps;
  o.speed = a.speed;
  o.style.title = title;
  o.style.exaggeration = a.exaggeration;
  o.camera.azimuth = a.azimuth * kDegree;
  o.camera.elevation = a.elevation * kDegree;
  o.camera.width = a.size;
  o.camera.height = a.size * 3 / 4;
  o.still_path = a.frame_png;
  o.still_time = a.frame_time;
  const ArmAnimationSummary s = write_arm_animation(m, run.traces[0].t(), run.q[0], a.out, o);
  print_safe(stdout, "wrote %s: %d frames, %.1f s of motion at %gx, deflection x%g%s\n", a.out.c_str(), s.frames, m.duration,
              a.speed, a.exaggeration, a.frame_png.empty() ? "" : (", and " + a.frame_png).c_str());
  if (run.status[0] != LaneStatus::kOk)
    print_safe(stdout, "warning: the run ended %s; %d frames show the warning instead of the arm\n",
                lane_status_name(run.status[0]), s.nonfinite_frames);
}

}  // namespace

void add_animate_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("animate", "Render one run as a video: the reference rig seen from above (hub, "
                                            "segments, payload, tip trace), an arm model in 3-D (perspective, every "
                                            "body, the tool's path); optional deflection exaggeration");
  auto args = std::make_shared<AnimateArgs>();
  cmd->add_option("input", args->input, "model YAML, or a study YAML with --eval")->required()->check(kPath)->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "video file: .avi (Motion-JPEG) or .mp4")->required()->check(kPath);
  cmd->add_option("--eval", args->eval_id, "the variant of a study to animate (its eval_id)");
  cmd->add_option("--set", args->sets, "override a model parameter, PATH=VALUE; repeatable (model input only)");
  cmd->add_option("--exaggerate", args->exaggeration, "scale the beam's deflection by this factor")
      ->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--fps", args->fps, "video frames per second")->check(CLI::Range(1.0, 240.0))->capture_default_str();
  cmd->add_option("--speed", args->speed, "simulated seconds per video second")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--size", args->size, "video width (and the rig's height; an arm's is 3/4 of it), px")
      ->check(CLI::Range(320, 4096))->capture_default_str();
  cmd->add_option("--azimuth", args->azimuth, "arm: camera azimuth, degrees")->capture_default_str();
  cmd->add_option("--elevation", args->elevation, "arm: camera elevation above the ground, degrees")
      ->check(CLI::Range(-90.0, 90.0))->capture_default_str();
  cmd->add_option("--frame", args->frame_png, "arm: also write one frame as this PNG (the time: --at)")->check(kPath);
  cmd->add_option("--at", args->frame_time, "arm: the time of the --frame PNG, s")->capture_default_str();
  cmd->callback([args] {
    if (args->eval_id >= 0 ? load_study(args->input).arm : is_arm_model_file(args->input)) {
      if (args->eval_id >= 0) {
        const Study study = load_study(args->input);
        if (args->eval_id >= static_cast<int>(study.variants.size()))
          throw CLI::ValidationError("--eval", "the study has eval_ids 0.." + std::to_string(study.variants.size() - 1));
        return animate_arm(make_variant_arm(study, study.variants[args->eval_id]),
                           study.name + ": " + study.variants[args->eval_id].label, *args);
      }
      const ArmModel m = load_arm_with(args->input, args->sets);
      return animate_arm(m, m.spec.description.empty() ? args->input : m.spec.description, *args);
    }
    if (!args->frame_png.empty()) throw CLI::ValidationError("--frame", "is for arm models");
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
    print_safe(stdout, "wrote %s: %zu frames, %.1f s of motion at %gx, deflection x%g\n", args->out.c_str(), a.frames.size(),
                m.duration, args->speed, args->exaggeration);
  });
}

}  // namespace ff
