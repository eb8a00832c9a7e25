// flexfarm diagnose / calibrate / record: find the physical effect a model lacks, add it, and make
// records with a hidden effect to test that this works (docs/validation.md).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "apps/verbs.hpp"
#include "common/files.hpp"
#include "kernel/model_io.hpp"
#include "validate/arm_diagnose.hpp"
#include "validate/arm_record.hpp"
#include "validate/diagnose.hpp"
#include "validate/ledger.hpp"
#include "validate/synthetic.hpp"

namespace ff {

namespace {

std::vector<std::string> split_list(const std::vector<std::string>& items) {
  std::vector<std::string> out;
  for (const auto& s : items) {
    std::size_t a = 0;
    while (a <= s.size()) {
      const auto b = std::min(s.find(',', a), s.size());
      if (b > a) out.push_back(s.substr(a, b - a));
      a = b + 1;
    }
  }
  return out;
}

constexpr const char* kRefitHelp =
    "existing parameters re-fitted with the baseline and with every effect: none, auto (for each effect the at most two "
    "the residual is most sensitive to, among hub.inertia, payload.mass, payload.inertia, friction.viscous, "
    "friction.coulomb, joints.stiffness, joints.damping, hub.torque_offset where nonzero, never one the effect fits), "
    "or paths, comma separated, e.g. hub.inertia,friction.viscous (an arm model: auto among each joint's friction, "
    "torque offset and armature and each link's damping_time; paths such as joints.elbow.friction.viscous)";

ReplayMode mode_of(const std::string& name) {
  try {
    return parse_replay_mode(name);
  } catch (const std::invalid_argument& e) {
    throw ExitError(std::string("--mode: ") + e.what(), 2);
  }
}

// What diagnose and calibrate read: the model's source (a rig's or an arm's) and the record, read as
// that model needs it. An arm is fitted in closed loop only.
struct FitInputs {
  bool arm = false;
  ModelSource src;
  Record record;
};
FitInputs read_fit_inputs(const std::string& model, const std::vector<std::string>& sets, const std::string& data,
                          ReplayMode mode, const std::string& verb) {
  FitInputs in;
  in.arm = is_arm_model_file(model);
  if (in.arm && mode != ReplayMode::kClosedLoop) throw ExitError("--mode: an arm model is " + verb + " in closed loop only", 2);
  in.src = in.arm ? load_arm_source(model, sets) : load_model_source(model, sets);
  in.record = read_record_csv(data, in.arm ? std::vector<std::string>{} : replay_inputs(mode));
  return in;
}

}  // namespace

void add_diagnose_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "diagnose", "Try every candidate effect on a model against a measurement record: fit each jointly over "
                  "its parameters (a global scan, then nonlinear least squares), rank them by delta BIC and give "
                  "the verdict: the effect that is missing, none, or unexplained");
  struct Args {
    std::string model, data, json, mode = "closed-loop";
    std::vector<std::string> sets, effects, refit = {"none"};
    int iterations = 25, samples = 1500;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--model", a->model, "model YAML file")->required()->check(kPath)->check(CLI::ExistingFile);
  cmd->add_option("--data", a->data, "measurement record CSV (docs/formats.md)")->required()->check(kPath)->check(CLI::ExistingFile);
  cmd->add_option("--json", a->json, "write the ranking here as JSON")->required()->check(kPath);
  cmd->add_option("--mode", a->mode, "closed-loop (ref drives the model's controller), open-loop (hub_torque "
                                     "drives the plant) or inverse-dynamics")->capture_default_str();
  cmd->add_option("--effects", a->effects, "only these effects, comma separated (default: every one that applies)");
  cmd->add_option("--refit", a->refit, kRefitHelp)->capture_default_str();
  cmd->add_option("--set", a->sets, "override a model parameter, PATH=VALUE; repeatable");
  cmd->add_option("--iterations", a->iterations, "Levenberg-Marquardt iterations per effect (its leading start's)")->capture_default_str();
  cmd->add_option("--samples", a->samples, "at most this many samples per channel are scored")->capture_default_str();
  cmd->callback([a] {
    DiagnoseOptions opt;
    opt.mode = mode_of(a->mode);
    opt.only = split_list(a->effects);
    opt.refit = split_list(a->refit);
    opt.max_iterations = a->iterations;
    opt.max_samples = a->samples;
    const auto [arm, src, r] = read_fit_inputs(a->model, a->sets, a->data, opt.mode, "diagnosed");
    print_safe(stderr, "diagnosing %s against %s (%s, %zu samples)...\n", a->model.c_str(), a->data.c_str(),
                 a->mode.c_str(), r.size());
    // One line per candidate as its fit ends, with the time since the start.
    const auto start = std::chrono::steady_clock::now();
    opt.on_fitted = [start](int done, int total, const EffectFit& f) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (f.ok)
        print_safe(stderr, "  [%d/%d] %s: delta BIC %.1f (%.0f s)\n", done, total, f.effect.c_str(), f.delta_bic, s);
      else
        print_safe(stderr, "  [%d/%d] %s: no fit (%.0f s)\n", done, total, f.effect.c_str(), s);
    };
    const Diagnosis d = arm ? diagnose_arm(src, r, opt) : diagnose(src, r, opt);
    write_file_atomic(a->json, format_diagnosis_json(d));
    print_safe(stdout, "%swrote %s\n", format_diagnosis_text(d).c_str(), a->json.c_str());
  });
}

void add_calibrate_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "calibrate", "Add effects to a model with their parameters fitted to a record, in turn; write the new model YAML "
                   "and record both versions and their fit in a model ledger (SQLite) with a plot of the error");
  struct Args {
    std::string model, data, add, out, ledger, mode = "closed-loop";
    std::vector<std::string> sets, refit = {"none"};
    int iterations = 25, samples = 1500;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--model", a->model, "model YAML file")->required()->check(kPath)->check(CLI::ExistingFile);
  cmd->add_option("--data", a->data, "measurement record CSV")->required()->check(kPath)->check(CLI::ExistingFile);
  cmd->add_option("--add", a->add, "the effects to add, comma separated, fitted in turn in this order, each on top of "
                                  "those before (diagnose's selected set, e.g. backlash,sensor_quantization)")->required();
  cmd->add_option("--out", a->out, "the new model YAML")->required()->check(kPath);
  cmd->add_option("--ledger", a->ledger, "model ledger (default: ledger.sqlite beside --out)")->check(kPath);
  cmd->add_option("--mode", a->mode, "closed-loop, open-loop or inverse-dynamics")->capture_default_str();
  cmd->add_option("--refit", a->refit, kRefitHelp)->capture_default_str();
  cmd->add_option("--set", a->sets, "override a model parameter, PATH=VALUE; repeatable");
  cmd->add_option("--iterations", a->iterations, "Levenberg-Marquardt iterations")->capture_default_str();
  cmd->add_option("--samples", a->samples, "at most this many samples per channel are scored")->capture_default_str();
  cmd->callback([a] {
    DiagnoseOptions opt;
    opt.mode = mode_of(a->mode);
    opt.max_iterations = a->iterations;
    opt.max_samples = a->samples;
    opt.refit = split_list(a->refit);
    const auto [arm, src, r] = read_fit_inputs(a->model, a->sets, a->data, opt.mode, "calibrated");
    const auto add = split_list({a->add});
    if (add.empty()) throw ExitError("--add: name at least one effect", 2);
    std::vector<std::string> offered;
    if (arm) {
      const ArmModel base = build_arm(src);
      check_arm_record(r, base);
      for (const auto& e : make_arm_candidate_effects(base, apply_overrides(src), r)) offered.push_back(e.name);
    } else {
      offered = effect_names();
    }
    for (const auto& name : add)
      if (std::find(offered.begin(), offered.end(), name) == offered.end()) {
        std::string names;
        for (const auto& n : offered) names += (names.empty() ? "" : ", ") + n;
        throw ExitError("--add: unknown effect '" + name + "' (this model offers: " + names + ")", 2);
      }
    EffectFit f;
    try {
      f = arm ? fit_arm_effects(src, r, opt, add) : fit_effects(src, r, opt, add);
    } catch (const std::invalid_argument& e) {  // a name twice, two that write the same path
      throw ExitError(std::string("--add: ") + e.what(), 2);
    }
    if (!f.ok) throw ExitError("the fit of " + a->add + " failed: " + f.note, 3);
    const std::string yaml = arm ? format_calibrated_arm(src, f, a->data, a->out) : format_calibrated_model(src, f, a->data);
    const std::string ledger = a->ledger.empty()
                                   ? (std::filesystem::path(a->out).parent_path() / "ledger.sqlite").string()
                                   : a->ledger;
    const auto dir = std::filesystem::path(a->out).parent_path();
    if (!dir.empty()) std::filesystem::create_directories(dir);
    write_file_atomic(a->out, yaml);
    const auto before = arm ? calc_arm_record_fits(build_arm(src), r) : calc_record_fits(build_model(src), r, opt.mode);
    const auto after = arm ? calc_arm_record_fits(load_arm_with(a->out, {}), r) : calc_record_fits(load_model(a->out), r, opt.mode);
    const auto versions = record_calibration(ledger, a->model, before, a->out, after, f, r, opt.mode);
    print_safe(stdout, "added %s to %s -> %s (delta BIC %.1f)\n", f.effect.c_str(), a->model.c_str(), a->out.c_str(),
                f.delta_bic);
    for (const auto& [p, v] : f.params) print_safe(stdout, "  %s = %.6g\n", p.c_str(), v);
    print_safe(stdout, "%s", versions.c_str());
  });
}

void add_record_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("record", "Make a measurement record from a model (a truth model, e.g. with an "
                                           "effect hidden by --set): its closed-loop run with noise on every channel "
                                           "(an arm model: the arm record form, noise by --noise-angle ...)");
  struct Args {
    std::string model, out;
    std::vector<std::string> sets, plant_sets;
    double noise = 0.01;
    std::uint64_t seed = 1;
    int decimate = 1;
    ArmRecordNoise arm;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("model", a->model, "model YAML file")->required()->check(kPath)->check(CLI::ExistingFile);
  cmd->add_option("--out", a->out, "record CSV to write")->required()->check(kPath);
  cmd->add_option("--set", a->sets, "override a model parameter, PATH=VALUE; repeatable");
  cmd->add_option("--plant-set", a->plant_sets, "override a plant parameter the controller's model does not know (a hidden effect, a true payload), PATH=VALUE; repeatable");
  auto* noise = cmd->add_option("--noise", a->noise, "noise standard deviation per channel, as a fraction of the channel's")
      ->capture_default_str();
  cmd->add_option("--seed", a->seed, "noise seed")->capture_default_str();
  auto* decimate = cmd->add_option("--decimate", a->decimate, "keep every n-th controller sample")->capture_default_str();
  // An arm model's record: absolute noise per kind of channel.
  CLI::Option* arm_noise[] = {
      cmd->add_option("--noise-angle", a->arm.angle, "arm models: noise standard deviation on every <joint>.angle, rad (m)")
          ->check(CLI::NonNegativeNumber)->capture_default_str(),
      cmd->add_option("--noise-rate", a->arm.rate, "arm models: on every <joint>.rate, rad/s (m/s)")
          ->check(CLI::NonNegativeNumber)->capture_default_str(),
      cmd->add_option("--noise-torque", a->arm.torque, "arm models: on every <joint>.torque, N m (N)")
          ->check(CLI::NonNegativeNumber)->capture_default_str(),
      cmd->add_option("--noise-position", a->arm.position, "arm models: on tool.x/y/z and the link deflections, m")
          ->check(CLI::NonNegativeNumber)->capture_default_str()};
  cmd->callback([a, noise, decimate, arm_noise] {
    if (is_arm_model_file(a->model)) {
      if (noise->count() > 0 || decimate->count() > 0)
        throw ExitError(std::string(noise->count() > 0 ? "--noise" : "--decimate") +
                            ": not for an arm model (its noise: --noise-angle, --noise-rate, --noise-torque, --noise-position)",
                        2);
      const ArmModel m = load_arm_with(a->model, a->sets, a->plant_sets);
      const Record r = make_arm_record(m, a->arm, a->seed);
      write_record_csv(r, arm_record_columns(m), a->out, 17);
      print_safe(stdout, "wrote %s: %zu samples\n", a->out.c_str(), r.size());
      return;
    }
    for (CLI::Option* o : arm_noise)
      if (o->count() > 0) throw ExitError(o->get_name() + ": only for an arm model", 2);
    const Model m = load_model_with(a->model, a->sets, a->plant_sets);
    const Record r = make_synthetic_record(m, a->noise, a->seed, a->decimate);
    write_record_csv(r, {"ref", "hub_torque", "hub_angle", "hub_rate", "tip_deflection"}, a->out);
    print_safe(stdout, "wrote %s: %zu samples\n", a->out.c_str(), r.size());
  });
}

}  // namespace ff
