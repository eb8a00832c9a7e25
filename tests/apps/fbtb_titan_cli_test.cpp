// `flexfarm run` on the FBTB carrying its Titan-class arm (configs/fbtb_titan.yaml, docs/fbtb-titan.md):
// a Monte Carlo study over both arms (the end frame's mass, the hub's gain, a shoulder actuator's
// supply pressure, the forearm's mass) with sensor noise on the hub and the elbow gives the same
// results.csv and traces, byte for byte, on one thread with one lane per batch, on two threads with
// three lanes, and on two MPI ranks.
#include <gtest/gtest.h>

#include "tests/apps/cli_fixture.hpp"

namespace ff::test {
namespace {

class FbtbTitanCli : public CliFixture {
 protected:
  FbtbTitanCli() : CliFixture("flexfarm_fbtb_titan_cli_", {{"configs/fbtb_titan.yaml", "fbtb_titan.yaml"}}) {}

  void SetUp() override {
    CliFixture::SetUp();
    write("configs/titan_mc.yaml",
          "name: titan_mc\n"
          "seed: 7\n"
          "model: ../fbtb_titan.yaml\n"
          "set:\n"
          "  trajectory.waypoints[0].time: 1.0\n"
          "  simulation.settle: 1.5\n"
          "  joints.hub.sensors.angle: {noise: 1.0e-5, resolution: 1.0e-6}\n"
          "  joints.elbow.sensors.rate: {noise: 1.0e-3}\n"
          "variables:\n"
          "  - path: bodies[beam].flexible.payload.mass\n"
          "    distribution: {type: uniform, lower: 150, upper: 300}\n"
          "  - path: joints.hub.controller.kp\n"
          "    distribution: {type: normal, mean: 1.0e5, std: 1.0e4}\n"
          "  - path: joints.shoulder.hydraulics.supply_pressure\n"
          "    distribution: {type: uniform, lower: 15.0e6, upper: 21.0e6}\n"
          "  - path: bodies[forearm].mass\n"
          "    distribution: {type: uniform, lower: 20, upper: 30}\n"
          "design: {type: monte_carlo, samples: 10}\n");
  }

  // results.csv and every trace of run `dir`, in file order.
  std::string outputs(const std::string& dir) const {
    std::string all = read_text(work / dir / "results.csv");
    for (const std::string& f : tree(work / dir / "traces")) all += "\n" + f + "\n" + read_text(work / dir / "traces" / f);
    return all;
  }
};

TEST_F(FbtbTitanCli, AMonteCarloStudyGivesTheSameBitsOnAnyThreadLaneAndRankCount) {
  const auto a = run("run configs/titan_mc.yaml --out one --threads 1 --lanes 1");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const std::string reference = outputs("one");
  EXPECT_EQ(split_lines(read_text(work / "one" / "results.csv")).size(), 11u);  // header and ten variants
  EXPECT_EQ(tree(work / "one" / "traces").size(), 10u);
  const auto b = run("run configs/titan_mc.yaml --out two --threads 2 --lanes 3");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  EXPECT_EQ(outputs("two"), reference);
  if (!on_path("mpirun")) GTEST_SKIP() << "mpirun is not on PATH: install OpenMPI (Debian openmpi-bin; CI has it)";
  const auto c = run_shell(mpirun(2) + quote(kBinary) + " run configs/titan_mc.yaml --out ranks --threads 1");
  ASSERT_EQ(c.exit_code, 0) << c.output;
  EXPECT_EQ(outputs("ranks"), reference);
}

}  // namespace
}  // namespace ff::test
