// Comparing one model with one measurement record (docs/cli.md, `flexfarm compare`): the record is
// replayed free-run and k-step-ahead (replay.hpp), each scored channel gets fit % and RMSE for both,
// and both residuals e = y - yhat are analysed (residuals.hpp) against the record's input and states.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "kernel/model.hpp"
#include "validate/observer.hpp"
#include "validate/record.hpp"
#include "validate/replay.hpp"
#include "validate/residuals.hpp"

namespace ff {

struct ChannelCompare {
  std::string name;                            // hub_angle, tip_deflection, hub_torque
  std::string unit;                            // rad, m, N m
  std::vector<double> measured, free_run, k_step;  // at the record's times
  Fit fit_free, fit_k;                         // percent = -inf when the prediction is not finite
  ResidualAnalysis free_analysis, k_analysis;  // of measured - free_run, measured - k_step
};

struct CompareResult {
  ReplayMode mode = ReplayMode::kClosedLoop;
  int k_ahead = 10;                     // controller samples
  double control_period = 0.0;          // s, the model's controller sample time
  std::string record_source;
  bool free_ok = true, k_ok = true;     // the replays' lane status
  std::string input;                    // the record column used as u: ref, hub_torque or hub_angle
  std::vector<double> t;                // s, the record's times
  std::vector<ChannelCompare> channels; // scored_channels(mode, record), in that order
  ResidualOptions options;
  bool observed = false;                // the k-step starts from an observer's estimate (not in inverse dynamics)
  ObserverDesign observer;              // that observer (validate/observer.hpp): channels, noise, gain
};

// The record's states to bin residuals against, (name, values at its times), those it has:
// hub_velocity (rad/s: hub_rate, else central differences of hub_angle), hub_angle (rad),
// hub_acceleration (rad/s^2: central differences of hub_velocity), hub_torque (N m),
// tip_deflection (m).
std::vector<std::pair<std::string, std::vector<double>>> record_states(const Record& r);

// Replays free-run and k_ahead samples ahead (k_ahead >= 1; std::invalid_argument otherwise; the
// k-step prediction restarts every k_ahead samples from the observer's state estimate, `observer`
// its options) and analyses both residuals of every scored channel. The record must hold
// replay_inputs(mode) (as read_record_csv checks). A failed replay is a result: its fits are -inf,
// its analyses invalid.
CompareResult compare_record(const Model& model, const Record& record, ReplayMode mode, int k_ahead = 10,
                             const ResidualOptions& options = {}, const ObserverOptions& observer = {});

// One sentence for report.md: how the k-step start state is estimated (channels, noise, gain).
std::string describe_observer(const CompareResult& r);
// The fit table (markdown) printed by `flexfarm compare`.
std::string format_fit_table(const CompareResult& r);
// report.md: fit tables and the failure summary in words, per channel.
std::string format_compare_report(const CompareResult& r);
// compare.json (docs/formats.md, "compare.json").
std::string format_compare_json(const CompareResult& r);

// Pieces of the report for other comparisons (validate/arm_compare.hpp): a residual analysis as
// compare.json's "failure" entry ("null" when not valid); the residual's autocorrelation (cross: its
// cross-correlation with `input`) and amplitude spectrum plots, free run and k-step where valid.
std::string format_failure_json(const ResidualAnalysis& a, const ResidualOptions& o);
// compare.json's observer entries "channels": [...], "noise_std": [...] (no braces).
std::string format_observer_channels_json(const std::vector<std::string>& channels, const std::vector<double>& noise_std);
// The k-step residual in words for report.md: its RMS, whiteness, correlation with the input and any
// step across zero `velocity` ("hub velocity"), as markdown bullets.
std::string format_k_step_errors(const FailureReport& f, const std::string& velocity);
void plot_residual_correlation(const ChannelCompare& c, bool cross, const std::string& input, const std::string& path);
void plot_residual_spectrum(const ChannelCompare& c, const std::string& path);
// A series for a plot: non-finite values (a failed prediction's) as NaN, which break its line
// instead of stretching the axes.
std::vector<double> break_at_nonfinite(std::vector<double> y);

// Writes DIR/report.md, DIR/compare.json and the plots (docs/cli.md) into `dir` (created); each file
// atomically. Returns the file names written.
std::vector<std::string> write_compare_report(const CompareResult& r, const std::string& dir);

}  // namespace ff
