// `flexfarm run` on the dual-arm machine's coupling study (configs/studies/sers_coupling.yaml,
// docs/sers.md): the same results.csv, byte for byte, on one thread with one lane per batch and on two
// threads with the default lanes; `table` then summarises both tools by default.
#include <gtest/gtest.h>

#include "tests/apps/cli_fixture.hpp"

namespace ff::test {
namespace {

class SersCli : public CliFixture {
 protected:
  SersCli()
      : CliFixture("flexfarm_sers_cli_", {{"configs/sers.yaml", "sers.yaml"},
                                          {"configs/studies/sers_coupling.yaml", "configs/sers_coupling.yaml"}}) {}
};

TEST_F(SersCli, TheCouplingStudyGivesTheSameTableOnOneThreadAndTwo) {
  const auto a = run("run configs/sers_coupling.yaml --out one --threads 1 --lanes 1");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const auto b = run("run configs/sers_coupling.yaml --out two --threads 2");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const std::string table = read_text(work / "one" / "results.csv");
  EXPECT_EQ(read_text(work / "two" / "results.csv"), table);
  EXPECT_EQ(split_lines(table).size(), 5u);  // header and four runs
  const auto t = run("table one");
  ASSERT_EQ(t.exit_code, 0) << t.output;
  for (const char* m : {"left_settling_s", "left_overshoot_pct", "right_settling_s", "right_overshoot_pct"})
    EXPECT_NE(t.output.find(m), std::string::npos) << m << "\n" << t.output;
}

}  // namespace
}  // namespace ff::test
