// The result table as an SQLite database: table `results` (eval_id, seed, label, status, one REAL
// column per parameter and metric, named as in the CSV) and table `study` (key, value).
#pragma once

#include <sqlite3.h>

#include <map>
#include <string>

#include "results/table.hpp"

namespace ff {

// An open SQLite database whose every failure throws std::runtime_error naming `name`.
class SqliteDb {
 public:
  // Opens (creating if needed) the database file `file`; errors say `name` (default: the file).
  explicit SqliteDb(const std::string& file, const std::string& name = "");
  ~SqliteDb();
  SqliteDb(const SqliteDb&) = delete;
  SqliteDb& operator=(const SqliteDb&) = delete;
  void exec(const std::string& sql);
  sqlite3_stmt* prepare(const std::string& sql);  // the caller finalises it
  void step(sqlite3_stmt* st);                    // runs a statement to SQLITE_DONE and resets it
  sqlite3* handle() { return db_; }
  [[noreturn]] void fail() const;

 private:
  sqlite3* db_ = nullptr;
  std::string name_;
};

// Writes `path` whole (a temporary database renamed into place). Throws std::runtime_error naming
// the path on failure.
void write_results_sqlite(const ResultTable& table, const std::map<std::string, std::string>& study_info,
                          const std::string& path);

}  // namespace ff
