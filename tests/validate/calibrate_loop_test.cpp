// Two effects hidden at once, found through the command line: diagnose selects one, then the other on
// top of it (verdict "coulomb_friction + sensor_delay.tip_deflection"), calibrate --add adds the set, the
// second diagnosis finds nothing missing, and the ledger shows the error falling to the noise.
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

TEST(CalibrateLoop, TwoHiddenEffectsAreFoundAsASetAndCalibratedTogetherAndTheErrorFalls) {
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
  const std::string set = "coulomb_friction,sensor_delay.tip_deflection";
  const std::string d1 = (dir / "d1.json").string(), d2 = (dir / "d2.json").string(), v2 = (dir / "v2.yaml").string();
  auto d = test::run_flexfarm("diagnose --model configs/fbtb.yaml" + common + " --json " + d1);
  ASSERT_EQ(d.exit_code, 0) << d.output;
  EXPECT_EQ(test::json_field(d1, "verdict"), "coulomb_friction + sensor_delay.tip_deflection") << d.output;
  const auto c = test::run_flexfarm("calibrate --model configs/fbtb.yaml" + common + " --add " + set + " --out " + v2 +
                                    " --ledger " + ledger);
  ASSERT_EQ(c.exit_code, 0) << c.output;
  EXPECT_NE(c.output.find("sensors.tip_deflection.delay = 25"), std::string::npos) << c.output;
  d = test::run_flexfarm("diagnose --model " + v2 + common + " --json " + d2);
  ASSERT_EQ(d.exit_code, 0) << d.output;
  EXPECT_EQ(test::json_field(d2, "verdict"), "none") << d.output;
  // A name twice, or two effects that write the same path, is refused.
  for (const char* bad : {"coulomb_friction,coulomb_friction", "coulomb_friction,stribeck_friction"}) {
    const auto e = test::run_flexfarm("calibrate --model configs/fbtb.yaml" + common + " --add " + bad + " --out " +
                                      (dir / "bad.yaml").string() + " --ledger " + ledger);
    EXPECT_EQ(e.exit_code, 2) << e.output;
    EXPECT_FALSE(fs::exists(dir / "bad.yaml"));
  }
  // The ledger: two versions, the error (100 - fit %, the mean over the scored channels) falling to the noise.
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
  ASSERT_EQ(effects, (std::vector<std::string>{"base", "coulomb_friction + sensor_delay.tip_deflection"}));
  EXPECT_LT(error[1], error[0] - 0.2);
  EXPECT_LT(error[1], 1.5);  // down to the record's 1 % noise
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ff
