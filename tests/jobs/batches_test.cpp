// jobs/batches.cpp: variants of one shape share a batch; a recorded sensor on or off changes the shape
// (the trace columns), its parameters do not.
#include "jobs/batches.hpp"

#include "kernel/batch.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace ff {
namespace {

Model rig(bool tip_position, int delay) {
  ModelSpec s;
  s.trajectory.moves = {{0.5, 1.0}};
  s.sensors.tip_position.enabled = tip_position;
  s.sensors.tip_position.delay = delay;
  return make_model(s);
}

TEST(Batches, RecordedSensorsOnOrOffSplitTheBatches) {
  const std::vector<Model> models = {rig(false, 0), rig(true, 0), rig(false, 5), rig(true, 9)};
  const auto batches = make_batches(models, {0, 1, 2, 3}, 8);
  ASSERT_EQ(batches.size(), 2u);
  EXPECT_EQ(batches[0].variants, (std::vector<int>{0, 2}));
  EXPECT_EQ(batches[1].variants, (std::vector<int>{1, 3}));
}

// The runner's grouping and the kernel's check are one definition (kernel/batch.hpp, BatchShape): every
// batch make_batches forms, make_batch accepts, and variants that differ in the integrator, the drive's
// parts or the notch are never put in one.
TEST(Batches, EveryBatchFormedIsOneTheKernelAccepts) {
  std::vector<Model> models;
  for (int k = 0; k < 8; ++k) {
    ModelSpec s;
    s.trajectory.moves = {{0.5, 1.0}};
    s.simulation.integrator = k % 2 ? Integrator::kMidpoint : Integrator::kRk4;
    s.drive.enabled = k % 4 >= 2;
    s.notch.enabled = k >= 4;
    models.push_back(make_model(s));
  }
  const auto batches = make_batches(models, {0, 1, 2, 3, 4, 5, 6, 7}, 8);
  EXPECT_EQ(batches.size(), 8u);
  for (const auto& b : batches) {
    std::vector<Model> lanes;
    for (int i : b.variants) lanes.push_back(models[i]);
    lanes.push_back(models[b.variants[0]]);  // two lanes of the same shape
    EXPECT_NO_THROW(make_batch(lanes));
  }
  const Model mixed[2] = {models[0], models[1]};  // RK4 beside the midpoint rule
  EXPECT_THROW(make_batch(std::span<const Model>(mixed, 2)), std::invalid_argument);
}

}  // namespace
}  // namespace ff
