// kernel/simulate.cpp with kernel/fixed_step.cpp and kernel/cvode.cpp: the closed loop against an
// independent implementation, the two integrators against each other, lanes, failures.
#include "kernel/simulate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "common/errors.hpp"
#include "common/isa.hpp"
#include "kernel/model_io.hpp"
#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

using test::max_abs_diff;

// The reference trace: N = 6, PD, cubic 0 -> 0.5 rad, 20 s, classical RK4 at 0.1 ms in absolute angles.
class ReferenceTraceTest : public ::testing::TestWithParam<Integrator> {};

TEST_P(ReferenceTraceTest, MatchesIndependentImplementationWellUnderAMillimetre) {
  const auto ref = test::load_reference_trace();
  ModelSpec spec = test::rig_spec(0.5, 17.0);
  spec.simulation.integrator = GetParam();
  // Tip deflection is 290 mm RMS. Measured: RK4 at 1 ms 0.012 um, CVODE ~0.2 um, SDIRK2 at 1 ms 23 um,
  // midpoint at 1 ms 47 um.
  const double bound = GetParam() == Integrator::kSdirk2 ? 5e-5 : GetParam() == Integrator::kMidpoint ? 1e-4 : 1e-6;
  spec.simulation.duration = 19.999;
  const auto run = test::run_one(make_model(spec));
  const Trace& tr = run.traces[0];
  ASSERT_EQ(tr.t.size(), ref.t.size());
  // Same sample instants, same reference, same torque law.
  EXPECT_LT(max_abs_diff(tr.t, ref.t), 1e-9);
  EXPECT_LT(max_abs_diff(tr.ref, ref.ref), 1e-10);  // the file keeps 10 significant digits
  EXPECT_LT(max_abs_diff(tr.tip_deflection, ref.tip_deflection), bound);
  EXPECT_LT(max_abs_diff(tr.hub_angle, ref.hub_angle), 0.1 * bound);
  EXPECT_LT(max_abs_diff(tr.torque, ref.hub_torque), 1e4 * bound);
}

INSTANTIATE_TEST_SUITE_P(Integrators, ReferenceTraceTest,
                         ::testing::Values(Integrator::kRk4, Integrator::kSdirk2, Integrator::kCvodeDense,
                                           Integrator::kCvodeKlu, Integrator::kMidpoint),
                         [](const auto& info) { return std::string(integrator_name(info.param)); });

// RK4 (batch kernel) against CVODE BDF (reference) on the seed's move at N = 6 and N = 24.
class IntegratorAgreementTest : public ::testing::TestWithParam<std::pair<int, double>> {};

TEST_P(IntegratorAgreementTest, CvodeAgreesWithFixedStep) {
  const auto [n, bound] = GetParam();
  ModelSpec spec = test::rig_spec(0.5, 5.0);
  spec.segments = n;
  const auto rk4 = test::run_one(make_model(spec));
  spec.simulation.integrator = Integrator::kCvodeKlu;
  const auto bdf = test::run_one(make_model(spec));
  ASSERT_EQ(rk4.status[0], LaneStatus::kOk);
  ASSERT_EQ(bdf.status[0], LaneStatus::kOk);
  EXPECT_LT(max_abs_diff(rk4.traces[0].tip_deflection, bdf.traces[0].tip_deflection), bound);
  EXPECT_LT(max_abs_diff(rk4.traces[0].hub_angle, bdf.traces[0].hub_angle), bound);
}

// Bounds, m: RK4 at the automatic step against CVODE at rtol 1e-8.
INSTANTIATE_TEST_SUITE_P(Segments, IntegratorAgreementTest,
                         ::testing::Values(std::make_pair(6, 1e-6), std::make_pair(24, 1e-6)),
                         [](const auto& info) { return "N" + std::to_string(info.param.first); });

// SDIRK2 (the batch kernel's stiff-safe integrator, one step per 1 ms sample) against CVODE at large N,
// where RK4 would need hundreds of substeps. Bound: 0.1 mm of tip deflection (peak ~670 mm).
class StiffAgreementTest : public ::testing::TestWithParam<int> {};

TEST_P(StiffAgreementTest, Sdirk2AgreesWithCvodeAtOneStepPerSample) {
  ModelSpec spec = test::rig_spec(0.5, 0.5);  // the move and half a second of ringing: CVODE is slow at N = 48
  spec.segments = GetParam();
  spec.simulation.integrator = Integrator::kSdirk2;
  const Model fast = make_model(spec);
  EXPECT_EQ(fast.substeps, 1);
  const auto sd = test::run_one(fast);
  spec.simulation.integrator = Integrator::kCvodeKlu;
  const auto bdf = test::run_one(make_model(spec));
  ASSERT_EQ(sd.status[0], LaneStatus::kOk);
  ASSERT_EQ(bdf.status[0], LaneStatus::kOk);
  EXPECT_LT(max_abs_diff(sd.traces[0].tip_deflection, bdf.traces[0].tip_deflection), 1e-4);
}

INSTANTIATE_TEST_SUITE_P(Segments, StiffAgreementTest, ::testing::Values(24, 48),
                         [](const auto& info) { return "N" + std::to_string(info.param); });

class LaneTest : public ::testing::TestWithParam<Integrator> {};

TEST_P(LaneTest, BatchLanesMatchSingleRunsBitForBit) {
  std::vector<Model> models;
  for (double payload : {200.0, 328.7, 450.0, 260.0, 390.0}) {
    ModelSpec spec = test::rig_spec(0.5, 2.0);
    spec.payload_mass = payload;
    spec.simulation.integrator = GetParam();
    spec.simulation.substeps = 2;
    spec.notch.enabled = true;
    models.push_back(make_model(spec));
  }
  const auto batch = simulate(make_batch(models));
  for (int l = 0; l < 5; ++l) {
    const auto one = test::run_one(models[l]);
    EXPECT_EQ(batch.traces[l].tip_deflection, one.traces[0].tip_deflection) << "lane " << l;
    EXPECT_EQ(batch.traces[l].torque, one.traces[0].torque) << "lane " << l;
  }
}

INSTANTIATE_TEST_SUITE_P(FixedStep, LaneTest,
                         ::testing::Values(Integrator::kRk4, Integrator::kSdirk2, Integrator::kMidpoint),
                         [](const auto& info) { return std::string(integrator_name(info.param)); });

TEST(Simulate, BatchLanesMatchSingleRunsBitForBit) {
  std::vector<Model> models;
  for (double payload : {200.0, 328.7, 450.0}) {
    ModelSpec spec = test::rig_spec(0.5, 2.0);
    spec.payload_mass = payload;
    spec.simulation.substeps = 2;
    models.push_back(make_model(spec));
  }
  const auto batch = simulate(make_batch(models));
  for (int l = 0; l < 3; ++l) {
    const auto one = test::run_one(models[l]);
    EXPECT_EQ(batch.traces[l].tip_deflection, one.traces[0].tip_deflection) << "lane " << l;
    EXPECT_EQ(batch.traces[l].torque, one.traces[0].torque) << "lane " << l;
  }
}

TEST(Simulate, DivergingLaneIsRecordedAndOthersFinish) {
  ModelSpec good = test::rig_spec(0.5, 2.0);
  good.simulation.substeps = 1;
  ModelSpec bad = good;
  bad.controller.kp = 1e12;  // far beyond what 1 kHz sampling can stabilise
  std::vector<Model> models{make_model(good), make_model(bad)};
  const auto run = simulate(make_batch(models));
  EXPECT_EQ(run.status[0], LaneStatus::kOk);
  EXPECT_EQ(run.status[1], LaneStatus::kNonfinite);
  EXPECT_TRUE(std::isfinite(run.traces[0].tip_deflection.back()));
}

TEST(Simulate, SampleHookChangesTheStateAndACopiedLaneContinuesAsItsSource) {
  // Two lanes of one model: the hook bends lane 1's beam at sample 300 and copies lane 0 into it at
  // sample 1000. Before 300 and from 1000 on the lanes are bit for bit the same (RK4 carries nothing
  // between samples outside the state); in between they differ.
  ModelSpec spec = test::rig_spec(0.5, 2.0);
  spec.simulation.substeps = 2;
  const std::vector<Model> models(2, make_model(spec));
  const BatchModel bm = make_batch(models);
  SampleInputs in;
  std::vector<long> seen;
  in.at_sample = [&](BatchState& s) {
    seen.push_back(s.sample);
    if (s.sample == 300) s.q[1 * bm.W + 1] += 0.01;  // joint 1 of lane 1, rad
    if (s.sample == 1000) copy_lane(bm, s, 0, 1);
  };
  const auto run = simulate(bm, nullptr, &in);
  const auto& a = run.traces[0].tip_deflection;
  const auto& b = run.traces[1].tip_deflection;
  ASSERT_EQ(seen.size(), a.size());
  EXPECT_EQ(seen[0], 0);
  EXPECT_EQ(seen.back(), static_cast<long>(a.size()) - 1);
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (k < 300 || k >= 1000) {
      EXPECT_EQ(a[k], b[k]) << "sample " << k;
    }
  }
  EXPECT_GT(std::abs(a[300] - b[300]), 0.005);  // m: the bend shows at the sample it is made
  EXPECT_EQ(run.traces[0].torque[1500], run.traces[1].torque[1500]);
}

// The midpoint rule and SDIRK2 carry a velocity predictor (the last step's accelerations) from step to
// step: it is state (BatchState::a_prev), so a copied lane continues bit for bit under them too.
TEST(Simulate, ACopiedLaneContinuesBitForBitUnderTheImplicitIntegrators) {
  for (const Integrator integ : {Integrator::kMidpoint, Integrator::kSdirk2}) {
    ModelSpec spec = test::rig_spec(0.5, 2.0);
    spec.simulation.integrator = integ;
    const std::vector<Model> models(2, make_model(spec));
    const BatchModel bm = make_batch(models);
    SampleInputs in;
    in.at_sample = [&](BatchState& s) {
      if (s.sample == 300) s.q[1 * bm.W + 1] += 0.01;
      if (s.sample == 1000) copy_lane(bm, s, 0, 1);
    };
    const auto run = simulate(bm, nullptr, &in);
    const auto& a = run.traces[0].tip_deflection;
    const auto& b = run.traces[1].tip_deflection;
    EXPECT_GT(std::abs(a[999] - b[999]), 1e-4) << "the lanes differ before the copy";
    for (std::size_t k = 1000; k < a.size(); ++k) ASSERT_EQ(a[k], b[k]) << "sample " << k;
  }
}

}  // namespace
}  // namespace ff

namespace ff {
namespace {

TEST(PayloadEvents, ReleaseAtTheStartIsTheEmptyArm) {
  ModelSpec spec = test::rig_spec(0.5, 2.0);
  spec.payload_events = {{0.0, 0.0, 0.0}};
  const auto released = test::run_one(make_model(spec));
  spec.payload_events.clear();
  spec.payload_mass = spec.payload_inertia = 0.0;
  const auto empty = test::run_one(make_model(spec));
  EXPECT_EQ(released.traces[0].tip_deflection, empty.traces[0].tip_deflection);
}

TEST(PayloadEvents, NothingChangesBeforeTheEventAndTheArmRespondsAfter) {
  ModelSpec spec = test::rig_spec(0.5, 4.0);
  const auto carried = test::run_one(make_model(spec)).traces[0];
  spec.payload_events = {{2.0, 0.0, 0.0}};  // drop the payload mid-move
  const auto dropped = test::run_one(make_model(spec)).traces[0];
  std::size_t k = 0;
  for (; dropped.t[k] < 2.0 - 1e-9; ++k) ASSERT_EQ(dropped.tip_deflection[k], carried.tip_deflection[k]) << k;
  EXPECT_EQ(dropped.tip_deflection[k], carried.tip_deflection[k]);  // state continuous at the event
  // Without its 328.7 kg the arm lags far less: the peak deflection after the drop is much smaller.
  double peak_c = 0, peak_d = 0;
  for (std::size_t j = k + 500; j < carried.t.size(); ++j) {
    peak_c = std::max(peak_c, std::fabs(carried.tip_deflection[j]));
    peak_d = std::max(peak_d, std::fabs(dropped.tip_deflection[j]));
  }
  EXPECT_LT(peak_d, 0.5 * peak_c);
}

TEST(PayloadEvents, PickAtRestGivesTheRigidArmTheHeavierInertia) {
  // A rigid arm (N = 1) in open loop: +tau for 0.5 s, -tau for 0.5 s brings the empty arm to rest at
  // theta_1 = tau 0.25 s^2 / J_empty; the payload is picked there at t = 1 s, then +tau turns the loaded
  // arm: theta = theta_1 + tau (t - 1)^2 / (2 J_loaded), J = the straight arm's inertia about the hub.
  ModelSpec spec = test::rig_spec(0.5, 2.0);
  spec.segments = 1;
  spec.simulation.duration = 2.0;
  spec.payload_mass = spec.payload_inertia = 0.0;
  const double J_empty = make_model(spec).rigid_inertia;
  const PayloadEvent pick{1.0, 328.7, 118.6};
  ModelSpec loaded = spec;
  loaded.payload_mass = pick.mass;
  loaded.payload_inertia = pick.inertia;
  const double J_loaded = make_model(loaded).rigid_inertia;
  spec.payload_events = {pick};
  const Model m = make_model(spec);
  const double tau = 1000.0;  // N m
  SampleInputs in;
  for (int k = 0; k <= 2000; ++k) in.torque.push_back(k < 500 ? tau : k < 1000 ? -tau : tau);
  const Trace tr = simulate(make_batch(std::span<const Model>(&m, 1)), nullptr, &in).traces[0];
  EXPECT_LT(std::abs(tr.hub_rate[1000]), 1e-12);  // rad/s: at rest when it picks
  EXPECT_NEAR(tr.hub_angle[1000], tau * 0.25 / J_empty, 1e-12);
  for (int k = 1000; k <= 2000; k += 100) {
    const double t = tr.t[k] - 1.0;
    EXPECT_NEAR(tr.hub_angle[k], tr.hub_angle[1000] + tau * t * t / (2.0 * J_loaded), 1e-11) << "t " << tr.t[k];
  }
  EXPECT_GT(J_loaded, 5.0 * J_empty);  // the pick is no detail: the empty arm would turn 5x as far
}

TEST(PayloadEvents, PickAtRestIsTheLoadedArmFromThenOn) {
  // The flexible arm in closed loop, reference held at 0 for 1 s (the arm at rest) and then a cubic move
  // to 0.5 rad: picking the payload at 0.5 s gives bit for bit the run of the arm loaded from the start,
  // and differs from the empty arm's.
  ModelSpec spec = test::rig_spec(0.5, 2.0);
  spec.simulation.duration = 6.0;
  spec.simulation.substeps = 1;  // the same step for both payloads (the automatic one follows the modes)
  SampleInputs in;
  for (int k = 0; k <= 6000; ++k) {
    const double u = std::clamp((k * 1e-3 - 1.0) / 3.0, 0.0, 1.0);
    in.ref.push_back(0.5 * u * u * (3.0 - 2.0 * u));
  }
  auto run = [&](const ModelSpec& s) {
    const Model m = make_model(s);
    return simulate(make_batch(std::span<const Model>(&m, 1)), nullptr, &in).traces[0];
  };
  const auto loaded = run(spec);
  spec.payload_events = {{0.5, spec.payload_mass, spec.payload_inertia}};
  spec.payload_mass = spec.payload_inertia = 0.0;
  const auto picked = run(spec);
  spec.payload_events.clear();
  const auto empty = run(spec);
  EXPECT_EQ(picked.tip_deflection, loaded.tip_deflection);
  EXPECT_EQ(picked.torque, loaded.torque);
  EXPECT_GT(max_abs_diff(empty.tip_deflection, loaded.tip_deflection), 0.05);  // m
}

TEST(PayloadEvents, NeedAFixedStepIntegrator) {
  ModelSpec spec = test::rig_spec();
  spec.payload_events = {{1.0, 0.0, 0.0}};
  spec.simulation.integrator = Integrator::kCvodeDense;
  EXPECT_THROW(make_model(spec), ConfigError);
}

// Whether two signals hold the same doubles, bit for bit (NaN included).
bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// The rig's kernels are compiled for SSE2, AVX2 and AVX-512 (common/isa.hpp); each width the CPU runs
// steps random variants (payload, stiffness, friction, move; a notch, a hydraulic or a compliant drive) to the
// same bits as SSE2, under every fixed-step integrator, at N = 6 and 24, with W = 5 lanes (a partial
// vector at every width).
TEST(VectorWidths, EveryWidthTheCpuRunsStepsTheRigToTheSameBits) {
  if (available_isa() == Isa::sse2) GTEST_SKIP() << "this CPU or build runs SSE2 only";
  const Isa was = active_isa();
  std::mt19937_64 rng(20261204);
  auto uniform = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  int batches = 0, finished = 0;
  for (Integrator integ : {Integrator::kRk4, Integrator::kSdirk2, Integrator::kMidpoint})
    for (int n : {6, 24})
      for (int drive = 0; drive < 3; ++drive) {
        if (integ == Integrator::kRk4 && n == 24) continue;  // RK4 would take hundreds of substeps
        std::vector<ModelSpec> specs;
        for (int l = 0; l < 5; ++l) {
          ModelSpec spec = test::rig_spec(uniform(-0.8, 0.8), 0.3);
          spec.segments = n;
          spec.simulation.integrator = integ;
          spec.payload_mass = uniform(0.0, 600.0);
          spec.joints.stiffness *= uniform(0.5, 2.0);
          spec.friction.viscous = uniform(0.0, 50.0);
          spec.friction.coulomb = uniform(0.0, 40.0);
          spec.notch.enabled = drive != 1;
          spec.hydraulics.enabled = drive == 1;
          spec.drive.enabled = drive == 2;
          spec.drive.backlash = drive == 2 ? uniform(0.0, 2e-3) : 0.0;
          specs.push_back(spec);
        }
        // One shape for the batch: every lane at the most substeps any of them asks for.
        int substeps = 1;
        for (const ModelSpec& spec : specs) substeps = std::max(substeps, make_model(spec).substeps);
        std::vector<Model> models;
        for (ModelSpec& spec : specs) {
          spec.simulation.substeps = substeps;
          models.push_back(make_model(spec));
        }
        const BatchModel bm = make_batch(models);
        select_isa(Isa::sse2);
        const BatchRun base = simulate(bm);
        for (Isa isa : {Isa::avx2, Isa::avx512}) {
          if (select_isa(isa) != isa) continue;
          const BatchRun wide = simulate(bm);
          for (int l = 0; l < 5; ++l) {
            const std::string at = std::string(isa_name(isa)) + " " + integrator_name(integ) + " N = " +
                                   std::to_string(n) + " drive " + std::to_string(drive) + " lane " + std::to_string(l);
            ASSERT_EQ(wide.status[l], base.status[l]) << at;
            if (base.status[l] == LaneStatus::kOk) ++finished;
            for (auto signal : {&Trace::tip_deflection, &Trace::tip_angle, &Trace::hub_rate, &Trace::torque})
              EXPECT_TRUE(same_bits(wide.traces[l].*signal, base.traces[l].*signal)) << at;
          }
        }
        ++batches;
      }
  select_isa(was);
  EXPECT_EQ(batches, 15);
  RecordProperty("lanes_finished", finished);
}

}  // namespace
}  // namespace ff
