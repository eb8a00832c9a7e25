// results/history.cpp: a run's summaries against a hand computation, the run record through results.sqlite's
// key-value form and through the history database, the previous run of a study, and what is refused.
#include "results/history.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <filesystem>

#include "../temp_dir.hpp"
#include "results/sqlite.hpp"

namespace ff {
namespace {

const double kNaN = std::nan("");

// Ten rows: x = 1..10 ("m_x"), and a settling time 1..7 s with three not settled at an 8 s horizon.
ResultTable ten_rows() {
  ResultTable t;
  t.params = {"p"};
  t.columns = {"m1_tip_settling_s", "m_x", "m1_settling_horizon_s"};
  const double settle[] = {1, 2, kNaN, 3, 4, kNaN, 5, 6, kNaN, 7};
  for (int i = 0; i < 10; ++i)
    t.rows.push_back({i, 100u + static_cast<unsigned>(i), "run " + std::to_string(i), std::isnan(settle[i]) ? "not_settled" : "ok",
                      {0.5 * i}, {settle[i], i + 1.0, 8.0}});
  return t;
}

TEST(RunSummaries, MeanIntervalAndMissProbabilityMatchAHandComputation) {
  const auto s = calc_metric_summaries(ten_rows(), {{"m_x", 8.5}});
  ASSERT_EQ(s.size(), 3u);
  const MetricSummary& x = s[1];
  EXPECT_EQ(x.metric, "m_x");
  EXPECT_EQ(x.count, 10);
  EXPECT_DOUBLE_EQ(x.mean, 5.5);
  // Sample standard deviation of 1..10: sqrt(82.5 / 9); the mean's interval +- 1.959964 sd / sqrt(10).
  const double half = 1.959963984540054 * std::sqrt(82.5 / 9.0) / std::sqrt(10.0);
  EXPECT_NEAR(x.mean_lower, 5.5 - half, 1e-9);
  EXPECT_NEAR(x.mean_upper, 5.5 + half, 1e-9);
  EXPECT_DOUBLE_EQ(x.p50, 5.5);
  // 9 and 10 miss 8.5: P = 0.2; Wilson at 95 %: (p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n).
  const double z = 1.959963984540054, n = 10, p = 0.2;
  const double centre = (p + z * z / (2 * n)) / (1 + z * z / n);
  const double spread = z * std::sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n);
  EXPECT_DOUBLE_EQ(x.spec, 8.5);
  EXPECT_DOUBLE_EQ(x.p_miss, 0.2);
  EXPECT_NEAR(x.p_miss_lower, centre - spread, 1e-12);
  EXPECT_NEAR(x.p_miss_upper, centre + spread, 1e-12);
  // The censored settling time: 7 settled, 3 not; its p95 lies above the horizon.
  EXPECT_EQ(s[0].count, 7);
  EXPECT_EQ(s[0].censored, 3);
  EXPECT_TRUE(std::isinf(s[0].p95));
  EXPECT_TRUE(std::isnan(s[0].spec));
}

TEST(Sha256, MatchesTheStandardsTestVectors) {
  // FIPS 180-2, appendix B.1, and the empty message.
  EXPECT_EQ(calc_sha256("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(calc_sha256(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

RunRecord sample_record(const std::string& study_path, const std::string& out) {
  RunRecord r;
  r.study = "nightly";
  r.study_path = study_path;
  r.out = out;
  r.study_hash = "0123456789abcdef";
  r.study_text = "model: m.yaml\n";
  r.model_path = "/x/m.yaml";
  r.model_text = "a: 1\n";
  r.study_sha256 = calc_sha256(r.study_text);
  r.model_sha256 = calc_sha256(r.model_text);
  r.version = "0.1.0";
  r.commit = "abc";
  r.host = "node7";
  r.started = "2026-12-05T02:00:00Z";
  r.finished = "2026-12-05T02:10:00Z";
  r.seconds = 600.5;
  r.processes = 2;
  r.threads = 4;
  r.lanes = 8;
  r.planned = 12;
  const ResultTable t = ten_rows();
  r.variants = 10;
  r.status = count_statuses(t);
  r.summaries = calc_metric_summaries(t, {{"m_x", 8.5}});
  r.verdicts = {{.requirement = "P(m_x <= 8.5) >= 0.9", .verdict = "undecided", .estimate = 0.8, .lower = 0.49, .upper = 0.94,
                 .n = 10, .more = 60, .evidence = "8 of 10"}};
  return r;
}

void expect_same(const RunRecord& a, const RunRecord& b) {
  EXPECT_EQ(a.study, b.study);
  EXPECT_EQ(a.study_path, b.study_path);
  EXPECT_EQ(a.out, b.out);
  EXPECT_EQ(a.study_text, b.study_text);
  EXPECT_EQ(a.model_text, b.model_text);
  EXPECT_EQ(a.study_sha256, b.study_sha256);
  EXPECT_EQ(a.version, b.version);
  EXPECT_EQ(a.commit, b.commit);
  EXPECT_EQ(a.host, b.host);
  EXPECT_EQ(a.started, b.started);
  EXPECT_EQ(a.finished, b.finished);
  EXPECT_EQ(a.seconds, b.seconds);
  EXPECT_EQ(a.processes, b.processes);
  EXPECT_EQ(a.threads, b.threads);
  EXPECT_EQ(a.planned, b.planned);
  EXPECT_EQ(a.variants, b.variants);
  EXPECT_EQ(a.status, b.status);
}

TEST(RunRecordInfo, TheKeyValueFormReadsBackTheSameRecord) {
  const RunRecord r = sample_record("/s/nightly.yaml", "/o/1");
  const RunRecord back = parse_run_info(format_run_info(r));
  expect_same(r, back);
  EXPECT_EQ(back.status.at("not_settled"), 3);
  EXPECT_EQ(back.failed(), 0);
}

TEST(RunHistory, RunsReadBackWithSummariesAndVerdictsAndThePreviousRunIsTheLatestEarlierOne) {
  const test::TempDir dir("history");
  const std::string h = (dir.path / "hist").string();
  EXPECT_TRUE(list_runs(h).empty());  // no history yet: no runs, nothing created
  EXPECT_FALSE(std::filesystem::exists(h));
  const long first = record_run(h, sample_record("/s/nightly.yaml", "/o/1"));
  const long other = record_run(h, sample_record("/s/other.yaml", "/o/2"));
  RunRecord third_in = sample_record("/s/nightly.yaml", "/o/3");
  third_in.status["nonfinite"] = 2;
  const long third = record_run(h, third_in);
  EXPECT_LT(first, other);
  EXPECT_LT(other, third);

  EXPECT_EQ(list_runs(h).size(), 3u);
  const auto nightly = list_runs(h, "/s/nightly.yaml");
  ASSERT_EQ(nightly.size(), 2u);
  EXPECT_EQ(nightly[0].id, first);
  EXPECT_EQ(nightly[1].id, third);
  EXPECT_EQ(list_runs(h, "nightly").size(), 3u);  // by name: both studies are called "nightly"

  const RunRecord back = read_history_run(h, third);
  expect_same(third_in, back);
  EXPECT_EQ(back.failed(), 2);
  ASSERT_EQ(back.summaries.size(), 3u);
  EXPECT_EQ(back.summaries[1].metric, "m_x");
  EXPECT_DOUBLE_EQ(back.summaries[1].mean, 5.5);
  EXPECT_DOUBLE_EQ(back.summaries[1].p_miss, 0.2);
  EXPECT_TRUE(std::isnan(back.summaries[0].spec));
  ASSERT_EQ(back.verdicts.size(), 1u);
  EXPECT_EQ(back.verdicts[0].verdict, "undecided");
  EXPECT_EQ(back.verdicts[0].more, 60);

  // The previous run of a study: the latest earlier one of the same study file, not itself.
  const auto previous = find_previous_run(h, back);
  ASSERT_TRUE(previous.has_value());
  EXPECT_EQ(previous->id, first);
  EXPECT_EQ(previous->summaries.size(), 3u);
  EXPECT_FALSE(find_previous_run(h, read_history_run(h, first)).has_value());
  EXPECT_THROW(read_history_run(h, 99), std::runtime_error);
}

TEST(RunHistory, AFileThatIsNoHistoryIsRefusedNamingIt) {
  const test::TempDir dir("history");
  {
    SqliteDb db((dir.path / "history.sqlite").string());
    db.exec("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT); INSERT INTO meta VALUES ('schema', 'ledger-1')");
  }
  try {
    record_run(dir.path.string(), sample_record("/s/a.yaml", "/o/1"));
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("history.sqlite: not a flexfarm run history"), std::string::npos) << e.what();
  }
}

TEST(RunHistory, TheDirectoryComesFromTheOptionThenTheEnvironment) {
  // The environment as it was, put back at the end.
  struct Saved {
    std::vector<std::pair<std::string, std::string>> vars;
    Saved() {
      for (const char* v : {"FLEXFARM_HISTORY", "XDG_DATA_HOME", "HOME"})
        if (const char* x = std::getenv(v)) vars.emplace_back(v, x);
    }
    ~Saved() {
      for (const char* v : {"FLEXFARM_HISTORY", "XDG_DATA_HOME", "HOME"}) ::unsetenv(v);
      for (const auto& [k, x] : vars) ::setenv(k.c_str(), x.c_str(), 1);
    }
  } saved;
  ::unsetenv("XDG_DATA_HOME");
  EXPECT_EQ(resolve_history_dir("/given"), "/given");
  ::setenv("FLEXFARM_HISTORY", "/from/env", 1);
  EXPECT_EQ(resolve_history_dir(""), "/from/env");
  ::unsetenv("FLEXFARM_HISTORY");
  ::setenv("XDG_DATA_HOME", "/xdg", 1);
  EXPECT_EQ(resolve_history_dir(""), "/xdg/flexfarm");
  ::unsetenv("XDG_DATA_HOME");
  ::setenv("HOME", "/home/u", 1);
  EXPECT_EQ(resolve_history_dir(""), "/home/u/.local/share/flexfarm");
}

}  // namespace
}  // namespace ff
