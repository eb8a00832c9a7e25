#include "validate/arm_compare.hpp"

#include <cmath>
#include <cstdio>

#include "common/files.hpp"
#include "plotting/plot.hpp"
#include "validate/arm_record.hpp"
#include "validate/replay.hpp"  // calc_fit
#include "validate/report_text.hpp"

namespace ff {

using namespace report_text;

ArmCompareResult compare_arm_record(const ArmModel& m, const Record& r, const ResidualOptions& options) {
  ArmCompareResult out;
  out.record_source = r.source;
  out.options = options;
  out.t = r.t;
  const ArmReplay replay = replay_arm_record(m, r);
  out.ok = replay.ok;
  out.resampled = replay.resampled;
  out.control_period = replay.control_period;
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
    const std::string input = (joint.empty() ? m.actuated.front().name : joint) + ".ref";
    c.fit_free = calc_fit(c.measured, c.free_run);
    c.fit_k.percent = NAN;
    c.fit_k.rmse = NAN;
    if (replay.ok && all_finite(c.free_run)) {
      std::vector<double> e(c.measured.size());
      for (std::size_t k = 0; k < e.size(); ++k) e[k] = c.measured[k] - c.free_run[k];
      std::vector<std::pair<std::string, std::vector<double>>> states;
      if (joint.empty()) states = all_states;
      else add_arm_joint_states(r, joint, true, states);
      c.free_analysis = analyse_residual(r.t, e, r.at(input), states, options);
    } else {
      c.fit_free.percent = -INFINITY;
      c.fit_free.rmse = NAN;
    }
    out.channels.push_back(std::move(c));
    out.inputs.push_back(input);
    out.refs.push_back(r.at(input));
  }
  return out;
}

std::string format_arm_fit_table(const ArmCompareResult& r) {
  std::string s = "| channel | unit | fit % | RMSE |\n|---|---|---:|---:|\n";
  for (const auto& c : r.channels)
    s += "| " + c.name + " | " + c.unit + " | " + fit_cell(c.fit_free.percent) + " | " + num_cell(c.fit_free.rmse) + " |\n";
  return s;
}

std::string format_arm_compare_report(const ArmCompareResult& r) {
  std::string s = "# Arm model vs record\n\n";
  s += "Record `" + r.record_source + "`: " + std::to_string(r.t.size()) + " samples, t = " +
       fmt("%.3f", r.t.empty() ? 0.0 : r.t.front()) + "-" + fmt("%.3f", r.t.empty() ? 0.0 : r.t.back()) + " s. ";
  s += "Free run: the model's controllers follow the record's `<joint>.ref` columns (" +
       std::string(r.resampled ? "linearly interpolated at the model's controller samples, every " + fmt("%.4g", r.control_period) +
                                     " s, the model's outputs interpolated back at the record's times"
                               : "one record sample per controller sample, every " + fmt("%.4g", r.control_period) + " s") +
       "), the feed-forward from their central differences; no k-step prediction.\n";
  if (!r.ok) s += "\n**The replay failed numerically** (its fits are marked `failed`).\n";
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
      continue;
    }
    if (c.fit_free.percent >= 99.5 && c.free_analysis.failure.rms > 0)
      s += "The model fits to " + fmt("%.2f", c.fit_free.percent) + " %: what follows describes differences at that level.\n\n";
    s += "Residual against `" + r.inputs[i] + "` and the states:\n\n";
    for (const auto& w : describe_failure(c.free_analysis.failure, r.options)) s += "- " + w + ".\n";
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
  std::string s = "{\n  \"model\": \"arm\",\n  \"mode\": \"closed-loop\",\n  \"control_period\": " + jnum(r.control_period) +
                  ",\n  \"record\": " + jstr(r.record_source) + ",\n  \"samples\": " + std::to_string(r.t.size()) +
                  ",\n  \"resampled\": " + (r.resampled ? "true" : "false") +
                  ",\n  \"replay_ok\": {\"free_run\": " + (r.ok ? "true" : "false") + "}";
  s += ",\n  \"channels\": [";
  for (std::size_t i = 0; i < r.channels.size(); ++i) {
    const ChannelCompare& c = r.channels[i];
    s += std::string(i ? ",\n    " : "\n    ") + "{\"name\": " + jstr(c.name) + ", \"unit\": " + jstr(c.unit) +
         ", \"input\": " + jstr(r.inputs[i]) + ", \"fit_percent\": " + jnum(c.fit_free.percent) +
         ", \"rmse\": " + jnum(c.fit_free.rmse) + ",\n     \"failure\": " + format_failure_json(c.free_analysis, r.options) + "}";
  }
  s += "\n  ],\n  \"not_scored\": [";
  for (std::size_t i = 0; i < r.constant.size(); ++i) s += (i ? ", " : "") + jstr(r.constant[i]);
  s += "],\n  \"fit_percent\": {";
  for (std::size_t i = 0; i < r.channels.size(); ++i)
    s += std::string(i ? ", " : "") + jstr(r.channels[i].name) + ": " + jnum(r.channels[i].fit_free.percent);
  s += "},\n  \"rmse\": {";
  for (std::size_t i = 0; i < r.channels.size(); ++i)
    s += std::string(i ? ", " : "") + jstr(r.channels[i].name) + ": " + jnum(r.channels[i].fit_free.rmse);
  return s + "}\n}\n";
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
    p.series.push_back({"model", r.t, break_at_nonfinite(c.free_run)});
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
    e.hlines.push_back({0.0, "", false});
    render_line_plot(e, put("residual_" + ch + ".png"));
    if (!c.free_analysis.valid) continue;
    plot_residual_correlation(c, false, r.inputs[i], put("acf_" + ch + ".png"));
    plot_residual_correlation(c, true, r.inputs[i], put("ccf_" + ch + ".png"));
    plot_residual_spectrum(c, put("spectrum_" + ch + ".png"));
  }
  return files;
}

}  // namespace ff
