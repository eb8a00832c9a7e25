#include "validate/arm_compare.hpp"

#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "common/files.hpp"
#include "plotting/plot.hpp"
#include "validate/arm_observer.hpp"
#include "validate/arm_record.hpp"
#include "validate/replay.hpp"  // calc_fit
#include "validate/report_text.hpp"
#include "common/text.hpp"

namespace ff {

using namespace report_text;

ArmCompareResult compare_arm_record(const ArmModel& m, const Record& r, const ResidualOptions& options, int k_ahead,
                                    const ArmObserverOptions& observer) {
  if (k_ahead < 0) throw std::invalid_argument("compare_arm_record: k must be >= 0 controller samples");
  ArmCompareResult out;
  out.record_source = r.source;
  out.options = options;
  out.t = r.t;
  out.k_ahead = k_ahead;
  const ArmReplay replay = replay_arm_record(m, r);
  out.ok = replay.ok;
  out.resampled = replay.resampled;
  out.control_period = replay.control_period;
  // The k-step prediction from the observer's estimate, at the record's times.
  std::map<std::string, std::vector<double>> k_step;
  if (k_ahead > 0) {
    ArmObserverRun run = run_arm_observer(std::span<const ArmModel>(&m, 1), r, k_ahead, observer);
    out.observer = run.design[0];
    out.k_ok = run.k_step_ok(0);
    k_step = sample_arm_trace_at_record(run.k_step[0], m, r, run.resampled);
  }
  const auto names = arm_scored_columns(m);
  std::vector<std::pair<std::string, std::vector<double>>> all_states;
  for (const ActuatedJoint& a : m.actuated) add_arm_joint_states(r, a.name, false, all_states);
  for (const auto& [name, joint] : names) {
    if (!r.has(name)) continue;
    if (is_constant_column(r.at(name))) {
      out.constant.push_back(name);
      continue;
    }
    ChannelCompare c;
    c.name = name;
    c.unit = arm_record_unit(m, name);
    c.measured = r.at(name);
    c.free_run = replay.at_record.at(name);
    if (k_ahead > 0) c.k_step = k_step.at(name);
    const std::string input = (joint.empty() ? m.actuated.front().name : joint) + ".ref";
    std::vector<std::pair<std::string, std::vector<double>>> states;
    if (joint.empty()) states = all_states;
    else add_arm_joint_states(r, joint, true, states);
    // Fit and residual analysis of each prediction; a failed one's fit -inf, its analysis invalid.
    auto score = [&](const std::vector<double>& yhat, bool ok, Fit& fit, ResidualAnalysis& analysis) {
      fit = calc_fit(c.measured, yhat);
      if (!ok || !all_finite(yhat)) {
        fit.percent = -INFINITY;
        fit.rmse = NAN;
        return;
      }
      std::vector<double> e(c.measured.size());
      for (std::size_t k = 0; k < e.size(); ++k) e[k] = c.measured[k] - yhat[k];
      analysis = analyse_residual(r.t, e, r.at(input), states, options);
    };
    score(c.free_run, replay.ok, c.fit_free, c.free_analysis);
    if (k_ahead > 0) {
      score(c.k_step, out.k_ok, c.fit_k, c.k_analysis);
    } else {
      c.fit_k.percent = NAN;
      c.fit_k.rmse = NAN;
    }
    out.channels.push_back(std::move(c));
    out.inputs.push_back(input);
    out.refs.push_back(r.at(input));
  }
  return out;
}

std::string format_arm_fit_table(const ArmCompareResult& r) {
  if (r.k_ahead == 0) {
    std::string s = "| channel | unit | fit % | RMSE |\n|---|---|---:|---:|\n";
    for (const auto& c : r.channels)
      s += "| " + md_cell(c.name) + " | " + md_cell(c.unit) + " | " + fit_cell(c.fit_free.percent) + " | " + num_cell(c.fit_free.rmse) + " |\n";
    return s;
  }
  std::string s = "| channel | unit | fit % free run | fit % k-step | RMSE free run | RMSE k-step |\n"
                  "|---|---|---:|---:|---:|---:|\n";
  for (const auto& c : r.channels)
    s += "| " + md_cell(c.name) + " | " + md_cell(c.unit) + " | " + fit_cell(c.fit_free.percent) + " | " + fit_cell(c.fit_k.percent) +
         " | " + num_cell(c.fit_free.rmse) + " | " + num_cell(c.fit_k.rmse) + " |\n";
  return s;
}

std::string describe_arm_observer(const ArmCompareResult& r) {
  const ArmObserverDesign& d = r.observer;
  std::string s = "The k-step prediction restarts every " + std::to_string(r.k_ahead) + " controller samples (" +
                  fmt("%.4g", r.k_ahead * r.control_period) +
                  " s) from the arm's full state (every joint's and cell's angle and rate, the actuators' states) "
                  "estimated from the measurements before that sample by an observer on the model: an extended "
                  "Kalman filter whose gain is the steady-state gain of the model linearised at the estimate every " +
                  std::to_string(d.relinearise) + " samples, measuring ";
  for (std::size_t c = 0; c < d.channels.size(); ++c) {
    s += (c == 0 ? "" : c + 1 == d.channels.size() ? " and " : ", ") + std::string("`") + d.channels[c] + "`";
    if (c < d.noise_std.size()) s += " (noise " + fmt("%.3g", d.noise_std[c]) + ")";
  }
  if (d.period > 1) s += " every " + std::to_string(d.period) + " controller samples";
  s += "; process noise " + fmt("%.3g", d.process_noise) + " rad/s^2 on every joint; " + std::to_string(d.gains) + " gains";
  // The slowest mode of the linearised estimation error decays as rho^(t / (m T)): time constant -m T / ln rho.
  if (d.ok && d.pole_radius > 0.0)
    s += ", the slowest mode of their estimation error decaying with a time constant of at most " +
         fmt("%.3g", -d.period * r.control_period / std::log(d.pole_radius)) + " s";
  if (!d.message.empty()) s += " (" + d.message + ")";
  return s + ".";
}

std::string format_arm_compare_report(const ArmCompareResult& r) {
  std::string s = "# Arm model vs record\n\n";
  s += "Record `" + r.record_source + "`: " + std::to_string(r.t.size()) + " samples, t = " +
       fmt("%.3f", r.t.empty() ? 0.0 : r.t.front()) + "-" + fmt("%.3f", r.t.empty() ? 0.0 : r.t.back()) + " s. ";
  s += "Free run: the model's controllers follow the record's `<joint>.ref` columns (" +
       std::string(r.resampled ? "linearly interpolated at the model's controller samples, every " + fmt("%.4g", r.control_period) +
                                     " s, the model's outputs interpolated back at the record's times"
                               : "one record sample per controller sample, every " + fmt("%.4g", r.control_period) + " s") +
       "), the feed-forward from their central differences" + (r.k_ahead > 0 ? "." : "; no k-step prediction.") + "\n";
  if (r.k_ahead > 0) s += "\n" + describe_arm_observer(r) + "\n";
  if (!r.ok) s += "\n**The replay failed numerically** (its fits are marked `failed`).\n";
  if (r.k_ahead > 0 && !r.k_ok)
    s += "\n**The k-step prediction failed" + (!r.observer.ok ? ": " + r.observer.message : std::string(" numerically")) +
         "** (its fits are marked `failed`).\n";
  s += "\n## Fit\n\nFit % = 100 (1 - |y - yhat| / |y - mean(y)|); RMSE in the channel's unit.\n\n" + format_arm_fit_table(r);
  if (!r.constant.empty()) {
    s += "\nNot scored (constant over the record):";
    for (std::size_t i = 0; i < r.constant.size(); ++i) s += std::string(i ? ", " : " ") + "`" + r.constant[i] + "`";
    s += ".\n";
  }
  s += "\n## Where the model fails\n";
  for (std::size_t i = 0; i < r.channels.size(); ++i) {
    const ChannelCompare& c = r.channels[i];
    s += "\n### " + c.name + "\n\n";
    if (!c.free_analysis.valid) {
      s += "The prediction is not finite: no residual analysis.\n";
    } else {
      if (c.fit_free.percent >= 99.5 && c.free_analysis.failure.rms > 0)
        s += "The model fits to " + fmt("%.2f", c.fit_free.percent) + " %: what follows describes differences at that level.\n\n";
      s += std::string(r.k_ahead > 0 ? "Free run, residual" : "Residual") + " against `" + r.inputs[i] + "` and the states:\n\n";
      for (const auto& w : describe_failure(c.free_analysis.failure, r.options)) s += "- " + w + ".\n";
    }
    if (c.k_analysis.valid)
      s += "\nk-step prediction errors:\n\n" + format_k_step_errors(c.k_analysis.failure, "joint velocity");
  }
  s += "\n## Plots\n\n";
  for (const auto& c : r.channels) {
    const std::string ch = make_file_stem(c.name);
    s += "- " + c.name + ": `overlay_" + ch + ".png`, `residual_" + ch + ".png`, `acf_" + ch + ".png`, `ccf_" + ch +
         ".png`, `spectrum_" + ch + ".png`\n";
  }
  return s;
}

std::string format_arm_compare_json(const ArmCompareResult& r) {
  const bool k = r.k_ahead > 0;
  std::string s = "{\n  \"model\": \"arm\",\n  \"mode\": \"closed-loop\",\n  \"control_period\": " + jnum(r.control_period) +
                  ",\n  \"record\": " + jstr(r.record_source) + ",\n  \"samples\": " + std::to_string(r.t.size()) +
                  ",\n  \"resampled\": " + (r.resampled ? "true" : "false") +
                  ",\n  \"k\": " + (k ? std::to_string(r.k_ahead) : std::string("null")) +
                  ",\n  \"replay_ok\": {\"free_run\": " + jbool(r.ok) + (k ? ", \"k_step\": " + jbool(r.k_ok) : std::string()) + "}";
  s += ",\n  \"observer\": ";
  if (!k) {
    s += "null";
  } else {
    const ArmObserverDesign& d = r.observer;
    s += "{\"ok\": " + jbool(d.ok) + ", " + format_observer_channels_json(d.channels, d.noise_std) +
         ", \"process_noise\": " + jnum(d.process_noise) + ", \"period\": " + std::to_string(d.period) +
         ", \"relinearise\": " + std::to_string(d.relinearise) + ", \"gains\": " + std::to_string(d.gains) +
         ", \"failed\": " + std::to_string(d.failed) +
         ", \"pole_radius\": " + (d.ok ? jnum(d.pole_radius) : std::string("null")) + ", \"message\": " + jstr(d.message) + "}";
  }
  s += ",\n  \"channels\": [";
  for (std::size_t i = 0; i < r.channels.size(); ++i) {
    const ChannelCompare& c = r.channels[i];
    s += std::string(i ? ",\n    " : "\n    ") + "{\"name\": " + jstr(c.name) + ", \"unit\": " + jstr(c.unit) +
         ", \"input\": " + jstr(r.inputs[i]) + ", \"fit_percent\": " + jnum(c.fit_free.percent) +
         ", \"rmse\": " + jnum(c.fit_free.rmse) + ",\n     \"failure\": " + format_failure_json(c.free_analysis, r.options);
    if (k)
      s += ",\n     \"k_step\": {\"fit_percent\": " + jnum(c.fit_k.percent) + ", \"rmse\": " + jnum(c.fit_k.rmse) +
           ",\n       \"failure\": " + format_failure_json(c.k_analysis, r.options) + "}";
    s += "}";
  }
  s += "\n  ],\n  \"not_scored\": [";
  for (std::size_t i = 0; i < r.constant.size(); ++i) s += (i ? ", " : "") + jstr(r.constant[i]);
  s += "]";
  // Per channel maps: the free run's fit and RMSE, and with k the k-step's.
  auto per_channel = [&](const char* key, auto value) {
    s += ",\n  \"" + std::string(key) + "\": {";
    for (std::size_t i = 0; i < r.channels.size(); ++i)
      s += std::string(i ? ", " : "") + jstr(r.channels[i].name) + ": " + jnum(value(r.channels[i]));
    s += "}";
  };
  per_channel("fit_percent", [](const ChannelCompare& c) { return c.fit_free.percent; });
  per_channel("rmse", [](const ChannelCompare& c) { return c.fit_free.rmse; });
  if (k) {
    per_channel("k_step_fit_percent", [](const ChannelCompare& c) { return c.fit_k.percent; });
    per_channel("k_step_rmse", [](const ChannelCompare& c) { return c.fit_k.rmse; });
  }
  return s + "\n}\n";
}

std::vector<std::string> write_arm_compare_report(const ArmCompareResult& r, const std::string& dir) {
  make_directories(dir);
  std::vector<std::string> files;
  auto put = [&](const std::string& name) {
    files.push_back(name);
    return dir + "/" + name;
  };
  write_file_atomic(put("report.md"), format_arm_compare_report(r));
  write_file_atomic(put("compare.json"), format_arm_compare_json(r));
  for (std::size_t i = 0; i < r.channels.size(); ++i) {
    const ChannelCompare& c = r.channels[i];
    const std::string ch = make_file_stem(c.name);
    LinePlot p;
    p.title = c.name + ": measured and model (free run on the record's references)";
    p.x_label = "time (s)";
    p.y_label = c.name + " (" + c.unit + ")";
    p.series.push_back({"measured", r.t, c.measured});
    p.series.push_back({r.k_ahead > 0 ? "free run" : "model", r.t, break_at_nonfinite(c.free_run)});
    if (r.k_ahead > 0)
      p.series.push_back({"k-step (k = " + std::to_string(r.k_ahead) + ")", r.t, break_at_nonfinite(c.k_step), -1, 2.0, true});
    if (c.name.size() > 6 && c.name.compare(c.name.size() - 6, 6, ".angle") == 0)
      p.series.push_back({"reference (" + r.inputs[i] + ")", r.t, r.refs[i], -1, 1.5, true});
    render_line_plot(p, put("overlay_" + ch + ".png"));
    LinePlot e;
    e.title = c.name + ": residual, measured - model";
    e.x_label = "time (s)";
    e.y_label = "residual (" + c.unit + ")";
    std::vector<double> res(c.measured.size());
    for (std::size_t k = 0; k < res.size(); ++k) res[k] = c.measured[k] - c.free_run[k];
    e.series.push_back({"free run", r.t, break_at_nonfinite(res)});
    if (r.k_ahead > 0) {
      for (std::size_t k = 0; k < res.size(); ++k) res[k] = c.measured[k] - c.k_step[k];
      e.series.push_back({"k-step", r.t, break_at_nonfinite(res)});
    }
    e.hlines.push_back({0.0, "", false});
    render_line_plot(e, put("residual_" + ch + ".png"));
    if (!c.free_analysis.valid && !c.k_analysis.valid) continue;
    plot_residual_correlation(c, false, r.inputs[i], put("acf_" + ch + ".png"));
    plot_residual_correlation(c, true, r.inputs[i], put("ccf_" + ch + ".png"));
    plot_residual_spectrum(c, put("spectrum_" + ch + ".png"));
  }
  return files;
}

}  // namespace ff
