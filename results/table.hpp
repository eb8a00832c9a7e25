// The result table: one row per variant (eval_id, label, status, metrics), as CSV and as the
// human-readable settling/overshoot table.
#pragma once

#include <string>
#include <vector>

namespace ff {

struct ResultRow {
  int eval_id = 0;
  std::string label;
  std::string status;            // ok, not_settled, nonfinite, solver_fail
  std::vector<double> values;    // in ResultTable::columns order; NaN = no number (e.g. not settled)
};

struct ResultTable {
  std::vector<std::string> columns;  // metric names
  std::vector<ResultRow> rows;       // ascending eval_id
};

// CSV with header eval_id,label,status,<columns>; NaN cells are empty; numbers with 10 significant digits.
std::string format_results_csv(const ResultTable& table);

// Markdown table, one line per run and move: tip and hub settling (s, "not settled"), overshoot (%),
// peak tip deflection (mm), residual vibration (mm), peak torque (kN·m).
// moves[row][j] describes move j of that row, e.g. "0 -> 0.5 rad".
std::string format_settling_table_md(const ResultTable& table, const std::vector<std::vector<std::string>>& moves);

}  // namespace ff
