// Requirements (results/requirements.hpp): the statement grammar and its errors, the YAML block, and
// the verdicts against hand-computed values: Wilson intervals, censored rows as misses, percentiles
// as their probability form, the mean's bootstrap, max / min about the sample, and `more`.
#include "results/requirements.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "common/errors.hpp"
#include "results/censoring.hpp"
#include "sweep/study.hpp"
#include "tests/docs_tables.hpp"

namespace {

using namespace ff;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A table of one metric `m` (and, when given, a settling time's horizon column).
ResultTable make_table(const std::vector<double>& values, const std::vector<double>& horizons = {},
                       const std::string& metric = "m") {
  ResultTable t;
  t.columns = {metric};
  if (!horizons.empty()) t.columns.push_back("m1_settling_horizon_s");
  for (std::size_t i = 0; i < values.size(); ++i) {
    ResultRow r;
    r.eval_id = static_cast<int>(i);
    r.status = "ok";
    r.values = {values[i]};
    if (!horizons.empty()) r.values.push_back(horizons[i]);
    t.rows.push_back(r);
  }
  return t;
}

RequirementSet make_set(const std::vector<std::string>& statements, double confidence = 0.95) {
  RequirementSet s;
  s.confidence = confidence;
  for (const auto& text : statements) s.statements.push_back(parse_requirement(text));
  return s;
}

Verdict judge(const std::string& statement, const ResultTable& t, bool complete = false, int total = 0) {
  return evaluate_requirements(make_set({statement}), t, complete, total).at(0);
}

// k values of 1 and n - k values of 5.
std::vector<double> proportion(int k, int n) {
  std::vector<double> v(static_cast<std::size_t>(n), 5.0);
  for (int i = 0; i < k; ++i) v[static_cast<std::size_t>(i)] = 1.0;
  return v;
}

// The Wilson bound, by its closed form.
double wilson(double k, double n, double z, int sign) {
  const double p = k / n;
  return (p + z * z / (2 * n) + sign * z * std::sqrt(p * (1 - p) / n + z * z / (4 * n * n))) / (1 + z * z / n);
}

std::string parse_error(const std::string& text) {
  try {
    parse_requirement(text);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Requirement, EveryFormParsesWithOrWithoutSpaces) {
  Requirement r = parse_requirement("P(m1_tip_settling_s <= 3.0) >= 0.95");
  EXPECT_EQ(r.kind, RequirementKind::kProbability);
  EXPECT_EQ(r.metric, "m1_tip_settling_s");
  EXPECT_EQ(r.op, Comparison::kLessEqual);
  EXPECT_EQ(r.threshold, 3.0);
  EXPECT_EQ(r.prob_op, Comparison::kGreaterEqual);
  EXPECT_EQ(r.probability, 0.95);

  r = parse_requirement("P(x>-1e-3)<0.01");
  EXPECT_EQ(r.op, Comparison::kGreater);
  EXPECT_EQ(r.threshold, -1e-3);
  EXPECT_EQ(r.prob_op, Comparison::kLess);
  EXPECT_EQ(r.probability, 0.01);

  r = parse_requirement("p95(peak_torque_Nm) <= 8000");
  EXPECT_EQ(r.kind, RequirementKind::kPercentile);
  EXPECT_EQ(r.metric, "peak_torque_Nm");
  EXPECT_DOUBLE_EQ(r.probability, 0.95);
  EXPECT_EQ(r.threshold, 8000.0);
  EXPECT_DOUBLE_EQ(parse_requirement("p99.9(a)>1").probability, 0.999);
  EXPECT_DOUBLE_EQ(parse_requirement("p50(a)>=1").probability, 0.5);

  r = parse_requirement("  mean( m1_overshoot_pct )  <  10 ");
  EXPECT_EQ(r.kind, RequirementKind::kMean);
  EXPECT_EQ(r.metric, "m1_overshoot_pct");
  EXPECT_EQ(r.op, Comparison::kLess);
  EXPECT_EQ(parse_requirement("max(a)<=2").kind, RequirementKind::kMax);
  r = parse_requirement("min(min_clearance_m) >= 0.05");
  EXPECT_EQ(r.kind, RequirementKind::kMin);
  EXPECT_EQ(r.op, Comparison::kGreaterEqual);
  EXPECT_EQ(r.threshold, 0.05);
}

TEST(Requirement, ParseErrorsSayWhatWasExpectedAndWhere) {
  const struct {
    const char* text;
    const char* words;
  } cases[] = {
      {"Q(m<=3)>=0.9", "at character 1 ('Q(m<=3)>'): expected P(METRIC OP X) OP PROB, pNN(METRIC) OP X"},
      {"P(m<=3)>=1.5", "at character 10 ('1.5'): expected a probability in [0, 1]"},
      {"P(m=3)>=0.9", "at character 4 ('=3)>=0.9'): expected a comparison (<=, <, >= or >) after the metric"},
      {"P(m<=3>=0.9", "at character 7 ('>=0.9'): expected ')' after the number"},
      {"P(m<=x)>=0.9", "at character 6 ('x)>=0.9'): expected a number after the comparison"},
      {"P(<=3)>=0.9", "at character 3 ('<=3)>=0.'): expected a metric"},
      {"p100(m)<=3", "at character 1 ('p100(m)<'): expected a percentile pNN with NN in (0, 100)"},
      {"p0(m)<=3", "expected a percentile pNN with NN in (0, 100)"},
      {"mean m <= 3", "at character 6 ('m <= 3'): expected '(' after mean"},
      {"mean(m) <= ", "at the end: expected a number after the comparison"},
      {"max(m)<=3 and more", "at character 11 ('and more'): expected the end of the statement"},
      {"min(m)", "at the end: expected a comparison (<=, <, >= or >) after min(...)"},
      {"", "at the end: expected P(METRIC OP X)"},
  };
  for (const auto& c : cases) EXPECT_NE(parse_error(c.text).find(c.words), std::string::npos) << c.text << ": " << parse_error(c.text);
}

TEST(Requirement, NinetySevenOfHundredAgainstTheWilsonBounds) {
  const ResultTable t = make_table(proportion(97, 100));
  const double z = calc_two_sided_z(0.95);
  const double lower = wilson(97, 100, z, -1), upper = wilson(97, 100, z, +1);
  EXPECT_NEAR(lower, 0.9155, 1e-4);  // by hand
  Verdict v = judge("P(m <= 3) >= 0.95", t);
  EXPECT_EQ(v.n, 100);
  EXPECT_EQ(v.misses, 3);
  EXPECT_DOUBLE_EQ(v.estimate, 0.97);
  EXPECT_NEAR(v.lower, lower, 1e-12);
  EXPECT_NEAR(v.upper, upper, 1e-12);
  EXPECT_EQ(v.verdict, "undecided");  // 0.9155 < 0.95 <= 0.9897
  EXPECT_GT(v.more, 0);
  EXPECT_EQ(judge("P(m <= 3) >= 0.90", t).verdict, "pass");  // lower 0.9155 >= 0.90
  EXPECT_EQ(judge("P(m <= 3) >= 0.995", t).verdict, "fail");  // upper 0.9897 < 0.995
  EXPECT_EQ(judge("P(m <= 3) >= 0.90", t).more, 0);
  // The miss form: P(m > 3) = 0.03 [0.0103, 0.0845].
  v = judge("P(m > 3) <= 0.1", t);
  EXPECT_NEAR(v.upper, 1 - lower, 1e-12);
  EXPECT_EQ(v.verdict, "pass");
  EXPECT_EQ(judge("P(m > 3) < 0.01", t).verdict, "fail");  // lower 0.0103 >= 0.01
  // Every row meets it: the upper bound is exactly 1.
  EXPECT_EQ(judge("P(m <= 3) >= 0.9", make_table(proportion(40, 40))).upper, 1.0);
}

TEST(Requirement, NotSettledAndMissingRowsAreMissesEvenBelowTheThreshold) {
  // 8 settled at 1 s, one not settled (horizon 2 s: it settles after 2 s, perhaps before 3 s), one diverged.
  std::vector<double> v(8, 1.0), h(8, 10.0);
  v.push_back(kNaN);
  h.push_back(2.0);
  v.push_back(kNaN);
  h.push_back(kNaN);
  const ResultTable t = make_table(v, h, "m1_tip_settling_s");
  const Verdict r = judge("P(m1_tip_settling_s <= 3) >= 0.5", t);
  EXPECT_EQ(r.n, 10);
  EXPECT_EQ(r.misses, 2);
  EXPECT_EQ(r.censored, 1);
  EXPECT_EQ(r.missing, 1);
  EXPECT_DOUBLE_EQ(r.estimate, 0.8);
  EXPECT_NE(r.evidence.find("1 not settled, 1 without a value"), std::string::npos) << r.evidence;
  // A lower bound too: a row without a value never meets the condition.
  EXPECT_EQ(judge("P(m1_tip_settling_s >= 0.5) >= 0.5", t).misses, 2);
  // max: the not-settled row violates max <= 3.
  EXPECT_EQ(judge("max(m1_tip_settling_s) <= 3", t).verdict, "fail");
}

TEST(Requirement, APercentileStatementDecidesAsItsProbabilityForm) {
  std::vector<double> v;
  for (int i = 0; i < 200; ++i) v.push_back(std::fmod(i * 0.6180339887, 1.0) * 10.0);  // spread over [0, 10)
  const ResultTable t = make_table(v);
  for (double x : {5.0, 8.5, 9.0, 9.3, 9.6, 9.9}) {
    SCOPED_TRACE(x);
    const Verdict p = judge("p90(m) <= " + std::to_string(x), t);
    const Verdict q = judge("P(m <= " + std::to_string(x) + ") >= 0.9", t);
    EXPECT_EQ(p.verdict, q.verdict);
    EXPECT_EQ(p.estimate, q.estimate);
    EXPECT_EQ(p.lower, q.lower);
    EXPECT_EQ(p.upper, q.upper);
    EXPECT_EQ(p.more, q.more);
    // The lower-bound form: p10(m) > x <=> P(m > x) > 0.9.
    const Verdict pl = judge("p10(m) > " + std::to_string(x), t);
    const Verdict ql = judge("P(m > " + std::to_string(x) + ") > 0.9", t);
    EXPECT_EQ(pl.verdict, ql.verdict);
    EXPECT_EQ(pl.estimate, ql.estimate);
  }
  const Verdict p = judge("p90(m) <= 9.5", t);
  EXPECT_EQ(p.statistic, calc_km_percentile(calc_kaplan_meier(v, {}), 90.0));
  EXPECT_EQ(judge("p90(m) <= 5", t).verdict, "fail");
  EXPECT_EQ(judge("p90(m) <= 9.9", t).verdict, "pass");
  // Above the horizon: the Kaplan–Meier percentile is +inf, read "> H (not settled)".
  std::vector<double> s(10, 1.0), h(10, 5.0);
  s[8] = s[9] = kNaN;
  const Verdict c = judge("p95(m1_tip_settling_s) <= 3", make_table(s, h, "m1_tip_settling_s"));
  EXPECT_TRUE(std::isinf(c.statistic));
  EXPECT_NE(c.evidence.find("p95 = > 5 (not settled)"), std::string::npos) << c.evidence;
}

TEST(Requirement, TheMeanIsDecidedByItsBootstrapIntervalAndRowsWithoutAValueAreWorstCase) {
  std::vector<double> v;
  for (int i = 1; i <= 100; ++i) v.push_back(i);  // mean 50.5, standard error 2.9
  const ResultTable t = make_table(v);
  const Verdict a = judge("mean(m) <= 60", t);
  EXPECT_DOUBLE_EQ(a.estimate, 50.5);
  EXPECT_NEAR(a.lower, 50.5 - 1.96 * 2.9, 1.0);
  EXPECT_NEAR(a.upper, 50.5 + 1.96 * 2.9, 1.0);
  EXPECT_EQ(a.verdict, "pass");
  EXPECT_EQ(judge("mean(m) >= 60", t).verdict, "fail");
  const Verdict u = judge("mean(m) <= 52", t);
  EXPECT_EQ(u.verdict, "undecided");
  EXPECT_GT(u.more, 0);
  // Deterministic: the same bits again.
  const Verdict b = judge("mean(m) <= 60", t);
  EXPECT_EQ(a.lower, b.lower);
  EXPECT_EQ(a.upper, b.upper);
  // A not-settled row: +inf for an upper bound (the mean fails), its horizon for a lower bound.
  std::vector<double> s(v), h(100, 200.0);
  s[0] = kNaN;
  const ResultTable c = make_table(s, h, "m1_tip_settling_s");
  const Verdict up = judge("mean(m1_tip_settling_s) <= 60", c);
  EXPECT_TRUE(std::isinf(up.estimate));
  EXPECT_TRUE(std::isinf(up.upper));
  EXPECT_EQ(up.verdict, "undecided");  // a third of the resamples miss it: the lower bound is finite
  EXPECT_EQ(up.more, kCannotDecide);   // and it can never pass
  for (int i = 0; i < 10; ++i) s[static_cast<std::size_t>(i)] = kNaN;
  EXPECT_EQ(judge("mean(m1_tip_settling_s) <= 60", make_table(s, h, "m1_tip_settling_s")).verdict, "fail")
      << "ten of them: every resample draws one";
  const Verdict low = judge("mean(m1_tip_settling_s) >= 40", c);
  EXPECT_DOUBLE_EQ(low.estimate, (5050.0 - 1.0 + 200.0) / 100.0);
  EXPECT_EQ(low.verdict, "pass");
}

TEST(Requirement, MaxAndMinAreAboutTheSampleAndPassOnlyWhenTheStudyIsComplete) {
  const ResultTable t = make_table({0.2, 0.07, 0.3});
  Verdict v = judge("min(m) >= 0.05", t, false, 10);
  EXPECT_EQ(v.verdict, "undecided");
  EXPECT_EQ(v.more, 7);
  EXPECT_DOUBLE_EQ(v.estimate, 0.07);
  EXPECT_EQ(judge("min(m) >= 0.05", t, true, 3).verdict, "pass");
  EXPECT_EQ(judge("min(m) >= 0.1", t, false, 10).verdict, "fail");  // one row violates it: fails at once
  EXPECT_EQ(judge("max(m) < 0.3", t, false, 10).verdict, "fail");
  EXPECT_EQ(judge("max(m) <= 0.3", t, true, 3).verdict, "pass");
  // The existential forms: one row suffices to pass.
  EXPECT_EQ(judge("max(m) >= 0.25", t, false, 10).verdict, "pass");
  EXPECT_EQ(judge("min(m) < 0.01", t, false, 10).verdict, "undecided");
  EXPECT_EQ(judge("min(m) < 0.01", t, true, 3).verdict, "fail");
  // A row without a value violates it.
  EXPECT_EQ(judge("min(m) >= 0.05", make_table({0.2, kNaN}), true, 2).verdict, "fail");
}

TEST(Requirement, MoreRowsAtTheSameProportionDecideIt) {
  const struct {
    int k, n;
    const char* statement;
  } cases[] = {
      {97, 100, "P(m <= 3) >= 0.95"}, {92, 100, "P(m <= 3) >= 0.95"}, {19, 20, "P(m <= 3) >= 0.9"},
      {97, 100, "P(m > 3) < 0.05"},    {48, 100, "p50(m) <= 3"},        {995, 1000, "P(m <= 3) > 0.99"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.statement + std::string(" with ") + std::to_string(c.k) + " of " + std::to_string(c.n));
    const Verdict v = judge(c.statement, make_table(proportion(c.k, c.n)));
    ASSERT_EQ(v.verdict, "undecided");
    ASSERT_GT(v.more, 0);
    const long long n = c.n + v.more;
    const auto k = static_cast<int>(std::llround(static_cast<double>(c.k) / c.n * static_cast<double>(n)));
    EXPECT_NE(judge(c.statement, make_table(proportion(k, static_cast<int>(n)))).verdict, "undecided") << "more " << v.more;
    if (v.more > 1) {
      const long long m = c.n + v.more - 1;
      const auto km = static_cast<int>(std::llround(static_cast<double>(c.k) / c.n * static_cast<double>(m)));
      EXPECT_EQ(judge(c.statement, make_table(proportion(km, static_cast<int>(m)))).verdict, "undecided")
          << "one fewer than `more` already decides it";
    }
  }
  // At the bound no number of rows decides it; nor can a proportion of 1 pass ">= 1".
  EXPECT_EQ(judge("P(m <= 3) >= 0.5", make_table(proportion(50, 100))).more, kCannotDecide);
  EXPECT_EQ(judge("P(m <= 3) >= 1", make_table(proportion(100, 100))).more, kCannotDecide);
}

RequirementSet read_from(const std::string& yaml) {
  const YAML::Node doc = load_yaml_text(yaml, "study.yaml");
  YamlReader top(doc, "study.yaml", "", nullptr);
  return read_requirements(top);
}

std::string read_error(const std::string& yaml) {
  try {
    read_from(yaml);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(RequirementYaml, AListOrAMapWithDefaults) {
  RequirementSet s = read_from("model: x\nrequirements:\n  - P(a <= 1) >= 0.9\n  - max(b) < 2\n");
  ASSERT_EQ(s.statements.size(), 2u);
  EXPECT_EQ(s.statements[1].key, "requirements[1]");
  EXPECT_EQ(s.statements[1].line, 4);
  EXPECT_EQ(s.confidence, 0.95);
  EXPECT_FALSE(s.stop_when_decided);
  EXPECT_EQ(s.check_every, 100);
  s = read_from("requirements:\n  statements: [\"mean(a) < 3\"]\n  confidence: 0.99\n  stop_when_decided: true\n"
                "  check_every: 50\n");
  ASSERT_EQ(s.statements.size(), 1u);
  EXPECT_EQ(s.statements[0].key, "requirements.statements[0]");
  EXPECT_EQ(s.confidence, 0.99);
  EXPECT_TRUE(s.stop_when_decided);
  EXPECT_EQ(s.check_every, 50);
  EXPECT_TRUE(read_from("model: x\n").statements.empty());
}

TEST(RequirementYaml, ErrorsNameTheFileLineAndKey) {
  EXPECT_EQ(read_error("model: x\nrequirements:\n  - P(a <= 1) >= 0.9\n  - max(b) =< 2\n"),
            "study.yaml:4: requirements[1]: 'max(b) =< 2': at character 8 ('=< 2'): expected a comparison (<=, <, >= or >) "
            "after max(...)");
  EXPECT_EQ(read_error("requirements: 3\n").rfind("study.yaml:1: requirements: expected a list of statements", 0), 0u);
  EXPECT_EQ(read_error("requirements: []\n").rfind("study.yaml:1: requirements: expected a non-empty list", 0), 0u);
  EXPECT_EQ(read_error("requirements:\n  - {a: 1}\n").rfind("study.yaml:2: requirements[0]: expected a statement", 0), 0u);
  EXPECT_EQ(read_error("requirements:\n  statements: [\"max(a)<1\"]\n  confidence: 1\n"),
            "study.yaml:3: requirements.confidence: must be in (0, 1), got 1");
  EXPECT_EQ(read_error("requirements:\n  statements: [\"max(a)<1\"]\n  check_every: 0\n"),
            "study.yaml:3: requirements.check_every: must be >= 1, got 0");
  EXPECT_NE(read_error("requirements:\n  statements: [\"max(a)<1\"]\n  stop: true\n").find("requirements.stop: unknown key"),
            std::string::npos)
      << read_error("requirements:\n  statements: [\"max(a)<1\"]\n  stop: true\n");
  EXPECT_EQ(read_error("requirements:\n  confidence: 0.9\n").rfind("study.yaml:2: requirements.statements: missing", 0), 0u);
}

TEST(RequirementYaml, AMetricThatIsNoColumnIsNamedWithTheColumnsThereAre) {
  const RequirementSet s = read_from("requirements:\n  - P(a <= 1) >= 0.9\n  - max(tip) < 2\n");
  EXPECT_NO_THROW(check_requirement_columns(s, {"a", "tip"}));
  try {
    check_requirement_columns(s, {"a", "b"});
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "study.yaml:3: requirements[1]: 'tip' is not a result column (the columns: a, b)");
  }
}

TEST(RequirementYaml, TheMapKeysAreDocumented) { ff::test::expect_documented("Study requirements", requirements_keys()); }

TEST(Requirement, TheStopPointIsTheFirstCheckpointWhereEveryStatementIsDecided) {
  RequirementSet s = make_set({"P(m <= 3) >= 0.5"});
  s.check_every = 10;
  const auto decided_from_30 = [](int k) { return k >= 30; };
  EXPECT_EQ(find_stop_point(s, 100, 100, decided_from_30), 100) << "stop_when_decided is off";
  s.stop_when_decided = true;
  EXPECT_EQ(find_stop_point(s, 100, 100, decided_from_30), 30);
  EXPECT_EQ(find_stop_point(s, 100, 25, decided_from_30), -1) << "rows 25..29 are missing: not known yet";
  int next = 0;
  std::vector<int> checked;
  const auto record = [&](int k) {
    checked.push_back(k);
    return k >= 30;
  };
  EXPECT_EQ(find_stop_point(s, 100, 25, record, &next), -1);
  EXPECT_EQ(next, 30);
  EXPECT_EQ(find_stop_point(s, 100, 31, record, &next), 30);
  EXPECT_EQ(checked, (std::vector<int>{10, 20, 30})) << "each checkpoint once";
  EXPECT_EQ(find_stop_point(s, 100, 100, [](int) { return false; }), 100);
  EXPECT_EQ(find_stop_point(s, 30, 30, decided_from_30), 30) << "the whole study: no early stop";
}

// The example of docs/formats.md: its block read with the study, its metrics checked against the columns.
TEST(RequirementYaml, TheProposalStudyReadsItsRequirements) {
  const Study st = load_study(std::string(FLEXFARM_SOURCE_DIR) + "/configs/studies/fbtb_proposal.yaml");
  ASSERT_EQ(st.requirements.statements.size(), 4u);
  EXPECT_TRUE(st.requirements.stop_when_decided);
  EXPECT_EQ(st.requirements.check_every, 100);
  EXPECT_EQ(st.requirements.seed, st.seed);
  EXPECT_EQ(st.requirements.statements[1].kind, RequirementKind::kPercentile);
  EXPECT_EQ(st.requirements.statements[1].metric, "m1_peak_torque_Nm");
}

}  // namespace
