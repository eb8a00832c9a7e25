#include "results/history.hpp"

#include <openssl/evp.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "common/files.hpp"
#include "common/yaml_reader.hpp"
#include "results/censoring.hpp"
#include "results/sqlite.hpp"
#include "results/summaries.hpp"

namespace ff {

std::vector<MetricSummary> calc_metric_summaries(const ResultTable& t, const std::map<std::string, double>& specs) {
  std::vector<MetricSummary> out;
  const double z = calc_two_sided_z(0.95);
  for (const std::string& m : t.columns) {
    const std::vector<double> v = column_values(t, m), h = horizon_values(t, m);
    const Summary s = calc_summary(v, h);
    MetricSummary ms{.metric = m, .count = s.count, .censored = s.censored, .missing = s.missing, .mean = s.mean,
                     .min = s.min, .p5 = s.p5, .p50 = s.p50, .p95 = s.p95, .max = s.max};
    // The mean's standard error from the restricted values (a not-settled run at the horizon).
    double tau = kStatsNaN;
    const Summary r = calc_summary(calc_restricted_values(t, m, &tau));
    if (r.count >= 2) {
      const double se = r.std / std::sqrt(static_cast<double>(r.count));
      ms.mean_lower = s.mean - z * se;
      ms.mean_upper = s.mean + z * se;
    }
    if (const auto spec = specs.find(m); spec != specs.end()) {
      const Interval miss = calc_miss_probability(v, spec->second, 0.95);
      ms.spec = spec->second;
      ms.p_miss = miss.estimate;
      ms.p_miss_lower = miss.lower;
      ms.p_miss_upper = miss.upper;
    }
    out.push_back(ms);
  }
  return out;
}

int RunRecord::failed() const {
  int n = 0;
  for (const char* s : {"nonfinite", "solver_fail", "invalid"})
    if (const auto it = status.find(s); it != status.end()) n += it->second;
  return n;
}

std::string RunRecord::describe() const {
  if (id > 0) return "run " + std::to_string(id) + " (" + study + ", " + finished + ")";
  return out.empty() ? study : out;
}

std::map<std::string, int> count_statuses(const ResultTable& t) {
  std::map<std::string, int> n{{"ok", 0}, {"not_settled", 0}, {"nonfinite", 0}, {"solver_fail", 0}, {"invalid", 0}};
  for (const ResultRow& r : t.rows) ++n[r.status];
  return n;
}

std::string calc_sha256(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest, &n, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("SHA-256 failed (OpenSSL)");
  std::string hex;
  char buf[3];
  for (unsigned int i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof buf, "%02x", digest[i]);
    hex += buf;
  }
  return hex;
}

std::string format_utc_now() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return buf;
}

std::string host_name() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "";
  return buf;
}

namespace {

std::string number_text(double x) {
  if (std::isnan(x)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

double text_number(const std::string& s) { return s.empty() ? kStatsNaN : std::strtod(s.c_str(), nullptr); }

const char* const kStatuses[] = {"ok", "not_settled", "nonfinite", "solver_fail", "invalid"};

}  // namespace

std::map<std::string, std::string> format_run_info(const RunRecord& r) {
  std::map<std::string, std::string> m{
      {"name", r.study},          {"study", r.study_path},      {"out", r.out},
      {"hash", r.study_hash},     {"study_text", r.study_text}, {"model", r.model_path},
      {"model_text", r.model_text}, {"study_sha256", r.study_sha256}, {"model_sha256", r.model_sha256},
      {"version", r.version},     {"commit", r.commit},
      {"host", r.host},           {"started", r.started},       {"finished", r.finished},
      {"seconds", number_text(r.seconds)}, {"processes", std::to_string(r.processes)},
      {"threads", std::to_string(r.threads)}, {"lanes", std::to_string(r.lanes)},
      {"planned", std::to_string(r.planned)}, {"variants", std::to_string(r.variants)}};
  for (const char* s : kStatuses) m[std::string("status_") + s] = std::to_string(r.status.count(s) ? r.status.at(s) : 0);
  return m;
}

RunRecord parse_run_info(const std::map<std::string, std::string>& info) {
  auto get = [&](const char* k) {
    const auto it = info.find(k);
    return it == info.end() ? std::string() : it->second;
  };
  auto integer = [&](const char* k, int fallback) {
    const std::string s = get(k);
    return s.empty() ? fallback : std::atoi(s.c_str());
  };
  RunRecord r;
  r.study = get("name");
  r.study_path = get("study");
  r.out = get("out");
  r.study_hash = get("hash");
  r.study_text = get("study_text");
  r.model_path = get("model");
  r.model_text = get("model_text");
  r.study_sha256 = get("study_sha256");
  r.model_sha256 = get("model_sha256");
  r.version = get("version");
  r.commit = get("commit");
  r.host = get("host");
  r.started = get("started");
  r.finished = get("finished");
  r.seconds = text_number(get("seconds"));
  r.processes = integer("processes", 1);
  r.threads = integer("threads", 0);
  r.lanes = integer("lanes", 0);
  r.planned = integer("planned", 0);
  r.variants = integer("variants", 0);
  for (const char* s : kStatuses) r.status[s] = integer((std::string("status_") + s).c_str(), 0);
  return r;
}

namespace {

void bind_number(sqlite3_stmt* st, int i, double x) {
  if (std::isnan(x)) sqlite3_bind_null(st, i);
  else sqlite3_bind_double(st, i, x);
}
void bind_text(sqlite3_stmt* st, int i, const std::string& s) { sqlite3_bind_text(st, i, s.c_str(), -1, SQLITE_TRANSIENT); }

}  // namespace

std::string format_run_yaml(const RunRecord& r) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  for (const auto& [k, v] : format_run_info(r)) {
    out << YAML::Key << k << YAML::Value;
    if (v.find('\n') != std::string::npos) out << YAML::Literal;
    out << v;
  }
  out << YAML::Key << "verdicts" << YAML::Value << YAML::BeginSeq;
  for (const Verdict& v : r.verdicts)
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "requirement" << YAML::Value << v.requirement << YAML::Key << "verdict"
        << YAML::Value << v.verdict << YAML::Key << "estimate" << YAML::Value << number_text(v.estimate) << YAML::Key << "lower"
        << YAML::Value << number_text(v.lower) << YAML::Key << "upper" << YAML::Value << number_text(v.upper) << YAML::Key
        << "n" << YAML::Value << v.n << YAML::Key << "more" << YAML::Value << v.more << YAML::Key << "evidence"
        << YAML::Value << v.evidence << YAML::EndMap;
  out << YAML::EndSeq << YAML::EndMap;
  return std::string("# The record of this run (flexfarm run): inputs, version, machine, times, verdicts.\n") + out.c_str() + "\n";
}

RunDir read_run_dir(const std::string& dir) {
  const std::string db_path = dir + "/results.sqlite", csv_path = dir + "/results.csv", yaml_path = dir + "/run.yaml";
  if (!std::filesystem::is_directory(dir)) throw std::runtime_error(dir + ": no such directory");
  if (!std::filesystem::exists(db_path) || !std::filesystem::exists(csv_path))
    throw std::runtime_error(dir + " is not a finished run's output directory (no results.sqlite and results.csv)");
  std::map<std::string, std::string> info;
  std::vector<Verdict> verdicts;
  if (std::filesystem::exists(yaml_path)) {
    const YAML::Node doc = load_yaml_file(yaml_path);
    if (!doc.IsMap()) throw std::runtime_error(yaml_path + ": not a run record");
    try {
      for (const auto& kv : doc) {
        const std::string key = kv.first.Scalar();
        if (key != "verdicts" && kv.second.IsScalar()) info[key] = kv.second.Scalar();
      }
      for (const auto& v : doc["verdicts"])
        verdicts.push_back({.requirement = v["requirement"].as<std::string>(""), .verdict = v["verdict"].as<std::string>(""),
                          .estimate = text_number(v["estimate"].as<std::string>("")),
                          .lower = text_number(v["lower"].as<std::string>("")),
                          .upper = text_number(v["upper"].as<std::string>("")), .n = v["n"].as<int>(0),
                          .more = v["more"].as<long long>(-1), .evidence = v["evidence"].as<std::string>("")});
    } catch (const YAML::Exception& e) {
      throw std::runtime_error(yaml_path + ": not a run record (" + e.what() + ")");
    }
  } else {
    info = read_results_study_info(db_path);
  }
  RunDir d{parse_run_info(info), parse_results_csv(read_file(csv_path), csv_path)};
  d.record.verdicts = std::move(verdicts);
  d.record.out = std::filesystem::absolute(dir).lexically_normal().string();
  if (info.find("variants") == info.end()) d.record.variants = static_cast<int>(d.table.rows.size());
  if (info.find("status_ok") == info.end()) d.record.status = count_statuses(d.table);
  return d;
}

RunDir read_run_dir(const RunRecord& recorded) {
  if (!std::filesystem::exists(recorded.out + "/results.sqlite"))
    throw std::runtime_error(recorded.describe() + ": its output directory " + recorded.out + " is gone (its rows are needed)");
  RunDir d = read_run_dir(recorded.out);
  d.record.id = recorded.id;
  return d;
}

std::string resolve_history_dir(const std::string& option) {
  if (!option.empty()) return option;
  // Set but blank ("  "): an error, not the current directory; set empty: as unset.
  for (const char* var : {"FLEXFARM_HISTORY", "XDG_DATA_HOME"})
    if (const char* v = std::getenv(var); v && *v && is_blank_path(v))
      throw std::runtime_error(std::string("$") + var + ": a blank path; unset it or give --history DIR");
  if (const char* v = std::getenv("FLEXFARM_HISTORY"); v && *v) return v;
  if (const char* v = std::getenv("XDG_DATA_HOME"); v && *v) return std::string(v) + "/flexfarm";
  if (const char* v = std::getenv("HOME"); v && *v) return std::string(v) + "/.local/share/flexfarm";
  return "";
}

namespace {

constexpr const char* kSchema = "flexfarm-history-1";
const char* const kRunColumns =
    "id, study, study_path, out, study_hash, study_sha256, model_sha256, model_path, version, git_commit, host, started, finished, seconds, "
    "processes, threads, lanes, planned, variants, ok, not_settled, nonfinite, solver_fail, invalid";

// The history database, its tables created when new; a file of another kind is refused.
struct HistoryDb {
  SqliteDb db;
  explicit HistoryDb(const std::string& path) : db(path) {
    sqlite3_busy_timeout(db.handle(), 30000);  // another run may be recording
    db.exec(
        "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT);"
        "INSERT OR IGNORE INTO meta VALUES ('schema', 'flexfarm-history-1');"
        "CREATE TABLE IF NOT EXISTS runs (id INTEGER PRIMARY KEY AUTOINCREMENT, study TEXT, study_path TEXT, "
        "out TEXT, study_hash TEXT, study_sha256 TEXT, model_sha256 TEXT, model_path TEXT, version TEXT, git_commit TEXT, host TEXT, started TEXT, "
        "finished TEXT, seconds REAL, processes INTEGER, threads INTEGER, lanes INTEGER, planned INTEGER, "
        "variants INTEGER, ok INTEGER, not_settled INTEGER, nonfinite INTEGER, solver_fail INTEGER, invalid INTEGER);"
        "CREATE TABLE IF NOT EXISTS inputs (run_id INTEGER, name TEXT, text TEXT);"
        "CREATE TABLE IF NOT EXISTS summaries (run_id INTEGER, metric TEXT, count INTEGER, censored INTEGER, "
        "missing INTEGER, mean REAL, mean_lower REAL, mean_upper REAL, min REAL, p5 REAL, p50 REAL, p95 REAL, "
        "max REAL, spec REAL, p_miss REAL, p_miss_lower REAL, p_miss_upper REAL);"
        "CREATE TABLE IF NOT EXISTS verdicts (run_id INTEGER, requirement TEXT, verdict TEXT, estimate REAL, "
        "lower REAL, upper REAL, n INTEGER, more INTEGER, evidence TEXT);");
    const SqliteStmt st = db.prepare("SELECT value FROM meta WHERE key = 'schema'");
    if (!db.next_row(st.get()) || sqlite_text(st.get(), 0) != kSchema)
      throw std::runtime_error(path + ": not a flexfarm run history (schema " + kSchema + ")");
  }
};

std::string history_file(const std::string& dir) { return dir + "/history.sqlite"; }

RunRecord read_run_row(sqlite3_stmt* st) {
  RunRecord r;
  r.id = sqlite_int(st, 0);
  r.study = sqlite_text(st, 1);
  r.study_path = sqlite_text(st, 2);
  r.out = sqlite_text(st, 3);
  r.study_hash = sqlite_text(st, 4);
  r.study_sha256 = sqlite_text(st, 5);
  r.model_sha256 = sqlite_text(st, 6);
  r.model_path = sqlite_text(st, 7);
  r.version = sqlite_text(st, 8);
  r.commit = sqlite_text(st, 9);
  r.host = sqlite_text(st, 10);
  r.started = sqlite_text(st, 11);
  r.finished = sqlite_text(st, 12);
  r.seconds = sqlite_real(st, 13);
  r.processes = static_cast<int>(sqlite_int(st, 14));
  r.threads = static_cast<int>(sqlite_int(st, 15));
  r.lanes = static_cast<int>(sqlite_int(st, 16));
  r.planned = static_cast<int>(sqlite_int(st, 17));
  r.variants = static_cast<int>(sqlite_int(st, 18));
  for (int k = 0; k < 5; ++k) r.status[kStatuses[k]] = static_cast<int>(sqlite_int(st, 19 + k));
  return r;
}

// A run's inputs, summaries and verdicts.
void read_details(SqliteDb& db, RunRecord& r) {
  const SqliteStmt in = db.prepare("SELECT name, text FROM inputs WHERE run_id = ?");
  sqlite3_bind_int64(in.get(), 1, r.id);
  while (db.next_row(in.get())) (sqlite_text(in.get(), 0) == "study" ? r.study_text : r.model_text) = sqlite_text(in.get(), 1);
  const SqliteStmt su = db.prepare(
      "SELECT metric, count, censored, missing, mean, mean_lower, mean_upper, min, p5, p50, p95, max, spec, p_miss, "
      "p_miss_lower, p_miss_upper FROM summaries WHERE run_id = ? ORDER BY rowid");
  sqlite3_bind_int64(su.get(), 1, r.id);
  while (db.next_row(su.get())) {
    sqlite3_stmt* s = su.get();
    const auto count = [s](int col) { return static_cast<int>(sqlite_int(s, col)); };
    r.summaries.push_back({sqlite_text(s, 0), count(1), count(2), count(3),
                           sqlite_real(s, 4), sqlite_real(s, 5), sqlite_real(s, 6), sqlite_real(s, 7),
                           sqlite_real(s, 8), sqlite_real(s, 9), sqlite_real(s, 10), sqlite_real(s, 11),
                           sqlite_real(s, 12), sqlite_real(s, 13), sqlite_real(s, 14), sqlite_real(s, 15)});
  }
  const SqliteStmt ve = db.prepare(
      "SELECT requirement, verdict, estimate, lower, upper, n, more, evidence FROM verdicts WHERE run_id = ? ORDER BY rowid");
  sqlite3_bind_int64(ve.get(), 1, r.id);
  while (db.next_row(ve.get())) {
    sqlite3_stmt* s = ve.get();
    r.verdicts.push_back({.requirement = sqlite_text(s, 0), .verdict = sqlite_text(s, 1), .estimate = sqlite_real(s, 2),
                          .lower = sqlite_real(s, 3), .upper = sqlite_real(s, 4), .n = static_cast<int>(sqlite_int(s, 5)),
                          .more = sqlite_int(s, 6), .evidence = sqlite_text(s, 7)});
  }
}

}  // namespace

long record_run(const std::string& history_dir, const RunRecord& r, const std::function<void(long)>& finish) {
  make_directories(history_dir);
  HistoryDb h(history_file(history_dir));
  SqliteDb& db = h.db;
  db.exec("BEGIN IMMEDIATE");
  try {
    const SqliteStmt st = db.prepare(
        "INSERT INTO runs (study, study_path, out, study_hash, study_sha256, model_sha256, model_path, version, git_commit, "
        "host, started, finished, seconds, processes, threads, lanes, planned, variants, ok, not_settled, nonfinite, "
        "solver_fail, invalid) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    sqlite3_stmt* s = st.get();
    int k = 1;
    for (const std::string* t : {&r.study, &r.study_path, &r.out, &r.study_hash, &r.study_sha256, &r.model_sha256,
                                 &r.model_path, &r.version, &r.commit, &r.host, &r.started, &r.finished})
      bind_text(s, k++, *t);
    bind_number(s, k++, r.seconds);
    for (int x : {r.processes, r.threads, r.lanes, r.planned, r.variants}) sqlite3_bind_int(s, k++, x);
    for (const char* name : kStatuses) sqlite3_bind_int(s, k++, r.status.count(name) ? r.status.at(name) : 0);
    db.step(s);
    const long id = static_cast<long>(sqlite3_last_insert_rowid(db.handle()));

    const SqliteStmt in = db.prepare("INSERT INTO inputs VALUES (?, ?, ?)");
    for (const auto& [name, text] : {std::pair<const char*, const std::string*>{"study", &r.study_text}, {"model", &r.model_text}}) {
      sqlite3_bind_int64(in.get(), 1, id);
      bind_text(in.get(), 2, name);
      bind_text(in.get(), 3, *text);
      db.step(in.get());
    }
    const SqliteStmt su = db.prepare("INSERT INTO summaries VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    for (const MetricSummary& m : r.summaries) {
      sqlite3_stmt* q = su.get();
      sqlite3_bind_int64(q, 1, id);
      bind_text(q, 2, m.metric);
      sqlite3_bind_int(q, 3, m.count);
      sqlite3_bind_int(q, 4, m.censored);
      sqlite3_bind_int(q, 5, m.missing);
      int j = 6;
      for (double x : {m.mean, m.mean_lower, m.mean_upper, m.min, m.p5, m.p50, m.p95, m.max, m.spec, m.p_miss,
                       m.p_miss_lower, m.p_miss_upper})
        bind_number(q, j++, x);
      db.step(q);
    }
    const SqliteStmt ve = db.prepare("INSERT INTO verdicts VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)");
    for (const Verdict& v : r.verdicts) {
      sqlite3_stmt* q = ve.get();
      sqlite3_bind_int64(q, 1, id);
      bind_text(q, 2, v.requirement);
      bind_text(q, 3, v.verdict);
      bind_number(q, 4, v.estimate);
      bind_number(q, 5, v.lower);
      bind_number(q, 6, v.upper);
      sqlite3_bind_int(q, 7, v.n);
      sqlite3_bind_int64(q, 8, v.more);
      bind_text(q, 9, v.evidence);
      db.step(q);
    }
    if (finish) finish(id);
    db.exec("COMMIT");
    return id;
  } catch (...) {
    sqlite3_exec(db.handle(), "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

std::vector<RunRecord> list_runs(const std::string& history_dir, const std::string& study, bool full) {
  std::vector<RunRecord> out;
  const std::string path = history_file(history_dir);
  if (history_dir.empty() || !std::filesystem::exists(path)) return out;
  HistoryDb h(path);
  const SqliteStmt st = h.db.prepare(std::string("SELECT ") + kRunColumns +
                                     " FROM runs WHERE ?1 = '' OR study = ?1 OR study_path = ?1 ORDER BY id");
  bind_text(st.get(), 1, study);
  while (h.db.next_row(st.get())) out.push_back(read_run_row(st.get()));
  if (full)
    for (RunRecord& r : out) read_details(h.db, r);
  return out;
}

RunRecord read_history_run(const std::string& history_dir, long id) {
  const std::string path = history_file(history_dir);
  if (history_dir.empty() || !std::filesystem::exists(path))
    throw std::runtime_error("no run history at " + (history_dir.empty() ? std::string("(none: set FLEXFARM_HISTORY)") : path));
  HistoryDb h(path);
  const SqliteStmt st = h.db.prepare(std::string("SELECT ") + kRunColumns + " FROM runs WHERE id = ?");
  sqlite3_bind_int64(st.get(), 1, id);
  if (!h.db.next_row(st.get())) throw std::runtime_error(path + ": no run " + std::to_string(id) + " (flexfarm history lists them)");
  RunRecord r = read_run_row(st.get());
  read_details(h.db, r);
  return r;
}

std::optional<RunRecord> find_previous_run(const std::string& history_dir, const RunRecord& r) {
  std::optional<RunRecord> best;
  for (RunRecord& c : list_runs(history_dir, r.study_path))
    if ((r.id == 0 || c.id < r.id) && c.out != r.out) best = std::move(c);
  if (best) return read_history_run(history_dir, best->id);
  return best;
}

}  // namespace ff
