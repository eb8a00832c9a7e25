// Two effects hidden at once, found one after the other through the command line: diagnose ranks one
// of them first (verdict "unexplained": neither explains the record alone), calibrate --add adds it,
// the second diagnosis names the other, and the ledger shows the error falling twice.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "results/sqlite.hpp"
#include "tests/cli_support.hpp"

namespace ff {
namespace {

namespace fs = std::filesystem;

TEST(CalibrateLoop, TwoHiddenEffectsAreFoundOneAfterTheOtherAndTheErrorFallsTwice) {
  const fs::path dir = fs::temp_directory_path() / ("ff_two_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string move = " --set 'trajectory.moves=[{target: 0.5, hold: 3}]'";
  const std::string rec = (dir / "two.csv").string();
  // Truth: Coulomb friction at the hub and a tip sensor 25 ms late.
  const auto r = test::run_flexfarm("record configs/fbtb.yaml" + move +
                                    " --set friction.coulomb=250 --set sensors.tip_deflection.delay=25 --decimate 5 --seed 4 --out " + rec);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string common = move + " --data " + rec + " --iterations 15";
  const std::string ledger = (dir / "ledger.sqlite").string();
  std::string model = "configs/fbtb.yaml";
  std::vector<std::string> found;
  for (int round = 1; round <= 2; ++round) {
    const std::string json = (dir / ("d" + std::to_string(round) + ".json")).string();
    const auto d = test::run_flexfarm("diagnose --model " + model + common + " --json " + json);
    ASSERT_EQ(d.exit_code, 0) << d.output;
    const std::string first = test::json_field(json, "effect"), verdict = test::json_field(json, "verdict");
    ASSERT_TRUE(first == "coulomb_friction" || first == "sensor_delay.tip_deflection") << d.output;
    // Round 1: two effects, neither explains the record alone. Round 2: the other one does.
    EXPECT_EQ(verdict, round == 1 ? "unexplained" : first) << d.output;
    if (round == 2) {
      EXPECT_NE(first, found[0]) << d.output;
    }
    found.push_back(first);
    const std::string next = (dir / ("v" + std::to_string(round + 1) + ".yaml")).string();
    const auto c = test::run_flexfarm("calibrate --model " + model + common + " --add " + first + " --out " + next +
                                      " --ledger " + ledger);
    ASSERT_EQ(c.exit_code, 0) << c.output;
    model = next;
  }
  // The ledger: three versions, the error (100 - fit %, the mean over the scored channels) falling at each.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(ledger.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(db,
                     "SELECT v.effect, AVG(100 - f.fit_percent) FROM versions v JOIN fits f ON f.version = v.version "
                     "GROUP BY v.version ORDER BY v.version",
                     -1, &st, nullptr);
  std::vector<std::string> effects;
  std::vector<double> error;
  while (sqlite3_step(st) == SQLITE_ROW) {
    effects.push_back(sqlite_text(st, 0));
    error.push_back(sqlite_real(st, 1));
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
  ASSERT_EQ(effects, (std::vector<std::string>{"base", found[0], found[1]}));
  EXPECT_LT(error[1], error[0] - 0.1);
  EXPECT_LT(error[2], error[1] - 0.1);
  EXPECT_LT(error[2], 1.5);  // down to the record's 1 % noise
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ff
