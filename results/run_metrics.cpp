#include "results/run_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "kernel/metrics.hpp"
#include "kernel/trajectory.hpp"

namespace ff {

const std::vector<std::string> kMoveMetrics = {"tip_settling_s",        "tip_overshoot_pct",    "hub_settling_s",
                                               "hub_overshoot_pct",     "peak_tip_deflection_m", "residual_vibration_m",
                                               "peak_torque_Nm",        "settling_horizon_s"};

std::vector<std::string> calc_metric_columns(int nmoves) {
  std::vector<std::string> cols;
  for (int j = 1; j <= nmoves; ++j)
    for (const auto& m : kMoveMetrics) {
      std::string name = "m";  // built piecewise: GCC 12 warns falsely (-Wrestrict) on "m" + to_string + ...
      name += std::to_string(j);
      name += '_';
      name += m;
      cols.push_back(name);
    }
  return cols;
}

std::string calc_horizon_column(const std::string& column) {
  // "m<digits>_" then a settling metric of kMoveMetrics.
  const std::size_t sep = column.find('_');
  if (sep < 2 || sep == std::string::npos || column[0] != 'm' ||
      column.find_first_not_of("0123456789", 1) != sep)
    // An arm's settling columns (arm/arm_metrics.hpp) share its one window.
    return column.ends_with("_settling_s") ? "settling_horizon_s" : "";
  const std::string metric = column.substr(sep + 1);
  return metric == "tip_settling_s" || metric == "hub_settling_s" ? column.substr(0, sep + 1) + "settling_horizon_s" : "";
}

namespace {
// f() over the samples with t in [from, to], or NaN when the run has none there: a move that the run
// (simulation.duration) ends before its end is not settled and has no residual vibration, as MATLAB's
// stepinfo reports a response that has not settled.
template <class F>
double over(std::span<const double> t, double from, double to, F f) {
  const bool any = std::lower_bound(t.begin(), t.end(), from) < std::upper_bound(t.begin(), t.end(), to);
  return any ? f() : std::nan("");
}

// Settling time, and "not settled" (NaN) unless the response then stays in the band for `dwell`
// seconds before the window ends: a response caught inside the band mid-swing is not settled.
double settled_for(std::span<const double> t, std::span<const double> y, const MoveWindow& w, double dwell) {
  const double ts = calc_settling_time(t, y, w);
  return w.t_window_end - (w.t_move_end + ts) >= dwell ? ts : std::nan("");
}
}  // namespace

std::vector<double> calc_run_metrics(const Model& model, const Trace& tr) {
  std::vector<double> out;
  // One column per metric of every move of the model (calc_metric_columns); NaN = "no number".
  const std::size_t ncols = kMoveMetrics.size() * model.spec.trajectory.moves.size();
  // A run that stopped being finite has no responses: every metric is "no number".
  for (const auto* sig : {&tr.tip_angle, &tr.hub_angle, &tr.tip_deflection, &tr.torque})
    for (double x : *sig)
      if (!std::isfinite(x)) return std::vector<double>(ncols, std::nan(""));
  // Dwell: one period of the slowest closed-loop resonance.
  const double dwell = model.resonances.empty() ? 0.0 : 2.0 * std::numbers::pi / model.resonances[0];
  for (const auto& mv : calc_moves(model.spec.trajectory, model.duration)) {
    const auto& w = mv.window;
    const std::span<const double> t = tr.t;
    const double t0 = mv.t_start, t1 = w.t_move_end, t2 = w.t_window_end;
    out.push_back(over(t, t1, t2, [&] { return settled_for(t, tr.tip_angle, w, dwell); }));
    out.push_back(over(t, t0, t2, [&] { return calc_overshoot(t, tr.tip_angle, t0, w); }));
    out.push_back(over(t, t1, t2, [&] { return settled_for(t, tr.hub_angle, w, dwell); }));
    out.push_back(over(t, t0, t2, [&] { return calc_overshoot(t, tr.hub_angle, t0, w); }));
    out.push_back(over(t, t0, t2, [&] { return calc_peak_abs(t, tr.tip_deflection, t0, t2); }));
    out.push_back(over(t, t1, t2, [&] { return calc_residual_amplitude(t, tr.tip_deflection, t1, t2); }));
    out.push_back(over(t, t0, t2, [&] { return calc_peak_abs(t, tr.torque, t0, t2); }));
    // Horizon: settled_for confirms ts only when t2 - (t1 + ts) >= dwell, so at most t2 - t1 - dwell.
    out.push_back(std::max(0.0, t2 - t1 - dwell));
  }
  out.resize(ncols, std::nan(""));  // moves that start after the run ends (simulation.duration): no number
  return out;
}

std::string calc_run_status(LaneStatus lane, const std::vector<std::string>& columns, const std::vector<double>& values) {
  if (lane != LaneStatus::kOk) return lane_status_name(lane);
  for (std::size_t i = 0; i < columns.size(); ++i)
    if (columns[i].ends_with("tip_settling_s") && std::isnan(values[i])) return "not_settled";
  return "ok";
}

}  // namespace ff
