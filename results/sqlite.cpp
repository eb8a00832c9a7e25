#include "results/sqlite.hpp"

#include <sqlite3.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "common/files.hpp"

namespace ff {

namespace {

std::string quote_ident(const std::string& s) {
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}


}  // namespace

SqliteDb::SqliteDb(const std::string& file, const std::string& name) : name_(name.empty() ? file : name) {
  if (sqlite3_open(file.c_str(), &db_) != SQLITE_OK) throw std::runtime_error(name_ + ": cannot open the database");
}

SqliteDb::~SqliteDb() { sqlite3_close(db_); }

void SqliteDb::fail() const { throw std::runtime_error(name_ + ": sqlite: " + sqlite3_errmsg(db_)); }

void SqliteDb::exec(const std::string& sql) {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw std::runtime_error(name_ + ": sqlite: " + msg);
  }
}

SqliteStmt SqliteDb::prepare(const std::string& sql) {
  sqlite3_stmt* st = nullptr;
  if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &st, nullptr) != SQLITE_OK) fail();
  return SqliteStmt(st);
}

bool SqliteDb::next_row(sqlite3_stmt* st) {
  const int rc = sqlite3_step(st);
  if (rc != SQLITE_ROW && rc != SQLITE_DONE) fail();
  return rc == SQLITE_ROW;
}

void SqliteDb::step(sqlite3_stmt* st) {
  if (sqlite3_step(st) != SQLITE_DONE) fail();
  sqlite3_reset(st);
}

std::string sqlite_text(sqlite3_stmt* st, int col) {
  const unsigned char* s = sqlite3_column_text(st, col);
  return s ? std::string(reinterpret_cast<const char*>(s), static_cast<std::size_t>(sqlite3_column_bytes(st, col))) : "";
}

double sqlite_real(sqlite3_stmt* st, int col) {
  return sqlite3_column_type(st, col) == SQLITE_NULL ? std::numeric_limits<double>::quiet_NaN()
                                                     : sqlite3_column_double(st, col);
}

std::int64_t sqlite_int(sqlite3_stmt* st, int col) { return sqlite3_column_int64(st, col); }  // NULL reads 0

std::map<std::string, std::string> read_results_study_info(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw std::runtime_error(path + ": not found");
  SqliteDb db(path);
  std::map<std::string, std::string> info;
  const SqliteStmt st = db.prepare("SELECT key, value FROM study");
  while (db.next_row(st.get())) info[sqlite_text(st.get(), 0)] = sqlite_text(st.get(), 1);
  return info;
}

void write_results_sqlite(const ResultTable& t, const std::map<std::string, std::string>& info, const std::string& path) {
  AtomicFile tmp(path);  // made exclusively; SQLite opens it by name in its private directory
  tmp.close();
  {
    SqliteDb d(tmp.path(), path);
    d.exec("BEGIN");
    d.exec("CREATE TABLE study (key TEXT PRIMARY KEY, value TEXT)");
    const SqliteStmt statement = d.prepare("INSERT INTO study VALUES (?, ?)");
    sqlite3_stmt* si = statement.get();
    for (const auto& [k, v] : info) {
      sqlite3_bind_text(si, 1, k.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(si, 2, v.c_str(), -1, SQLITE_TRANSIENT);
      d.step(si);
    }

    // One REAL column per parameter and metric; NULL where the CSV cell is empty.
    std::string cols = "eval_id INTEGER PRIMARY KEY, seed INTEGER, label TEXT, status TEXT";
    std::string marks = "?, ?, ?, ?";
    for (const auto* names : {&t.params, &t.columns})
      for (const auto& c : *names) {
        cols += ", " + quote_ident(c) + " REAL";
        marks += ", ?";
      }
    d.exec("CREATE TABLE results (" + cols + ")");
    const SqliteStmt insert = d.prepare("INSERT INTO results VALUES (" + marks + ")");
    sqlite3_stmt* st = insert.get();
    for (const auto& r : t.rows) {
      sqlite3_bind_int64(st, 1, r.eval_id);
      sqlite3_bind_int64(st, 2, static_cast<sqlite3_int64>(r.seed));
      sqlite3_bind_text(st, 3, r.label.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(st, 4, r.status.c_str(), -1, SQLITE_TRANSIENT);
      int k = 5;
      for (const auto* vals : {&r.params, &r.values})
        for (double x : *vals) {
          if (std::isnan(x)) sqlite3_bind_null(st, k++);
          else sqlite3_bind_double(st, k++, x);
        }
      d.step(st);
    }
    d.exec("COMMIT");
  }
  tmp.commit();  // a failure above (a full disk) leaves nothing behind: the temporary goes with `tmp`
}

}  // namespace ff
