// The commanded hub angle: a chain of cubic moves r = r0 + (r1 - r0)(3u^2 - 2u^3), u = t/T_m,
// each followed by a hold (reference-rig.md, "Controller and motion"; the seed's TELEGRIP planner).
#pragma once

#include <string>
#include <vector>

#include "kernel/metrics.hpp"
#include "kernel/model.hpp"
#include "kernel/shaper.hpp"

namespace ff {

// r(t), rad (0 before t = 0).
double calc_reference(const TrajectorySpec& traj, double t);

// The shaped reference sum_i A_i r(t - t_i) (kernel/shaper.hpp), rad.
double calc_shaped_reference(const TrajectorySpec& traj, const std::vector<Impulse>& shaper, double t);

// First and second derivatives of r(t): (6u - 6u^2) (r1 - r0) / T_m, rad/s, and (6 - 12u) (r1 - r0) / T_m^2,
// rad/s^2, during a move; and of the shaped reference.
double calc_reference_rate(const TrajectorySpec& traj, double t);
double calc_reference_accel(const TrajectorySpec& traj, double t);
double calc_shaped_reference_rate(const TrajectorySpec& traj, const std::vector<Impulse>& shaper, double t);
double calc_shaped_reference_accel(const TrajectorySpec& traj, const std::vector<Impulse>& shaper, double t);

// One commanded move: when it starts, and the window in which its response is judged.
struct Move {
  double t_start;     // move begins, s
  MoveWindow window;  // move end, window end (next move or end of record), start and target values
};
std::vector<Move> calc_moves(const TrajectorySpec& traj, double duration);

// "0 -> 0.5 rad" for each move, for tables.
std::vector<std::string> describe_moves(const TrajectorySpec& traj);

}  // namespace ff
