// Comparing a model with a record (validate/compare.cpp): a model against its own output fits, a
// model missing the hub's Coulomb friction is told so, and the report files are complete.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "kernel/simulate.hpp"
#include "validate/compare.hpp"
#include "validate/synthetic.hpp"

namespace ff {
namespace {

namespace fs = std::filesystem;

ModelSpec rig(double coulomb = 0.0) {
  ModelSpec s;
  s.trajectory.moves = {{0.5, 2.0}, {0.0, 3.0}};
  s.payload_mass = 328.7;
  s.friction.coulomb = coulomb;
  return s;
}

// The model's own closed-loop run as a measurement record.
Record record_of(const Model& m) { return make_synthetic_record(m, 0.0, 1); }  // noise-free

const ChannelCompare& channel(const CompareResult& r, const std::string& name) {
  for (const auto& c : r.channels)
    if (c.name == name) return c;
  throw std::out_of_range(name);
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(Compare, ModelAgainstItsOwnOutputFitsFreeRunAndKStep) {
  const Model m = make_model(rig());
  const CompareResult r = compare_record(m, record_of(m), ReplayMode::kClosedLoop, 10);
  EXPECT_TRUE(r.free_ok);
  EXPECT_TRUE(r.k_ok);
  EXPECT_EQ(r.input, "ref");
  ASSERT_EQ(r.channels.size(), 3u);  // hub_angle, tip_deflection, hub_torque
  for (const auto& c : r.channels) {
    EXPECT_GT(c.fit_free.percent, 99.9) << c.name;
    EXPECT_GT(c.fit_k.percent, 99.9) << c.name;
    EXPECT_TRUE(c.free_analysis.valid) << c.name;
    EXPECT_EQ(c.free_analysis.binned.size(), 5u) << c.name;  // velocity, angle, acceleration, torque, deflection
  }
}

TEST(Compare, ModelWithoutCoulombFrictionIsToldAFrictionLikeEffectIsMissing) {
  const Model truth = make_model(rig(800.0)), model = make_model(rig(0.0));
  const CompareResult r = compare_record(model, record_of(truth), ReplayMode::kClosedLoop, 10);
  const auto& torque = channel(r, "hub_torque");
  ASSERT_TRUE(torque.free_analysis.valid);
  const auto& f = torque.free_analysis.failure;
  ASSERT_TRUE(f.velocity_step.ok);
  // The missing torque is Fc sign(w): a step of about 2 Fc = 1600 N m across zero velocity.
  EXPECT_GT(f.velocity_step.step, 800.0);
  EXPECT_TRUE(f.friction_like);
  const std::string report = format_compare_report(r);
  EXPECT_NE(report.find("across zero hub velocity: a friction-like effect is missing"), std::string::npos) << report;
  // The model's own friction-free record shows no such step.
  const CompareResult self = compare_record(model, record_of(model), ReplayMode::kClosedLoop, 10);
  EXPECT_LT(std::abs(channel(self, "hub_torque").free_analysis.failure.velocity_step.step), 1.0);
}

TEST(Compare, ReportFilesAreWrittenWithFitsAndFindingsInTheJson) {
  const Model truth = make_model(rig(800.0)), model = make_model(rig(0.0));
  const CompareResult r = compare_record(model, record_of(truth), ReplayMode::kClosedLoop, 10);
  const fs::path dir = fs::temp_directory_path() / ("ff_compare_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const auto files = write_compare_report(r, dir.string());
  // report.md, compare.json, and per channel overlay, acf, ccf, spectrum and 5 binned plots.
  EXPECT_EQ(files.size(), 2u + 3u * 9u);
  for (const auto& f : files) EXPECT_TRUE(fs::exists(dir / f)) << f;
  const std::string json = read_text(dir / "compare.json");
  EXPECT_EQ(json.rfind("{\n  \"mode\": \"closed-loop\",\n  \"k\": 10,", 0), 0u) << json;
  char fit[128];
  const auto& c = channel(r, "hub_torque");
  std::snprintf(fit, sizeof fit, "\"hub_torque\": {\"free_run\": %.10g, \"k_step\": %.10g}", c.fit_free.percent,
                c.fit_k.percent);
  EXPECT_NE(json.find(fit), std::string::npos) << fit << "\n" << json;
  EXPECT_NE(json.find("\"friction_like\": true"), std::string::npos) << json;
  // The k-step's start state: the observer's channels and gain, in the JSON and in words.
  EXPECT_NE(json.find("\"observer\": {\"ok\": true, \"channels\": [\"hub_angle\", \"hub_rate\", \"tip_deflection\"], "
                      "\"noise_std\": ["),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("\"process_noise\": 0.005, \"period\": 1, \"pole_radius\": 0.99"), std::string::npos) << json;
  const std::string md = read_text(dir / "report.md");
  EXPECT_NE(md.find("| hub_torque | N m | "), std::string::npos) << md;
  EXPECT_NE(md.find("estimated from the measurements before that sample by an observer on the model"), std::string::npos)
      << md;
  EXPECT_NE(md.find("a friction-like effect is missing"), std::string::npos) << md;
  fs::remove_all(dir);
}

TEST(Compare, ExactReproductionIsReportedAsSuch) {
  const Model m = make_model(rig());
  const std::string md = format_compare_report(compare_record(m, record_of(m), ReplayMode::kClosedLoop, 10));
  EXPECT_NE(md.find("| hub_angle | rad | 100.00 | 100.00 | 0 | 0 |"), std::string::npos) << md;
  EXPECT_NE(md.find("the model reproduces the record exactly"), std::string::npos) << md;
}

TEST(Compare, VelocityStateFromTheAngleWhenTheRecordHasNoRate) {
  Record r;
  for (int k = 0; k < 100; ++k) r.t.push_back(k * 0.01);
  for (double t : r.t) r.columns["hub_angle"].push_back(0.5 * t * t);  // w = t, a = 1
  const auto s = record_states(r);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].first, "hub_velocity");
  EXPECT_NEAR(s[0].second[50], 0.5, 1e-12);
  EXPECT_EQ(s[2].first, "hub_acceleration");
  EXPECT_NEAR(s[2].second[50], 1.0, 1e-9);
}

TEST(Compare, InverseDynamicsHasNoObserver) {
  const Model m = make_model(rig());
  const CompareResult r = compare_record(m, record_of(m), ReplayMode::kInverseDynamics, 10);
  EXPECT_FALSE(r.observed);
  EXPECT_NE(format_compare_json(r).find("\"observer\": null,"), std::string::npos);
  EXPECT_EQ(r.channels[0].k_step, r.channels[0].free_run);
}

TEST(Compare, KBelowOneIsRefused) {
  const Model m = make_model(rig());
  EXPECT_THROW(compare_record(m, record_of(m), ReplayMode::kClosedLoop, 0), std::invalid_argument);
}

}  // namespace
}  // namespace ff
