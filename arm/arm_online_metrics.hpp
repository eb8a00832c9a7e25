// The arm metrics (arm_metrics.hpp) accumulated while an arm runs: fed a lane's trace row at every
// controller sample (the columns of arm_trace_names), OnlineArmRun gives calc_arm_metrics's vector for
// the same run bit for bit (the same expressions in the same order; the shared pieces are
// arm_metrics.hpp's and kernel/online_metrics.hpp's) without the trace:
//   joints  settling by the last exit from the band about the final target (the last sample outside it
//           and its successor); overshoot, peak torque and peak speed by running maxima;
//   tools   peak, final and sag tracking error by running max, last and first; settling and overshoot
//           are measured about the tool's last sample, known only at the end, so each tool keeps its
//           x, y, z at every sample (and the run the sample times): 3 doubles a tool a sample, plus 1,
//           where the trace keeps every column;
//   links   peak deflection by running max, residual by running min and max after the move, sag from
//           the first sample;
//   world   the clearances by ClearanceMetrics, as the stored form;
//   monitors  the trips, stopping distance and time by MonitorMetrics, as the stored form.
// simulate_arms feeds it (ArmRunOptions::online) when a study writes no traces (jobs/runner.cpp).
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "arm/arm_metrics.hpp"
#include "arm/arm_model.hpp"
#include "kernel/batch.hpp"  // LaneStatus
#include "kernel/online_metrics.hpp"

namespace ff {

// last_exit of arm_metrics.cpp one sample at a time: the last sample with t >= t0 and e > band (outside
// [0, band]; NaN counts as inside) and its successor.
class ArmLastExit {
 public:
  ArmLastExit(double t0, double band) : t0_(t0), band_(band) {}
  void add(double t, double e);
  // 0 when no sample was outside, NaN when the last one was, else calc_arm_exit_time up to t_end.
  double result(double t_end, double dwell) const;

 private:
  double t0_, band_;
  bool out_ = false, pending_ = false;  // a sample outside seen / its successor not yet seen
  double t_out_ = 0.0, e_out_ = 0.0, t_next_ = 0.0, e_next_ = 0.0;
};

// One lane's accumulators (above), made from its model.
class OnlineArmRun {
 public:
  explicit OnlineArmRun(const ArmModel& m);
  // One controller sample, in time order: column c of arm_trace_names(m) at row[c * stride].
  void add(const double* row, std::size_t stride);
  // The values of arm_metric_columns(m), as calc_arm_metrics gives them; all NaN when the lane failed
  // (or no sample was added).
  std::vector<double> result(LaneStatus status) const;

 private:
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  struct Joint {
    std::size_t q, qd, torque;  // their columns
    ArmJointMoves moves;
    ArmLastExit settling;
    std::optional<OnlineOvershoot> overshoot;  // of its last move, from its start on; none without a move
    OnlinePeakAbs peak_torque{-kInf, kInf}, peak_speed{-kInf, kInf};
  };
  struct Tool {
    std::size_t x = 0, ref_x = 0;     // the columns of x and ref_x (y, z follow each)
    Vec3 begin = Vec3::Zero(), target = Vec3::Zero();  // the reference's first and last sample
    Vec3 last_begin = Vec3::Zero();   // its first sample from the arm's last move's start on
    bool last_started = false;
    double largest = 0.0;             // the reference's largest distance from begin
    OnlinePeakAbs peak_error{-kInf, kInf};  // |tool - reference|
    double final_error = 0.0, sag = 0.0;
    std::vector<double> x_path, y_path, z_path;  // every sample's, for the settling and overshoot
  };
  struct Link {
    std::size_t dy, dz;
    OnlineResidual residual_y, residual_z;  // after t0
    OnlinePeakAbs peak{-kInf, kInf};        // hypot(dy, dz)
    double sag = 0.0;
  };
  ArmSettleRule rule_;
  double last_move_start_;  // calc_arm_last_move_start, s
  std::size_t ncolumns_;
  std::vector<Joint> joints_;
  std::vector<Tool> tools_;
  std::vector<Link> links_;
  std::optional<ClearanceMetrics> clearance_;  // with a world: from the trace's column "clearance" on
  std::size_t clearance_column_ = 0, clearance_columns_ = 0;
  std::optional<MonitorMetrics> monitors_;   // with monitors: from the first <monitor>.tripped column on
  std::size_t monitor_column_ = 0, monitor_tool_ = 0, monitor_count_ = 0;  // and the first tool's x
  std::vector<double> t_;  // the sample times (kept with tools only)
  double t_last_ = 0.0;
  long n_ = 0;             // samples added
};

}  // namespace ff
