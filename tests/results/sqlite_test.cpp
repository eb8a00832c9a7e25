// results/sqlite.hpp: a statement whose step fails is still finalised, so the database closes (under
// the sanitizer build a connection left open is a leak at exit).
#include "results/sqlite.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string>

#include "tests/temp_dir.hpp"

namespace ff {
namespace {

TEST(Sqlite, AFailedStepThrowsAndTheDatabaseStillCloses) {
  const test::TempDir dir("ff_sqlite");
  const std::string path = (dir.path / "t.sqlite").string();
  {
    SqliteDb db(path);
    db.exec("CREATE TABLE t (x INTEGER UNIQUE); INSERT INTO t VALUES (1)");
    const SqliteStmt insert = db.prepare("INSERT INTO t VALUES (1)");
    try {
      db.step(insert.get());
      ADD_FAILURE() << "a second 1 was inserted into a UNIQUE column";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path + ": sqlite: UNIQUE constraint failed: t.x"), std::string::npos) << e.what();
    }
  }
  // Closed: a new connection can take the write lock at once.
  SqliteDb again(path);
  again.exec("BEGIN EXCLUSIVE; INSERT INTO t VALUES (2); COMMIT");
  const SqliteStmt count = again.prepare("SELECT COUNT(*) FROM t");
  ASSERT_TRUE(again.next_row(count.get()));
  EXPECT_EQ(sqlite_int(count.get(), 0), 2);
  EXPECT_FALSE(again.next_row(count.get()));
}

TEST(Sqlite, AnErrorInAQueryThrowsNamingTheDatabase) {
  const test::TempDir dir("ff_sqlite");
  SqliteDb db((dir.path / "t.sqlite").string(), "results.sqlite");
  try {
    db.prepare("SELECT x FROM nowhere");
    ADD_FAILURE() << "a query of a missing table was prepared";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "results.sqlite: sqlite: no such table: nowhere");
  }
}

// Every read goes through sqlite_text, sqlite_real and sqlite_int: a NULL cell (a file edited by hand) is
// "", NaN and 0, never a null pointer in a std::string; a text with a NUL byte is read whole.
TEST(Sqlite, NullCellsReadAsEmptyTextNaNAndZero) {
  const test::TempDir dir("ff_sqlite");
  SqliteDb db((dir.path / "t.sqlite").string());
  db.exec("CREATE TABLE t (s TEXT, x REAL, n INTEGER); INSERT INTO t VALUES (NULL, NULL, NULL), ('a' || char(0) || 'b', 2.5, 7)");
  const SqliteStmt st = db.prepare("SELECT s, x, n FROM t ORDER BY rowid");
  ASSERT_TRUE(db.next_row(st.get()));
  EXPECT_EQ(sqlite_text(st.get(), 0), "");
  EXPECT_TRUE(std::isnan(sqlite_real(st.get(), 1)));
  EXPECT_EQ(sqlite_int(st.get(), 2), 0);
  ASSERT_TRUE(db.next_row(st.get()));
  EXPECT_EQ(sqlite_text(st.get(), 0), std::string("a\0b", 3));
  EXPECT_EQ(sqlite_real(st.get(), 1), 2.5);
  EXPECT_EQ(sqlite_int(st.get(), 2), 7);
}

// A run's study table with NULL keys and values reads as empty strings; a file that is not a database is
// refused naming it.
TEST(Sqlite, TheStudyTableOfResultsSqliteReadsNullCellsAsEmpty) {
  const test::TempDir dir("ff_sqlite");
  const std::string path = (dir.path / "results.sqlite").string();
  write_results_sqlite({}, {{"name", "n"}, {"study", "s.yaml"}}, path);
  SqliteDb(path).exec("UPDATE study SET value = NULL WHERE key = 'name'; INSERT INTO study VALUES (NULL, 'x')");
  const auto info = read_results_study_info(path);
  EXPECT_EQ(info.at("name"), "");
  EXPECT_EQ(info.at("study"), "s.yaml");
  EXPECT_EQ(info.at(""), "x");
  const std::string junk = (dir.path / "junk.sqlite").string();
  std::ofstream(junk) << "not a database, but long enough to be read as a header of one ........................";
  try {
    (void)read_results_study_info(junk);
    ADD_FAILURE() << "junk read as a database";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), junk + ": sqlite: file is not a database");
  }
}

}  // namespace
}  // namespace ff
