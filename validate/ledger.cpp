#include "validate/ledger.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "plotting/plot.hpp"
#include "results/sqlite.hpp"

namespace ff {

std::string format_calibrated_model(const ModelSource& src, const EffectFit& fit, const std::string& record_path) {
  YAML::Node doc = apply_overrides(src);
  for (const auto& a : fit.assignments()) set_path(doc, a.path, a.value, "calibrate");
  std::string head = "# " + src.path + " with " + fit.effect + " (" + fit.physics + ") added by flexfarm calibrate,\n";
  head += "# fitted to " + record_path + ":";
  char buf[160];
  for (const auto& [p, v] : fit.params) {
    std::snprintf(buf, sizeof buf, " %s = %.6g", p.c_str(), v);
    head += buf;
  }
  std::snprintf(buf, sizeof buf, " (delta BIC %.1f).\n", fit.delta_bic);
  head += buf;
  YAML::Emitter out;
  out.SetDoublePrecision(10);
  out << doc;
  return head + out.c_str() + "\n";
}

namespace {

// The model ledger's tables, on an open database.
struct Ledger {
  SqliteDb db;
  explicit Ledger(const std::string& path) : db(path) {
    db.exec("CREATE TABLE IF NOT EXISTS versions (version INTEGER PRIMARY KEY, model TEXT, parent INTEGER, "
            "effect TEXT, params TEXT, record TEXT, mode TEXT)");
    db.exec("CREATE TABLE IF NOT EXISTS fits (version INTEGER, channel TEXT, fit_percent REAL, rmse REAL, "
            "PRIMARY KEY (version, channel))");
  }
  // The latest version of a model file fitted to this record in this mode, or 0.
  long find(const std::string& model, const std::string& record, const std::string& mode) {
    const SqliteStmt query = db.prepare("SELECT MAX(version) FROM versions WHERE model = ? AND record = ? AND mode = ?");
    sqlite3_stmt* st = query.get();
    sqlite3_bind_text(st, 1, model.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 2, record.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 3, mode.c_str(), -1, SQLITE_TRANSIENT);
    long v = 0;
    if (db.next_row(st)) v = sqlite_int(st, 0);  // MAX of no rows is NULL: 0
    return v;
  }
  long add(const std::string& model, long parent, const std::string& effect, const std::string& params,
           const std::string& record, const std::string& mode, const std::map<std::string, Fit>& fits) {
    const SqliteStmt insert = db.prepare("INSERT INTO versions (model, parent, effect, params, record, mode) VALUES (?, ?, ?, ?, ?, ?)");
    sqlite3_stmt* st = insert.get();
    sqlite3_bind_text(st, 1, model.c_str(), -1, SQLITE_TRANSIENT);
    if (parent > 0) sqlite3_bind_int64(st, 2, parent); else sqlite3_bind_null(st, 2);
    sqlite3_bind_text(st, 3, effect.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 4, params.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 5, record.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 6, mode.c_str(), -1, SQLITE_TRANSIENT);
    db.step(st);
    const long v = sqlite3_last_insert_rowid(db.handle());
    const SqliteStmt insert_fit = db.prepare("INSERT OR REPLACE INTO fits VALUES (?, ?, ?, ?)");
    sqlite3_stmt* fs = insert_fit.get();
    for (const auto& [c, f] : fits) {
      sqlite3_bind_int64(fs, 1, v);
      sqlite3_bind_text(fs, 2, c.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_double(fs, 3, f.percent);
      sqlite3_bind_double(fs, 4, f.rmse);
      db.step(fs);
    }
    return v;
  }
};


}  // namespace

std::map<std::string, Fit> calc_record_fits(const Model& m, const Record& r, ReplayMode mode) {
  std::map<std::string, Fit> out;
  const auto p = replay(std::span<const Model>(&m, 1), r, mode)[0];
  for (const auto& c : scored_channels(mode, r)) out[c] = p.ok ? calc_fit(r.at(c), p.channels.at(c)) : Fit{-INFINITY, INFINITY};
  return out;
}

std::string record_calibration(const std::string& ledger_path, const std::string& before_path,
                               const std::map<std::string, Fit>& before, const std::string& after_path,
                               const std::map<std::string, Fit>& after, const EffectFit& fit, const Record& r,
                               ReplayMode mode) {
  Ledger led(ledger_path);
  led.db.exec("BEGIN");
  long parent = led.find(before_path, r.source, replay_mode_name(mode));
  if (parent == 0) parent = led.add(before_path, 0, "base", "", r.source, replay_mode_name(mode), before);
  std::string params;
  for (const auto& [p, v] : fit.params) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "%s%s=%.6g", params.empty() ? "" : " ", p.c_str(), v);
    params += buf;
  }
  led.add(after_path, parent, fit.effect, params, r.source, replay_mode_name(mode), after);
  led.db.exec("COMMIT");
  return report_ledger(ledger_path, r.source, mode);
}

std::string report_ledger(const std::string& ledger_path, const std::string& record, ReplayMode mode) {
  Ledger led(ledger_path);
  // Read back the versions fitted to this record in this mode: a text table and the plot of the
  // error (100 - fit %) per channel by version.
  const SqliteStmt query = led.db.prepare(
      "SELECT v.version, v.model, v.effect, f.channel, f.fit_percent, f.rmse FROM versions v JOIN fits f "
      "ON f.version = v.version WHERE v.record = ? AND v.mode = ? ORDER BY v.version, f.channel");
  sqlite3_stmt* st = query.get();
  sqlite3_bind_text(st, 1, record.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(st, 2, replay_mode_name(mode), -1, SQLITE_TRANSIENT);
  std::string text = "ledger " + ledger_path + ", " + record + " (" + replay_mode_name(mode) +
                     "):\n  version  effect                     channel          fit %        RMSE  model\n";
  std::vector<double> versions;
  std::vector<std::string> version_labels;  // "2 +coulomb_friction": the effect each version added
  std::map<std::string, Series> lines;
  while (led.db.next_row(st)) {
    const long v = sqlite_int(st, 0);
    const std::string model = sqlite_text(st, 1), effect = sqlite_text(st, 2), channel = sqlite_text(st, 3);
    const double pct = sqlite_real(st, 4), rmse = sqlite_real(st, 5);
    char buf[512];
    std::snprintf(buf, sizeof buf, "  %7ld  %-26s %-14s %7.2f  %10.4g  %s\n", v, effect.c_str(), channel.c_str(), pct, rmse,
                  model.c_str());
    text += buf;
    auto& s = lines[channel];
    s.label = channel;
    s.x.push_back(static_cast<double>(v));
    s.y.push_back(100.0 - pct);
    s.marker = Series::Marker::kDot;
    if (versions.empty() || versions.back() != static_cast<double>(v)) {
      versions.push_back(static_cast<double>(v));
      version_labels.push_back(std::to_string(v) + (effect == "base" ? " base" : " +" + effect));
    }
  }
  LinePlot plot;
  plot.title = "error of each model version on " + std::filesystem::path(record).filename().string() + " (" +
               replay_mode_name(mode) + ")";
  plot.x_label = "model version";
  plot.y_label = "error: 100 - fit (%)";
  plot.x_ticks = versions;
  plot.x_tick_labels = version_labels;
  plot.y_min = 0.0;
  for (auto& [c, s] : lines) plot.series.push_back(s);
  render_line_plot(plot, ledger_path + ".png");
  return text + "plot: " + ledger_path + ".png\n";
}

}  // namespace ff
