// Replaying records on models (validate/replay.cpp): a model replayed on its own output is exact; the
// k-step prediction (from the observer's estimate, validate/observer.hpp) runs candidates as lanes.
#include <gtest/gtest.h>

#include <cmath>

#include "kernel/simulate.hpp"
#include "validate/replay.hpp"
#include "validate/synthetic.hpp"

namespace ff {
namespace {

ModelSpec rig(double payload = 328.7) {
  ModelSpec s;
  s.trajectory.moves = {{0.5, 4.0}};
  s.payload_mass = payload;
  return s;
}

// The model's own closed-loop run as a measurement record.
Record record_of(const Model& m) { return make_synthetic_record(m, 0.0, 1); }  // noise-free

TEST(Replay, ClosedLoopReplayOfTheModelsOwnRunIsExact) {
  const Model m = make_model(rig());
  const Record r = record_of(m);
  const auto p = replay(std::span<const Model>(&m, 1), r, ReplayMode::kClosedLoop);
  ASSERT_TRUE(p[0].ok);
  for (const auto& c : scored_channels(ReplayMode::kClosedLoop, r))
    EXPECT_GT(calc_fit(r.at(c), p[0].channels.at(c)).percent, 99.999) << c;
}

TEST(Replay, AClosedLoopReplayKeepsTheControllersModel) {
  // A rig carrying 400 kg whose notch sits at the nominal 328.7 kg rig's resonances (make_model's
  // `controller`, as a plant-only payload builds it) replays its own run exactly: the replay model keeps
  // that notch, not one at the 400 kg rig's resonances (which fits the record worse).
  ModelSpec nominal_spec = rig();
  nominal_spec.notch.enabled = true;
  const Model nominal = make_model(nominal_spec);
  ModelSpec heavy = nominal_spec;
  heavy.payload_mass = 400.0;
  const Model plant = make_model(heavy, "<plant>", &nominal);
  const Record r = record_of(plant);
  const Model replayed = make_replay_model(plant, r);
  EXPECT_EQ(replayed.omega_z[0], nominal.resonances[0]);
  EXPECT_EQ(replayed.omega_z[1], nominal.resonances[1]);
  EXPECT_EQ(replayed.control_inertia, nominal.rigid_inertia);
  const auto p = replay(std::span<const Model>(&plant, 1), r, ReplayMode::kClosedLoop);
  ASSERT_TRUE(p[0].ok);
  for (const auto& c : scored_channels(ReplayMode::kClosedLoop, r))
    EXPECT_GT(calc_fit(r.at(c), p[0].channels.at(c)).percent, 99.999) << c;
  const Model knows = make_model(heavy);  // the controller told the payload: another notch
  EXPECT_GT(std::abs(knows.omega_z[0] - nominal.omega_z[0]), 0.05 * nominal.omega_z[0]);
  const auto q = replay(std::span<const Model>(&knows, 1), r, ReplayMode::kClosedLoop);
  EXPECT_LT(calc_fit(r.at("hub_torque"), q[0].channels.at("hub_torque")).percent, 99.0);
}

TEST(Replay, OpenLoopReplayOfItsTorqueReproducesTheMotion) {
  const Model m = make_model(rig());
  const Record r = record_of(m);
  const auto p = replay(std::span<const Model>(&m, 1), r, ReplayMode::kOpenLoop);
  EXPECT_GT(calc_fit(r.at("hub_angle"), p[0].channels.at("hub_angle")).percent, 99.99);
  EXPECT_GT(calc_fit(r.at("tip_deflection"), p[0].channels.at("tip_deflection")).percent, 99.9);
}

TEST(Replay, InverseDynamicsRecoversTheTorqueThatMovedTheArm) {
  const Model m = make_model(rig());
  const Record r = record_of(m);
  const auto p = replay(std::span<const Model>(&m, 1), r, ReplayMode::kInverseDynamics);
  ASSERT_TRUE(p[0].ok);
  // Zero-order-hold torque against the smooth inverse dynamics of the sampled motion: within 2 %.
  EXPECT_GT(calc_fit(r.at("hub_torque"), p[0].channels.at("hub_torque")).percent, 98.0);
}

TEST(Replay, KStepPredictionOfAWrongModelFitsBetterThanItsFreeRun) {
  const Model truth = make_model(rig(450.0)), wrong = make_model(rig(250.0));
  const Record r = record_of(truth);
  const double free_run = calc_fit(r.at("hub_angle"), replay(std::span<const Model>(&wrong, 1), r, ReplayMode::kClosedLoop)[0].channels.at("hub_angle")).percent;
  const double ahead = calc_fit(r.at("hub_angle"), replay(std::span<const Model>(&wrong, 1), r, ReplayMode::kClosedLoop, 10)[0].channels.at("hub_angle")).percent;
  EXPECT_LT(free_run, 99.0);
  EXPECT_GT(ahead, free_run);
}

TEST(Replay, CandidatesRunAsLanesGiveTheSameAsAlone) {
  const Model a = make_model(rig(300.0)), b = make_model(rig(350.0));
  const Record r = record_of(make_model(rig()));
  const std::vector<Model> both = {a, b};
  const auto together = replay(both, r, ReplayMode::kClosedLoop);
  const auto alone = replay(std::span<const Model>(&b, 1), r, ReplayMode::kClosedLoop);
  EXPECT_EQ(together[1].channels.at("tip_deflection"), alone[0].channels.at("tip_deflection"));
}

TEST(Replay, KStepCandidatesRunAsLanesGiveTheSameAsAlone) {
  // Each candidate has its own observer (its own linearisation and gain) in the one batch.
  const Model a = make_model(rig(300.0)), b = make_model(rig(350.0));
  const Record r = make_synthetic_record(make_model(rig()), 0.01, 2);
  const std::vector<Model> both = {a, b};
  const auto together = replay(both, r, ReplayMode::kClosedLoop, 10);
  const auto alone = replay(std::span<const Model>(&b, 1), r, ReplayMode::kClosedLoop, 10);
  ASSERT_TRUE(together[1].ok);
  EXPECT_EQ(together[1].channels.at("tip_deflection"), alone[0].channels.at("tip_deflection"));
  EXPECT_NE(together[0].channels.at("tip_deflection"), alone[0].channels.at("tip_deflection"));
}

TEST(Fit, PerfectIsHundredAndTheMeanIsZero) {
  const std::vector<double> y = {1, 2, 3, 4};
  EXPECT_DOUBLE_EQ(calc_fit(y, y).percent, 100.0);
  EXPECT_NEAR(calc_fit(y, {2.5, 2.5, 2.5, 2.5}).percent, 0.0, 1e-12);
  EXPECT_NEAR(calc_fit(y, {1, 2, 3, 5}).rmse, 0.5, 1e-12);
}

}  // namespace
}  // namespace ff
