// Tests of study files (sweep/study.hpp): the paper study loads into its four variants, and bad
// study files are rejected with one ConfigError naming the study file, the line and the study key.
#include "sweep/study.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "common/errors.hpp"
#include "arm/arm_simulate.hpp"
#include "kernel/model_io.hpp"
#include "tests/temp_dir.hpp"

namespace {

namespace fs = std::filesystem;

const std::string kSource = FLEXFARM_SOURCE_DIR;
const std::string kModel = kSource + "/configs/fbtb.yaml";
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// A grid study of the reference rig with two cases, plain and notched, over `variables` (YAML list items).
std::string plain_and_notched_study(const std::string& variables) {
  return "model: " + kModel + "\ncases:\n  - label: plain\n  - label: notched\n    set: {notch.enabled: true}\n" +
         "variables:\n" + variables + "design: {type: grid}\n";
}

// A fresh directory per test, removed with its contents.
class StudyFiles : public ::testing::Test {
 protected:
  ff::test::TempDir temp{"ff_study"};
  const fs::path& dir = temp.path;
  std::string write(const std::string& name, const std::string& text) { return temp.write(name, text); }
  // Loads `path`, which must fail; returns the error.
  static ff::ConfigError load_error(const std::string& path) {
    try {
      ff::load_study(path);
    } catch (const ff::ConfigError& e) {
      return e;
    }
    ADD_FAILURE() << path << " was accepted";
    return ff::ConfigError("", 0, "", "");
  }
  // Reads `path` with a limit of `max_variants`, which must fail; returns the error.
  static ff::ConfigError read_error(const std::string& path, int max_variants) {
    try {
      ff::read_study(path, max_variants);
    } catch (const ff::ConfigError& e) {
      return e;
    }
    ADD_FAILURE() << path << " was accepted with at most " << max_variants << " variants";
    return ff::ConfigError("", 0, "", "");
  }
};

// ---- the paper study ---------------------------------------------------------------------

TEST(PaperStudy, LoadsFourVariantsWithLabelsAndIds) {
  const ff::Study st = ff::load_study(kSource + "/configs/studies/fbtb_paper.yaml");
  EXPECT_EQ(st.name, "fbtb_paper");
  EXPECT_FALSE(st.description.empty());
  EXPECT_EQ(fs::path(st.model_path).filename(), "fbtb.yaml");
  EXPECT_TRUE(fs::equivalent(st.model_path, kModel));
  ASSERT_EQ(st.variants.size(), 4u);
  const char* labels[] = {"PD, 0.5 rad", "PD + notch, 0.5 rad", "PD, 1.0 rad", "PD + notch, 1.0 rad"};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(st.variants[i].eval_id, i);
    EXPECT_EQ(st.variants[i].label, labels[i]);
    const auto set = ff::make_variant_set(st, st.variants[i]);
    ASSERT_EQ(set.size(), st.set.size() + 2u);
    const ff::Assignment* own = &set[st.set.size()];  // the run's own overrides follow the study's
    EXPECT_EQ(own[0].path, "trajectory.moves[0].target");
    EXPECT_EQ(own[0].key, "runs[" + std::to_string(i) + "].set.trajectory.moves[0].target");
    EXPECT_EQ(own[1].path, "notch.enabled");
  }
  // Line numbers of the set entries in the study file: runs start at line 14, four lines each.
  EXPECT_EQ(ff::make_variant_set(st, st.variants[0])[st.set.size()].line, 16);
  EXPECT_EQ(ff::make_variant_set(st, st.variants[1])[st.set.size() + 1].line, 21);
}

TEST(PaperStudy, TheDescriptionGivesTheModelsMovesAndHolds) {
  // The description says what every variant runs: 3 s moves, 7 s out, then back to 0 and a 45 s hold.
  const ff::Study st = ff::load_study(kSource + "/configs/studies/fbtb_paper.yaml");
  const ff::Model m = ff::make_variant_model(st, st.variants[0]);
  ASSERT_EQ(m.spec.trajectory.moves.size(), 2u);
  EXPECT_EQ(m.spec.trajectory.move_time, 3.0);
  EXPECT_EQ(m.spec.trajectory.moves[0].hold, 7.0);
  EXPECT_EQ(m.spec.trajectory.moves[1].hold, 45.0);
  EXPECT_NE(st.description.find("cubic moves (3 s) of 0.5 rad and 1.0 rad out, 7 s hold, back to 0 and 45 s hold"),
            std::string::npos)
      << st.description;
}

TEST(PaperStudy, VariantOneHasTheNotchAtTheClosedLoopResonances) {
  const ff::Study st = ff::load_study(kSource + "/configs/studies/fbtb_paper.yaml");
  const ff::Model m = ff::make_variant_model(st, st.variants[1]);
  EXPECT_TRUE(m.spec.notch.enabled);
  EXPECT_EQ(m.spec.notch.order, 1);
  EXPECT_DOUBLE_EQ(m.spec.notch.alpha[0], 1.6);
  EXPECT_DOUBLE_EQ(m.spec.notch.zeta[1], 1.0);
  EXPECT_NEAR(m.omega_z[0], kTwoPi * 0.274, 0.005);
  EXPECT_NEAR(m.omega_z[1], kTwoPi * 2.289, 0.01);
  EXPECT_DOUBLE_EQ(m.spec.trajectory.moves[0].target, 0.5);
}

TEST(PaperStudy, VariantsDifferOnlyInTheirOverrides) {
  const ff::Study st = ff::load_study(kSource + "/configs/studies/fbtb_paper.yaml");
  const double targets[] = {0.5, 0.5, 1.0, 1.0};
  const bool notch[] = {false, true, false, true};
  for (int i = 0; i < 4; ++i) {
    const ff::Model m = ff::make_variant_model(st, st.variants[i]);
    EXPECT_EQ(m.nseg, 6);
    EXPECT_DOUBLE_EQ(m.spec.trajectory.moves[0].target, targets[i]) << i;
    EXPECT_EQ(m.spec.notch.enabled, notch[i]) << i;
    EXPECT_DOUBLE_EQ(m.spec.payload_mass, 328.7);
  }
  // A variant's overrides never leak into the shared model document.
  EXPECT_FALSE(ff::make_variant_model(st, st.variants[0]).spec.notch.enabled);
}

// ---- good studies written here -----------------------------------------------------------

TEST_F(StudyFiles, ModelPathIsRelativeToTheStudyFile) {
  fs::create_directories(dir / "studies");
  fs::copy_file(kModel, dir / "rig.yaml");
  const auto path = write("studies/s.yaml", "model: ../rig.yaml\nruns:\n  - set: {payload.mass: 400}\n");
  const ff::Study st = ff::load_study(path);
  EXPECT_EQ(st.name, "s");  // defaults to the file's stem
  EXPECT_TRUE(fs::equivalent(st.model_path, dir / "rig.yaml"));
  ASSERT_EQ(st.variants.size(), 1u);
  EXPECT_EQ(st.variants[0].label, "run 0");
  EXPECT_DOUBLE_EQ(ff::make_variant_model(st, st.variants[0]).spec.payload_mass, 400.0);
}

TEST_F(StudyFiles, AVariablesOrARunsPayloadIsThePlantsAloneAndTheStudysSetAndCasesTheControllers) {
  // The feed-forward's inertia (Model::control_inertia) follows the study's `set:` and its case's, not a
  // variable's or a run's value: those change the plant only (docs/formats.md, "The controller's model").
  const double J_nominal = ff::load_model(kModel).rigid_inertia;
  const auto grid = write("g.yaml", "model: " + kModel + "\nset: {controller.feedforward: 1}\ncases:\n  - label: nominal\n" +
                                         "  - label: heavy\n    set: {payload.mass: 500}\nvariables:\n" +
                                         "  - {path: payload.mass, levels: [300, 400]}\ndesign: {type: grid}\n");
  const ff::Study g = ff::load_study(grid);
  ASSERT_EQ(g.variants.size(), 4u);
  for (std::size_t i = 0; i < 2; ++i) {
    const ff::Model m = ff::make_variant_model(g, g.variants[i]);
    EXPECT_EQ(m.control_inertia, J_nominal) << g.variants[i].label;
    EXPECT_NE(m.rigid_inertia, J_nominal) << g.variants[i].label;
  }
  // The heavy case: the controller knows its 500 kg, the plant has the variable's payload.
  const ff::Model heavy = ff::make_variant_model(g, g.variants[2]);
  EXPECT_DOUBLE_EQ(heavy.spec.payload_mass, 300.0);
  EXPECT_GT(heavy.control_inertia, J_nominal + 2000.0);  // kg m^2: 171 kg more at the tip, 4.17 m out
  const auto runs = write("r.yaml", "model: " + kModel + "\nset: {payload.mass: 400}\nruns:\n  - set: {payload.mass: 300}\n");
  const ff::Study r = ff::load_study(runs);
  const ff::Model run = ff::make_variant_model(r, r.variants[0]);
  EXPECT_DOUBLE_EQ(run.spec.payload_mass, 300.0);
  EXPECT_GT(run.control_inertia, run.rigid_inertia + 1000.0);  // the controller's is the study's 400 kg
}

TEST_F(StudyFiles, StudyWideSetAppliesToEveryRun) {
  const auto path = write("s.yaml", "model: " + kModel + "\nset:\n  segments: 8\nruns:\n  - label: a\n  - label: b\n");
  const ff::Study st = ff::load_study(path);
  for (const auto& v : st.variants) EXPECT_EQ(ff::make_variant_model(st, v).nseg, 8);
}

// A plot's legend names what differs between the variants shown: shared `path=value` items go,
// the case stays; one variant keeps its whole label.
TEST_F(StudyFiles, LegendLabelsDropWhatTheShownVariantsShare) {
  const auto path = write("s.yaml", plain_and_notched_study("  - path: payload.mass\n"
                                                            "    levels: [200, 300]\n"
                                                            "  - path: controller.kp\n"
                                                            "    levels: [1e5, 2e5]\n"));
  const ff::Study st = ff::load_study(path);
  ASSERT_EQ(st.variants.size(), 8u);
  EXPECT_EQ(st.variants[1].label, "plain | payload.mass=200, controller.kp=200000");
  using L = std::vector<std::string>;
  EXPECT_EQ(ff::calc_legend_labels(st, {0, 1}), (L{"plain | controller.kp=100000", "plain | controller.kp=200000"}));
  EXPECT_EQ(ff::calc_legend_labels(st, {0, 4}), (L{"plain", "notched"}));
  EXPECT_EQ(ff::calc_legend_labels(st, {1, 2, 6}),
            (L{"plain | payload.mass=200, controller.kp=200000", "plain | payload.mass=300, controller.kp=100000",
               "notched | payload.mass=300, controller.kp=100000"}));
  EXPECT_EQ(ff::calc_legend_labels(st, {3}), (L{st.variants[3].label}));
  EXPECT_EQ(ff::calc_legend_labels(st, {3, 3}), (L{"plain", "plain"}));
}

TEST_F(StudyFiles, CasesAreCrossedWithEveryDesignPoint) {
  const auto path = write("s.yaml", plain_and_notched_study("  - path: payload.mass\n"
                                                            "    levels: [200, 300, 400]\n"));
  const ff::Study st = ff::load_study(path);
  ASSERT_EQ(st.variants.size(), 6u);
  EXPECT_EQ(st.params, (std::vector<std::string>{"case", "payload.mass"}));
  EXPECT_EQ(st.case_labels, (std::vector<std::string>{"plain", "notched"}));
  const double masses[] = {200, 300, 400};
  for (int i = 0; i < 6; ++i) {
    const auto& v = st.variants[i];
    EXPECT_EQ(v.eval_id, i);
    EXPECT_EQ(v.params[0], i / 3);
    EXPECT_EQ(v.params[1], masses[i % 3]);
    const auto m = ff::make_variant_model(st, v);
    EXPECT_EQ(m.spec.notch.enabled, i >= 3);
    EXPECT_DOUBLE_EQ(m.spec.payload_mass, masses[i % 3]);
  }
  EXPECT_EQ(st.variants[4].label, "notched | payload.mass=300");
}

// ---- bad studies -------------------------------------------------------------------------

TEST_F(StudyFiles, UnknownKeyInARunIsRejectedWithItsLine) {
  const auto path = write("s.yaml",
                          "model: " + kModel +
                              "\n"
                              "runs:\n"
                              "  - label: a\n"
                              "    colour: red\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 4);
  EXPECT_EQ(e.key(), "runs[0].colour");
  EXPECT_NE(e.message().find("unknown key"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, UnknownTopLevelKeyIsRejected) {
  const auto path = write("s.yaml", "model: " + kModel + "\nrusn:\n  - label: a\nruns:\n  - label: a\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.key(), "rusn");
  EXPECT_NE(e.message().find("unknown key"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, AMisspeltKeyNamesTheClosestValidKey) {
  const auto path = write("s.yaml", "model: " + kModel + "\nrusn:\n  - label: a\nruns:\n  - label: a\n");
  EXPECT_EQ(std::string(load_error(path).what()), path + ":2: rusn: unknown key (did you mean `runs`?)");
  const auto nested = write("t.yaml", "model: " + kModel + "\nruns:\n  - lable: a\n");
  EXPECT_EQ(std::string(load_error(nested).what()), nested + ":3: runs[0].lable: unknown key (did you mean `label`?)");
}

TEST_F(StudyFiles, AModelFileGivenAsAStudyIsNamedWithTheVerbThatTakesIt) {
  // `flexfarm run configs/fbtb.yaml`: not "model: missing required value".
  EXPECT_EQ(std::string(load_error(kModel).what()),
            kModel + ":4: this is a model file (it has `beam:`), not a study: simulate it with `flexfarm simulate " + kModel +
                " --out DIR` (or `flexfarm modes " + kModel + "`); `flexfarm run` takes a study file, whose `model:` names a model file");
  const std::string arm = kSource + "/configs/two_link_flexible.yaml";
  EXPECT_NE(std::string(load_error(arm).what()).find("this is a model file (it has `bodies:`), not a study"), std::string::npos);
  // A study whose model is a study.
  const auto inner = write("inner.yaml", "model: " + kModel + "\nruns:\n  - label: a\n");
  const auto outer = write("outer.yaml", "model: inner.yaml\nruns:\n  - label: a\n");
  EXPECT_NE(std::string(load_error(outer).what()).find(inner + ":1: model: this is a study file"), std::string::npos)
      << load_error(outer).what();
}

// (#32.9) A misspelled metric under specs: or tolerances: is refused when the study is loaded, naming the
// line and key, the closest column and the columns: a spec or regression guard that names no column
// would never fire. The rig's columns and an arm's.
TEST_F(StudyFiles, AMisspelledSpecOrToleranceIsRefusedWithTheClosestColumn) {
  const std::string rig = "name: s\nmodel: " + kModel + "\nruns:\n  - label: a\n";
  auto e = load_error(write("spec.yaml", rig + "specs:\n  m1_tip_settling_s: 3\n  m1_tip_setling_s: 3\n"));
  EXPECT_EQ(e.line(), 7);
  EXPECT_EQ(e.key(), "specs.m1_tip_setling_s");
  EXPECT_EQ(e.message().rfind("'m1_tip_setling_s' is not a result column (did you mean `m1_tip_settling_s`?) (the columns: "
                              "m1_tip_settling_s, m1_tip_overshoot_pct, ", 0), 0u) << e.what();
  e = load_error(write("tol.yaml", rig + "tolerances:\n  m1_peak_torque_Nm: {increase: 3%}\n  m1_peak_torqe_Nm: {increase: 3%}\n"));
  EXPECT_EQ(e.line(), 7);
  EXPECT_EQ(e.key(), "tolerances.m1_peak_torqe_Nm");
  EXPECT_NE(e.message().find("(did you mean `m1_peak_torque_Nm`?)"), std::string::npos) << e.what();
  // A name far from every column: no guess, the list.
  e = load_error(write("far.yaml", rig + "specs:\n  overshoot: 3\n"));
  EXPECT_EQ(e.message().rfind("'overshoot' is not a result column (the columns: m1_tip_settling_s, ", 0), 0u) << e.what();
  // An arm study: its own columns (the tool's).
  const std::string arm = "name: a\nmodel: " + kSource + "/configs/two_link_flexible.yaml\nruns:\n  - label: a\n";
  e = load_error(write("arm.yaml", arm + "specs:\n  tool_setling_s: 2\n"));
  EXPECT_EQ(e.line(), 6);
  EXPECT_EQ(e.key(), "specs.tool_setling_s");
  EXPECT_NE(e.message().find("(did you mean `tool_settling_s`?)"), std::string::npos) << e.what();
  EXPECT_NO_THROW(ff::load_study(write("ok.yaml", arm + "specs:\n  tool_settling_s: 2\ntolerances:\n  tool_sag_m: {increase: 1%}\n")));
  // Read from a recorded study text (flexfarm diff): the same check against the run's columns.
  const ff::StudyCriteria c = ff::read_study_criteria("tolerances:\n  tool_setling_s: {increase: 1}\n", "rec.yaml");
  try {
    ff::check_criteria_columns(c, {"tool_settling_s", "settling_horizon_s"});
    ADD_FAILURE() << "accepted";
  } catch (const ff::ConfigError& x) {
    EXPECT_STREQ(x.what(), "rec.yaml:2: tolerances.tool_setling_s: 'tool_setling_s' is not a result column (did you mean "
                           "`tool_settling_s`?) (the columns: tool_settling_s, settling_horizon_s)");
  }
}

TEST_F(StudyFiles, NegativeMassInARunNamesTheStudyLineAndKey) {
  const auto path = write("s.yaml",
                          "name: bad\n"
                          "model: " + kModel +
                              "\n"
                              "runs:\n"
                              "  - label: heavy\n"
                              "    set:\n"
                              "      payload.mass: -1\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);  // the STUDY file, not the model
  EXPECT_EQ(e.line(), 6);
  EXPECT_EQ(e.key(), "runs[0].set.payload.mass");
  EXPECT_NE(e.message().find(">= 0"), std::string::npos) << e.what();
  EXPECT_EQ(std::string(e.what()).rfind(path + ":6: runs[0].set.payload.mass: ", 0), 0u) << e.what();
}

TEST_F(StudyFiles, BadValueInALaterRunNamesThatRun) {
  const auto path = write("s.yaml",
                          "model: " + kModel +
                              "\n"
                              "runs:\n"
                              "  - set: {segments: 4}\n"
                              "  - label: b\n"
                              "    set:\n"
                              "      trajectory.moves[1].target: 0.5\n");  // = moves[0]: zero amplitude
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 6);
  EXPECT_EQ(e.key(), "runs[1].set.trajectory.moves[1].target");
  EXPECT_NE(e.message().find("zero amplitude"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, WrongTypeInARunIsRejected) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns:\n  - set:\n      segments: six\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 4);
  EXPECT_EQ(e.key(), "runs[0].set.segments");
  EXPECT_NE(e.message().find("expected an integer"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, UnknownModelKeyInARunIsRejected) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns:\n  - set:\n      payload.colour: red\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 4);
  EXPECT_EQ(e.key(), "runs[0].set.payload.colour");
  EXPECT_NE(e.message().find("unknown key"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, ErrorBelowAnOverriddenMapNamesTheExactKey) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns:\n  - set:\n      payload: {mass: -1, inertia: 2}\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 4);
  EXPECT_EQ(e.key(), "runs[0].set.payload.mass");
}

TEST_F(StudyFiles, IndexOutOfRangeInASetIsRejected) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns:\n  - set:\n      trajectory.moves[5].target: 1\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 4);
  EXPECT_EQ(e.key(), "runs[0].set.trajectory.moves[5].target");
  EXPECT_NE(e.message().find("index [5]"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, BadPathInStudyWideSetIsRejected) {
  const auto path = write("s.yaml", "model: " + kModel + "\nset:\n  payload..mass: 1\nruns:\n  - label: a\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.key(), "set.payload..mass");
  EXPECT_NE(e.message().find("bad parameter path"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, SetThatIsNotAMapIsRejected) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns:\n  - set: [payload.mass, 1]\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.key(), "runs[0].set");
  EXPECT_NE(e.message().find("expected a map"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, MissingModelFileIsRejected) {
  const auto path = write("s.yaml", "model: no_such_model.yaml\nruns:\n  - label: a\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 1);
  EXPECT_EQ(e.key(), "model");
  EXPECT_NE(e.message().find("does not exist"), std::string::npos) << e.what();
  EXPECT_NE(e.message().find("no_such_model.yaml"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, MissingModelKeyIsRejected) {
  const auto path = write("s.yaml", "runs:\n  - label: a\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.key(), "model");
  EXPECT_NE(e.message().find("missing required value"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, CasesWithARunListAreRejected) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns:\n  - label: a\ncases:\n  - label: b\n");
  EXPECT_EQ(load_error(path).key(), "cases");
}

TEST_F(StudyFiles, EmptyRunListIsRejected) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns: []\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.key(), "runs");
  EXPECT_NE(e.message().find("at least one run"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, MissingRunsIsRejected) {
  const auto path = write("s.yaml", "model: " + kModel + "\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.key(), "runs");
  EXPECT_NE(e.message().find("give either `runs:`"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, EmptyStudyFileIsRejected) {
  const auto path = write("s.yaml", "# nothing\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_NE(e.message().find("empty"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, UnparsableStudyNamesItsLine) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns:\n  - label: a\n   set: {segments: 4}\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 4) << e.what();
}

TEST_F(StudyFiles, MissingStudyFileIsRejected) {
  const auto e = load_error((dir / "absent.yaml").string());
  EXPECT_EQ(e.file(), (dir / "absent.yaml").string());
  EXPECT_NE(e.message().find("cannot open"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, BadModelFileNamesTheModelFile) {
  std::ifstream in(kModel);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find("  inertia: 50.0");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 15, "  inertia: -50.");
  const auto model = write("rig.yaml", text);
  const auto e = load_error(write("s.yaml", "model: rig.yaml\nruns:\n  - label: a\n"));
  EXPECT_TRUE(fs::equivalent(e.file(), model)) << e.what();
  EXPECT_EQ(e.key(), "hub.inertia");
  EXPECT_NE(e.message().find(">= 0"), std::string::npos) << e.what();
}

// Each variant parses the model text afresh, so an error in the model file keeps its line.
TEST_F(StudyFiles, BadModelFileNamesTheModelLine) {
  std::ifstream in(kModel);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.replace(text.find("  inertia: 50.0"), 15, "  inertia: -50.");
  write("rig.yaml", text);
  const auto e = load_error(write("s.yaml", "model: rig.yaml\nruns:\n  - label: a\n"));
  EXPECT_EQ(e.line(), 19) << e.what();
}

// A bad value in the study-wide `set` is reported at the study file's line of that entry.
TEST_F(StudyFiles, NegativeMassInStudyWideSetNamesTheStudyLine) {
  const auto path = write("s.yaml", "model: " + kModel + "\nset:\n  payload.mass: -1\nruns:\n  - label: a\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path) << e.what();
  EXPECT_EQ(e.line(), 3) << e.what();
  EXPECT_EQ(e.key(), "set.payload.mass") << e.what();
}

// ---- keys written twice, and the variant limit ------------------------------------------------

TEST_F(StudyFiles, StudyKeyWrittenTwiceNamesBothLines) {
  const auto path = write("s.yaml", "model: " + kModel + "\nseed: 3\nruns:\n  - label: a\nseed: 4\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.key(), "seed");
  EXPECT_EQ(e.line(), 5);
  EXPECT_NE(e.message().find("lines 2 and 5"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, KeyWrittenTwiceInARunsSetNamesItsFullPath) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns:\n  - set:\n      payload.mass: 300\n      payload.mass: 400\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.key(), "runs[0].set.payload.mass");
  EXPECT_NE(e.message().find("lines 4 and 5"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, KeyWrittenTwiceInADistributionNamesItsFullPath) {
  const auto path = write("s.yaml", "model: " + kModel +
                                        "\nvariables:\n  - path: payload.mass\n    distribution: {type: uniform, lower: 1, "
                                        "upper: 2, lower: 0}\ndesign: {type: monte_carlo, samples: 2}\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.key(), "variables[0].distribution.lower");
  EXPECT_EQ(e.line(), 4);
  EXPECT_NE(e.message().find("written twice"), std::string::npos) << e.what();
}

// `runs: &r [*r]` is a list holding itself: refused when the file is loaded (it overflowed the stack).
TEST_F(StudyFiles, RunsHoldingThemselvesAreRejected) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns: &r [*r]\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.key(), "runs[0]");
  EXPECT_EQ(e.line(), 2);
  EXPECT_NE(e.message().find("cycle"), std::string::npos) << e.what();
}

// A design of two million Monte Carlo samples is refused at once, before it is drawn.
TEST_F(StudyFiles, DesignOverTheVariantLimitIsRefusedBeforeItIsDrawn) {
  const auto path = write("s.yaml", "model: " + kModel +
                                        "\nvariables:\n  - path: payload.mass\n    distribution: {type: uniform, lower: 1, "
                                        "upper: 2}\ndesign:\n  type: monte_carlo\n  samples: 2000000\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.key(), "design.type");
  EXPECT_EQ(e.line(), 6);
  EXPECT_NE(e.message().find("2000000 variants, over the limit of 1000000"), std::string::npos) << e.what();
}

// A range's levels are made as it is read: its count is held to the variant limit first, with the
// ranges before it (a grid or centered design has at least 1 + the sum of count - 1 rows), whatever the
// design.
TEST_F(StudyFiles, ARangeCountOverTheLimitIsRefusedBeforeItsLevelsAreMade) {
  for (const std::string design : {"grid", "centered", "monte_carlo"}) {
    const auto path = write("s.yaml", "model: " + kModel +
                                          "\nvariables:\n  - path: payload.mass\n    range: {lower: 1, upper: 2, count: 2000000000}\n"
                                          "    distribution: {type: uniform, lower: 1, upper: 2}\ndesign: {type: " + design + ", samples: 4}\n");
    const auto e = load_error(path);
    EXPECT_EQ(e.key(), "variables[0].range.count") << design;
    EXPECT_EQ(e.line(), 4) << design;
    EXPECT_EQ(e.message(), "2000000000 levels take the study's ranges over 1000000 variants, its limit (a grid or centered "
                           "design has at least 1 + the sum of count - 1)")
        << design;
  }
  // Two ranges within the limit each, over it together: the second is named. At the limit, the centered
  // design (the centre and 3 + 3 levels off it) is read.
  const auto two = write("t.yaml", "model: " + kModel +
                                       "\nvariables:\n  - path: payload.mass\n    range: {lower: 1, upper: 2, count: 4}\n"
                                       "  - path: payload.inertia\n    range: {lower: 1, upper: 2, count: 4}\ndesign: {type: centered}\n");
  EXPECT_EQ(ff::read_study(two, 7).variants.size(), 7u);
  const auto e = read_error(two, 6);
  EXPECT_EQ(e.key(), "variables[1].range.count");
  EXPECT_EQ(e.line(), 6);
  EXPECT_NE(e.message().find("4 levels take the study's ranges over 6 variants"), std::string::npos) << e.what();
}

// The limit counts the design's rows times its cases, and a list of runs.
TEST_F(StudyFiles, CasesAndRunsCountTowardsTheVariantLimit) {
  const auto crossed = write("c.yaml", "model: " + kModel +
                                           "\nvariables:\n  - path: payload.mass\n    levels: [1, 2, 3]\ndesign: {type: grid}\n"
                                           "cases:\n  - label: a\n  - label: b\n");
  EXPECT_EQ(ff::read_study(crossed, 6).variants.size(), 6u);
  const auto e = read_error(crossed, 5);
  EXPECT_NE(e.message().find("6 variants, over the limit of 5"), std::string::npos) << e.what();
  const auto runs = write("r.yaml", "model: " + kModel + "\nruns:\n  - label: a\n  - label: b\n  - label: c\n");
  const auto r = read_error(runs, 2);
  EXPECT_EQ(r.key(), "runs");
  EXPECT_NE(r.message().find("3 runs exceed the limit of 2"), std::string::npos) << r.what();
}

// read_study makes the variants without checking their models; check_models checks them (and
// builds the nominal one) as load_study does.
TEST_F(StudyFiles, ReadStudyThenCheckModelsIsLoadStudy) {
  const auto path = write("s.yaml", "model: " + kModel + "\nruns:\n  - set: {payload.mass: 400}\n  - set: {payload.mass: -5}\n");
  ff::Study st = ff::read_study(path);
  EXPECT_EQ(st.variants.size(), 2u);
  EXPECT_THROW(ff::check_models(st), ff::ConfigError);
  EXPECT_THROW(ff::load_study(path), ff::ConfigError);
  const auto good = write("g.yaml", "model: " + kModel + "\nruns:\n  - set: {payload.mass: 400}\n  - set: {payload.mass: 500}\n");
  ff::Study g = ff::read_study(good);
  ff::check_models(g);
  EXPECT_DOUBLE_EQ(g.nominal.spec.payload_mass, 400.0);  // a list of runs: run 0
  EXPECT_DOUBLE_EQ(ff::make_variant_model(g, g.variants[1]).spec.payload_mass, 500.0);
}

}  // namespace

// ---- drawn values: a distribution's tail is a result, the nominal point is the file's ----------

// A normal stiffness of mean 39.5e3 and std 4e4 draws negative values about 16 % of the time: the
// study still loads (those variants run as `invalid`), and its nominal model has the medians.
TEST_F(StudyFiles, DrawsTheModelRejectsDoNotStopTheLoad) {
  const auto path = write("s.yaml", "model: " + kModel +
                                        "\nvariables:\n"
                                        "  - path: joints.stiffness\n"
                                        "    distribution: {type: normal, mean: 39.5e3, std: 4.0e4}\n"
                                        "  - path: segments\n"
                                        "    integer: true\n"
                                        "    distribution: {type: uniform, lower: 3.2, upper: 8.0}\n"
                                        "design: {type: monte_carlo, samples: 64}\n");
  const ff::Study st = ff::load_study(path);
  ASSERT_EQ(st.variants.size(), 64u);
  EXPECT_TRUE(st.drawn);
  int negative = 0;
  for (const auto& v : st.variants) negative += v.params[0] <= 0;
  EXPECT_GT(negative, 0) << "the draw must reach the rejected tail for this test to mean anything";
  EXPECT_DOUBLE_EQ(st.nominal.spec.joints.stiffness, 39.5e3);  // the normal's median
  EXPECT_EQ(st.nominal.spec.segments, 6);                      // uniform median 5.6, rounded
  for (const auto& v : st.variants)
    if (v.params[0] <= 0) {
      EXPECT_THROW(ff::make_variant_model(st, v), ff::ConfigError) << v.label;
    }
}

TEST_F(StudyFiles, ARejectedNominalPointIsAnErrorOfTheFile) {
  const auto path = write("s.yaml", "model: " + kModel +
                                        "\nvariables:\n"
                                        "  - path: joints.stiffness\n"
                                        "    distribution: {type: normal, mean: -1.0e3, std: 4.0e4}\n"
                                        "design: {type: monte_carlo, samples: 8}\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 3);
  EXPECT_NE(e.message().find("nominal point"), std::string::npos) << e.what();
}

// A run's metric columns follow its moves: a run with another number of moves than the first is refused
// at load, naming it and both counts.
TEST_F(StudyFiles, RunsWithDifferentNumbersOfMovesAreRefused) {
  const auto path = write("s.yaml", "model: " + kModel +
                                        "\nruns:\n"
                                        "  - label: one\n"
                                        "  - label: two\n"
                                        "    set: {trajectory.moves: [{target: 0.5, hold: 2}]}\n");
  try {
    ff::load_study(path);
    FAIL() << "loaded";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("eval_id 1: " + path + ": 1 move where the study's nominal model has 2 moves"), std::string::npos) << m;
  }
}

// A case's set is written in the file: a bad value in the second case of a drawn design fails at load,
// naming its line, though case 0's nominal point is fine.
TEST_F(StudyFiles, ABadValueInACaseOfADrawnDesignIsAnErrorOfTheFile) {
  const auto path = write("s.yaml", "model: " + kModel +
                                        "\ncases:\n"
                                        "  - label: light\n"
                                        "  - label: broken\n"
                                        "    set: {payload.mass: -5}\n"
                                        "variables:\n"
                                        "  - path: joints.stiffness\n"
                                        "    distribution: {type: normal, mean: 39.5e3, std: 1.0e3}\n"
                                        "design: {type: monte_carlo, samples: 8}\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 5);
  EXPECT_NE(e.message().find(">= 0"), std::string::npos) << e.what();
}

TEST_F(StudyFiles, ARejectedGridLevelIsAnErrorOfTheFile) {
  const auto path = write("s.yaml", "model: " + kModel +
                                        "\nvariables:\n"
                                        "  - path: payload.mass\n"
                                        "    levels: [300, -5, 400]\n"
                                        "design: {type: grid}\n");
  const auto e = load_error(path);
  EXPECT_EQ(e.line(), 3);
  EXPECT_NE(e.message().find(">= 0"), std::string::npos) << e.what();
}

namespace {

// An arm study: each variant gets its own seed for its sensors' noise, so two variants with the same
// parameters measure differently, and a variant built twice measures the same.
TEST(ArmStudies, EachVariantHasItsOwnSensorNoiseAndTheSameVariantRepeatsIt) {
  ff::test::TempDir dir("arm_study");
  dir.write("arm.yaml",
            "bodies:\n"
            "  - {name: arm, parent: base, mass: 2.0, com: [0.5, 0, 0], inertia: {ixx: 0.001, iyy: 0.01, izz: 0.01},\n"
            "     joint: {axis: [0, 0, 1], armature: 0.05}}\n"
            "joints:\n"
            "  arm: {controller: {kp: 100, kd: 10}, sensors: {angle: {noise: 1.0e-3}}}\n"
            "simulation: {duration: 0.1}\n");
  const std::string path = dir.write("study.yaml",
                                     "model: arm.yaml\n"
                                     "runs:\n"
                                     "  - label: a\n"
                                     "  - label: b\n");
  const ff::Study st = ff::load_study(path);
  ASSERT_TRUE(st.arm);
  auto measured = [&](int i) {
    const ff::ArmModel m = ff::make_variant_arm(st, st.variants[static_cast<std::size_t>(i)]);
    return ff::simulate_arms(std::span<const ff::ArmModel>(&m, 1)).traces[0].column("arm.q_measured");
  };
  const auto a = measured(0), b = measured(1);
  EXPECT_NE(a, b);
  EXPECT_EQ(a, measured(0));
  EXPECT_NE(st.variants[0].seed, st.variants[1].seed);
}

// A parameter's plot axis carries its unit from the field tables (issue 32, item 23: axes named
// `bodies[forearm].flexible.payload.mass` alone), a joint's by its type.
TEST(ParameterUnits, ComeFromTheFieldTablesAndTheJointsType) {
  const ff::Study arm = ff::load_study(kSource + "/configs/studies/two_link_tradeoff.yaml");
  EXPECT_EQ(ff::parameter_axis_label(arm, "bodies[forearm].flexible.payload.mass"), "bodies[forearm].flexible.payload.mass (kg)");
  EXPECT_EQ(ff::parameter_axis_label(arm, "trajectory.waypoints[0].time"), "trajectory.waypoints[0].time (s)");
  EXPECT_EQ(ff::parameter_unit(arm, "joints.shoulder.controller.kp"), "N·m/rad");
  EXPECT_EQ(ff::parameter_unit(arm, "trajectory.waypoints[0].joints.elbow"), "rad");
  EXPECT_EQ(ff::parameter_unit(arm, "world.floor.position[2]"), "m");
  EXPECT_EQ(ff::parameter_axis_label(arm, "case"), "case");
  EXPECT_EQ(ff::parameter_unit(arm, "bodies[forearm].flexible.segments"), "");
  // The mobile base's prismatic joint: metres, and its gain per metre.
  const ff::Study sers = ff::load_study(kSource + "/configs/studies/sers_tradeoff.yaml");
  EXPECT_EQ(ff::parameter_unit(sers, "trajectory.waypoints[0].joints.base_x"), "m");
  EXPECT_EQ(ff::parameter_unit(sers, "joints.base_x.controller.kp"), "N/m");
  // The reference rig's own table.
  const ff::Study rig = ff::load_study(kSource + "/configs/studies/fbtb_paper.yaml");
  EXPECT_EQ(ff::parameter_axis_label(rig, "payload.mass"), "payload.mass (kg)");
  EXPECT_EQ(ff::parameter_unit(rig, "trajectory.moves[0].target"), "rad");
}

}  // namespace
