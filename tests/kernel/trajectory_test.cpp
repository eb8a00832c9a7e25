// kernel/trajectory.cpp: the cubic move of the seed's planner and the move windows.
#include "kernel/trajectory.hpp"

#include <gtest/gtest.h>

namespace ff {
namespace {

TrajectorySpec seed_moves() {
  TrajectorySpec t;
  t.move_time = 3.0;
  t.moves = {{0.5, 7.0}, {0.0, 20.0}};
  return t;
}

TEST(Trajectory, CubicMatchesReferenceTraceSamples) {
  const auto t = seed_moves();
  EXPECT_NEAR(calc_reference(t, 0.001), 1.666296296e-07, 1e-15);  // first sample of the reference trace
  EXPECT_NEAR(calc_reference(t, 0.002), 6.663703704e-07, 1e-15);
  EXPECT_DOUBLE_EQ(calc_reference(t, 1.5), 0.25);                  // 3u^2 - 2u^3 = 1/2 at u = 1/2
  EXPECT_DOUBLE_EQ(calc_reference(t, 3.0), 0.5);
  EXPECT_DOUBLE_EQ(calc_reference(t, 0.0), 0.0);
}

TEST(Trajectory, CubicStartsAndEndsAtRest) {
  const auto t = seed_moves();
  const double h = 1e-6;
  EXPECT_NEAR((calc_reference(t, h) - calc_reference(t, 0.0)) / h, 0.0, 1e-5);
  EXPECT_NEAR((calc_reference(t, 3.0) - calc_reference(t, 3.0 - h)) / h, 0.0, 1e-5);
  // Peak rate 1.5 A / T_m at mid-move.
  EXPECT_NEAR((calc_reference(t, 1.5 + h) - calc_reference(t, 1.5 - h)) / (2 * h), 1.5 * 0.5 / 3.0, 1e-8);
}

TEST(Trajectory, AccelerationIsTheSecondDerivative) {
  const auto t = seed_moves();
  const double h = 1e-4;
  for (double x : {0.3, 1.5, 2.9, 5.0, 10.5, 12.2}) {
    const double fd = (calc_reference(t, x + h) - 2 * calc_reference(t, x) + calc_reference(t, x - h)) / (h * h);
    EXPECT_NEAR(calc_reference_accel(t, x), fd, 1e-5) << "t = " << x;
  }
  EXPECT_DOUBLE_EQ(calc_reference_accel(t, 0.0), 6.0 * 0.5 / 9.0);  // (6 - 12u) A / T^2 at u = 0
  for (double x : {0.3, 1.5, 2.9, 10.5}) {
    const double fd = (calc_reference(t, x + h) - calc_reference(t, x - h)) / (2 * h);
    EXPECT_NEAR(calc_reference_rate(t, x), fd, 1e-8) << "t = " << x;
  }
}

TEST(Trajectory, MovesChainWithHolds) {
  const auto t = seed_moves();
  EXPECT_DOUBLE_EQ(calc_reference(t, 8.0), 0.5);                 // holding
  EXPECT_DOUBLE_EQ(calc_reference(t, 10.0), 0.5);                // second move starts at 3 + 7
  EXPECT_DOUBLE_EQ(calc_reference(t, 11.5), 0.25);               // half-way back
  EXPECT_DOUBLE_EQ(calc_reference(t, 13.0), 0.0);
  EXPECT_DOUBLE_EQ(calc_reference(t, 100.0), 0.0);
}

TEST(Trajectory, MoveWindowsEndAtTheNextMoveOrTheRecord) {
  const auto moves = calc_moves(seed_moves(), 33.0);
  ASSERT_EQ(moves.size(), 2u);
  EXPECT_DOUBLE_EQ(moves[0].t_start, 0.0);
  EXPECT_DOUBLE_EQ(moves[0].window.t_move_end, 3.0);
  EXPECT_DOUBLE_EQ(moves[0].window.t_window_end, 10.0);
  EXPECT_DOUBLE_EQ(moves[0].window.start, 0.0);
  EXPECT_DOUBLE_EQ(moves[0].window.target, 0.5);
  EXPECT_DOUBLE_EQ(moves[1].t_start, 10.0);
  EXPECT_DOUBLE_EQ(moves[1].window.t_window_end, 33.0);
  EXPECT_DOUBLE_EQ(moves[1].window.start, 0.5);
  // A record cut short ends the last window early.
  EXPECT_DOUBLE_EQ(calc_moves(seed_moves(), 12.0).back().window.t_window_end, 12.0);
  EXPECT_EQ(describe_moves(seed_moves()), (std::vector<std::string>{"0 -> 0.5 rad", "0.5 -> 0 rad"}));
}

}  // namespace
}  // namespace ff
