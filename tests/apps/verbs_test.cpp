// apps/verb_table.cpp, verb_plot.cpp, verb_animate.cpp: the reporting verbs end to end.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/cli_support.hpp"

namespace {

namespace fs = std::filesystem;

using Result = ff::test::CliResult;

// Runs flexfarm with `args` from the source tree, stdout and stderr together.
Result flexfarm(const std::string& args) { return ff::test::run_flexfarm(args); }

class Verbs : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("ff_verbs_" + std::to_string(::getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    // A listed study small enough to run in a second: three payloads, one short move, the notch placed for
    // each variant's payload (controller.model: plant; at the nominal payload's resonances the light arm
    // rings through its hold).
    std::ofstream(dir / "s.yaml") << "name: three\nmodel: " FLEXFARM_SOURCE_DIR "/configs/fbtb.yaml\n"
                                     "set:\n  trajectory.moves: [{target: 0.2, hold: 8}]\n  notch.enabled: true\n"
                                     "  controller.model: plant\n"
                                     "runs:\n  - {label: light, set: {payload.mass: 200}}\n"
                                     "  - {label: light too, set: {payload.mass: 200}}\n"
                                     "  - {label: heavy, set: {payload.mass: 450}}\n";
  }
  void TearDown() override { fs::remove_all(dir); }
  fs::path dir;
};

TEST_F(Verbs, TableGroupsRowsByParameterWithSpecMisses) {
  ASSERT_EQ(flexfarm("run " + (dir / "s.yaml").string() + " --out " + (dir / "out").string()).exit_code, 0);
  const auto r = flexfarm("table " + (dir / "out").string() + " --by payload.mass --metric m1_tip_settling_s "
                          "--spec m1_tip_settling_s=1000 --format csv");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::istringstream lines(r.output);
  std::string header, light, heavy;
  std::getline(lines, header);
  std::getline(lines, light);
  std::getline(lines, heavy);
  EXPECT_EQ(header, "payload.mass,metric,count,\"not settled\",missing,horizon,mean,min,p5,p50,p95,max,"
                    "\"P(miss spec)\",\"95% CI\",censored");
  EXPECT_EQ(light.rfind("200,m1_tip_settling_s,2,0,0,,", 0), 0u) << light;   // two identical runs in one group
  // The heavy arm still rings at the end of its 8 s hold: not settled, censored at its horizon (every
  // statistic a bound, the mean the horizon itself), and a miss of the spec.
  EXPECT_EQ(heavy.rfind("450,m1_tip_settling_s,0,1,0,", 0), 0u) << heavy;
  EXPECT_NE(heavy.find(",1.000,"), std::string::npos) << heavy;
  EXPECT_EQ(heavy.substr(heavy.rfind(',') + 1), "\"mean min p5 p50 p95 max\"") << heavy;
  EXPECT_NE(light.find(",0.000,"), std::string::npos) << light;            // nothing misses a 1000 s spec
  const auto bad = flexfarm("table " + (dir / "out").string() + " --by payload.colour");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("--by: 'payload.colour' is not a parameter or result column (the parameters and columns: payload.mass, "),
            std::string::npos) << bad.output;
}

TEST_F(Verbs, PlotResimulatesChosenVariantsExactly) {
  ASSERT_EQ(flexfarm("run " + (dir / "s.yaml").string() + " --out " + (dir / "out").string()).exit_code, 0);
  const auto r = flexfarm("plot " + (dir / "s.yaml").string() + " --eval 2 --out " + (dir / "plot").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto read = [](const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  // The re-simulated trace is the study's own, byte for byte.
  EXPECT_EQ(read(dir / "plot" / "trace_000002.csv"), read(dir / "out" / "traces" / "000002.csv"));
  EXPECT_TRUE(fs::exists(dir / "plot" / "tip_angle.png"));
  EXPECT_NE(flexfarm("plot " + (dir / "s.yaml").string() + " --eval 3 --out " + (dir / "p2").string()).exit_code, 0);
  EXPECT_FALSE(fs::exists(dir / "p2"));
}

TEST_F(Verbs, AnimateWritesAVideoWithOneFramePerStep) {
  const auto r = flexfarm("animate configs/fbtb.yaml --out " + (dir / "arm.avi").string() +
                          " --set 'trajectory.moves=[{target: 0.5, hold: 1}]' --fps 10 --size 320 --exaggerate 4");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("41 frames"), std::string::npos) << r.output;  // 4 s at 10 frames/s, both ends
  EXPECT_GT(fs::file_size(dir / "arm.avi"), 1000u);
  for (const auto& e : fs::directory_iterator(dir)) EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos);
}

}  // namespace

// A rigid one-body arm (N = 1, configs/emps.yaml) has no beam joints: modes and simulate must not
// read joint 1 (under -DFLEXFARM_SANITIZE=ON they stopped on a heap-buffer-overflow).
TEST_F(Verbs, RigidOneBodyArmRunsModesAndSimulate) {
  const Result modes = flexfarm("modes configs/emps.yaml");
  EXPECT_EQ(modes.exit_code, 0) << modes.output;
  EXPECT_NE(modes.output.find("N = 1, one rigid arm"), std::string::npos) << modes.output;
  const Result sim = flexfarm("simulate configs/emps.yaml --out '" + (dir / "emps").string() + "'");
  EXPECT_EQ(sim.exit_code, 0) << sim.output;
  EXPECT_TRUE(fs::exists(dir / "emps" / "trace.csv"));
}
