#include "results/table.hpp"

#include <algorithm>
#include <cmath>
#include <cctype>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "common/text.hpp"
#include "common/closest.hpp"
#include "results/run_metrics.hpp"

namespace ff {

namespace {

std::string csv_quote(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}

}  // namespace

std::string format_cell(double x, const char* format) { return std::isnan(x) ? "-" : fmt(format, x); }

std::string format_metric_cell(double x, double horizon, const char* format) {
  if (std::isnan(x) && !std::isnan(horizon)) return "> " + fmt(format, horizon) + " (not settled)";
  return format_cell(x, format);
}

double find_row_horizon(const ResultTable& t, const ResultRow& row, const std::string& column) {
  const std::string h = calc_horizon_column(column);
  for (std::size_t c = 0; c < t.columns.size() && c < row.values.size(); ++c)
    if (!h.empty() && t.columns[c] == h) return row.values[c];
  return std::nan("");
}

std::string explain_unknown_column(const std::string& name, const std::vector<std::string>& valid, const std::string& what,
                                   const std::string& list_name) {
  if (std::find(valid.begin(), valid.end(), name) != valid.end()) return "";
  std::string list;
  for (const std::string& v : valid) list += (list.empty() ? "" : ", ") + v;
  return "'" + name + "' is not " + what + format_did_you_mean(name, valid) + " (" + list_name + ": " + list + ")";
}

std::string format_results_header(const ResultTable& t) {
  std::string out = "eval_id,seed,label,status";
  for (const auto& c : t.params) out += "," + csv_quote(c);
  for (const auto& c : t.columns) out += "," + csv_quote(c);
  return out + "\n";
}

std::string format_results_row(const ResultRow& r) {
  std::string out = std::to_string(r.eval_id);
  out += ',';
  out += std::to_string(r.seed);
  out += ',';
  out += csv_quote(r.label);
  out += ',';
  out += csv_quote(r.status);
  for (const auto* v : {&r.params, &r.values})
    for (double x : *v) {
      out += ',';
      if (!std::isnan(x)) out += fmt("%.17g", x);  // round-trips every double: equal tables mean equal bits
    }
  out += '\n';
  return out;
}

std::string format_results_csv(const ResultTable& t) {
  std::string out = format_results_header(t);
  for (const auto& r : t.rows) out += format_results_row(r);
  return out;
}

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      cells.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      cells.emplace_back();
    } else if (c != '\r') {
      cells.back() += c;
    }
  }
  if (quoted) throw std::invalid_argument("a quote is not closed");
  return cells;
}

ResultTable parse_results_csv(const std::string& text, const std::string& source) {
  ResultTable t;
  std::size_t pos = 0;
  int line_no = 0;
  std::vector<std::string> header;
  int nparams = -1;
  while (pos < text.size()) {
    const std::size_t end = text.find('\n', pos);
    const std::string line = text.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
    pos = end == std::string::npos ? text.size() : end + 1;
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    auto bad = [&](const std::string& col, const std::string& why) {
      throw std::runtime_error(source + ":" + std::to_string(line_no) + ": " + col + ": " + why);
    };
    std::vector<std::string> cells;
    try {
      cells = split_csv_line(header.empty() ? strip_bom(line) : line);
    } catch (const std::invalid_argument& e) {
      bad(header.empty() ? "header" : "row", e.what());
    }
    if (header.empty()) {
      header = cells;
      if (header.size() < 4 || header[0] != "eval_id" || header[1] != "seed" || header[2] != "label" || header[3] != "status")
        bad("header", "expected eval_id,seed,label,status,...");
      // Parameters come before the metrics: from the first name "m<digit>..." (the reference rig's) or
      // "..._settling_s" (an arm's first, arm/arm_metrics.hpp) on, every column is a metric.
      for (std::size_t c = 4; c < header.size(); ++c)
        if (header[c].empty()) bad("header", "column " + std::to_string(c + 1) + " has no name");
      check_csv_header(header, source, line_no);  // a name twice
      for (std::size_t c = 4; c < header.size(); ++c) {
        const bool metric = (header[c].size() > 1 && header[c][0] == 'm' && std::isdigit(static_cast<unsigned char>(header[c][1]))) ||
                            header[c].ends_with("_settling_s");
        if (metric && nparams < 0) nparams = static_cast<int>(c) - 4;
        (nparams >= 0 ? t.columns : t.params).push_back(header[c]);
      }
      if (nparams < 0) nparams = static_cast<int>(header.size()) - 4;
      continue;
    }
    if (cells.size() != header.size())
      bad("row", "has " + std::to_string(cells.size()) + " cells, the header has " + std::to_string(header.size()));
    ResultRow r;
    const auto eval_id = parse_integer(cells[0], 0, INT_MAX);
    const auto seed = parse_integer<std::uint64_t>(cells[1]);
    if (!eval_id) bad("eval_id", "'" + cells[0] + "' is not an eval_id (an integer from 0)");
    if (!seed) bad("seed", "'" + cells[1] + "' is not a seed (an unsigned 64-bit integer)");
    r.eval_id = static_cast<int>(*eval_id);
    r.seed = *seed;
    r.label = cells[2];
    r.status = cells[3];
    for (std::size_t c = 4; c < cells.size(); ++c) {
      double x = std::nan("");
      if (!cells[c].empty()) {
        char* endp = nullptr;
        x = std::strtod(cells[c].c_str(), &endp);
        if (*endp != '\0') bad(header[c], "'" + cells[c] + "' is not a number");
      }
      (static_cast<int>(c) - 4 < nparams ? r.params : r.values).push_back(x);
    }
    t.rows.push_back(std::move(r));
  }
  if (header.empty()) throw std::runtime_error(source + ": no header row");
  return t;
}

std::string format_settling_table_md(const ResultTable& t, const std::vector<std::vector<std::string>>& moves) {
  std::string out =
      "| run | move | tip settling (s) | tip overshoot (%) | hub settling (s) | hub overshoot (%) | "
      "peak tip deflection (mm) | residual vibration (mm) | peak torque (kN·m) |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  const std::size_t per_move = kMoveMetrics.size();
  // Not settled: "> H (not settled)" with the move's horizon H, the largest settling time the run could confirm.
  auto settle = [](double x, double horizon) { return format_metric_cell(x, horizon, "%.2f"); };
  // "-": no number (a move the run ended before).
  auto number = [](const char* format, double x) { return std::isnan(x) ? std::string("-") : fmt(format, x); };
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    for (std::size_t j = 0; j < moves[i].size() && (j + 1) * per_move <= r.values.size(); ++j) {
      const double* v = &r.values[j * per_move];
      out += "| " + md_cell(r.label) + " | " + md_cell(moves[i][j]) + " | " + settle(v[0], v[7]) + " | " + number("%.1f", v[1]) + " | " +
             settle(v[2], v[7]) + " | " + number("%.1f", v[3]) + " | " + number("%.1f", 1e3 * v[4]) + " | " +
             number("%.2f", 1e3 * v[5]) + " | " + number("%.2f", 1e-3 * v[6]) + " |\n";
    }
  }
  return out;
}

}  // namespace ff
