// multibody/joint_trajectory: waypoints reached exactly and at rest, velocity and acceleration the
// derivatives of position, the cubic's and quintic's peak velocities 1.5 d/T and 1.875 d/T
// (Lynch and Park, Modern Robotics, sec. 9.2.2), the holds before and after, and bad input.
#include "multibody/joint_trajectory.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

// Three joints (two angles, one slide), four waypoints, the third a hold of the second.
JointTrajectory three_joint_path(TrajectoryShape shape) {
  return {shape,
          {0.1, -0.4, 0.02},
          {{0.8, {1.2, 0.3, 0.15}}, {2.0, {-0.5, 0.9, 0.05}}, {2.5, {-0.5, 0.9, 0.05}}, {3.7, {0.7, -1.1, 0.3}}}};
}

struct State {
  std::vector<double> q, qd, qdd;
  explicit State(std::size_t n) : q(n), qd(n), qdd(n) {}
};

State eval(const JointTrajectory& tr, double t) {
  State s(tr.start.size());
  eval_joint_trajectory(tr, t, s.q.data(), s.qd.data(), s.qdd.data());
  return s;
}

const TrajectoryShape kShapes[] = {TrajectoryShape::kCubic, TrajectoryShape::kQuintic};

const char* name(TrajectoryShape s) { return s == TrajectoryShape::kCubic ? "cubic" : "quintic"; }

TEST(JointTrajectory, WaypointsAreReachedExactlyAndAtRest) {
  for (TrajectoryShape shape : kShapes) {
    const JointTrajectory tr = three_joint_path(shape);
    check_joint_trajectory(tr);
    const State s0 = eval(tr, 0.0);
    EXPECT_EQ(s0.q, tr.start) << name(shape);
    for (std::size_t k = 0; k < tr.waypoints.size(); ++k) {
      const State s = eval(tr, tr.waypoints[k].time);
      EXPECT_EQ(s.q, tr.waypoints[k].q) << name(shape) << " waypoint " << k;  // bit for bit
      for (std::size_t j = 0; j < s.q.size(); ++j) EXPECT_EQ(s.qd[j], 0.0) << name(shape) << " waypoint " << k;
      // Just before the waypoint: the end of its segment, at rest to O(dt) (cubic) or O(dt²) (quintic).
      const State b = eval(tr, tr.waypoints[k].time - 1e-9);
      for (std::size_t j = 0; j < s.q.size(); ++j) {
        EXPECT_NEAR(b.q[j], tr.waypoints[k].q[j], 1e-15);
        EXPECT_NEAR(b.qd[j], 0.0, 1e-7);
      }
    }
  }
}

TEST(JointTrajectory, QuinticAccelerationVanishesAtWaypointsWhileTheCubicsJumps) {
  // Either side of waypoint k (segment k ends, k+1 begins): the quintic's s'' = 0 at u = 0 and 1;
  // the cubic's s''(1) = -6 and s''(0) = +6, so qdd jumps from -6 d_k/T_k² to +6 d_{k+1}/T_{k+1}².
  const double eps = 1e-10;
  for (TrajectoryShape shape : kShapes) {
    const JointTrajectory tr = three_joint_path(shape);
    for (std::size_t k = 0; k + 1 < tr.waypoints.size(); ++k) {
      const double tk = tr.waypoints[k].time;
      const double Tk = tk - (k == 0 ? 0.0 : tr.waypoints[k - 1].time), Tn = tr.waypoints[k + 1].time - tk;
      const std::vector<double>& qa = k == 0 ? tr.start : tr.waypoints[k - 1].q;
      const State before = eval(tr, tk - eps), at = eval(tr, tk);
      for (std::size_t j = 0; j < tr.start.size(); ++j) {
        const double dk = tr.waypoints[k].q[j] - qa[j], dn = tr.waypoints[k + 1].q[j] - tr.waypoints[k].q[j];
        if (shape == TrajectoryShape::kQuintic) {
          EXPECT_NEAR(before.qdd[j], 0.0, 1e-7) << "waypoint " << k << " joint " << j;
          EXPECT_EQ(at.qdd[j], 0.0) << "waypoint " << k << " joint " << j;
        } else {
          EXPECT_NEAR(before.qdd[j], -6.0 * dk / (Tk * Tk), 1e-8) << "waypoint " << k << " joint " << j;
          EXPECT_NEAR(at.qdd[j], 6.0 * dn / (Tn * Tn), 1e-12) << "waypoint " << k << " joint " << j;
        }
      }
    }
  }
}

TEST(JointTrajectory, VelocityAndAccelerationAreCentralDifferencesOfPositionAtRandomTimes) {
  // (q(t+h) - q(t-h)) / 2h = qd + O(h²), (qd(t+h) - qd(t-h)) / 2h = qdd + O(h²), h = 1e-5 s,
  // at 200 random times inside segments (not within h of a waypoint, where the cubic's qdd jumps).
  test::Rng rng(20260611);
  const double h = 1e-5;
  for (TrajectoryShape shape : kShapes) {
    const JointTrajectory tr = three_joint_path(shape);
    double worst_v = 0.0, worst_a = 0.0;
    for (int n = 0; n < 200;) {
      const double t = rng.uniform(0.0, tr.waypoints.back().time);
      bool near_waypoint = t < 2 * h;
      for (const JointWaypoint& w : tr.waypoints) near_waypoint = near_waypoint || std::abs(t - w.time) < 2 * h;
      if (near_waypoint) continue;
      ++n;
      const State s = eval(tr, t), p = eval(tr, t + h), m = eval(tr, t - h);
      for (std::size_t j = 0; j < s.q.size(); ++j) {
        worst_v = std::max(worst_v, std::abs((p.q[j] - m.q[j]) / (2 * h) - s.qd[j]));
        worst_a = std::max(worst_a, std::abs((p.qd[j] - m.qd[j]) / (2 * h) - s.qdd[j]));
      }
    }
    EXPECT_LT(worst_v, 1e-8) << name(shape);
    EXPECT_LT(worst_a, 1e-7) << name(shape);
    RecordProperty(std::string(name(shape)) + "_worst_velocity_error", test::sci(worst_v));
    RecordProperty(std::string(name(shape)) + "_worst_acceleration_error", test::sci(worst_a));
  }
}

TEST(JointTrajectory, SingleSegmentPeaksAtMidTimeWithTheShapesPeakVelocity) {
  // d = 1.3 rad in T = 2 s: peak 1.5 d/T = 0.975 rad/s (cubic), 1.875 d/T = 1.21875 rad/s (quintic),
  // at t = T/2, halfway (s(1/2) = 1/2) and with zero acceleration there.
  const double d = 1.3, T = 2.0, q0 = -0.2;
  for (TrajectoryShape shape : kShapes) {
    const JointTrajectory tr{shape, {q0}, {{T, {q0 + d}}}};
    const double peak = (shape == TrajectoryShape::kCubic ? 1.5 : 1.875) * d / T;
    const State mid = eval(tr, T / 2);
    EXPECT_NEAR(mid.qd[0], peak, 1e-15) << name(shape);
    EXPECT_NEAR(mid.q[0], q0 + d / 2, 1e-15) << name(shape);
    EXPECT_NEAR(mid.qdd[0], 0.0, 1e-15) << name(shape);
    double highest = 0.0;
    for (int i = 0; i <= 10000; ++i) highest = std::max(highest, eval(tr, T * i / 10000.0).qd[0]);
    EXPECT_NEAR(highest, peak, 1e-15) << name(shape);
  }
}

TEST(JointTrajectory, HoldsTheStartBeforeTimeZeroAndTheLastWaypointAfterTheEnd) {
  for (TrajectoryShape shape : kShapes) {
    const JointTrajectory tr = three_joint_path(shape);
    for (double t : {-1.0, -1e-12}) {
      const State s = eval(tr, t);
      EXPECT_EQ(s.q, tr.start);
      EXPECT_EQ(s.qd, std::vector<double>(3, 0.0));
      EXPECT_EQ(s.qdd, std::vector<double>(3, 0.0));
    }
    for (double t : {3.7, 3.7 + 1e-12, 10.0, 1e300, std::nan("")}) {
      const State s = eval(tr, t);
      EXPECT_EQ(s.q, tr.waypoints.back().q) << t;
      EXPECT_EQ(s.qd, std::vector<double>(3, 0.0)) << t;
      EXPECT_EQ(s.qdd, std::vector<double>(3, 0.0)) << t;
    }
    // The repeated waypoint (2.0 s -> 2.5 s) is a hold: still, at its q, in between.
    const State mid_hold = eval(tr, 2.25);
    EXPECT_EQ(mid_hold.q, tr.waypoints[1].q);
    EXPECT_EQ(mid_hold.qd, std::vector<double>(3, 0.0));
    EXPECT_EQ(mid_hold.qdd, std::vector<double>(3, 0.0));
  }
}

TEST(JointTrajectory, FirstSegmentStartsAtTimeZeroFromStart) {
  // A first waypoint at 4 s: the move takes 4 s from t = 0, halfway at 2 s.
  const JointTrajectory tr{TrajectoryShape::kQuintic, {1.0, 2.0}, {{4.0, {3.0, -2.0}}}};
  const State s = eval(tr, 2.0);
  EXPECT_NEAR(s.q[0], 2.0, 1e-15);
  EXPECT_NEAR(s.q[1], 0.0, 1e-15);
  EXPECT_NEAR(s.qd[0], 1.875 * 2.0 / 4.0, 1e-15);
  EXPECT_NEAR(s.qd[1], -1.875 * 4.0 / 4.0, 1e-15);
}

void expect_rejected(const JointTrajectory& tr, const std::string& words) {
  try {
    check_joint_trajectory(tr);
    ADD_FAILURE() << "accepted; expected an error with \"" << words << "\"";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(JointTrajectory, BadTrajectoriesAreRejectedNamingTheWaypoint) {
  const double inf = std::numeric_limits<double>::infinity();
  JointTrajectory good = three_joint_path(TrajectoryShape::kCubic);
  EXPECT_NO_THROW(check_joint_trajectory(good));

  JointTrajectory tr = good;
  tr.waypoints.clear();
  expect_rejected(tr, "no waypoints");
  tr = good;
  tr.waypoints[2].q.pop_back();
  expect_rejected(tr, "waypoint 2: has 2 joint values, start has 3");
  tr = good;
  tr.waypoints[0].time = 0.0;
  expect_rejected(tr, "waypoint 0: time 0 s is not after the start");
  tr = good;
  tr.waypoints[0].time = -0.5;
  expect_rejected(tr, "waypoint 0: time -0.5 s");
  tr = good;
  tr.waypoints[3].time = 2.5;
  expect_rejected(tr, "waypoint 3: time 2.5 s is not after waypoint 2's 2.5 s");
  tr = good;
  tr.waypoints[1].time = 0.5;
  expect_rejected(tr, "waypoint 1: time 0.5 s is not after waypoint 0's 0.8 s");
  tr = good;
  tr.waypoints[2].time = std::nan("");
  expect_rejected(tr, "waypoint 2: time is not finite");
  tr = good;
  tr.waypoints[1].q[1] = inf;
  expect_rejected(tr, "waypoint 1: has a non-finite joint value");
  tr = good;
  tr.start[0] = std::nan("");
  expect_rejected(tr, "start has a non-finite value");
}

}  // namespace
}  // namespace ff
