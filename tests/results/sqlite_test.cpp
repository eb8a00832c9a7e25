// results/sqlite.hpp: a statement whose step fails is still finalised, so the database closes (under
// the sanitizer build a connection left open is a leak at exit).
#include "results/sqlite.hpp"

#include <gtest/gtest.h>

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
  EXPECT_EQ(sqlite3_column_int(count.get(), 0), 2);
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

}  // namespace
}  // namespace ff
