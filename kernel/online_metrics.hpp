// Online forms of the move metrics (kernel/metrics.hpp): fed a run's samples (t, y) one at a time, t
// strictly increasing, they keep a few doubles instead of the record and return the same doubles, bit
// for bit, as the stored-trace functions on the same finite samples (the same expressions in the same
// order). result() is NaN when no sample fell in the metric's time range (where the stored form throws);
// the constructors throw std::invalid_argument as the stored forms do for a zero amplitude or band.
#pragma once

#include <vector>

#include "kernel/metrics.hpp"
#include "kernel/model.hpp"

namespace ff {

// calc_settling_time by the last exit from the band: the last sample outside it and its successor,
// plus the sample just before w.t_move_end (taken into the window when no sample falls on t_move_end).
class OnlineSettling {
 public:
  explicit OnlineSettling(const MoveWindow& w, double band = 0.02);
  void add(double t, double y);
  double result() const;

 private:
  void take(double t, double y);
  MoveWindow w_;
  double tol_;                              // band·|amplitude|
  double t_prev_ = 0.0, y_prev_ = 0.0;      // the last sample before t_move_end
  bool has_prev_ = false, started_ = false;  // a sample before t_move_end / in the window seen
  bool out_ = false, pending_ = false;      // a sample outside the band seen / its successor not yet seen
  double t_out_ = 0.0, e_out_ = 0.0;        // the last sample outside the band: t, y − target
  double t_next_ = 0.0, e_next_ = 0.0;      // its successor
};

// calc_overshoot by the running largest excursion past the target over [t_from, w.t_window_end].
class OnlineOvershoot {
 public:
  OnlineOvershoot(double t_from, const MoveWindow& w);
  void add(double t, double y);
  double result() const;

 private:
  double t_from_, t_to_, target_, amplitude_, dir_;
  double past_ = 0.0;
  bool any_ = false;
};

// calc_peak_abs by the running largest |y| over [t_from, t_to].
class OnlinePeakAbs {
 public:
  OnlinePeakAbs(double t_from, double t_to) : t_from_(t_from), t_to_(t_to) {}
  void add(double t, double y);
  double result() const;

 private:
  double t_from_, t_to_;
  double peak_ = 0.0;
  bool any_ = false;
};

// calc_residual_amplitude by the running min (first smallest) and max (last largest, as
// std::minmax_element) over [t_from, t_to].
class OnlineResidual {
 public:
  OnlineResidual(double t_from, double t_to) : t_from_(t_from), t_to_(t_to) {}
  void add(double t, double y);
  double result() const;

 private:
  double t_from_, t_to_;
  double lo_ = 0.0, hi_ = 0.0;
  bool any_ = false;
};

// One move's accumulators for the metrics of results/run_metrics.hpp (same order of signals).
struct OnlineMove {
  MoveWindow window;
  OnlineSettling tip_settling, hub_settling;   // over [t_move_end, t_window_end]
  OnlineOvershoot tip_overshoot, hub_overshoot;  // over [t_start, t_window_end]
  OnlinePeakAbs peak_deflection, peak_torque;    // over [t_start, t_window_end]
  OnlineResidual residual_vibration;             // tip deflection over [t_move_end, t_window_end]
};

// A lane's run metrics, accumulated from the signals simulate records at each controller sample.
struct OnlineRun {
  std::vector<OnlineMove> moves;  // calc_moves(model.spec.trajectory, model.duration)
  bool finite = true;             // every sample of the four signals finite
  void add(double t, double tip_angle, double hub_angle, double deflection, double torque);
};
OnlineRun make_online_run(const Model& model);

}  // namespace ff
