// Rest-to-rest joint-space trajectories through waypoints (point-to-point motion with a polynomial
// time scaling; Lynch and Park, Modern Robotics, 2017, sec. 9.2.2; Biagiotti and Melchiorri,
// Trajectory Planning for Automatic Machines and Robots, 2008, sec. 2.1).
//
// Segment k runs from the previous waypoint (time 0 and `start` for k = 0) to waypoint k, every
// joint along the straight line q = q_a + (q_b - q_a) s(u), u = (t - t_a) / (t_b - t_a), with
//   cubic    s(u) = 3u² - 2u³:            s'(0) = s'(1) = 0, peak velocity 1.5 d/T at u = 1/2,
//                                          acceleration ±6 d/T² jumping at each waypoint;
//   quintic  s(u) = 10u³ - 15u⁴ + 6u⁵:    s' = s'' = 0 at both ends, peak velocity 1.875 d/T,
// so the motion rests at every waypoint. A waypoint repeating the previous q holds it until its time.
// Before t = 0 the trajectory holds `start`, after the last waypoint it holds the last one. At a
// waypoint's time the next segment's start is returned (position exact; for the cubic the
// acceleration is the next segment's initial +6 d/T²).
#pragma once

#include <vector>

namespace ff {

enum class TrajectoryShape { kCubic, kQuintic };

struct JointWaypoint {
  double time = 0.0;      // arrival time, s (strictly increasing; the first > 0)
  std::vector<double> q;  // joint values there, rad or m (one per joint, as `start`)
};

struct JointTrajectory {
  TrajectoryShape shape = TrajectoryShape::kQuintic;
  std::vector<double> start;             // joint values at t <= 0, rad or m
  std::vector<JointWaypoint> waypoints;  // at least one
};

// Position, velocity and acceleration at time t (s) into q, qd, qdd (each of start.size() entries;
// rad, rad/s, rad/s² or m, m/s, m/s²). Allocates nothing and checks nothing (it runs every controller
// sample): call check_joint_trajectory once beforehand. O(log waypoints) to find the segment; a
// non-finite t gives the final hold.
void eval_joint_trajectory(const JointTrajectory& tr, double t, double* q, double* qd, double* qdd);

// Throws std::invalid_argument naming the waypoint index on: no waypoints, a waypoint whose q is not
// the size of `start`, a first time <= 0 or a time not after the previous one, a non-finite time or
// value (also in `start`).
void check_joint_trajectory(const JointTrajectory& tr);

}  // namespace ff
