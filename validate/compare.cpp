#include "validate/compare.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "common/files.hpp"
#include "plotting/plot.hpp"
#include "validate/report_text.hpp"
#include "common/text.hpp"

namespace ff {

using namespace report_text;

namespace {

const char* channel_unit(const std::string& c) {
  if (c == "hub_angle") return "rad";
  if (c == "hub_rate") return "rad/s";
  if (c == "tip_deflection") return "m";
  if (c == "hub_torque") return "N m";
  return "";
}

const char* input_column(ReplayMode m) {
  switch (m) {
    case ReplayMode::kClosedLoop: return "ref";
    case ReplayMode::kOpenLoop: return "hub_torque";
    case ReplayMode::kInverseDynamics: return "hub_angle";
  }
  return "ref";
}


}  // namespace

std::string format_failure_json(const ResidualAnalysis& a, const ResidualOptions& o) {
  if (!a.valid) return "null";
  const FailureReport& f = a.failure;
  std::string s = "{\"rms\": " + jnum(f.rms) + ", \"worst_windows\": [";
  for (std::size_t i = 0; i < f.worst_windows.size(); ++i) {
    const auto& w = f.worst_windows[i];
    s += std::string(i ? ", " : "") + "{\"t0\": " + jnum(w.t0) + ", \"t1\": " + jnum(w.t1) + ", \"rms\": " + jnum(w.rms) + "}";
  }
  s += "], \"peaks\": [";
  for (std::size_t i = 0; i < f.peaks.size(); ++i)
    s += std::string(i ? ", " : "") + "{\"frequency_hz\": " + jnum(f.peaks[i].frequency) +
         ", \"amplitude\": " + jnum(f.peaks[i].amplitude) + "}";
  s += "], \"states\": [";
  for (std::size_t i = 0; i < f.states.size(); ++i)
    s += std::string(i ? ", " : "") + "{\"state\": " + jstr(f.states[i].first) + ", \"departure\": " + jnum(f.states[i].second) + "}";
  s += "], \"velocity_step\": ";
  s += f.velocity_step.ok ? "{\"step\": " + jnum(f.velocity_step.step) + ", \"relative\": " + jnum(f.velocity_step.relative) +
                                ", \"below\": " + std::to_string(f.velocity_step.below) +
                                ", \"above\": " + std::to_string(f.velocity_step.above) + "}"
                          : std::string("null");
  s += ", \"friction_like\": " + jbool(f.friction_like) + ", \"acf_outside\": " + jnum(f.acf_outside) +
       ", \"white\": " + jbool(f.white) + ", \"ccf_outside\": " + jnum(f.ccf_outside) +
       ", \"uncorrelated\": " + jbool(f.uncorrelated) + ", \"findings\": [";
  const auto words = describe_failure(f, o);
  for (std::size_t i = 0; i < words.size(); ++i) s += std::string(i ? ", " : "") + jstr(words[i]);
  return s + "]}";
}

namespace {

// ---------------------------------------------------------------- plots

std::vector<double> lags_of(const Correlation& c) { return {c.lag.begin(), c.lag.end()}; }

}  // namespace

void plot_residual_correlation(const ChannelCompare& c, bool cross, const std::string& input, const std::string& path) {
  LinePlot p;
  p.title = (cross ? "residual-input cross-correlation: " + c.name + " with " + input
                   : "residual autocorrelation: " + c.name);
  p.x_label = "lag (record samples)";
  p.y_label = cross ? "r_eu" : "r_e";
  const std::pair<const ResidualAnalysis*, const char*> runs[] = {{&c.free_analysis, "free run"},
                                                                  {&c.k_analysis, "k-step"}};
  for (const auto& [a, label] : runs) {
    if (!a->valid) continue;
    const Correlation& r = cross ? a->ccf : a->acf;
    p.series.push_back({label, lags_of(r), r.value});
    p.hlines.push_back({r.band, std::string("99 % band (") + label + ")"});
    p.hlines.push_back({-r.band, ""});
  }
  render_line_plot(p, path);
}

void plot_residual_spectrum(const ChannelCompare& c, const std::string& path) {
  LinePlot p;
  p.title = "residual amplitude spectrum: " + c.name;
  p.x_label = "frequency (Hz)";
  p.y_label = "amplitude (" + c.unit + ")";
  // Up to 50 Hz, further if a reported peak lies beyond.
  double fmax = 50.0;
  for (const auto* a : {&c.free_analysis, &c.k_analysis})
    if (a->valid)
      for (const auto& pk : a->failure.peaks) fmax = std::max(fmax, 1.2 * pk.frequency);
  const std::pair<const ResidualAnalysis*, const char*> runs[] = {{&c.free_analysis, "free run"},
                                                                  {&c.k_analysis, "k-step"}};
  for (const auto& [a, label] : runs) {
    if (!a->valid) continue;
    Series s{label, {}, {}};
    for (std::size_t i = 0; i < a->spectrum.frequency.size() && a->spectrum.frequency[i] <= fmax; ++i) {
      s.x.push_back(a->spectrum.frequency[i]);
      s.y.push_back(a->spectrum.amplitude[i]);
    }
    p.series.push_back(s);
  }
  render_line_plot(p, path);
}

namespace {

void plot_binned(const ChannelCompare& c, std::size_t state, const std::string& path) {
  const auto& ref = c.free_analysis.valid ? c.free_analysis : c.k_analysis;
  const std::string& name = ref.binned[state].state;
  static const std::pair<const char*, const char*> units[] = {{"hub_velocity", "rad/s"}, {"hub_angle", "rad"},
      {"hub_acceleration", "rad/s^2"}, {"hub_torque", "N m"}, {"tip_deflection", "m"}};
  std::string unit;
  for (const auto& [n, u] : units)
    if (name == n) unit = u;
  LinePlot p;
  p.title = "mean " + c.name + " residual binned against " + name;
  p.x_label = name + (unit.empty() ? "" : " (" + unit + ")");
  p.y_label = "mean residual (" + c.unit + ")";
  const std::pair<const ResidualAnalysis*, const char*> runs[] = {{&c.free_analysis, "free run"},
                                                                  {&c.k_analysis, "k-step"}};
  for (const auto& [a, label] : runs)
    if (a->valid) p.series.push_back({label, a->binned[state].centre, a->binned[state].mean});
  p.hlines.push_back({0.0, "", false});
  render_line_plot(p, path);
}

void plot_overlay(const CompareResult& r, const ChannelCompare& c, const std::string& path) {
  LinePlot p;
  p.title = c.name + ": measured and predicted (" + replay_mode_name(r.mode) + ")";
  p.x_label = "time (s)";
  p.y_label = c.name + " (" + channel_unit(c.name) + ")";
  p.series.push_back({"measured", r.t, c.measured});
  p.series.push_back({"free run", r.t, break_at_nonfinite(c.free_run)});
  p.series.push_back({"k-step (k = " + std::to_string(r.k_ahead) + ")", r.t, break_at_nonfinite(c.k_step), -1, 2.0, true});
  render_line_plot(p, path);
}

}  // namespace

std::vector<double> break_at_nonfinite(std::vector<double> y) {
  for (double& v : y) v = std::isfinite(v) ? v : NAN;
  return y;
}

std::vector<std::pair<std::string, std::vector<double>>> record_states(const Record& r) {
  std::vector<std::pair<std::string, std::vector<double>>> s;
  std::vector<double> w;
  if (r.has("hub_rate")) w = r.at("hub_rate");
  else if (r.has("hub_angle")) w = time_derivative(r.t, r.at("hub_angle"));
  if (!w.empty()) s.emplace_back("hub_velocity", w);
  if (r.has("hub_angle")) s.emplace_back("hub_angle", r.at("hub_angle"));
  if (!w.empty()) s.emplace_back("hub_acceleration", time_derivative(r.t, w));
  if (r.has("hub_torque")) s.emplace_back("hub_torque", r.at("hub_torque"));
  if (r.has("tip_deflection")) s.emplace_back("tip_deflection", r.at("tip_deflection"));
  return s;
}

CompareResult compare_record(const Model& model, const Record& record, ReplayMode mode, int k_ahead,
                             const ResidualOptions& options, const ObserverOptions& observer) {
  if (k_ahead < 1) throw std::invalid_argument("compare_record: k must be >= 1 controller sample");
  CompareResult out;
  out.mode = mode;
  out.k_ahead = k_ahead;
  out.control_period = model.control_period;
  out.record_source = record.source;
  out.input = input_column(mode);
  out.t = record.t;
  out.options = options;
  const auto free_run = replay(std::span<const Model>(&model, 1), record, mode, 0)[0];
  const auto k_step = replay(std::span<const Model>(&model, 1), record, mode, k_ahead, observer)[0];
  if (mode != ReplayMode::kInverseDynamics) {  // the observer replay() ran, designed again for the report
    out.observed = true;
    out.observer = design_observer(model, record, mode, observer);
  }
  out.free_ok = free_run.ok;
  out.k_ok = k_step.ok;
  const auto states = record_states(record);
  const auto& u = record.at(out.input);
  for (const auto& name : scored_channels(mode, record)) {
    ChannelCompare c;
    c.name = name;
    c.unit = channel_unit(name);
    c.measured = record.at(name);
    c.free_run = free_run.channels.at(name);
    c.k_step = k_step.channels.at(name);
    const std::pair<const std::vector<double>*, bool> preds[] = {{&c.free_run, free_run.ok}, {&c.k_step, k_step.ok}};
    for (int i = 0; i < 2; ++i) {
      const auto& yhat = *preds[i].first;
      Fit fit = calc_fit(c.measured, yhat);
      ResidualAnalysis a;
      if (preds[i].second && all_finite(yhat)) {
        std::vector<double> e(c.measured.size());
        for (std::size_t k = 0; k < e.size(); ++k) e[k] = c.measured[k] - yhat[k];
        a = analyse_residual(record.t, e, u, states, options);
      } else {
        fit.percent = -INFINITY;
        fit.rmse = NAN;
      }
      (i == 0 ? c.fit_free : c.fit_k) = fit;
      (i == 0 ? c.free_analysis : c.k_analysis) = std::move(a);
    }
    out.channels.push_back(std::move(c));
  }
  return out;
}

std::string describe_observer(const CompareResult& r) {
  const ObserverDesign& d = r.observer;
  std::string s = "The k-step prediction restarts every " + std::to_string(r.k_ahead) +
                  " samples from the model's full state (joint angles, rates, drive states) estimated from the "
                  "measurements before that sample by an observer on the model: a steady-state Kalman filter with "
                  "its gain from the model linearised at rest, measuring ";
  for (std::size_t c = 0; c < d.channels.size(); ++c) {
    s += (c == 0 ? "" : c + 1 == d.channels.size() ? " and " : ", ") + std::string("`") + d.channels[c] + "`";
    if (c < d.noise_std.size()) s += " (noise " + fmt("%.3g", d.noise_std[c]) + " " + channel_unit(d.channels[c]) + ")";
  }
  if (d.period > 1) s += " every " + std::to_string(d.period) + " controller samples";
  s += "; process noise " + fmt("%.3g", d.process_noise) + " rad/s^2 on every joint";
  // The slowest mode of the linearised estimation error decays as rho^(t / (m T)): time constant -m T / ln rho.
  if (d.ok && d.pole_radius > 0.0)
    s += "; the slowest mode of its estimation error decays with a time constant of " +
         fmt("%.3g", -d.period * r.control_period / std::log(d.pole_radius)) + " s";
  return s + ".";
}

std::string format_k_step_errors(const FailureReport& f, const std::string& velocity) {
  if (!(f.rms > 0)) return "- zero: the model predicts the record exactly.\n";
  std::string s = fmt("- RMS %.4g; ", f.rms) + (f.white ? "white" : "not white") +
                  fmt(" (%.0f %% of ACF lags outside the 99 %% band); ", 100.0 * f.acf_outside) +
                  (f.uncorrelated ? "uncorrelated" : "correlated") +
                  fmt(" with the input (%.0f %% of CCF lags outside).\n", 100.0 * f.ccf_outside);
  if (f.velocity_step.ok)
    s += fmt("- steps by %.0f %% of its RMS across zero ", 100.0 * std::abs(f.velocity_step.relative)) + velocity +
         (f.friction_like ? ": a friction-like effect is missing.\n" : ".\n");
  return s;
}

std::string format_fit_table(const CompareResult& r) {
  std::string s = "| channel | unit | fit % free run | fit % k-step | RMSE free run | RMSE k-step |\n"
                  "|---|---|---:|---:|---:|---:|\n";
  for (const auto& c : r.channels)
    s += "| " + md_cell(c.name) + " | " + md_cell(c.unit) + " | " + fit_cell(c.fit_free.percent) + " | " + fit_cell(c.fit_k.percent) +
         " | " + num_cell(c.fit_free.rmse) + " | " + num_cell(c.fit_k.rmse) + " |\n";
  return s;
}

std::string format_compare_report(const CompareResult& r) {
  std::string s = "# Model vs record\n\n";
  s += "Record `" + r.record_source + "`: " + std::to_string(r.t.size()) + " samples, t = " +
       fmt("%.3f", r.t.empty() ? 0.0 : r.t.front()) + "-" + fmt("%.3f", r.t.empty() ? 0.0 : r.t.back()) + " s. ";
  s += std::string("Mode ") + replay_mode_name(r.mode) + "; input u = `" + r.input + "`; k-step prediction " +
       std::to_string(r.k_ahead) + " controller samples (" + fmt("%.4g", r.k_ahead * r.control_period) + " s) ahead.\n";
  if (r.mode == ReplayMode::kInverseDynamics)
    s += "\nInverse dynamics follows the measured hub motion in both replays: the k-step columns equal the free run.\n";
  if (r.observed) s += "\n" + describe_observer(r) + "\n";
  if (!r.free_ok) s += "\n**The free-run replay failed numerically** (its fits are marked `failed`).\n";
  if (!r.k_ok)
    s += "\n**The k-step replay failed" +
         (r.observed && !r.observer.ok ? ": " + r.observer.message : std::string(" numerically")) +
         "** (its fits are marked `failed`).\n";
  s += "\n## Fit\n\nFit % = 100 (1 - |y - yhat| / |y - mean(y)|); RMSE in the channel's unit.\n\n" + format_fit_table(r);
  s += "\n## Where the model fails\n";
  for (const auto& c : r.channels) {
    s += "\n### " + c.name + "\n\n";
    if (!c.free_analysis.valid) {
      s += "The free-run prediction is not finite: no residual analysis.\n";
    } else {
      if (c.fit_free.percent >= 99.5 && c.free_analysis.failure.rms > 0)
        s += "The free run fits to " + fmt("%.2f", c.fit_free.percent) +
             " %: what follows describes differences at that level.\n\n";
      s += "Free run:\n\n";
      for (const auto& w : describe_failure(c.free_analysis.failure, r.options)) s += "- " + w + ".\n";
    }
    if (c.k_analysis.valid && r.mode != ReplayMode::kInverseDynamics) {
      s += "\nk-step prediction errors:\n\n" + format_k_step_errors(c.k_analysis.failure, "hub velocity");
    }
  }
  s += "\n## Plots\n\n";
  for (const auto& c : r.channels) {
    s += "- " + c.name + ": `overlay_" + c.name + ".png`, `acf_" + c.name + ".png`, `ccf_" + c.name +
         ".png`, `spectrum_" + c.name + ".png`, `binned_" + c.name + "_<state>.png`\n";
  }
  return s;
}

std::string format_observer_channels_json(const std::vector<std::string>& channels, const std::vector<double>& noise_std) {
  std::string s = "\"channels\": [";
  for (std::size_t c = 0; c < channels.size(); ++c) s += (c ? ", " : "") + jstr(channels[c]);
  s += "], \"noise_std\": [";
  for (std::size_t c = 0; c < noise_std.size(); ++c) s += (c ? ", " : "") + jnum(noise_std[c]);
  return s + "]";
}

std::string format_compare_json(const CompareResult& r) {
  std::string s = "{\n  \"mode\": " + jstr(replay_mode_name(r.mode)) + ",\n  \"k\": " + std::to_string(r.k_ahead) +
                  ",\n  \"control_period\": " + jnum(r.control_period) + ",\n  \"record\": " + jstr(r.record_source) +
                  ",\n  \"samples\": " + std::to_string(r.t.size()) + ",\n  \"input\": " + jstr(r.input) +
                  ",\n  \"replay_ok\": {\"free_run\": " + jbool(r.free_ok) + ", \"k_step\": " + jbool(r.k_ok) + "}";
  s += ",\n  \"observer\": ";
  if (!r.observed) {
    s += "null";
  } else {
    const ObserverDesign& d = r.observer;
    s += "{\"ok\": " + jbool(d.ok) + ", " + format_observer_channels_json(d.channels, d.noise_std) +
         ", \"process_noise\": " + jnum(d.process_noise) + ", \"period\": " + std::to_string(d.period) +
         ", \"pole_radius\": " + (d.ok ? jnum(d.pole_radius) : std::string("null")) +
         ", \"message\": " + jstr(d.message) + "}";
  }
  auto per_channel = [&](const char* key, auto value) {
    s += ",\n  \"" + std::string(key) + "\": {";
    for (std::size_t i = 0; i < r.channels.size(); ++i)
      s += std::string(i ? ",\n    " : "\n    ") + jstr(r.channels[i].name) + ": " + value(r.channels[i]);
    s += "\n  }";
  };
  per_channel("fit_percent", [](const ChannelCompare& c) {
    return "{\"free_run\": " + jnum(c.fit_free.percent) + ", \"k_step\": " + jnum(c.fit_k.percent) + "}";
  });
  per_channel("rmse", [](const ChannelCompare& c) {
    return "{\"free_run\": " + jnum(c.fit_free.rmse) + ", \"k_step\": " + jnum(c.fit_k.rmse) + "}";
  });
  per_channel("failure", [&](const ChannelCompare& c) {
    return "{\"free_run\": " + format_failure_json(c.free_analysis, r.options) +
           ",\n      \"k_step\": " + format_failure_json(c.k_analysis, r.options) + "}";
  });
  return s + "\n}\n";
}

std::vector<std::string> write_compare_report(const CompareResult& r, const std::string& dir) {
  make_directories(dir);
  std::vector<std::string> files;
  auto put = [&](const std::string& name) {
    files.push_back(name);
    return dir + "/" + name;
  };
  write_file_atomic(put("report.md"), format_compare_report(r));
  write_file_atomic(put("compare.json"), format_compare_json(r));
  for (const auto& c : r.channels) {
    const std::string ch = make_file_stem(c.name);
    plot_overlay(r, c, put("overlay_" + ch + ".png"));
    if (!c.free_analysis.valid && !c.k_analysis.valid) continue;
    plot_residual_correlation(c, false, r.input, put("acf_" + ch + ".png"));
    plot_residual_correlation(c, true, r.input, put("ccf_" + ch + ".png"));
    plot_residual_spectrum(c, put("spectrum_" + ch + ".png"));
    const auto& a = c.free_analysis.valid ? c.free_analysis : c.k_analysis;
    for (std::size_t i = 0; i < a.binned.size(); ++i)
      plot_binned(c, i, put("binned_" + ch + "_" + make_file_stem(a.binned[i].state) + ".png"));
  }
  return files;
}

}  // namespace ff
