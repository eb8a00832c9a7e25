// The result table: one row per variant (eval_id, seed, label, status, parameters, metrics), as
// CSV and as the human-readable settling/overshoot table.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ff {

struct ResultRow {
  int eval_id = 0;
  std::uint64_t seed = 0;        // the variant's random seed (from the study seed and eval_id)
  std::string label;
  std::string status;            // ok, not_settled, nonfinite, solver_fail, invalid (its model rejected its values)
  std::vector<double> params;    // in ResultTable::params order
  std::vector<double> values;    // in ResultTable::columns order; NaN = no number (e.g. not settled)
};

struct ResultTable {
  std::vector<std::string> params;   // parameter paths
  std::vector<std::string> columns;  // metric names
  std::vector<ResultRow> rows;       // ascending eval_id
};

// A number for a readable table: printf `format` ("%.4g"), "-" for NaN (no number).
std::string format_cell(double x, const char* format = "%.4g");

// A metric's cell in a readable table: x in `format`; without a number, "> H (not settled)" when it is a
// settling time right-censored at its horizon H (a number), else "-": no value (a run that diverged, a
// move it never ran, an event that did not happen) is not censored.
std::string format_metric_cell(double x, double horizon, const char* format = "%.4g");

// The horizon `column` of `row` is censored at (calc_horizon_column), NaN for a column that is not a
// settling time or a table without its horizon column.
double find_row_horizon(const ResultTable& table, const ResultRow& row, const std::string& column);

// Every reader of a metric's or parameter's name (specs, tolerances, requirements, `table --by/--metric/
// --spec`, the diff) checks it here: "" when `name` is one of `valid`, else "'NAME' is not a result
// column (did you mean `CLOSEST`?) (the columns: A, B, ...)" (`what`: "a result column").
std::string explain_unknown_column(const std::string& name, const std::vector<std::string>& valid,
                                   const std::string& what = "a result column", const std::string& list_name = "the columns");

// CSV header: eval_id,seed,label,status,<params>,<columns>.
std::string format_results_header(const ResultTable& table);
// One CSV row (with its newline); NaN cells are empty; numbers with 17 significant digits (exact).
// Labels, status and names holding a comma or a quote are quoted: what parse_results_csv reads, these
// write back the same.
std::string format_results_row(const ResultRow& row);
// Header and every row.
std::string format_results_csv(const ResultTable& table);

// Splits one CSV line (no newline) into cells; "..." quotes may hold commas and doubled quotes. A
// quote left open throws std::invalid_argument.
std::vector<std::string> split_csv_line(const std::string& line);

// Reads a results CSV (as written by format_results_csv). Throws std::runtime_error naming
// `source`, the line and the column on a malformed file.
ResultTable parse_results_csv(const std::string& text, const std::string& source);

// Markdown table, one line per run and move: tip and hub settling (s; not settled: "> H (not settled)",
// H the move's settling_horizon_s; "-" without one: a diverged run, a move never run), overshoot (%),
// peak tip deflection (mm), residual vibration (mm), peak torque (kN·m).
// moves[row][j] describes move j of that row, e.g. "0 -> 0.5 rad".
std::string format_settling_table_md(const ResultTable& table, const std::vector<std::vector<std::string>>& moves);

}  // namespace ff
