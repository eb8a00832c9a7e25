// Response metrics of sampled signals: the project's move metrics and a MATLAB-compatible stepinfo.
//
// A. Move metrics, as defined in reference-rig.md:
//   "Settling time: measured from the end of the commanded move, the last time the response leaves
//    a band of ±2 % of the move amplitude around its final value, interpolated between samples; a
//    response still outside the band at the end of the record is 'not settled', never a number.
//    Overshoot: 100·(peak − final)/|amplitude| in the direction of the move."
//   Here "final value" is the commanded target and amplitude = target − start. A move's window runs
//   from its end (t_move_end) to the next move's start or the end of the record (t_window_end).
//
// B. calc_stepinfo() reproduces MATLAB's stepinfo(y, t, yfinal, yinit) (Control System Toolbox,
//   current definitions), with ynorm = (y − yinit)/(yfinal − yinit):
//   RiseTime      time from ynorm first reaching rise_lo to ynorm first reaching rise_hi;
//   SettlingTime  first T with |y − yfinal| <= ST·|yfinal − yinit| for all t >= T;
//   TransientTime first T with |y − yfinal| <= ST·emax for all t >= T, emax = max |y − yfinal|;
//   SettlingMin/Max  min/max of y from the first sample at which ynorm >= rise_hi on;
//   Overshoot     max(0, 100·(max ynorm − 1));  Undershoot  max(0, −100·min ynorm);
//   Peak          max |y − yinit|;  PeakTime  the time of that sample.
//   Threshold crossings (rise, settling, transient) are interpolated linearly between samples.
//   On MATLAB's documented example H(s) = (8s²+18s+32)/(s³+6s²+14s+24) the response starts at
//   y = 0 = yinit, so emax = |yfinal − yinit| = |yfinal| and the three candidate thresholds
//   (2 % of |yfinal − yinit|, of the peak error, of |yfinal|) all give 3.4972 s; we use
//   |yfinal − yinit| for SettlingTime and the peak error for TransientTime, as the docs state.
//   Times are values on the caller's t axis (MATLAB assumes the step at t = 0). MATLAB's printed
//   values for stepinfo(sys) come from the samples of its own step() grid (23 ms for H, peak
//   sample at 0.5987 s); on a dense grid this function returns the continuous-time values
//   (H: PeakTime 0.6079 s, Overshoot 26.5435 %). metrics_test.cpp checks both.
//
// All functions require t and y of equal, non-zero length with t strictly increasing, and throw
// std::invalid_argument otherwise, or when a time range holds no sample, or when the move
// amplitude (target − start, yfinal − yinit) is zero: every metric is relative to it.
#pragma once

#include <span>

namespace ff {

// One commanded move and the stretch of record that belongs to it.
struct MoveWindow {
  double t_move_end;    // end of the commanded move, s
  double t_window_end;  // next move's start or end of record, s
  double start;         // value before the move
  double target;        // commanded final value
};

// The move amplitude w.target − w.start, which every move metric is relative to. Throws
// std::invalid_argument "WHO: move amplitude must be finite and non-zero" otherwise.
double calc_move_amplitude(const MoveWindow& w, const char* who);

// Time at which the straight line through (t0, v0), (t1, v1) takes the value `level`: the band
// crossings of the settling times (kernel/online_metrics.hpp uses it too, for the same bits).
inline double calc_crossing_time(double t0, double t1, double v0, double v1, double level) {
  return t0 + (t1 - t0) * (level - v0) / (v1 - v0);
}

// Settling time after w.t_move_end, s, over the samples with t in [t_move_end, t_window_end].
// The last sample with |y − target| > band·|amplitude| is found; if it is the last sample of the
// window the move is not settled (NaN); if there is none the result is 0; otherwise the band
// crossing is interpolated between it and the next sample and returned as crossing − t_move_end.
// The sample just before t_move_end also takes part, so that a crossing between it and the first
// window sample is interpolated; results are clamped to >= 0.
double calc_settling_time(std::span<const double> t, std::span<const double> y, const MoveWindow& w,
                          double band = 0.02);

// Overshoot, percent, over the samples with t in [t_from, w.t_window_end] (pass the move START as
// t_from): 100·(peak − target)/|amplitude| with the peak taken in the direction of the move, so a
// move 0.5 → 0 overshoots when y goes below 0. 0 when the response never passes the target.
double calc_overshoot(std::span<const double> t, std::span<const double> y, double t_from, const MoveWindow& w);

// Largest |y| over the samples with t in [t_from, t_to].
double calc_peak_abs(std::span<const double> t, std::span<const double> y, double t_from, double t_to);

// Residual vibration amplitude: half the peak-to-peak of y over the samples with t in [t_from, t_to]
// (e.g. tip deflection after the move).
double calc_residual_amplitude(std::span<const double> t, std::span<const double> y, double t_from, double t_to);

// MATLAB stepinfo fields (definitions above). Times in s on the t axis, percentages in %.
// RiseTime, SettlingMin and SettlingMax are NaN when ynorm never reaches rise_hi;
// SettlingTime and TransientTime are NaN when the last sample is still outside their band, and t[0]
// when no sample is outside it.
struct StepInfo {
  double rise_time, transient_time, settling_time, settling_min, settling_max,
      overshoot, undershoot, peak, peak_time;
};

// stepinfo(y, t, y_final, y_init, 'SettlingTimeThreshold', settling_threshold,
//          'RiseTimeLimits', [rise_lo rise_hi]). Requires 0 < settling_threshold < 1 and
// 0 <= rise_lo < rise_hi <= 1.
StepInfo calc_stepinfo(std::span<const double> t, std::span<const double> y, double y_final, double y_init = 0.0,
                       double settling_threshold = 0.02, double rise_lo = 0.1, double rise_hi = 0.9);

}  // namespace ff
