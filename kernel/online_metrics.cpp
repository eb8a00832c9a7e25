// Online move metrics (definitions in online_metrics.hpp; the stored forms in metrics.cpp).
#include "kernel/online_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "kernel/trajectory.hpp"

namespace ff {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// t in [from, to], as the stored forms' lower_bound(from) .. upper_bound(to).
bool in_range(double t, double from, double to) { return t >= from && !(t > to); }
}  // namespace

OnlineSettling::OnlineSettling(const MoveWindow& w, double band)
    : w_(w), tol_(band * std::abs(calc_move_amplitude(w, "OnlineSettling"))) {
  if (!(band > 0.0)) throw std::invalid_argument("OnlineSettling: band must be positive");
}

void OnlineSettling::add(double t, double y) {
  if (t < w_.t_move_end) {
    t_prev_ = t;
    y_prev_ = y;
    has_prev_ = true;
    return;
  }
  if (t > w_.t_window_end) return;
  // The first window sample: the one before the move end joins unless this one falls on it.
  if (!started_ && has_prev_ && t > w_.t_move_end) take(t_prev_, y_prev_);
  started_ = true;
  take(t, y);
}

// One sample of the window, in order: remember it when outside the band |y − target| <= tol, and
// the successor of the last one outside.
void OnlineSettling::take(double t, double y) {
  const double e = y - w_.target;
  if (pending_) {
    t_next_ = t;
    e_next_ = e;
    pending_ = false;
  }
  if (std::abs(e) > tol_) {
    out_ = pending_ = true;
    t_out_ = t;
    e_out_ = e;
  }
}

double OnlineSettling::result() const {
  if (!started_) return kNaN;
  if (!out_) return 0.0;
  if (pending_) return kNaN;  // still outside the band at the window end: not settled
  const double level = e_out_ > 0.0 ? tol_ : -tol_;  // the band edge on the side the response comes from
  const double time = calc_crossing_time(t_out_, t_next_, e_out_, e_next_, level);
  if (std::isnan(time)) return kNaN;
  return std::max(0.0, time - w_.t_move_end);
}

OnlineOvershoot::OnlineOvershoot(double t_from, const MoveWindow& w)
    : t_from_(t_from), t_to_(w.t_window_end), target_(w.target), amplitude_(calc_move_amplitude(w, "OnlineOvershoot")),
      dir_(amplitude_ > 0.0 ? 1.0 : -1.0) {}

void OnlineOvershoot::add(double t, double y) {
  if (!in_range(t, t_from_, t_to_)) return;
  any_ = true;
  past_ = std::max(past_, dir_ * (y - target_));
}

double OnlineOvershoot::result() const { return any_ ? 100.0 * past_ / std::abs(amplitude_) : kNaN; }

void OnlinePeakAbs::add(double t, double y) {
  if (!in_range(t, t_from_, t_to_)) return;
  any_ = true;
  peak_ = std::max(peak_, std::abs(y));
}

double OnlinePeakAbs::result() const { return any_ ? peak_ : kNaN; }

void OnlineResidual::add(double t, double y) {
  if (!in_range(t, t_from_, t_to_)) return;
  if (!any_) {
    lo_ = hi_ = y;
    any_ = true;
    return;
  }
  if (y < lo_) lo_ = y;    // the first smallest
  if (!(y < hi_)) hi_ = y;  // the last largest
}

double OnlineResidual::result() const { return any_ ? 0.5 * (hi_ - lo_) : kNaN; }

void OnlineRun::add(double t, double tip_angle, double hub_angle, double deflection, double torque) {
  finite = finite && std::isfinite(tip_angle) && std::isfinite(hub_angle) && std::isfinite(deflection) &&
           std::isfinite(torque);
  for (OnlineMove& m : moves) {
    m.tip_settling.add(t, tip_angle);
    m.hub_settling.add(t, hub_angle);
    m.tip_overshoot.add(t, tip_angle);
    m.hub_overshoot.add(t, hub_angle);
    m.peak_deflection.add(t, deflection);
    m.peak_torque.add(t, torque);
    m.residual_vibration.add(t, deflection);
  }
}

OnlineRun make_online_run(const Model& model) {
  OnlineRun run;
  for (const Move& mv : calc_moves(model.spec.trajectory, model.duration)) {
    const MoveWindow& w = mv.window;
    run.moves.push_back({w, OnlineSettling(w), OnlineSettling(w), OnlineOvershoot(mv.t_start, w),
                         OnlineOvershoot(mv.t_start, w), OnlinePeakAbs(mv.t_start, w.t_window_end),
                         OnlinePeakAbs(mv.t_start, w.t_window_end), OnlineResidual(w.t_move_end, w.t_window_end)});
  }
  return run;
}

}  // namespace ff
