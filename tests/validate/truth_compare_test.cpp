// flexfarm on records of the independent truth simulator (tests/validate/truth/): with no hidden effect
// configs/fbtb.yaml explains a truth record, and with one the flexfarm model built by the mapping of
// tests/validate/truth/README.md explains it (exactly where both use the same law, to the
// regularisations' difference where they do not), while the base model does not.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "kernel/model_io.hpp"
#include "tests/validate/truth/truth_sim.hpp"
#include "validate/compare.hpp"
#include "validate/replay.hpp"

namespace ff {
namespace {

const std::string kModel = FLEXFARM_SOURCE_DIR "/configs/fbtb.yaml";

// 0 -> 0.5 rad in 3 s, held 2 s.
truth::TruthRig short_rig() {
  truth::TruthRig r;
  r.trajectory.moves = {{0.5, 2.0}};
  return r;
}

double fit(const CompareResult& c, const std::string& channel) {
  for (const auto& ch : c.channels)
    if (ch.name == channel) return ch.fit_free.percent;
  ADD_FAILURE() << "no channel " << channel;
  return NAN;
}

const char* const kChannels[] = {"hub_angle", "tip_deflection", "hub_torque"};

TEST(TruthCompare, TheRigsModelExplainsANoisyRecordWithNothingHidden) {
  truth::TruthRig r = short_rig();
  r.sensors.hub_angle.noise = 1e-5;
  r.sensors.hub_rate.noise = 1e-4;
  r.sensors.hub_torque.noise = 2.0;
  r.sensors.tip_deflection.noise = 1e-4;
  r.seed = 11;
  const CompareResult c = compare_record(load_model(kModel), truth::simulate_truth(r), ReplayMode::kClosedLoop);
  for (const char* ch : kChannels) EXPECT_GT(fit(c, ch), 99.0) << ch;
  // Without noise: the two implementations agree to their integrators' error.
  const CompareResult exact = compare_record(load_model(kModel), truth::simulate_truth(short_rig()), ReplayMode::kClosedLoop);
  for (const char* ch : kChannels) EXPECT_GT(fit(exact, ch), 99.999) << ch;
}

TEST(TruthCompare, TheHydraulicRigsModelExplainsTheHydraulicTruth) {
  // The truth's actuator (own orifice regularisation, no relief valves) against configs/fbtb_hydraulic.yaml.
  truth::TruthRig r = short_rig();
  r.controller.kd = 2.0e4;
  r.hydraulics.enabled = true;
  const Record rec = truth::simulate_truth(r);
  const CompareResult c = compare_record(load_model(FLEXFARM_SOURCE_DIR "/configs/fbtb_hydraulic.yaml"), rec,
                                         ReplayMode::kClosedLoop);
  ModelSpec rigid_drive = load_model(kModel).spec;
  rigid_drive.controller.kd = 2.0e4;
  const CompareResult without = compare_record(make_model(rigid_drive), rec, ReplayMode::kClosedLoop);
  for (const char* ch : kChannels) {
    EXPECT_GT(fit(c, ch), 99.9) << ch;
    EXPECT_LT(fit(without, ch), 99.0) << ch;
  }
}

struct Case {
  const char* name;
  std::vector<std::pair<const char*, const char*>> truth;  // truth field = value
  std::function<void(ModelSpec&)> flexfarm;                // the same effect in flexfarm's terms
  double min_fit;                                          // % on every channel, free run
};

TEST(TruthCompare, TheMappedFlexfarmModelExplainsEachHiddenEffect) {
  // The truth's record (record.as_seen false) logs the hub angle and rate on time: logged: true.
  ModelSpec base = load_model(kModel).spec;
  base.sensors.hub_angle.logged = base.sensors.hub_rate.logged = "true";
  const double k = base.joints.stiffness;
  const std::vector<Case> cases = {
      // The same laws: agreement to the integrators' error.
      {"torque_offset", {{"torque_offset", "300"}}, [](ModelSpec& s) { s.hub_torque_offset = 300; }, 99.999},
      {"stiffening", {{"joint.stiffening", "0.5"}, {"joint.stiffening_angle", "0.01"}},
       [k](ModelSpec& s) { s.joints.cubic_stiffness = 0.5 * k / (0.01 * 0.01); }, 99.999},
      {"hub_angle delay", {{"sensors.hub_angle.delay", "8"}}, [](ModelSpec& s) { s.sensors.hub_angle.delay = 8; }, 99.999},
      {"hub_rate delay", {{"sensors.hub_rate.delay", "2"}}, [](ModelSpec& s) { s.sensors.hub_rate.delay = 2; }, 99.999},
      {"torque limit", {{"controller.torque_limit", "1500"}}, [](ModelSpec& s) { s.controller.torque_limit = 1500; }, 99.999},
      {"segments", {{"segments", "12"}}, [](ModelSpec& s) { s.segments = 12; }, 99.999},
      {"drive", {{"drive.enabled", "true"}, {"drive.stiffness", "3e7"}},
       [](ModelSpec& s) {
         s.drive.enabled = true;
         s.drive.stiffness = 3e7;
       },
       99.99},
      {"encoder", {{"sensors.hub_angle.quantize", "true"}, {"sensors.hub_angle.encoder_bits", "14"}},
       [](ModelSpec& s) { s.sensors.hub_angle.resolution = 2 * M_PI / 16384; }, 99.9},  // the record's angle is quantised
      // Friction: atan (truth) against tanh (flexfarm) regularisation.
      {"coulomb", {{"friction.coulomb", "400"}}, [](ModelSpec& s) { s.friction.coulomb = 400; }, 99.5},
      {"stribeck",
       {{"friction.coulomb", "300"}, {"friction.stiction", "900"}, {"friction.stribeck_velocity", "0.02"},
        {"friction.viscous", "500"}},
       [](ModelSpec& s) {
         s.friction.coulomb = 300;
         s.friction.stiction = 900;
         s.friction.stribeck_velocity = 0.02;
         s.friction.viscous = 500;
       },
       99.5},
      // LuGre's bristles (the same law; the truth's CVODE against the bristles' implicit stage).
      {"lugre",
       {{"friction.coulomb", "300"}, {"friction.stiction", "600"}, {"friction.stribeck_velocity", "0.02"},
        {"friction.bristle_stiffness", "3e6"}, {"friction.bristle_damping", "5e4"}},
       [](ModelSpec& s) {
         s.friction.model = "lugre";
         s.friction.coulomb = 300;
         s.friction.stiction = 600;
         s.friction.stribeck_velocity = 0.02;
         s.friction.bristle_stiffness = 3e6;
         s.friction.bristle_damping = 5e4;
       },
       99.5},
      // A worn gear: Fc (1 + A cos(p q + phi)) in the truth, Fc (1 + a cos(p q) + b sin(p q)) in flexfarm,
      // a = A cos(phi), b = -A sin(phi).
      {"worn gear",
       {{"friction.coulomb", "400"}, {"friction.position_amplitude", "0.6"}, {"friction.position_waves", "20"},
        {"friction.position_phase", "1"}},
       [](ModelSpec& s) {
         s.friction.coulomb = 400;
         s.friction.position_waves = 20;
         s.friction.position_cos = 0.6 * std::cos(1.0);
         s.friction.position_sin = -0.6 * std::sin(1.0);
       },
       99.5},
  };
  for (const auto& c : cases) {
    truth::TruthRig r = short_rig();
    for (const auto& [key, value] : c.truth) truth::set_truth_field(r, key, value);
    const Record rec = truth::simulate_truth(r);
    ModelSpec spec = base;
    c.flexfarm(spec);
    const CompareResult mapped = compare_record(make_model(spec), rec, ReplayMode::kClosedLoop);
    const CompareResult unmapped = compare_record(make_model(base), rec, ReplayMode::kClosedLoop);
    double worst_base = 100.0, worst = 100.0;
    for (const char* ch : kChannels) {
      EXPECT_GT(fit(mapped, ch), c.min_fit) << c.name << ", " << ch;
      worst = std::min(worst, fit(mapped, ch));
      worst_base = std::min(worst_base, fit(unmapped, ch));
    }
    std::printf("%-16s worst free-run fit: mapped model %.4f %%, base model %.4f %%\n", c.name, worst, worst_base);
    // The base model misses the effect visibly (its worst channel).
    EXPECT_LT(worst_base, c.min_fit - 0.01) << c.name;
  }
}

// The torque's rattle: RMS of its second difference over the record, N m (what a mesh that chatters in its
// free play adds; a free run cannot follow the chatter's phase, so its statistics are compared).
double rattle(const std::vector<double>& x) {
  double s2 = 0.0;
  for (std::size_t k = 1; k + 1 < x.size(); ++k) s2 += std::pow(x[k + 1] - 2.0 * x[k] + x[k - 1], 2);
  return std::sqrt(s2 / static_cast<double>(x.size() - 2));
}

TEST(TruthCompare, AMeshDampedOnlyAsTheTeethCloseRattlesAsTheTruthsDoes) {
  // A soft drive with free play chatters through the move; damping only as the teeth close
  // (drive.closing_damping; the truth's drive.one_sided_damping) lets it chatter harder. Each law's chatter in
  // flexfarm within 30 % of the independent simulator's, and the two laws told apart by both alike.
  ModelSpec base = load_model(kModel).spec;
  base.sensors.hub_angle.logged = base.sensors.hub_rate.logged = "true";
  double truth_level[2], model_level[2];
  for (int closing = 0; closing < 2; ++closing) {
    truth::TruthRig r = short_rig();
    for (const auto& [k, v] : std::vector<std::pair<std::string, std::string>>{
             {"drive.enabled", "true"}, {"drive.stiffness", "3e7"}, {"drive.backlash", "1e-3"}, {"drive.damping", "1e4"},
             {"drive.one_sided_damping", closing ? "true" : "false"}})
      truth::set_truth_field(r, k, v);
    const Record rec = truth::simulate_truth(r);
    ModelSpec spec = base;
    spec.drive.enabled = true;
    spec.drive.stiffness = 3e7;
    spec.drive.backlash = 1e-3;
    spec.drive.damping = 1e4;
    spec.drive.closing_damping = closing;
    const Model m = make_model(spec);
    const auto p = replay(std::span<const Model>(&m, 1), rec, ReplayMode::kClosedLoop);
    ASSERT_TRUE(p[0].ok);
    truth_level[closing] = rattle(rec.at("hub_torque"));
    model_level[closing] = rattle(p[0].channels.at("hub_torque"));
    std::printf("closing damping %d: chatter %.1f N m (truth), %.1f N m (flexfarm)\n", closing, truth_level[closing],
                model_level[closing]);
    EXPECT_NEAR(model_level[closing], truth_level[closing], 0.3 * truth_level[closing]) << closing;
  }
  EXPECT_GT(truth_level[1], 1.5 * truth_level[0]);
  EXPECT_GT(model_level[1], 1.5 * model_level[0]);
}

}  // namespace
}  // namespace ff
