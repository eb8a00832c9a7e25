// The result table as an SQLite database: table `results` (eval_id, seed, label, status, one REAL
// column per parameter and metric, named as in the CSV) and table `study` (key, value).
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "results/table.hpp"

namespace ff {

// A prepared statement, finalised when it goes out of scope (also when a step throws: a statement
// left open keeps sqlite3_close from closing the database).
struct SqliteFinalize {
  void operator()(sqlite3_stmt* st) const { sqlite3_finalize(st); }
};
using SqliteStmt = std::unique_ptr<sqlite3_stmt, SqliteFinalize>;

// An open SQLite database whose every failure throws std::runtime_error naming `name`.
class SqliteDb {
 public:
  // Opens (creating if needed) the database file `file`; errors say `name` (default: the file).
  explicit SqliteDb(const std::string& file, const std::string& name = "");
  ~SqliteDb();
  SqliteDb(const SqliteDb&) = delete;
  SqliteDb& operator=(const SqliteDb&) = delete;
  void exec(const std::string& sql);
  SqliteStmt prepare(const std::string& sql);
  void step(sqlite3_stmt* st);                    // runs a statement to SQLITE_DONE and resets it
  // Steps a query: true for a row, false when done; an error throws.
  bool next_row(sqlite3_stmt* st);
  sqlite3* handle() { return db_; }
  [[noreturn]] void fail() const;

 private:
  sqlite3* db_ = nullptr;
  std::string name_;
};

// The one way to read a cell of a result row (every SQLite read in flexfarm goes through these): a NULL
// cell, as a file edited by hand may hold, reads as "" (text), NaN (real) or 0 (integer).
std::string sqlite_text(sqlite3_stmt* st, int col);
double sqlite_real(sqlite3_stmt* st, int col);
std::int64_t sqlite_int(sqlite3_stmt* st, int col);

// The `study` table (key, value) of a run's results.sqlite, as `flexfarm view RUN_DIR` reads it. Throws
// std::runtime_error naming `path` when it is not such a database.
std::map<std::string, std::string> read_results_study_info(const std::string& path);

// Writes `path` whole (a temporary database renamed into place). Throws std::runtime_error naming
// the path on failure.
void write_results_sqlite(const ResultTable& table, const std::map<std::string, std::string>& study_info,
                          const std::string& path);

}  // namespace ff
