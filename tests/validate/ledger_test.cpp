// Tests of the model ledger's read-back (validate/ledger.hpp, report_ledger): a ledger edited by hand
// or damaged is read or refused with a std::runtime_error, never a crash.
#include "validate/ledger.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "tests/temp_dir.hpp"

namespace {

namespace fs = std::filesystem;

// A fresh directory per test, removed with its contents.
class LedgerFiles : public ::testing::Test {
 protected:
  ff::test::TempDir temp{"ff_ledger"};
  const fs::path& dir = temp.path;
  // A ledger made by the SQL `sql`.
  std::string ledger(const std::string& sql) {
    const std::string path = (dir / "ledger.sqlite").string();
    sqlite3* db = nullptr;
    EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    sqlite3_close(db);
    return path;
  }
};

const std::string kSchema =
    "CREATE TABLE versions (version INTEGER PRIMARY KEY, model TEXT, parent INTEGER, effect TEXT, params TEXT, "
    "record TEXT, mode TEXT);"
    "CREATE TABLE fits (version INTEGER, channel TEXT, fit_percent REAL, rmse REAL, PRIMARY KEY (version, channel));";

}  // namespace

TEST_F(LedgerFiles, ReportListsEachVersionWithItsFit) {
  const auto path = ledger(kSchema +
                           "INSERT INTO versions VALUES (1, 'emps.yaml', NULL, 'base', '', 'rec.csv', 'inverse-dynamics');"
                           "INSERT INTO versions VALUES (2, 'v2.yaml', 1, 'coulomb_friction', 'friction.coulomb=20', "
                           "'rec.csv', 'inverse-dynamics');"
                           "INSERT INTO fits VALUES (1, 'hub_torque', 71.5, 12.5);"
                           "INSERT INTO fits VALUES (2, 'hub_torque', 93.25, 3.5);");
  const std::string text = ff::report_ledger(path, "rec.csv", ff::ReplayMode::kInverseDynamics);
  EXPECT_NE(text.find("      1  base"), std::string::npos) << text;
  // version, effect (26 wide), channel (14 wide), fit % and RMSE, model.
  const std::string row2 = "      2  coulomb_friction" + std::string(11, ' ') + "hub_torque" + std::string(7, ' ') + "93.25" +
                           std::string(9, ' ') + "3.5  v2.yaml\n";
  EXPECT_NE(text.find(row2), std::string::npos) << text;
  EXPECT_TRUE(fs::exists(path + ".png"));
}

// A NULL model, effect or channel (a std::string made from a null pointer) crashed the report (found
// while writing fuzz_ledger).
TEST_F(LedgerFiles, NullCellsOfAHandEditedLedgerReadAsEmpty) {
  const auto path = ledger(kSchema +
                           "INSERT INTO versions VALUES (1, NULL, NULL, NULL, NULL, 'rec.csv', 'inverse-dynamics');"
                           "INSERT INTO fits VALUES (1, NULL, 71.5, 12.5);");
  const std::string text = ff::report_ledger(path, "rec.csv", ff::ReplayMode::kInverseDynamics);
  const std::string row = "      1" + std::string(46, ' ') + "71.50" + std::string(8, ' ') + "12.5  \n";
  EXPECT_NE(text.find(row), std::string::npos) << text;
}

TEST_F(LedgerFiles, AFileThatIsNoDatabaseIsRefusedNamingIt) {
  const std::string path = (dir / "ledger.sqlite").string();
  std::ofstream(path) << std::string(2048, 'x');
  try {
    ff::report_ledger(path, "rec.csv", ff::ReplayMode::kInverseDynamics);
    ADD_FAILURE() << "a file of x's was read as a ledger";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": sqlite: file is not a database"), std::string::npos) << e.what();
  }
}

// A ledger whose tables have other columns: the read-back's query fails with SQLite's message.
TEST_F(LedgerFiles, ALedgerOfAnotherSchemaIsRefusedNamingIt) {
  const auto path = ledger("CREATE TABLE versions (v INTEGER); CREATE TABLE fits (v INTEGER);");
  try {
    ff::report_ledger(path, "rec.csv", ff::ReplayMode::kInverseDynamics);
    ADD_FAILURE() << "a ledger of another schema was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": sqlite: no such column"), std::string::npos) << e.what();
  }
}
