// The responses of one run, per commanded move (reference-rig.md, "Signals and sign conventions").
#pragma once

#include <string>
#include <vector>

#include "kernel/batch.hpp"
#include "kernel/online_metrics.hpp"
#include "kernel/simulate.hpp"

namespace ff {

// Metrics of each move, in this order (column suffixes):
//   tip_settling_s       settling time of the tip angle after the move ends (reference-rig.md), NaN = not
//                        settled; also NaN unless the tip then stays in the band for one period of the
//                        slowest closed-loop resonance before the window ends
//   tip_overshoot_pct    overshoot of the tip angle, %
//   hub_settling_s       settling time of the hub angle, NaN = not settled
//   hub_overshoot_pct    overshoot of the hub angle, %
//   peak_tip_deflection_m  largest |tip deflection| from the move's start to the next move, m
//   residual_vibration_m   half the peak-to-peak tip deflection after the move ends, m
//   peak_torque_Nm         largest |hub torque| from the move's start to the next move, N·m
//   settling_horizon_s     the largest settling time the run can confirm for this move: the window
//                          (the hold, or up to the end of the run) minus the dwell, >= 0; a settling
//                          time of NaN is right-censored here (> horizon; censoring.hpp)
extern const std::vector<std::string> kMoveMetrics;

// Column names "m1_tip_settling_s", ... for `nmoves` moves.
std::vector<std::string> calc_metric_columns(int nmoves);

// The column holding the horizon a settling column is censored at ("m2_hub_settling_s" ->
// "m2_settling_horizon_s"; an arm's "<joint>_settling_s" or "tool_settling_s" -> "settling_horizon_s");
// "" for a column that is not a settling time.
std::string calc_horizon_column(const std::string& column);

// Values in calc_metric_columns order (every move of the model); all NaN when the trace is not finite (a
// diverged run). A move the run (simulation.duration) ends before its end has no settling times and no
// residual vibration (NaN: not settled), its overshoot and peaks over the part that ran; a move that
// starts after the run ends has no numbers at all.
std::vector<double> calc_run_metrics(const Model& model, const Trace& trace);
// The same values, bit for bit, from a run's online accumulators (kernel/online_metrics.hpp; built by
// make_online_run(model) and fed by simulate) instead of its trace.
std::vector<double> calc_run_metrics(const Model& model, const OnlineRun& run);

// "ok", "not_settled" (a tip settling time is NaN), or the lane's failure.
std::string calc_run_status(LaneStatus lane, const std::vector<std::string>& columns, const std::vector<double>& values);

// Whether a run's status is a numerical failure ("nonfinite", "solver_fail"): no metrics, exit 3.
bool is_failed_status(const std::string& status);

}  // namespace ff
