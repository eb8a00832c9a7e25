// flexfarm compare --model M.yaml --data D.csv --out DIR: the model against a measurement record,
// free-run and k-step-ahead (from an observer's state estimate); fit table, failure report and residual plots.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>

#include "apps/verbs.hpp"
#include "validate/arm_compare.hpp"
#include "validate/arm_observer.hpp"
#include "validate/arm_record.hpp"
#include "validate/compare.hpp"
#include "validate/observer.hpp"
#include "validate/record.hpp"
#include "validate/replay.hpp"

namespace ff {

namespace {

namespace fs = std::filesystem;

// Writes the report into a sibling staging directory, then moves it into place: a fresh DIR
// appears whole; into an existing DIR each file is renamed over its old version.
std::vector<std::string> write_report_into(const std::function<std::vector<std::string>(const std::string&)>& write,
                                           const std::string& out) {
  const fs::path target = fs::path(out).lexically_normal();
  const fs::path stage = target.parent_path() / (target.filename().string() + ".partial-" + std::to_string(::getpid()));
  std::error_code ec;
  fs::remove_all(stage, ec);
  try {
    const auto files = write(stage.string());
    if (!fs::exists(target)) {
      fs::rename(stage, target);
    } else {
      for (const auto& f : files) fs::rename(stage / f, target / f);
      fs::remove_all(stage);
    }
    return files;
  } catch (...) {
    fs::remove_all(stage, ec);
    throw;
  }
}

// An arm model (arm/): the free run on the record's references, with k > 0 the k-step prediction
// from the arm observer's estimate, every channel scored.
void compare_arm(const std::string& model, const std::vector<std::string>& sets, const std::string& data,
                 const std::string& out, int k, const ArmObserverOptions& observer) {
  const ArmModel m = load_arm_with(model, sets);
  const Record r = read_record_csv(data, {});
  check_arm_record(r, m);
  if (k > 0)
    print_safe(stderr, "comparing %s with %s: %zu samples, free run and k = %d from the observer's estimate\n",
                 model.c_str(), data.c_str(), r.size(), k);
  else
    print_safe(stderr, "comparing %s with %s: %zu samples, free run on the record's references\n", model.c_str(),
                 data.c_str(), r.size());
  const ArmCompareResult result = compare_arm_record(m, r, {}, k, observer);
  const auto files =
      write_report_into([&](const std::string& dir) { return write_arm_compare_report(result, dir); }, out);
  print_safe(stdout, "%s\nwrote %s/{report.md, compare.json} and %zu plots\n", format_arm_fit_table(result).c_str(), out.c_str(),
              files.size() - 2);
  if (!result.ok) print_safe(stdout, "the replay failed numerically: see %s/report.md\n", out.c_str());
  if (k > 0 && !result.k_ok) print_safe(stdout, "the k-step prediction failed: see %s/report.md\n", out.c_str());
}

}  // namespace

void add_compare_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "compare",
      "Compare a model with a measurement record, free-run and k-step-ahead: writes DIR/report.md, "
      "DIR/compare.json and plots (overlay, residual ACF, CCF, spectrum, residual binned against the states)");
  struct Args {
    std::string model, data, out, mode = "closed-loop";
    int k = 10;
    double process_noise = kDefaultProcessNoise;
    double relinearise = kDefaultRelinearise;
    std::vector<std::string> sets;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("--model", args->model, "model YAML file")->required()->check(kPath)->check(CLI::ExistingFile);
  cmd->add_option("--data", args->data, "measurement record CSV (docs/formats.md, \"Measurement record\")")->required()->check(kPath);
  cmd->add_option("--mode", args->mode, "replay: closed-loop (record's ref drives the model's controller), "
                                        "open-loop (record's hub_torque drives the plant), inverse-dynamics")
      ->check(CLI::IsMember({"closed-loop", "open-loop", "inverse-dynamics"}))
      ->capture_default_str();
  auto* k_opt = cmd->add_option("--k", args->k, "k-step prediction horizon, controller samples")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  auto* noise_opt = cmd->add_option("--process-noise", args->process_noise,
                  "the k-step observer's process noise: white acceleration on every joint, rad/s^2 "
                  "(larger: the estimate follows the measurements more, the model less; an arm model's default: 1)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  auto* relin_opt = cmd->add_option("--relinearise", args->relinearise,
                  "an arm model's k-step observer: seconds between its linearisations at the estimate (its gain "
                  "re-designed for the pose)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--set", args->sets, "override a model parameter, PATH=VALUE; repeatable");
  cmd->add_option("--out", args->out, "output directory (created)")->required()->check(kPath);
  cmd->callback([args, k_opt, noise_opt, relin_opt] {
    if (is_arm_model_file(args->model)) {
      if (args->mode != "closed-loop") throw ExitError("--mode: an arm model is compared in closed loop only", 2);
      // The k-step prediction only when asked for (--k): the observer's linearisations cost some runs.
      if (k_opt->count() == 0 && (noise_opt->count() > 0 || relin_opt->count() > 0))
        throw ExitError(std::string(noise_opt->count() > 0 ? "--process-noise" : "--relinearise") +
                            ": the k-step prediction's option: give --k too (an arm model is compared free-run only without it)", 2);
      ArmObserverOptions observer;
      if (noise_opt->count() > 0) observer.process_noise = args->process_noise;
      observer.relinearise = args->relinearise;
      return compare_arm(args->model, args->sets, args->data, args->out, k_opt->count() > 0 ? args->k : 0, observer);
    }
    if (relin_opt->count() > 0) throw ExitError("--relinearise: only for an arm model (the rig's observer has one gain)", 2);
    // Every input is checked before anything is written.
    const ReplayMode mode = parse_replay_mode(args->mode);
    const Model m = load_model_with(args->model, args->sets);
    const Record r = read_record_csv(args->data, replay_inputs(mode));
    print_safe(stderr, "comparing %s with %s: %zu samples, %s, k = %d\n", args->model.c_str(), args->data.c_str(),
                 r.size(), replay_mode_name(mode), args->k);
    ObserverOptions observer;
    observer.process_noise = args->process_noise;
    const CompareResult result = compare_record(m, r, mode, args->k, {}, observer);
    const auto files =
        write_report_into([&](const std::string& dir) { return write_compare_report(result, dir); }, args->out);
    print_safe(stdout, "%s\nwrote %s/{report.md, compare.json} and %zu plots\n", format_fit_table(result).c_str(),
                args->out.c_str(), files.size() - 2);
    if (!result.free_ok || !result.k_ok)
      print_safe(stdout, "a replay failed numerically: see %s/report.md\n", args->out.c_str());
  });
}

}  // namespace ff
