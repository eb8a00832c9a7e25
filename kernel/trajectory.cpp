#include "kernel/trajectory.hpp"

#include <algorithm>
#include <cstdio>

namespace ff {

double calc_reference(const TrajectorySpec& traj, double t) {
  double r = 0.0, t0 = 0.0;
  for (const auto& mv : traj.moves) {
    if (t < t0) break;
    const double u = std::clamp((t - t0) / traj.move_time, 0.0, 1.0);
    const double target = mv.target;
    const double r_now = r + (target - r) * u * u * (3.0 - 2.0 * u);
    if (u < 1.0) return r_now;
    r = target;
    t0 += traj.move_time + mv.hold;
  }
  return r;
}

double calc_shaped_reference(const TrajectorySpec& traj, const std::vector<Impulse>& shaper, double t) {
  if (shaper.size() <= 1) return calc_reference(traj, t);
  double r = 0.0;
  for (const auto& p : shaper) r += p.amplitude * calc_reference(traj, t - p.time);
  return r;
}

namespace {
// d^order r / dt^order (order 1 or 2) of the move under way at t; 0 outside moves.
double derivative(const TrajectorySpec& traj, double t, int order) {
  double r = 0.0, t0 = 0.0;
  for (const auto& mv : traj.moves) {
    if (t < t0) break;
    const double u = (t - t0) / traj.move_time, a = mv.target - r;
    if (u < 1.0)
      return order == 1 ? a * (6.0 * u - 6.0 * u * u) / traj.move_time
                        : a * (6.0 - 12.0 * u) / (traj.move_time * traj.move_time);
    r = mv.target;
    t0 += traj.move_time + mv.hold;
  }
  return 0.0;
}

double shaped(const TrajectorySpec& traj, const std::vector<Impulse>& shaper, double t, int order) {
  double x = 0.0;
  for (const auto& p : shaper) x += p.amplitude * derivative(traj, t - p.time, order);
  return x;
}
}  // namespace

double calc_reference_rate(const TrajectorySpec& traj, double t) { return derivative(traj, t, 1); }
double calc_reference_accel(const TrajectorySpec& traj, double t) { return derivative(traj, t, 2); }
double calc_shaped_reference_rate(const TrajectorySpec& traj, const std::vector<Impulse>& shaper, double t) {
  return shaped(traj, shaper, t, 1);
}
double calc_shaped_reference_accel(const TrajectorySpec& traj, const std::vector<Impulse>& shaper, double t) {
  return shaped(traj, shaper, t, 2);
}

std::vector<Move> calc_moves(const TrajectorySpec& traj, double duration) {
  std::vector<Move> out;
  double r = 0.0, t0 = 0.0;
  for (const auto& mv : traj.moves) {
    if (t0 >= duration) break;
    const double t_end = t0 + traj.move_time;
    out.push_back({t0, {t_end, std::min(t_end + mv.hold, duration), r, mv.target}});
    r = mv.target;
    t0 = t_end + mv.hold;
  }
  if (!out.empty()) out.back().window.t_window_end = duration;
  return out;
}

std::vector<std::string> describe_moves(const TrajectorySpec& traj) {
  std::vector<std::string> out;
  double from = 0.0;
  for (const auto& mv : traj.moves) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g -> %g rad", from, mv.target);
    out.push_back(buf);
    from = mv.target;
  }
  return out;
}

}  // namespace ff
