// apps/verb_view.cpp: `flexfarm view` of a finished study's output directory and of the study with --eval,
// whatever the number of ghosts asked for; ghosts only on the solid variant's time base; a results.sqlite
// with NULL cells or that is not a database.
#include <gtest/gtest.h>

#include <string>

#include "results/sqlite.hpp"
#include "tests/apps/cli_fixture.hpp"

namespace ff::test {
namespace {

// The two-link trade study (move time 1.0, 1.5, 2.5 s x payload 0.1, 0.2, 0.4 kg x shaper off / ZV: 18
// variants), with 1 s to settle instead of 6 to keep it short.
class ViewCli : public CliFixture {
 protected:
  ViewCli()
      : CliFixture("ff_view_cli_", {{"configs/two_link_flexible.yaml", "two_link_flexible.yaml"},
                                    {"configs/studies/two_link_tradeoff.yaml", "configs/two_link_tradeoff.yaml"}}) {}
  void SetUp() override {
    CliFixture::SetUp();
    std::string model = read_text(work / "two_link_flexible.yaml");  // the study's ../two_link_flexible.yaml
    const auto at = model.find("settle: 6.0");
    ASSERT_NE(at, std::string::npos);
    model.replace(at, 11, "settle: 1.0");
    write("two_link_flexible.yaml", model);
  }
  // The eval_ids of the variants on the page, solid first ("variant N: " in its labels, in order).
  static std::vector<int> shown(const std::string& page) {
    std::vector<int> ids;
    for (std::size_t at = page.find("\"label\":\"variant "); at != std::string::npos;
         at = page.find("\"label\":\"variant ", at + 1))
      ids.push_back(std::stoi(page.substr(at + 17)));
    return ids;
  }
};

TEST_F(ViewCli, ARunDirectoryAndEvalZeroShowEveryVariantOnTheSolidOnesTimeBase) {
  const auto ran = run("run configs/two_link_tradeoff.yaml --out out --no-history");
  ASSERT_EQ(ran.exit_code, 0) << ran.output;
  // No world: eval_id 0 solid (move time 1.0 s); the 20 ghosts asked for (the default) are more than the 5
  // other variants of a 1.0 s move, which are all shown; the 12 of 1.5 and 2.5 s are not.
  const auto from_run = run("view out --out run.html");
  ASSERT_EQ(from_run.exit_code, 0) << from_run.output;
  EXPECT_NE(from_run.output.find("variant 0: "), std::string::npos) << from_run.output;
  EXPECT_NE(from_run.output.find("and 5 ghosts"), std::string::npos) << from_run.output;
  EXPECT_NE(from_run.output.find("view: 12 of the 18 variants move on another time base"), std::string::npos)
      << from_run.output;
  const std::vector<int> ids = shown(read_text(work / "run.html"));
  ASSERT_EQ(ids.size(), 6u);
  EXPECT_EQ(ids[0], 0);
  const auto study = run("view configs/two_link_tradeoff.yaml --out eval0.html --eval 0");
  ASSERT_EQ(study.exit_code, 0) << study.output;
  EXPECT_EQ(shown(read_text(work / "eval0.html")), ids);
  // The last variant solid, two ghosts of its time base; every ghost count from 0 up.
  for (int ghosts : {0, 2, 6, 1000}) {
    const auto r = run("view out --out last.html --eval 17 --ghosts " + std::to_string(ghosts));
    ASSERT_EQ(r.exit_code, 0) << ghosts << ": " << r.output;
    const std::vector<int> last = shown(read_text(work / "last.html"));
    ASSERT_EQ(last.size(), static_cast<std::size_t>(std::min(ghosts, 5) + 1)) << ghosts;
    EXPECT_EQ(last[0], 17);
    for (std::size_t i = 1; i < last.size(); ++i) EXPECT_NE(last[i], 17);
  }
}

TEST_F(ViewCli, ANullCellInResultsSqliteIsReadAsEmptyAndAJunkFileIsOneError) {
  ASSERT_EQ(run("run configs/two_link_tradeoff.yaml --out out --no-history").exit_code, 0);
  // run.yaml, when there, is the run's record; without it (as flexfarm diff reads such a directory) the
  // `study` table of results.sqlite is.
  ASSERT_TRUE(fs::remove(work / "out/run.yaml"));
  const std::string db = (work / "out/results.sqlite").string();
  SqliteDb(db).exec("UPDATE study SET value = NULL WHERE key = 'name'; INSERT INTO study VALUES (NULL, NULL)");
  const auto named_null = run("view out --out a.html --ghosts 1");
  ASSERT_EQ(named_null.exit_code, 0) << named_null.output;
  EXPECT_NE(named_null.output.find("wrote a.html: variant 0: "), std::string::npos) << named_null.output;
  // The study's path or hash NULL: the run's study cannot be found, or does not match.
  SqliteDb(db).exec("UPDATE study SET value = NULL WHERE key = 'hash'");
  expect_one_error_line(run("view out --out b.html"), "configs/two_link_tradeoff.yaml has changed since the run in out");
  SqliteDb(db).exec("UPDATE study SET value = NULL WHERE key = 'study'");
  const auto no_study = run("view out --out c.html");
  expect_one_error_line(no_study, "out's study '' (as the run named it) is not found from here");
  EXPECT_EQ(no_study.exit_code, 2);
  write("out/results.sqlite", "SQLite format 3 is what this file is not, though it is long enough to be read as one.");
  const auto junk = run("view out --out d.html");
  expect_one_error_line(junk, "out/results.sqlite: sqlite: file is not a database");
  EXPECT_EQ(junk.exit_code, 2);
  for (const char* page : {"b.html", "c.html", "d.html"}) EXPECT_FALSE(fs::exists(work / page)) << page;
}

}  // namespace
}  // namespace ff::test
