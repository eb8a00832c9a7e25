// A payload picked or released during a run (payload.events): the tip body it changes is run state
// (BatchState::tip), read by the dynamics as their input; the batch model stays as made.
#include <gtest/gtest.h>

#include <span>
#include <vector>

#include "kernel/batch.hpp"
#include "kernel/model.hpp"
#include "kernel/simulate.hpp"
#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

constexpr double kPickTime = 1.5;  // s, in the middle of the 3 s move: the arm is moving and bent
constexpr long kPickSample = 1500;

// The rig (a 0.5 rad move over 3 s, then 2 s) with an empty tip, at one step per sample whatever the
// payload (the automatic step follows the modes) and the given integrator.
ModelSpec empty_rig(Integrator integrator) {
  ModelSpec spec = test::rig_spec(0.5, 2.0);
  spec.simulation.integrator = integrator;
  spec.simulation.substeps = 1;
  spec.payload_mass = spec.payload_inertia = 0.0;
  return spec;
}

PayloadEvent rig_payload() {
  const ModelSpec nominal;
  return {kPickTime, nominal.payload_mass, nominal.payload_inertia};
}

BatchRun run_batch(std::span<const Model> models, const SampleInputs* in = nullptr) {
  return simulate(make_batch(models), nullptr, in);
}

void expect_same_from(const Trace& a, const Trace& b, std::size_t k0, const char* what) {
  ASSERT_EQ(a.t.size(), b.t.size());
  for (std::size_t k = k0; k < a.t.size(); ++k) {
    ASSERT_EQ(a.tip_deflection[k], b.tip_deflection[k]) << what << ", sample " << k;
    ASSERT_EQ(a.hub_angle[k], b.hub_angle[k]) << what << ", sample " << k;
    ASSERT_EQ(a.torque[k], b.torque[k]) << what << ", sample " << k;
  }
}

// Picking the 328.7 kg payload mid-move: from the pick on, the hub's closed loop responds exactly as
// the arm built with that payload from the start does from the same state (bit for bit, under every
// fixed-step integrator), and not as the empty arm.
TEST(PickedPayload, RespondsFromThePickAsTheArmLoadedFromTheStartFromTheSameState) {
  for (const Integrator integ : {Integrator::kRk4, Integrator::kSdirk2, Integrator::kMidpoint}) {
    ModelSpec picking = empty_rig(integ);
    picking.payload_events = {rig_payload()};
    ModelSpec loaded = empty_rig(integ);
    loaded.payload_mass = rig_payload().mass;
    loaded.payload_inertia = rig_payload().inertia;
    const Model mp = make_model(picking), ml = make_model(loaded), me = make_model(empty_rig(integ));

    BatchState at_pick;
    SampleInputs save;
    save.at_sample = [&](BatchState& s) {
      if (s.sample == kPickSample) at_pick = s;
    };
    const Trace picked = run_batch(std::span<const Model>(&mp, 1), &save).traces[0];
    EXPECT_EQ(at_pick.tip.mass[0], ml.body.back().mass);  // the state carries the picked tip body
    EXPECT_EQ(at_pick.tip.inertia[0], ml.body.back().inertia);

    SampleInputs restore;
    restore.at_sample = [&](BatchState& s) {
      if (s.sample == kPickSample) s = at_pick;
    };
    const Trace loaded_from_pick = run_batch(std::span<const Model>(&ml, 1), &restore).traces[0];
    const Trace empty = run_batch(std::span<const Model>(&me, 1)).traces[0];
    expect_same_from(picked, loaded_from_pick, kPickSample, "loaded arm from the picked state");
    EXPECT_EQ(picked.tip_deflection[kPickSample - 1], empty.tip_deflection[kPickSample - 1]);  // empty before
    EXPECT_GT(test::max_abs_diff(picked.tip_deflection, empty.tip_deflection), 0.01);  // m: the pick matters
  }
}

// The payload the arm holds is state: a checkpoint taken after the pick resumes on the empty arm's own
// model (no payload, no events) as the picking run goes on, and a copied lane carries its payload.
TEST(PickedPayload, IsStateACheckpointAndACopiedLaneCarryIt) {
  ModelSpec bare = empty_rig(Integrator::kSdirk2);
  ModelSpec picking = bare;
  picking.payload_events = {rig_payload()};
  const Model mp = make_model(picking), mb = make_model(bare);
  constexpr long kCheckpoint = 2500;

  BatchState checkpoint;
  SampleInputs save;
  save.at_sample = [&](BatchState& s) {
    if (s.sample == kCheckpoint) checkpoint = s;
  };
  const Trace picked = run_batch(std::span<const Model>(&mp, 1), &save).traces[0];
  SampleInputs resume;
  resume.at_sample = [&](BatchState& s) {
    if (s.sample == kCheckpoint) s = checkpoint;
  };
  const Trace resumed = run_batch(std::span<const Model>(&mb, 1), &resume).traces[0];
  expect_same_from(picked, resumed, kCheckpoint, "resumed from the checkpoint");

  // Lane 0 picks, lane 1 does not; lane 0 copied onto lane 1 after the pick: lane 1 goes on as lane 0.
  const std::vector<Model> lanes = {mp, mb};
  const BatchModel bm = make_batch(lanes);
  SampleInputs copy;
  copy.at_sample = [&](BatchState& s) {
    if (s.sample == kCheckpoint) copy_lane(bm, s, 0, 1);
  };
  const BatchRun run = simulate(bm, nullptr, &copy);
  expect_same_from(run.traces[0], picked, 0, "lane 0 beside a lane without events");
  expect_same_from(run.traces[1], picked, kCheckpoint, "lane 1 after the copy");
}

// A run with payload events leaves its batch model as made: every body table, row by row.
TEST(PickedPayload, LeavesTheBatchModelAsMade) {
  ModelSpec picking = empty_rig(Integrator::kRk4);
  picking.payload_events = {rig_payload(), {3.0, 0.0, 0.0}};
  const std::vector<Model> lanes = {make_model(picking), make_model(empty_rig(Integrator::kRk4))};
  const BatchModel bm = make_batch(lanes);
  const BatchModel before = bm;
  simulate(bm);
  EXPECT_EQ(bm.body_mass, before.body_mass);
  EXPECT_EQ(bm.body_first, before.body_first);
  EXPECT_EQ(bm.body_inertia, before.body_inertia);
  const BatchState fresh = make_state(bm);  // and a new run starts from the model's tip again
  EXPECT_EQ(fresh.tip.mass, std::vector<double>(bm.body_mass.end() - bm.W, bm.body_mass.end()));
  EXPECT_EQ(fresh.tip.inertia, std::vector<double>(bm.body_inertia.end() - bm.W, bm.body_inertia.end()));
}

}  // namespace
}  // namespace ff
