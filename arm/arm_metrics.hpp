// The responses of one arm run (arm_simulate.hpp's trace), the reference rig's definitions
// (kernel/metrics.hpp, docs/reference-rig.md) applied per joint, to the tool point and to each flexible
// link's tip. The settling window runs from the end of the last waypoint to the end of the run.
//   <joint>_settling_s        last exit of the joint from its final target's band (band x the joint's
//                             largest move), NaN = not settled
//   <joint>_overshoot_pct     beyond the target of the joint's last move, % of that move, from its start on
//   <joint>_peak_torque_Nm    largest |torque| (prismatic: N)
//   <joint>_peak_speed        largest |rate|, rad/s (m/s)
// Each tool point has the five tool_* metrics under its own name (<tool>_settling_s, ...; "tool" is the
// `tool:` block's):
//   tool_settling_s           last exit of the tool point from a ball about where it comes to rest (its
//                             last sample, as MATLAB's stepinfo takes yfinal) of radius band x the tool's
//                             largest move in the rigid reference, NaN = not settled
//   tool_overshoot_pct        largest excursion past its resting point along the reference's last move
//                             (where the reference is when the arm's last move begins, to its final
//                             target), % of that move
//   tool_peak_error_m         largest |tool - where the rigid arm at the reference puts it|: tracking
//   tool_final_error_m        that error at the end of the run (a flexible arm's static sag among it)
//   tool_sag_m                that error at the start: the static sag under gravity at the start pose
//   <link>_peak_deflection_m  largest |tip deflection| of a flexible link
//   <link>_residual_m         half the peak-to-peak of its tip deflection after the move (the larger plane)
//   <link>_sag_m              |tip deflection| at the start (the static sag under gravity, held)
// With a world (or two arms), the clearances (arm_collision.hpp) over the run:
//   min_clearance_m           the least clearance of any part to the world or another arm, m (< 0: overlap;
//                             inf: nothing ever constrained it)
//   min_clearance_time_s      when it was least (the first such sample)
//   first_contact_s           when the clearance first reached 0, interpolated between samples; NaN = never
//   contacts                  how many times it reached 0 (from above, or at the start)
//   contact                   1 when it did at all, else 0 (its mean over a Monte Carlo study is P(contact))
//   <part>_clearance_m        each part's least clearance (a rigid body or a flexible link)
//   <obstacle>_clearance_m    each obstacle's least clearance to the arm
// With safety monitors (`monitors:`), from the trace's <monitor>.tripped columns and the first tool's point:
//   <monitor>_trip_s          when each monitor tripped, s; NaN = never
//   trip_s                    the first trip of any monitor; NaN = none
//   trip_cause                the 1-based index (in `monitors:` order) of the monitor that tripped first, 0 = none
//   stopping_distance_m       the first tool's path length (the sum of its steps between samples) from the
//                             action's start (the acting monitor's trip plus its delay; the acting monitor
//                             is the first to trip whose action is not `record`, else the first to trip)
//                             to the end of the run; NaN without a trip or when the action has not started
//   stop_time_s               from the action's start to the last sample at which the first tool still moved
//                             (its step from the sample before, over the sample time, >= 1 mm/s), 0 when it
//                             never moved after; NaN without a trip, or when it still moved at the last sample
//   settling_horizon_s        the longest settling time the run can confirm: its window less that dwell
//                             (a NaN settling time is right-censored there, results/censoring.hpp)
#pragma once

#include <limits>
#include <span>
#include <string>
#include <vector>

#include "arm/arm_model.hpp"
#include "arm/arm_simulate.hpp"

namespace ff {

// The suffixes of each tool's metrics, in column order.
inline constexpr const char* kToolMetricSuffixes[] = {"_settling_s", "_overshoot_pct", "_peak_error_m",
                                                      "_final_error_m", "_sag_m"};

std::vector<std::string> arm_metric_columns(const ArmModel& m);

// The tools of a result table or metrics row, by their columns (<tool>_peak_error_m), in column order.
std::vector<std::string> arm_tool_names(const std::vector<std::string>& columns);

// Values in arm_metric_columns order; all NaN when the lane failed.
std::vector<double> calc_arm_metrics(const ArmModel& m, const ArmTrace& trace, LaneStatus status);

// ---- The pieces calc_arm_metrics shares with its online form (arm_online_metrics.hpp) ----

// The settling rule of an arm's metrics.
struct ArmSettleRule {
  double t0;         // the settling window's start: the end of the last waypoint, s
  double band;       // of a joint's largest move (m.spec.band)
  double tool_band;  // m; 0 = band x the tool's largest move in the rigid reference
  double dwell;      // s in the band to count as settled: one period of the slowest closed-loop resonance, 1 s without
};
ArmSettleRule make_arm_settle_rule(const ArmModel& m);

// Joint j's moves on the trajectory: its largest, its last (start -> target, beginning at t_start, s)
// and where it ends. The overshoot is the last move's, over the samples from t_start on: the poses
// before it (an earlier move's start or target) are not past its target.
// A step of a joint's waypoints below kArmMoveTolerance (rad or m; the inverse kinematics' tolerance) is
// round-off, not a move (a wrist the tool's targets do not need, moved by 1e-17 rad): no overshoot or
// settling band relative to it.
inline constexpr double kArmMoveTolerance = 1e-9;
struct ArmJointMoves {
  double largest, start, target, final_target, t_start;
};
ArmJointMoves calc_arm_joint_moves(const ArmModel& m, std::size_t j);

// When the arm's last move begins, s: the waypoint before the last one at which any joint moves (0 for
// the first). A tool's overshoot is along that move (the rigid reference there to its final target).
double calc_arm_last_move_start(const ArmModel& m);

// The last exit of e >= 0 from [0, band], interpolated between the last sample outside it (t_out, e_out)
// and its successor (t_next, e_next), less t0, >= 0; NaN (not settled) when it lies within dwell of the
// run's last sample t_end.
double calc_arm_exit_time(double t_out, double e_out, double t_next, double e_next, double band, double t0,
                          double t_end, double dwell);

// A tool's settling time and overshoot (%) about where it comes to rest, its last sample (x, y, z at the
// samples t), from its reference's start `begin` and final `target` and its largest move in the reference.
struct ArmToolRest {
  double settling_s, overshoot_pct;
};
ArmToolRest calc_arm_tool_rest(const ArmSettleRule& r, std::span<const double> t, std::span<const double> x,
                               std::span<const double> y, std::span<const double> z, const Vec3& begin,
                               const Vec3& target, double largest);

// The clearance metrics (above), fed the trace's clearance columns one sample at a time: calc_arm_metrics
// and its online form both use it.
class ClearanceMetrics {
 public:
  explicit ClearanceMetrics(std::size_t columns) : mins_(columns, std::numeric_limits<double>::infinity()) {}
  // Sample at t: c[i * stride] for the trace's columns "clearance", "<part>.clearance", ...
  void add(double t, const double* c, std::size_t stride);
  // min_clearance_m, min_clearance_time_s, first_contact_s, contacts, contact, then each part's and
  // obstacle's.
  void result(double* out) const;
  static constexpr std::size_t kLeading = 5;

 private:
  std::vector<double> mins_;
  double t_min_ = std::numeric_limits<double>::quiet_NaN(), first_contact_ = std::numeric_limits<double>::quiet_NaN();
  double t_prev_ = 0.0, c_prev_ = std::numeric_limits<double>::infinity();
  long contacts_ = 0;
  bool started_ = false;
};

// The monitor metrics (above), fed the trace's monitor columns one sample at a time: calc_arm_metrics and
// its online form both use it.
class MonitorMetrics {
 public:
  explicit MonitorMetrics(const ArmModel& m);
  // Sample at t: tripped[i * stride] the column <monitor i>.tripped, tool[0], tool[stride], tool[2 stride]
  // the first tool's x, y, z.
  void add(double t, const double* tripped, const double* tool, std::size_t stride);
  // <monitor>_trip_s per monitor, then trip_s, trip_cause, stopping_distance_m, stop_time_s.
  void result(double* out) const;
  static constexpr std::size_t kTrailing = 4;
  static constexpr double kRestSpeed = 1e-3;  // m/s: the tool at rest below it

 private:
  // The first tool's path from an action's start (a sample) on.
  struct Path {
    long start = -1;                  // -1: not known yet
    double distance = 0.0, t_start = 0.0, t_moved = 0.0;
    bool started = false, moving = false;  // the start reached / the last step a move
    void add(long k, double t, double step, double dt);
  };
  std::vector<MonitorAction> actions_;
  std::vector<long> delays_;
  std::vector<double> trip_t_;
  int first_ = -1, acting_ = -1;
  Path from_first_, from_acting_;
  Vec3 previous_ = Vec3::Zero();
  double t_previous_ = 0.0;
  long n_ = 0;
};

// "ok", "not_settled" (a tool's settling time is NaN), or the lane's failure.
std::string calc_arm_status(const ArmModel& m, LaneStatus lane, const std::vector<std::string>& columns,
                            const std::vector<double>& values);

}  // namespace ff
