#include "results/run_metrics.hpp"

#include <algorithm>
#include <array>
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

// A settling time ts, or "not settled" (NaN) unless the response then stays in the band for `dwell`
// seconds before the window ends: a response caught inside the band mid-swing is not settled.
double confirmed(double ts, const MoveWindow& w, double dwell) {
  return w.t_window_end - (w.t_move_end + ts) >= dwell ? ts : std::nan("");
}

// The row of a run: per move of the model, move_values(j, move) (the seven metrics before the
// horizon), then the horizon; all NaN when the run is not finite.
template <class F>
std::vector<double> assemble_run_metrics(const Model& model, bool finite, F move_values) {
  // One column per metric of every move of the model (calc_metric_columns); NaN = "no number".
  const std::size_t ncols = kMoveMetrics.size() * model.spec.trajectory.moves.size();
  // A run that stopped being finite has no responses: every metric is "no number".
  if (!finite) return std::vector<double>(ncols, std::nan(""));
  // Dwell: one period of the slowest closed-loop resonance.
  const double dwell = model.resonances.empty() ? 0.0 : 2.0 * std::numbers::pi / model.resonances[0];
  std::vector<double> out;
  const std::vector<Move> moves = calc_moves(model.spec.trajectory, model.duration);
  for (std::size_t j = 0; j < moves.size(); ++j) {
    const MoveWindow& w = moves[j].window;
    const std::array<double, 7> v = move_values(j, moves[j]);
    out.insert(out.end(), {confirmed(v[0], w, dwell), v[1], confirmed(v[2], w, dwell), v[3], v[4], v[5], v[6]});
    // Horizon: confirmed() keeps ts only when t2 - (t1 + ts) >= dwell, so at most t2 - t1 - dwell.
    out.push_back(std::max(0.0, w.t_window_end - w.t_move_end - dwell));
  }
  out.resize(ncols, std::nan(""));  // moves that start after the run ends (simulation.duration): no number
  return out;
}
}  // namespace

std::vector<double> calc_run_metrics(const Model& model, const Trace& tr) {
  bool finite = true;
  for (const auto* sig : {&tr.tip_angle, &tr.hub_angle, &tr.tip_deflection, &tr.torque})
    finite = finite && std::all_of(sig->begin(), sig->end(), [](double x) { return std::isfinite(x); });
  const std::span<const double> t = tr.t;
  return assemble_run_metrics(model, finite, [&](std::size_t, const Move& mv) {
    const auto& w = mv.window;
    const double t0 = mv.t_start, t1 = w.t_move_end, t2 = w.t_window_end;
    return std::array<double, 7>{
        over(t, t1, t2, [&] { return calc_settling_time(t, tr.tip_angle, w); }),
        over(t, t0, t2, [&] { return calc_overshoot(t, tr.tip_angle, t0, w); }),
        over(t, t1, t2, [&] { return calc_settling_time(t, tr.hub_angle, w); }),
        over(t, t0, t2, [&] { return calc_overshoot(t, tr.hub_angle, t0, w); }),
        over(t, t0, t2, [&] { return calc_peak_abs(t, tr.tip_deflection, t0, t2); }),
        over(t, t1, t2, [&] { return calc_residual_amplitude(t, tr.tip_deflection, t1, t2); }),
        over(t, t0, t2, [&] { return calc_peak_abs(t, tr.torque, t0, t2); })};
  });
}

std::vector<double> calc_run_metrics(const Model& model, const OnlineRun& run) {
  return assemble_run_metrics(model, run.finite, [&](std::size_t j, const Move&) {
    const OnlineMove& m = run.moves[j];
    return std::array<double, 7>{m.tip_settling.result(),    m.tip_overshoot.result(),      m.hub_settling.result(),
                                 m.hub_overshoot.result(),   m.peak_deflection.result(),    m.residual_vibration.result(),
                                 m.peak_torque.result()};
  });
}

std::string calc_run_status(LaneStatus lane, const std::vector<std::string>& columns, const std::vector<double>& values) {
  if (lane != LaneStatus::kOk) return lane_status_name(lane);
  for (std::size_t i = 0; i < columns.size(); ++i)
    if (columns[i].ends_with("tip_settling_s") && std::isnan(values[i])) return "not_settled";
  return "ok";
}

bool is_failed_status(const std::string& status) {
  return status == lane_status_name(LaneStatus::kNonfinite) || status == lane_status_name(LaneStatus::kSolverFail);
}

}  // namespace ff
