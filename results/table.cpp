#include "results/table.hpp"

#include <cmath>
#include <cstdio>

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

std::string format_results_csv(const ResultTable& t) {
  std::string out = "eval_id,label,status";
  for (const auto& c : t.columns) out += "," + c;
  out += "\n";
  for (const auto& r : t.rows) {
    out += std::to_string(r.eval_id);
    out += ',';
    out += csv_quote(r.label);
    out += ',';
    out += r.status;
    for (double x : r.values) {
      out += ',';
      if (!std::isnan(x)) out += fmt("%.10g", x);
    }
    out += '\n';
  }
  return out;
}

std::string format_settling_table_md(const ResultTable& t, const std::vector<std::vector<std::string>>& moves) {
  std::string out =
      "| run | move | tip settling (s) | tip overshoot (%) | hub settling (s) | hub overshoot (%) | "
      "peak tip deflection (mm) | residual vibration (mm) | peak torque (kN·m) |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  const std::size_t per_move = 7;
  auto settle = [](double x) { return std::isnan(x) ? std::string("not settled") : fmt("%.2f", x); };
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    for (std::size_t j = 0; j < moves[i].size() && (j + 1) * per_move <= r.values.size(); ++j) {
      const double* v = &r.values[j * per_move];
      out += "| " + r.label + " | " + moves[i][j] + " | " + settle(v[0]) + " | " + fmt("%.1f", v[1]) + " | " +
             settle(v[2]) + " | " + fmt("%.1f", v[3]) + " | " + fmt("%.1f", 1e3 * v[4]) + " | " +
             fmt("%.2f", 1e3 * v[5]) + " | " + fmt("%.2f", 1e-3 * v[6]) + " |\n";
    }
  }
  return out;
}

}  // namespace ff
