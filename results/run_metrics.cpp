#include "results/run_metrics.hpp"

#include <cmath>
#include <numbers>

#include "kernel/metrics.hpp"
#include "kernel/trajectory.hpp"

namespace ff {

const std::vector<std::string> kMoveMetrics = {"tip_settling_s",        "tip_overshoot_pct",    "hub_settling_s",
                                               "hub_overshoot_pct",     "peak_tip_deflection_m", "residual_vibration_m",
                                               "peak_torque_Nm"};

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

namespace {
// Settling time, and "not settled" (NaN) unless the response then stays in the band for `dwell`
// seconds before the window ends: a response caught inside the band mid-swing is not settled.
double settled_for(std::span<const double> t, std::span<const double> y, const MoveWindow& w, double dwell) {
  const double ts = calc_settling_time(t, y, w);
  return w.t_window_end - (w.t_move_end + ts) >= dwell ? ts : std::nan("");
}
}  // namespace

std::vector<double> calc_run_metrics(const Model& model, const Trace& tr) {
  std::vector<double> out;
  // A run that stopped being finite has no responses: every metric is "no number".
  for (const auto* sig : {&tr.tip_angle, &tr.hub_angle, &tr.tip_deflection, &tr.torque})
    for (double x : *sig)
      if (!std::isfinite(x))
        return std::vector<double>(kMoveMetrics.size() * calc_moves(model.spec.trajectory, model.duration).size(),
                                   std::nan(""));
  // Dwell: one period of the slowest closed-loop resonance.
  const double dwell = model.resonances.empty() ? 0.0 : 2.0 * std::numbers::pi / model.resonances[0];
  for (const auto& mv : calc_moves(model.spec.trajectory, model.duration)) {
    const auto& w = mv.window;
    out.push_back(settled_for(tr.t, tr.tip_angle, w, dwell));
    out.push_back(calc_overshoot(tr.t, tr.tip_angle, mv.t_start, w));
    out.push_back(settled_for(tr.t, tr.hub_angle, w, dwell));
    out.push_back(calc_overshoot(tr.t, tr.hub_angle, mv.t_start, w));
    out.push_back(calc_peak_abs(tr.t, tr.tip_deflection, mv.t_start, w.t_window_end));
    out.push_back(calc_residual_amplitude(tr.t, tr.tip_deflection, w.t_move_end, w.t_window_end));
    out.push_back(calc_peak_abs(tr.t, tr.torque, mv.t_start, w.t_window_end));
  }
  return out;
}

std::string calc_run_status(LaneStatus lane, const std::vector<std::string>& columns, const std::vector<double>& values) {
  if (lane != LaneStatus::kOk) return lane_status_name(lane);
  for (std::size_t i = 0; i < columns.size(); ++i)
    if (columns[i].ends_with("tip_settling_s") && std::isnan(values[i])) return "not_settled";
  return "ok";
}

}  // namespace ff
