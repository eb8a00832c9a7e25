// jobs/batches.cpp: variants of one shape share a batch; a recorded sensor on or off changes the shape
// (the trace columns), its parameters do not.
#include "jobs/batches.hpp"

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

}  // namespace
}  // namespace ff
