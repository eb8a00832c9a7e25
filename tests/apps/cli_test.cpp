// End-to-end tests of the `flexfarm` command line: help, `modes` on the reference rig, bad models,
// studies and `--set` values rejected with one clear line and nothing written, and a short
// `simulate` / `run` writing complete outputs (no leftover temporary files).
#include <gtest/gtest.h>

#include <regex>

#include "tests/apps/cli_fixture.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace ff::test;

// Each test runs the binary in its own fresh working directory, with the reference rig's model.
class Cli : public CliFixture {
 protected:
  Cli() : CliFixture("ff_cli_", {{"configs/fbtb.yaml", "configs/fbtb.yaml"}}) {}

  // The reference model with line `n` (1-based) replaced, written to work/NAME.
  void write_model(const std::string& name, int n, const std::string& line) const {
    auto lines = split_lines(read_text(kSource + "/configs/fbtb.yaml"));
    lines.at(n - 1) = line;
    std::ofstream out(work / name);
    for (const auto& l : lines) out << l << "\n";
  }
};

const char* kTraceHeader = "t,ref,ref_filtered,hub_torque,hub_angle,hub_rate,tip_deflection,tip_angle";
const char* kPlots[] = {"tip_angle.png", "hub_angle.png", "tip_deflection.png", "hub_torque.png"};

// ---- help --------------------------------------------------------------------------------

TEST_F(Cli, HelpListsEveryVerb) {
  const auto r = run("--help");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const char* verb : {"modes", "simulate", "run", "compare"}) EXPECT_NE(r.output.find(verb), std::string::npos) << verb;
}

TEST_F(Cli, VerbHelpListsEveryOption) {
  const struct {
    const char* verb;
    std::vector<std::string> words;
  } cases[] = {
      {"modes", {"model", "--set", "--count"}},
      {"simulate", {"model", "--out", "--set", "trace.csv"}},
      {"run", {"study", "--out", "--threads"}},
      {"compare", {"--model", "--data", "--mode", "--k", "--process-noise", "--set", "--out", "report.md", "compare.json"}},
  };
  for (const auto& c : cases) {
    const auto r = run(std::string(c.verb) + " --help");
    EXPECT_EQ(r.exit_code, 0) << c.verb << ": " << r.output;
    for (const auto& w : c.words) EXPECT_NE(r.output.find(w), std::string::npos) << c.verb << " lacks " << w;
  }
}

TEST_F(Cli, NoVerbOrUnknownVerbFails) {
  EXPECT_NE(run("").exit_code, 0);
  EXPECT_NE(run("launch configs/fbtb.yaml").exit_code, 0);
  EXPECT_NE(run("modes").exit_code, 0);  // the model is required
}

TEST_F(Cli, AMisspeltVerbIsNamedWithTheClosestVerb) {
  // Not CLI11's "A subcommand is required": the word given, and the verb meant. A usage error: exit 2.
  const auto r = run("simulat configs/fbtb.yaml --out out");
  expect_one_error_line(r, "unknown verb 'simulat' (did you mean `simulate`?) (flexfarm --help lists the verbs)");
  EXPECT_EQ(r.exit_code, 2);
  expect_one_error_line(run("mdoes configs/fbtb.yaml"), "unknown verb 'mdoes' (did you mean `modes`?)");
  expect_one_error_line(run("launch configs/fbtb.yaml"), "unknown verb 'launch' (flexfarm --help lists the verbs)");
  EXPECT_FALSE(fs::exists(work / "out"));
}

TEST_F(Cli, AStudyGivenToSimulateAndAModelGivenToRunAreNamedWithTheVerbThatTakesEach) {
  std::ofstream(work / "study.yaml") << "model: configs/fbtb.yaml\nruns:\n  - label: a\n";
  const auto sim = run("simulate study.yaml --out out");
  expect_one_error_line(sim, "study.yaml:1: model: this is a study file (it names a `model:`), not a model: run it with "
                             "`flexfarm run study.yaml --out DIR`");
  EXPECT_EQ(sim.exit_code, 2);
  const auto rn = run("run configs/fbtb.yaml --out out");
  expect_one_error_line(rn, "configs/fbtb.yaml:4: this is a model file (it has `beam:`), not a study: simulate it with "
                            "`flexfarm simulate configs/fbtb.yaml --out DIR`");
  EXPECT_EQ(rn.exit_code, 2);
  EXPECT_FALSE(fs::exists(work / "out"));
}

TEST_F(Cli, ATargetInDegreesSetOnTheCommandLineIsRefused) {
  const auto r = run("simulate configs/fbtb.yaml --out out --set trajectory.moves[0].target=30");
  expect_one_error_line(r, "--set: trajectory.moves[0].target: 30 rad is more than a turn (2 pi): looks like degrees (30 deg = 0.5236 rad)");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(fs::exists(work / "out"));
  expect_one_error_line(run("modes configs/fbtb.yaml --set beam.youngs_modulus=207"), "--set: beam.youngs_modulus: 207 Pa is far below");
  expect_one_error_line(run("modes configs/fbtb.yaml --set notch.ordre=2"), "--set: notch.ordre: unknown key (did you mean `order`?)");
}

// ---- modes -------------------------------------------------------------------------------

TEST_F(Cli, ModesOfTheReferenceRig) {
  const auto r = run("modes configs/fbtb.yaml");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto& out = r.output;
  EXPECT_NE(out.find("N = 6 segments"), std::string::npos) << out;
  EXPECT_NE(out.find("130.89 kN m/rad"), std::string::npos) << out;
  EXPECT_NE(out.find("26.18 kN m/rad"), std::string::npos) << out;
  const auto clamped = out.find("clamped hub:");
  const auto closed = out.find("closed loop");
  ASSERT_NE(clamped, std::string::npos) << out;
  ASSERT_NE(closed, std::string::npos) << out;
  ASSERT_LT(clamped, closed);
  const std::string clamped_table = out.substr(clamped, closed - clamped);
  const std::string closed_table = out.substr(closed);
  EXPECT_NE(clamped_table.find(" 0.3000 "), std::string::npos) << out;
  EXPECT_NE(clamped_table.find(" 2.3003 "), std::string::npos) << out;
  EXPECT_NE(closed_table.find(" 0.2740 "), std::string::npos) << out;
  EXPECT_NE(closed_table.find(" 2.2892 "), std::string::npos) << out;
  EXPECT_EQ(tree(work).size(), 2u) << "modes writes nothing";  // configs/ and configs/fbtb.yaml
}

TEST_F(Cli, ModesAcceptsSet) {
  const auto r = run("modes configs/fbtb.yaml --set segments=11 --count 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("N = 11 segments"), std::string::npos) << r.output;
}

TEST_F(Cli, ModesOfAMissingFileFails) {
  const auto r = run("modes configs/none.yaml");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("none.yaml"), std::string::npos) << r.output;
}

// A kinematic tree: a pendulum (mass 2 kg at 0.5 m below a revolute joint about y, gravity 9.81)
// with a torsion spring of 3 N m/rad: omega^2 = (m g l + k) / (m l^2 + I_c), I_c of a 0.1 m cube.
TEST_F(Cli, ModesOfATreeDescriptionAtItsPoseWithItsShapes) {
  write("pendulum.yaml",
        "gravity: [0, 0, -9.81]\n"
        "bodies:\n"
        "  - name: bob\n"
        "    parent: base\n"
        "    joint: {name: swing, type: revolute, axis: [0, 1, 0], stiffness: 3.0}\n"
        "    mass: 2.0\n"
        "    com: [0, 0, -0.5]\n"
        "    inertia: {ixx: 0.0033333333333333335, iyy: 0.0033333333333333335, izz: 0.0033333333333333335}\n");
  const double Ic = 2.0 * 0.01 / 6.0, w = std::sqrt((2.0 * 9.81 * 0.5 + 3.0) / (2.0 * 0.25 + Ic));
  const auto r = run("modes pendulum.yaml --shapes shapes.csv");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  char expect[64];
  std::snprintf(expect, sizeof expect, " %.4f ", w / (2.0 * 3.141592653589793));
  EXPECT_NE(r.output.find(expect), std::string::npos) << expect << " in " << r.output;
  const auto rows = split_lines(read_text(work / "shapes.csv"));
  ASSERT_EQ(rows.size(), 2u) << read_text(work / "shapes.csv");
  EXPECT_EQ(rows[0], "mode,omega_rad_s,frequency_hz,zeta,oscillatory,swing");
  EXPECT_NEAR(std::stod(rows[1].substr(2)), w, 1e-6 * w) << rows[1];
  // Upside down (swing = pi) the spring no longer holds it: omega^2 = (k - m g l) / J < 0, a real pole.
  const auto up = run("modes pendulum.yaml --at swing=3.141592653589793");
  ASSERT_EQ(up.exit_code, 0) << up.output;
  EXPECT_NE(up.output.find("unstable: grows e-fold in"), std::string::npos) << up.output;
  // A locked joint leaves nothing to move.
  EXPECT_EQ(run("modes pendulum.yaml --lock swing").exit_code, 0);
  expect_one_error_line(run("modes pendulum.yaml --lock elbow"), "--lock: elbow: no moving joint of that name");
  // A pose in degrees (item 32.10), and a typo of the joint's name (32.15).
  expect_one_error_line(run("modes pendulum.yaml --at swing=90"),
                        "--at: swing: 90 rad is more than a turn (2 pi): looks like degrees (90 deg = 1.571 rad)");
  expect_one_error_line(run("modes pendulum.yaml --at swnig=0.5"), "--at: swnig: no moving joint of that name (did you mean `swing`?)");
  // A tree YAML is an arm model: --set paths work on it, and a wrong one is named.
  expect_one_error_line(run("modes pendulum.yaml --set swing=1"), "--set: swing: unknown key");
}

TEST_F(Cli, ModesOfAUrdfAndOfItsTreeYamlAreTheSame) {
  const std::string urdf = quote(kSource + "/tests/data/urdf/arm6.urdf");
  const std::string side = quote(kSource + "/tests/data/urdf/arm6_sidecar.yaml");
  const std::string yaml = quote(kSource + "/tests/data/urdf/arm6.yaml");
  const std::string pose = " --at shoulder_lift=-0.6 --at elbow=0.9 --lock shoulder_pan --count 6";
  const auto a = run("modes " + urdf + " --sidecar " + side + pose);
  const auto b = run("modes " + yaml + pose);
  ASSERT_EQ(a.exit_code, 0) << a.output;
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const auto table = [](const std::string& out) { return out.substr(out.find("linearised modes:")); };
  EXPECT_EQ(table(a.output), table(b.output));
  // wrist_3 has neither spring nor gravity stiffness; shoulder_lift's damper makes real poles.
  EXPECT_NE(a.output.find("free: nothing resists this motion"), std::string::npos) << a.output;
  EXPECT_NE(a.output.find(" 0.4844 "), std::string::npos) << a.output;
}

// The Titan arm on the FBTB: the closed loop's table opens with the beam's first mode (about 0.24 Hz),
// and the six actuators' mean chamber pressures, which nothing restores, are counted, not listed.
TEST_F(Cli, ModesOfTheTitanOnTheBeamListTheBeamsModeAndCountTheNeutralPressures) {
  const auto r = run("modes " + quote(kSource + "/configs/fbtb_titan.yaml") + " --count 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string loop = r.output.substr(r.output.find("closed loop"));
  EXPECT_NE(loop.find("  1          0.2369 "), std::string::npos) << r.output;
  EXPECT_EQ(loop.find("  4  "), std::string::npos) << r.output;  // --count 3
  EXPECT_EQ(loop.find("free: nothing resists"), std::string::npos) << r.output;
  EXPECT_NE(loop.find("and 6 neutral states that move no joint"), std::string::npos) << r.output;
}

// ---- rejected input: one line, non-zero exit, nothing written ----------------------------

TEST_F(Cli, SimulateBadModelWritesNothing) {
  write_model("bad.yaml", 22, "  mass: -328.7");
  const auto r = run("simulate bad.yaml --out out");
  expect_one_error_line(r, "bad.yaml:22: payload.mass: ");
  EXPECT_NE(r.output.find(">= 0"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(work / "out"));
}

TEST_F(Cli, SimulateUnknownKeyWritesNothing) {
  write_model("bad.yaml", 24, "  colour: red");
  const auto r = run("simulate bad.yaml --out out");
  expect_one_error_line(r, "bad.yaml:24: payload.colour: unknown key");
  EXPECT_FALSE(fs::exists(work / "out"));
}

TEST_F(Cli, ModesBadTypeIsOneLine) {
  write_model("bad.yaml", 11, "segments: six");
  const auto r = run("modes bad.yaml");
  expect_one_error_line(r, "bad.yaml:11: segments: expected an integer");
}

// diagnose and calibrate read the model as a source (its document kept for the candidates' paths): a
// bad value is still reported at its line.
TEST_F(Cli, DiagnoseAndCalibrateNameTheLineOfABadModelValue) {
  write_model("bad.yaml", 11, "segments: six");
  const std::string data = quote(kSource + "/tests/data/reference-traces/fbtb_n6_pd_0p5rad.csv");
  expect_one_error_line(run("diagnose --model bad.yaml --data " + data + " --json out.json"),
                        "bad.yaml:11: segments: expected an integer");
  expect_one_error_line(run("calibrate --model bad.yaml --data " + data + " --add payload --out new.yaml"),
                        "bad.yaml:11: segments: expected an integer");
  EXPECT_FALSE(fs::exists(work / "out.json"));
  EXPECT_FALSE(fs::exists(work / "new.yaml"));
}

TEST_F(Cli, SimulateUnparsableModelWritesNothing) {
  write_model("bad.yaml", 6, "   height: 0.3048");
  const auto r = run("simulate bad.yaml --out out");
  expect_one_error_line(r, "bad.yaml:6: ");
  EXPECT_FALSE(fs::exists(work / "out"));
}

TEST_F(Cli, NegativeMassSetIsRejectedNamingTheKey) {
  const auto r = run("simulate configs/fbtb.yaml --out out --set payload.mass=-3");
  expect_one_error_line(r, "--set");
  EXPECT_NE(r.output.find("payload.mass: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(">= 0"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(work / "out"));
}

TEST_F(Cli, BadSetPathsAreRejected) {
  for (const std::string set : {"payload.colour=1", "segments=0", "'trajectory.moves[7].target=1'", "payload.mass"}) {
    const auto r = run("simulate configs/fbtb.yaml --out out --set " + set);
    expect_one_error_line(r, "--set");
    EXPECT_FALSE(fs::exists(work / "out")) << set;
  }
}

// issue 32, item 17: an index or shard past int's range was "flexfarm: error: stoi", exit 1.
TEST_F(Cli, AnIndexOrAShardPastIntsRangeIsAUsageErrorNamingTheKey) {
  const auto set = run("simulate configs/fbtb.yaml --out out --set 'trajectory.moves[99999999999].target=1'");
  EXPECT_EQ(set.exit_code, 2) << set.output;
  expect_one_error_line(set, "--set: trajectory.moves[99999999999].target: index [99999999999] is not in the list");
  write("study.yaml", "model: configs/fbtb.yaml\nruns:\n  - set: {payload.mass: 300}\n");
  for (const std::string shard : {"99999999999/1", "0/99999999999", "3/2"}) {
    const auto r = run("run study.yaml --out out --shard " + shard);
    EXPECT_EQ(r.exit_code, 2) << shard << ": " << r.output;
    EXPECT_NE(r.output.find("--shard: needs 0 <= I < N <= 2147483647, got '" + shard + "'"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("stoi"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(work / "out"));
}

// issue 32, items 3, 6, 7: a URDF nested 50,000 deep, a range of 2e8 levels, a tree of 10,000 links, a
// flexible link of a million segments: each one line, exit 2, at once, nothing written.
TEST_F(Cli, HostileSizesAreRefusedAtOnceWithOneLine) {
  std::string deep = "<robot name=\"deep\">\n";
  for (int i = 0; i < 50000; ++i) deep += "<link>";
  write("deep.urdf", deep);
  auto r = run("modes deep.urdf");
  EXPECT_EQ(r.exit_code, 2) << r.output.substr(0, 500);
  expect_one_error_line(r, "deep.urdf:2: <link>: elements nested more than 100 deep");

  std::string chain = "<robot name=\"chain\">\n<link name=\"l0\"/>\n";
  for (int i = 1; i <= 10000; ++i)
    chain += "<link name=\"l" + std::to_string(i) + "\"/><joint name=\"j" + std::to_string(i) +
             "\" type=\"fixed\"><parent link=\"l" + std::to_string(i - 1) + "\"/><child link=\"l" + std::to_string(i) +
             "\"/></joint>\n";
  write("chain.urdf", chain + "</robot>\n");
  r = run("modes chain.urdf");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  expect_one_error_line(r, "chain.urdf:1003: link \"l1001\": the tree has 10000 bodies");

  write("study.yaml", "model: configs/fbtb.yaml\nvariables:\n  - path: payload.mass\n"
                      "    range: {lower: 100, upper: 400, count: 200000000}\ndesign: {type: grid}\n");
  r = run("run study.yaml --out out");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  expect_one_error_line(r, "study.yaml:4: variables[0].range.count: 200000000 levels take the study's ranges over 1000000 variants");

  fs::copy_file(kSource + "/configs/two_link_flexible.yaml", work / "configs/two_link_flexible.yaml");
  r = run("modes configs/two_link_flexible.yaml --set bodies[upper_arm].flexible.segments=1000000");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  expect_one_error_line(r, "--set: bodies[upper_arm].flexible.segments: must be <= 256 (a flexible link's limit), got 1000000");
  EXPECT_FALSE(fs::exists(work / "out"));
}

// A range error in a `--set` value names --set, not the line of the file that holds the old value.
TEST_F(Cli, NegativeMassSetSaysItCameFromSet) {
  const auto r = run("modes configs/fbtb.yaml --set payload.mass=-3");
  EXPECT_NE(r.output.find("--set"), std::string::npos) << r.output;
}

TEST_F(Cli, RunBadStudyWritesNothing) {
  write("study.yaml",
        "model: configs/fbtb.yaml\n"
        "runs:\n"
        "  - label: fine\n"
        "  - label: heavy\n"
        "    set:\n"
        "      payload.mass: -1\n");
  const auto r = run("run study.yaml --out out");
  expect_one_error_line(r, "study.yaml:6: runs[1].set.payload.mass: ");
  EXPECT_FALSE(fs::exists(work / "out"));
}

TEST_F(Cli, RunStudyWithUnknownKeyWritesNothing) {
  write("study.yaml", "model: configs/fbtb.yaml\nruns:\n  - label: a\n    colour: red\n");
  const auto r = run("run study.yaml --out out");
  expect_one_error_line(r, "study.yaml:4: runs[0].colour: unknown key");
  EXPECT_FALSE(fs::exists(work / "out"));
}

TEST_F(Cli, RunStudyWithMissingModelWritesNothing) {
  write("study.yaml", "model: configs/none.yaml\nruns:\n  - label: a\n");
  const auto r = run("run study.yaml --out out");
  expect_one_error_line(r, "study.yaml:1: model: ");
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(work / "out"));
}

TEST_F(Cli, RunStudyWithoutRunsWritesNothing) {
  write("study.yaml", "model: configs/fbtb.yaml\nruns: []\n");
  const auto r = run("run study.yaml --out out");
  expect_one_error_line(r, "study.yaml:2: runs: ");
  EXPECT_FALSE(fs::exists(work / "out"));
}

// A measurement record (t, ref, hub_torque, hub_angle, tip_deflection) of 30 rows at 1 kHz with `bad`
// put in the hub_angle cell of data line `bad_line` (file line bad_line + 1).
std::string record_text(int bad_line = -1, const std::string& bad = "") {
  std::string text = "t,ref,hub_torque,hub_angle,tip_deflection\n";
  for (int k = 0; k < 30; ++k) {
    const std::string angle = k + 1 == bad_line ? bad : std::to_string(0.001 * k);
    text += std::to_string(0.001 * k) + ",0.1,100," + angle + ",0.0\n";
  }
  return text;
}

TEST_F(Cli, CompareRecordWithNanCellNamesFileLineAndColumnAndWritesNothing) {
  write("rec.csv", record_text(6, "nan"));
  const auto r = run("compare --model configs/fbtb.yaml --data rec.csv --out out");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  expect_one_error_line(r, "rec.csv:7: hub_angle: 'nan' is not finite");
  EXPECT_FALSE(fs::exists(work / "out"));
  EXPECT_EQ(tree(work).size(), 3u) << "compare writes nothing";  // configs/, configs/fbtb.yaml, rec.csv
}

TEST_F(Cli, BadRecordStopsDiagnoseAndCalibrateToo) {
  write("rec.csv", record_text(6, "nan"));
  for (const std::string verb : {"compare --out out", "diagnose --json out.json",
                                 "calibrate --add coulomb_friction --out out/model.yaml"}) {
    const auto r = run(verb.substr(0, verb.find(' ')) + " --model configs/fbtb.yaml --data rec.csv" +
                       verb.substr(verb.find(' ')));
    EXPECT_EQ(r.exit_code, 2) << verb << ": " << r.output;
    expect_one_error_line(r, "rec.csv:7: hub_angle: 'nan' is not finite");
    EXPECT_EQ(tree(work).size(), 3u) << verb << " writes nothing";  // configs/, configs/fbtb.yaml, rec.csv
  }
}

TEST_F(Cli, DiagnoseJsonHasTheBaselineTheRankingAndTheVerdict) {
  const std::string emps = " --data " + quote(kSource + "/tests/data/emps/emps_estimation.csv") +
                           " --mode inverse-dynamics --samples 300 --refit auto --effects coulomb_friction,payload";
  const auto r = run("diagnose --model " + quote(kSource + "/configs/emps.yaml") + emps + " --json d.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string json = read_text(work / "d.json");
  EXPECT_NE(json.find("\"baseline\": {\"fit_percent\": {\"hub_torque\": 30."), std::string::npos) << json;
  EXPECT_NE(json.find("\"refit\": [\"hub.inertia\"]"), std::string::npos) << json;
  const auto first = json.find("{\"effect\": \"coulomb_friction\", \"params\": {\"friction.coulomb\": ");
  const auto second = json.find("{\"effect\": \"payload\"");
  ASSERT_NE(first, std::string::npos) << json;
  ASSERT_NE(second, std::string::npos) << json;
  EXPECT_LT(first, second);  // ranked: Coulomb friction first
  for (const char* key : {"\"stderr\": {", "\"fit_percent\": {", "\"delta_bic\": -", "\"significant\": true"})
    EXPECT_NE(json.find(key, first), std::string::npos) << key;
  // The payload on a one-body axis: its mass and inertia add to the hub's, one number; not identifiable.
  EXPECT_NE(json.find("\"unidentifiable\": [\"payload.mass\", \"payload.inertia\"", second),
            std::string::npos) << json;
  EXPECT_NE(json.find("\"payload.mass\": null", second), std::string::npos) << json;
  // Coulomb friction alone does not explain a real axis (viscous friction, the offset): "unexplained".
  EXPECT_NE(json.find("\"misfit\": [{\"channel\": \"hub_torque\""), std::string::npos) << json;
  // Selected in turn: Coulomb friction, then nothing more is significant on top of it.
  EXPECT_NE(json.find("\"selected\": [\n    {\"effect\": \"coulomb_friction\""), std::string::npos) << json;
  const std::string end = "],\n  \"verdict\": \"unexplained\"\n}\n";
  EXPECT_EQ(json.substr(json.size() - end.size()), end);
}

TEST_F(Cli, CompareRecordMissingAColumnTheModeNeedsWritesNothing) {
  write("rec.csv", record_text());
  const auto r = run("compare --model configs/fbtb.yaml --data rec.csv --mode open-loop --out out");
  // open-loop has hub_torque and hub_angle: fine; a record without hub_torque is not.
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::string text = "t,ref,hub_angle\n";
  for (int k = 0; k < 30; ++k) text += std::to_string(0.001 * k) + ",0.1,0.0\n";
  write("short.csv", text);
  const auto bad = run("compare --model configs/fbtb.yaml --data short.csv --mode open-loop --out out2");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  expect_one_error_line(bad, "short.csv:1: hub_torque: missing column");
  EXPECT_FALSE(fs::exists(work / "out2"));
}

// ---- complete outputs --------------------------------------------------------------------

TEST_F(Cli, SimulateShortMoveWritesEveryOutput) {
  const auto r = run("simulate configs/fbtb.yaml --out out/sim --set " + quote("trajectory.moves=[{target: 0.2, hold: 2}]"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path out = work / "out" / "sim";

  const auto trace = split_lines(read_text(out / "trace.csv"));
  ASSERT_FALSE(trace.empty());
  EXPECT_EQ(trace[0], kTraceHeader);
  EXPECT_EQ(trace.size() - 1, 5001u);  // 0 .. 5 s at the 1 kHz controller rate
  EXPECT_EQ(trace[1].rfind("0.000000,", 0), 0u) << trace[1];
  EXPECT_EQ(trace.back().rfind("5.000000,", 0), 0u) << trace.back();

  const auto metrics = split_lines(read_text(out / "metrics.csv"));
  ASSERT_EQ(metrics.size(), 2u);
  EXPECT_EQ(metrics[0].rfind("eval_id,seed,label,status,m1_tip_settling_s", 0), 0u) << metrics[0];
  EXPECT_EQ(metrics[1].rfind("0,", 0), 0u) << metrics[1];

  const std::string table = read_text(out / "table.md");
  EXPECT_NE(table.find("0 -> 0.2 rad"), std::string::npos) << table;

  for (const char* png : kPlots) expect_png(out / png);
  expect_no_tmp_files(work / "out");
  EXPECT_EQ(tree(out).size(), 7u);  // trace.csv, metrics.csv, table.md, four PNGs
}

// (#32.8) A run that goes non-finite (PD gain 1e12, one explicit RK4 step a period) writes its outputs and
// exits 3, as `run` does, so a script can tell; (#32.12) its metrics are "-", not "not settled".
TEST_F(Cli, SimulateOfARunThatGoesNonFiniteExitsThreeWithNoValues) {
  const auto r = run("simulate configs/fbtb.yaml --out out --set controller.kp=1e12 --set simulation.integrator=rk4 "
                     "--set simulation.substeps=1 --set " + quote("trajectory.moves=[{target: 0.5, hold: 2}]"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("status: nonfinite"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("flexfarm: error: the run failed numerically (status nonfinite): it has no metrics"), std::string::npos)
      << r.output;
  const auto metrics = split_lines(read_text(work / "out" / "metrics.csv"));
  ASSERT_EQ(metrics.size(), 2u);
  EXPECT_NE(metrics[1].find(",nonfinite,,,"), std::string::npos) << metrics[1];
  const std::string table = read_text(work / "out" / "table.md");
  EXPECT_NE(table.find("| - | - | - | - | - | - | - |"), std::string::npos) << table;
  EXPECT_EQ(table.find("not settled"), std::string::npos) << table;
  for (const char* png : kPlots) expect_png(work / "out" / png);

  const auto arm = run("simulate " + kSource + "/configs/two_link_flexible.yaml --out arm --set joints.shoulder.controller.kp=1.0e12 "
                       "--set simulation.integrator=rk4 --set simulation.substeps=1");
  EXPECT_EQ(arm.exit_code, 3) << arm.output;
  EXPECT_NE(arm.output.find("status: nonfinite"), std::string::npos) << arm.output;
  const std::string arm_table = read_text(work / "arm" / "table.md");
  EXPECT_NE(arm_table.find("| tool_settling_s | - |"), std::string::npos) << arm_table;
  EXPECT_NE(arm_table.find("| shoulder_overshoot_pct | - |"), std::string::npos) << arm_table;
  EXPECT_EQ(arm_table.find("not settled"), std::string::npos) << arm_table;
  // A run that is fine exits 0; one that did not settle too (a result), its settling time a bound.
  const auto slow = run("simulate " + kSource + "/configs/two_link_flexible.yaml --out slow --set simulation.settle=0.5");
  EXPECT_EQ(slow.exit_code, 0) << slow.output;
  EXPECT_NE(read_text(work / "slow" / "table.md").find("| tool_settling_s | > 0"), std::string::npos) << read_text(work / "slow" / "table.md");
}

TEST_F(Cli, RunShortStudyWritesEveryOutput) {
  write("study.yaml",
        "name: short\n"
        "model: configs/fbtb.yaml\n"
        "set:\n"
        "  trajectory.moves: [{target: 0.2, hold: 1}]\n"
        "runs:\n"
        "  - label: PD\n"
        "  - label: PD + notch\n"
        "    set: {notch.enabled: true}\n");
  const auto r = run("run study.yaml --out res --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path out = work / "res";
  const auto results = split_lines(read_text(out / "results.csv"));
  ASSERT_EQ(results.size(), 3u);
  EXPECT_EQ(results[0].rfind("eval_id,seed,label,status,notch.enabled,m1_tip_settling_s", 0), 0u) << results[0];
  EXPECT_NE(results[1].find(",PD,"), std::string::npos) << results[1];
  EXPECT_EQ(results[1].rfind("0,", 0), 0u) << results[1];
  EXPECT_NE(results[2].find(",PD + notch,"), std::string::npos) << results[2];
  EXPECT_EQ(results[2].rfind("1,", 0), 0u) << results[2];
  for (const char* trace : {"000000.csv", "000001.csv"}) {
    const auto lines = split_lines(read_text(out / "traces" / trace));
    ASSERT_FALSE(lines.empty()) << trace;
    EXPECT_EQ(lines[0], kTraceHeader);
    EXPECT_EQ(lines.size() - 1, 4001u) << trace;
  }
  EXPECT_EQ(read_text(out / "table.md").rfind("# short", 0), 0u);
  for (const char* png : kPlots) expect_png(out / png);
  expect_no_tmp_files(out);
}

// ---- vector width (common/isa.hpp) ----------------------------------------------------------

TEST_F(Cli, VersionNamesTheVectorWidthInUse) {
  const auto r = run_shell("FLEXFARM_ISA=sse2 " + quote(kBinary) + " --version");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The version, the commit built from when known (cmake/version.cmake), then the kernels' width.
  EXPECT_TRUE(std::regex_search(r.output, std::regex(R"(^flexfarm 0\.1\.0( \([0-9a-f]{12}(-dirty)?\))?, kernels sse2 \(this CPU and build: up to )")))
      << r.output;
}

TEST_F(Cli, ABadVectorWidthIsOneErrorLine) {
  const auto r = run_shell("FLEXFARM_ISA=avx3 " + quote(kBinary) + " simulate configs/fbtb.yaml --out out");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  expect_one_error_line(r, "environment: FLEXFARM_ISA: 'avx3' is not a vector width (sse2, avx2 or avx512)");
  EXPECT_FALSE(fs::exists(work / "out"));
}

// The same outputs, byte for byte, at every width the CPU runs: a trace of the rig, and a Monte Carlo
// study of the rig on SDIRK2 in lanes of 3 over 2 threads with its traces.
TEST_F(Cli, EveryVectorWidthWritesTheSameBytes) {
  write("study.yaml",
        "name: widths\n"
        "seed: 7\n"
        "model: configs/fbtb.yaml\n"
        "set:\n"
        "  trajectory.moves: [{target: 0.3, hold: 0.5}]\n"
        "  simulation.integrator: sdirk2\n"
        "variables:\n"
        "  - path: payload.mass\n"
        "    distribution: {type: uniform, lower: 100.0, upper: 500.0}\n"
        "  - path: joints.stiffness\n"
        "    distribution: {type: uniform, lower: 2.0e4, upper: 6.0e4}\n"
        "design: {type: monte_carlo, samples: 7}\n");
  const std::string moves = quote("trajectory.moves=[{target: 0.4, hold: 1}]");
  std::vector<std::string> widths;
  for (const char* isa : {"sse2", "avx2", "avx512"}) {
    const auto v = run_shell(std::string("FLEXFARM_ISA=") + isa + " " + quote(kBinary) + " --version");
    if (v.output.find(std::string("kernels ") + isa + " ") == std::string::npos) continue;  // not on this CPU
    widths.push_back(isa);
    const std::string env = std::string("FLEXFARM_ISA=") + isa + " " + quote(kBinary);
    ASSERT_EQ(run_shell(env + " simulate configs/fbtb.yaml --set " + moves + " --out sim_" + isa).exit_code, 0);
    const auto r = run_shell(env + " run study.yaml --lanes 3 --threads 2 --out run_" + isa);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  if (widths.size() < 2) GTEST_SKIP() << "this CPU or build runs one width only";
  for (std::size_t i = 1; i < widths.size(); ++i) {
    EXPECT_EQ(read_text(work / ("sim_" + widths[i]) / "trace.csv"), read_text(work / ("sim_" + widths[0]) / "trace.csv"))
        << widths[i];
    EXPECT_EQ(read_text(work / ("run_" + widths[i]) / "results.csv"),
              read_text(work / ("run_" + widths[0]) / "results.csv"))
        << widths[i];
    for (const char* trace : {"000000.csv", "000006.csv"})
      EXPECT_EQ(read_text(work / ("run_" + widths[i]) / "traces" / trace),
                read_text(work / ("run_" + widths[0]) / "traces" / trace))
          << widths[i] << " " << trace;
  }
}

// Without traces the rig's metrics accumulate online (kernel/online_metrics.hpp): the same results.csv,
// byte for byte, as from the stored traces. Two moves (up, then down past the start), random rigs of
// which some settle and some do not, lanes not dividing the variants.
TEST_F(Cli, RunWithoutTracesGivesTheResultsOfTheTraces) {
  const auto study = [](bool traces) {
    return std::string("name: online\n"
                       "model: configs/fbtb.yaml\n"
                       "seed: 13\n"
                       "set:\n"
                       "  trajectory.moves: [{target: 0.3, hold: 6.0}, {target: -0.1, hold: 5.0}]\n"
                       "  notch.enabled: true\n"
                       "  controller.model: plant\n"  // the notch placed for each variant: some settle
                       "variables:\n"
                       "  - path: payload.mass\n"
                       "    distribution: {type: uniform, lower: 150.0, upper: 450.0}\n"
                       "  - path: joints.damping\n"
                       "    distribution: {type: uniform, lower: 20.0, upper: 200.0}\n"
                       "design: {type: monte_carlo, samples: 7}\n"
                       "outputs: {traces: ") +
           (traces ? "true" : "false") + "}\n";
  };
  write("with.yaml", study(true));
  write("without.yaml", study(false));
  const auto a = run("run with.yaml --out with --threads 2 --lanes 3");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const auto b = run("run without.yaml --out without --threads 2 --lanes 3");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  EXPECT_TRUE(fs::exists(work / "with" / "traces" / "000006.csv"));
  EXPECT_FALSE(fs::exists(work / "without" / "traces"));
  const std::string with = read_text(work / "with" / "results.csv");
  ASSERT_EQ(split_lines(with).size(), 8u) << with;
  EXPECT_NE(with.find(",ok,"), std::string::npos) << with;
  EXPECT_NE(with.find(",not_settled,"), std::string::npos) << with;
  EXPECT_EQ(read_text(work / "without" / "results.csv"), with);
}

TEST_F(Cli, CompareModelWithItsOwnTraceWritesEveryOutput) {
  const std::string moves = quote("trajectory.moves=[{target: 0.2, hold: 1}]");
  ASSERT_EQ(run("simulate configs/fbtb.yaml --out sim --set " + moves).exit_code, 0);
  const auto r = run("compare --model configs/fbtb.yaml --data sim/trace.csv --set " + moves + " --k 5 --out cmp");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("| hub_angle | rad | 100.00 | 100.00 |"), std::string::npos) << r.output;
  const fs::path out = work / "cmp";
  const std::string json = read_text(out / "compare.json");
  EXPECT_NE(json.find("\"k\": 5,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"hub_angle\": {\"free_run\": 99.9999"), std::string::npos) << json;  // the trace has 10 digits
  EXPECT_NE(read_text(out / "report.md").find("| hub_torque | N m | 100.00 | 100.00 |"), std::string::npos);
  for (const char* ch : {"hub_angle", "tip_deflection", "hub_torque"})
    for (const std::string kind : {"overlay_", "acf_", "ccf_", "spectrum_", "binned_"})
      expect_png(out / (kind + ch + (kind == "binned_" ? "_hub_velocity" : "") + ".png"));
  expect_no_tmp_files(work);
  EXPECT_EQ(tree(out).size(), 2u + 3u * 9u);
  // Into an existing directory: the files are replaced, no staging directory is left.
  ASSERT_EQ(run("compare --model configs/fbtb.yaml --data sim/trace.csv --set " + moves + " --out cmp").exit_code, 0);
  EXPECT_EQ(tree(out).size(), 2u + 3u * 9u);
  for (const auto& e : fs::directory_iterator(work))
    EXPECT_EQ(e.path().filename().string().find(".partial"), std::string::npos) << e.path();
}

}  // namespace

// ---- arm models ---------------------------------------------------------------------------

namespace {
// A 2 kg bob 0.5 m out on a hinge about y, gravity compensated: it holds every pose it is sent to.
const char* kPendulumArm =
    "description: held pendulum\n"
    "gravity: [0, 0, -9.81]\n"
    "bodies:\n"
    "  - name: arm\n"
    "    parent: base\n"
    "    mass: 2.0\n"
    "    com: [0.5, 0, 0]\n"
    "    inertia: {ixx: 0.001, iyy: 0.01, izz: 0.01}\n"
    "    joint: {axis: [0, 1, 0], armature: 0.05}\n"
    "tool: {body: arm, point: [0.5, 0, 0]}\n"
    "controller: {rate: 500}\n"
    "joints:\n"
    "  arm: {controller: {kp: 400, kd: 40, feedforward: 1, gravity_compensation: 1}}\n"
    "trajectory:\n"
    "  waypoints:\n"
    "    - {time: 1.0, joints: {arm: -0.5}}\n"
    "simulation: {settle: 2.0}\n";
}  // namespace

TEST_F(Cli, SimulateAnArmModelWritesItsTraceMetricsAndPlots) {
  write("arm.yaml", kPendulumArm);
  const auto r = run("simulate arm.yaml --out out/arm");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path out = work / "out" / "arm";
  const auto trace = split_lines(read_text(out / "trace.csv"));
  ASSERT_EQ(trace.size(), 1u + 1501u);  // 0 .. 3 s at 500 Hz
  EXPECT_EQ(trace[0], "t,arm.ref,arm.q,arm.qd,arm.torque,tool.x,tool.y,tool.z,tool.ref_x,tool.ref_y,tool.ref_z,arm.q_measured,arm.qd_measured");
  // At rest at the end: the tool at 0.5 (cos 0.5, 0, sin 0.5) (a turn of -0.5 about y lifts it).
  std::vector<std::string> last;
  std::stringstream row(trace.back());
  for (std::string cell; std::getline(row, cell, ',');) last.push_back(cell);
  EXPECT_NEAR(std::stod(last[5]), 0.5 * std::cos(0.5), 1e-5);
  EXPECT_NEAR(std::stod(last[7]), 0.5 * std::sin(0.5), 1e-5);
  const auto metrics = split_lines(read_text(out / "metrics.csv"));
  ASSERT_EQ(metrics.size(), 2u);
  EXPECT_EQ(metrics[0].rfind("eval_id,seed,label,status,arm_settling_s,arm_overshoot_pct,arm_peak_torque_Nm", 0), 0u)
      << metrics[0];
  EXPECT_NE(metrics[1].find(",ok,"), std::string::npos) << metrics[1];
  for (const char* png : {"joints.png", "torques.png", "tool_error.png"}) expect_png(out / png);
  EXPECT_FALSE(fs::exists(out / "deflection.png"));  // no flexible link
  expect_no_tmp_files(work / "out");
}

TEST_F(Cli, AnArmStudyRunsPlotsAndTabulatesEveryVariant) {
  write("arm.yaml", kPendulumArm);
  write("study.yaml",
        "name: pendulum gains\n"
        "model: arm.yaml\n"
        "variables:\n"
        "  - path: joints.arm.controller.kp\n"
        "    levels: [200, 400]\n"
        "  - path: bodies[arm].mass\n"
        "    levels: [1.0, 2.0]\n"
        "design: {type: grid}\n");
  const auto r = run("run study.yaml --out res --threads 2 --lanes 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto results = split_lines(read_text(work / "res" / "results.csv"));
  ASSERT_EQ(results.size(), 5u);
  EXPECT_EQ(results[0].rfind("eval_id,seed,label,status,joints.arm.controller.kp,bodies[arm].mass,arm_settling_s", 0), 0u)
      << results[0];
  for (int k = 0; k < 4; ++k) EXPECT_TRUE(fs::exists(work / "res" / "traces" / ("00000" + std::to_string(k) + ".csv")));
  expect_png(work / "res" / "joints.png");
  // The same rows with one lane per batch and one thread.
  ASSERT_EQ(run("run study.yaml --out res1 --threads 1 --lanes 1").exit_code, 0);
  EXPECT_EQ(read_text(work / "res1" / "results.csv"), read_text(work / "res" / "results.csv"));
  const auto t = run("table res --by joints.arm.controller.kp");
  ASSERT_EQ(t.exit_code, 0) << t.output;
  EXPECT_NE(t.output.find("tool_settling_s"), std::string::npos) << t.output;
  const auto p = run("plot study.yaml --eval 0,3 --out plots");
  ASSERT_EQ(p.exit_code, 0) << p.output;
  EXPECT_EQ(read_text(work / "plots" / "trace_000003.csv"), read_text(work / "res" / "traces" / "000003.csv"));
}

TEST_F(Cli, AnArmStudyInShardsMergesToTheOneProcessTableAndAKilledRunResumes) {
  write("arm.yaml", kPendulumArm);
  write("study.yaml",
        "name: pendulum draws\n"
        "model: arm.yaml\n"
        "seed: 3\n"
        "variables:\n"
        "  - path: bodies[arm].mass\n"
        "    distribution: {type: uniform, lower: 1.0, upper: 3.0}\n"
        "design: {type: monte_carlo, samples: 10}\n");
  ASSERT_EQ(run("run study.yaml --out one").exit_code, 0);
  for (const char* shard : {"0/2", "1/2"}) ASSERT_EQ(run(std::string("run study.yaml --out two --shard ") + shard).exit_code, 0);
  const auto m = run("merge study.yaml --out two");
  ASSERT_EQ(m.exit_code, 0) << m.output;
  EXPECT_EQ(read_text(work / "two" / "results.csv"), read_text(work / "one" / "results.csv"));
  // A journal cut after its first rows (a run killed mid-way) resumes to the same table.
  ASSERT_EQ(run("run study.yaml --out three --lanes 2").exit_code, 0);
  const auto journal = split_lines(read_text(work / "three" / "journal-main.csv"));
  ASSERT_GT(journal.size(), 4u);
  {
    std::ofstream cut(work / "three" / "journal-main.csv");
    for (std::size_t k = 0; k < 4; ++k) cut << journal[k] << "\n";
  }
  fs::remove(work / "three" / "results.csv");
  const auto r = run("run study.yaml --out three --resume");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_text(work / "three" / "results.csv"), read_text(work / "one" / "results.csv"));
}

TEST_F(Cli, ModesOfAnArmModelAreClampedAndClosedLoopAndItsSagIsPrinted) {
  // The held pendulum's closed loop with kd = 10: omega_n^2 = kp / J, zeta = kd / (2 sqrt(kp J)) (no
  // spring; gravity's stiffness m g l sin q is 0 at q = 0), J = m l^2 + I_yy + armature.
  write("arm.yaml", kPendulumArm);
  const auto r = run("modes arm.yaml --static --set joints.arm.controller.kd=10");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("clamped (the actuated joints held)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("closed loop"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("static deflection under gravity"), std::string::npos) << r.output;
  const double J = 2.0 * 0.25 + 0.01 + 0.05, w = std::sqrt(400.0 / J), zeta = 10.0 / (2.0 * std::sqrt(400.0 * J));
  char expect[64];
  std::snprintf(expect, sizeof expect, " %.4f %12.4f %10.4f", w / (2 * 3.141592653589793), w, zeta);
  EXPECT_NE(r.output.find(expect), std::string::npos) << expect << " in " << r.output;
}

TEST_F(Cli, AnArmAnimationWritesItsVideoAndFrame) {
  write("arm.yaml", kPendulumArm);
  const auto r = run("animate arm.yaml --out arm.avi --frame frame.png --at 1.0 --fps 10");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_GT(fs::file_size(work / "arm.avi"), 1000u);
  expect_png(work / "frame.png");
}

TEST_F(Cli, ABadArmModelIsOneLineAndWritesNothing) {
  std::string text = kPendulumArm;
  text.replace(text.find("kp: 400"), 7, "kq: 400");
  write("arm.yaml", text);
  expect_one_error_line(run("simulate arm.yaml --out out/arm"), "arm.yaml:13: joints.arm.controller.kq: unknown key (did you mean `kd`?)");
  EXPECT_FALSE(fs::exists(work / "out"));
  write("arm.yaml", kPendulumArm);
  expect_one_error_line(run("simulate arm.yaml --out out/arm --set trajectory.waypoints[0].joints.elbow=1"),
                        "--set: trajectory.waypoints[0].joints.elbow: no moving joint of that name");
  expect_one_error_line(run("simulate arm.yaml --out out/arm --set trajectory.waypoints[0].tool=[2,0,0]"),
                        "--set: trajectory.waypoints[0].tool: a waypoint is either");
  EXPECT_FALSE(fs::exists(work / "out"));
}

// ---- paths and names from hostile or careless input (issue 32) --------------------------------

// (#32.4) An empty or blank path, an unset $OUT in a script, is a usage error for every verb and every
// option or argument that names a path: exit 2, one line naming the option, nothing written anywhere
// (not "/journal-main.csv" at the filesystem root).
TEST_F(Cli, AnEmptyOrBlankPathIsAUsageErrorForEveryVerbAndPathOption) {
  write("s.yaml", "name: s\nmodel: configs/fbtb.yaml\nruns:\n  - label: a\n");
  write("d.csv", "t,ref\n0,0\n");
  const std::pair<const char*, const char*> cases[] = {
      {"modes @", "model"},
      {"modes configs/fbtb.yaml --sidecar @", "--sidecar"},
      {"modes configs/fbtb.yaml --shapes @", "--shapes"},
      {"simulate @ --out o", "model"},
      {"simulate configs/fbtb.yaml --out @", "--out"},
      {"run @ --out o", "study"},
      {"run s.yaml --out @", "--out"},
      {"run s.yaml --out o --history @", "--history"},
      {"merge @ --out configs", "study"},
      {"merge s.yaml --out @", "--out"},
      {"merge s.yaml --out configs --history @", "--history"},
      {"table @", "results"},
      {"history @", "what"},
      {"history --history @", "--history"},
      {"diff @", "runs"},
      {"diff configs @", "runs"},
      {"diff configs --history @", "--history"},
      {"diff configs --out @", "--out"},
      {"plot @ --eval 0 --out o", "study"},
      {"plot s.yaml --eval 0 --out @", "--out"},
      {"animate @ --out a.avi", "input"},
      {"animate configs/fbtb.yaml --out @", "--out"},
      {"animate configs/fbtb.yaml --out a.avi --frame @", "--frame"},
      {"view @ --out v.html", "input"},
      {"view configs/fbtb.yaml --out @", "--out"},
      {"compare --model @ --data d.csv --out o", "--model"},
      {"compare --model configs/fbtb.yaml --data @ --out o", "--data"},
      {"compare --model configs/fbtb.yaml --data d.csv --out @", "--out"},
      {"diagnose --model @ --data d.csv --json j.json", "--model"},
      {"diagnose --model configs/fbtb.yaml --data @ --json j.json", "--data"},
      {"diagnose --model configs/fbtb.yaml --data d.csv --json @", "--json"},
      {"calibrate --model @ --data d.csv --add x --out n.yaml", "--model"},
      {"calibrate --model configs/fbtb.yaml --data @ --add x --out n.yaml", "--data"},
      {"calibrate --model configs/fbtb.yaml --data d.csv --add x --out @", "--out"},
      {"calibrate --model configs/fbtb.yaml --data d.csv --add x --out n.yaml --ledger @", "--ledger"},
      {"record @ --out r.csv", "model"},
      {"record configs/fbtb.yaml --out @", "--out"},
  };
  const std::vector<std::string> before = tree(work);
  for (const auto& [command, option] : cases)
    for (const std::string blank : {"''", "'  '", "'\t'"}) {
      std::string args = command;
      args.replace(args.find('@'), 1, blank);
      const auto r = run(args);
      EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
      EXPECT_EQ(r.output.rfind(std::string(option) + ": an empty or blank path (an unset variable?)", 0), 0u) << args << "\n" << r.output;
      EXPECT_EQ(tree(work), before) << args;
    }
  for (const char* root : {"/journal-main.csv", "/journal-main.lock", "/timings-main.csv", "/traces"})
    EXPECT_FALSE(fs::exists(root)) << root;
  // A path in a file, blank: one line naming the file, line and key.
  write("blank_model.yaml", "name: s\nmodel: \"  \"\nruns:\n  - label: a\n");
  expect_one_error_line(run("run blank_model.yaml --out o"), "blank_model.yaml:2: model: must not be empty or blank");
  write("blank_urdf.yaml", "urdf: \" \"\n");
  expect_one_error_line(run("modes blank_urdf.yaml"), "blank_urdf.yaml:1: urdf: must not be empty or blank");
  EXPECT_FALSE(fs::exists(work / "o"));
  // A history directory from a variable set blank: the same, before anything runs.
  const auto r = run_shell("FLEXFARM_HISTORY='  ' " + quote(kBinary) + " run s.yaml --out o");
  expect_one_error_line(r, "$FLEXFARM_HISTORY: a blank path; unset it or give --history DIR");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(fs::exists(work / "o"));
}

// (#32.21) A study named with an escape sequence and the report's placeholder, a run label with '|':
// report.html is whole (filled in one pass), table.md's rows keep their columns ('|' escaped), and no
// escape sequence reaches the terminal from the run, its progress line, `history` or an error.
TEST_F(Cli, HostileNamesKeepTheReportAndTablesWholeAndReachTheTerminalAsText) {
  write("s.yaml", "name: \"red\\e[31m@@BODY@@\"\nmodel: configs/fbtb.yaml\nset:\n  trajectory.moves: [{target: 0.2, hold: 1}]\n"
                  "runs:\n  - label: \"left | right\"\n  - label: \"a|b\\e]0;owned\\a\"\n");
  const std::string history = "FLEXFARM_HISTORY=" + quote((base / "history").string()) + " ";
  const auto r = run_shell(history + quote(kBinary) + " run s.yaml --out o");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find('\x1b'), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("red?[31m@@BODY@@: 100%"), std::string::npos) << r.output;  // the progress line
  const std::string html = read_text(work / "o/report.html");
  EXPECT_NE(html.find("<title>red\x1b[31m@@BODY@@: flexfarm report</title>"), std::string::npos);
  EXPECT_NE(html.find("<h2 id=\"provenance\">"), std::string::npos);
  EXPECT_NE(html.find("</html>"), std::string::npos);
  EXPECT_NE(html.find("<td>left | right</td><td>0 -&gt; 0.2 rad</td>"), std::string::npos);
  // table.md: a row per run, each with as many unescaped '|' as the header.
  const auto table = split_lines(read_text(work / "o/table.md"));
  const auto bars = [](const std::string& line) {
    int n = 0;
    for (std::size_t i = 0; i < line.size(); ++i) n += line[i] == '|' && (i == 0 || line[i - 1] != '\\');
    return n;
  };
  const auto header = std::find_if(table.begin(), table.end(), [](const std::string& l) { return l.rfind("| run | move |", 0) == 0; });
  ASSERT_NE(header, table.end()) << read_text(work / "o/table.md");
  EXPECT_EQ(header[2].rfind("| left \\| right | 0 -> 0.2 rad |", 0), 0u) << header[2];
  EXPECT_EQ(header[3].rfind("| a\\|b\x1b]0;owned\a | 0 -> 0.2 rad |", 0), 0u) << header[3];
  for (int k : {2, 3}) EXPECT_EQ(bars(header[k]), bars(header[0])) << header[k];
  const auto listed = run_shell(history + quote(kBinary) + " history");
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  EXPECT_EQ(listed.output.find('\x1b'), std::string::npos) << listed.output;
  EXPECT_NE(listed.output.find("| red?[31m@@BODY@@ |"), std::string::npos) << listed.output;
  const auto one = run_shell(history + quote(kBinary) + " history 1");
  EXPECT_EQ(one.output.find('\x1b'), std::string::npos) << one.output;
  // An error quoting a path with an escape sequence in it.
  const auto error = run("table 'no\x1b[2Jdir'");
  EXPECT_EQ(error.exit_code, 2) << error.output;
  EXPECT_EQ(error.output.find('\x1b'), std::string::npos) << error.output;
  EXPECT_NE(error.output.find("no?[2Jdir"), std::string::npos) << error.output;
}
