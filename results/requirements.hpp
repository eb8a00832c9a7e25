// Requirements for proposal evaluation (docs/formats.md, "Requirements"): probability statements
// about a study's responses, each judged pass / fail / undecided on the rows there are, with its
// evidence (estimate, interval, rows, and how many more rows would decide it).
//
//   P(METRIC OP X) OP PROB     e.g. P(m1_tip_settling_s <= 3.0) >= 0.95    (PROB in [0, 1])
//   pNN(METRIC) OP X           e.g. p95(m1_peak_torque_Nm) <= 8000         (NN in (0, 100))
//   mean(METRIC) OP X          e.g. mean(m1_overshoot_pct) < 10
//   max(METRIC) OP X, min(METRIC) OP X                                     (about the sample itself)
//
// OP is one of <=, <, >=, >; spaces between the tokens are ignored. A row without a value (NaN:
// missing, e.g. a diverged run, or right-censored "not settled", censoring.hpp) never meets a
// statement's condition: it is a miss, even when the bound lies above its horizon. Pure functions,
// deterministic (the bootstrap draws from draw_index, statistics.hpp).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/field_table.hpp"
#include "common/yaml_reader.hpp"
#include "results/statistics.hpp"
#include "results/table.hpp"

namespace ff {

enum class RequirementKind { kProbability, kPercentile, kMean, kMax, kMin };
enum class Comparison { kLess, kLessEqual, kGreater, kGreaterEqual };

// "<=", "<", ">=", ">".
const char* comparison_text(Comparison op);
// a OP b.
bool compare(double a, Comparison op, double b);

struct Requirement {
  std::string text;         // as written
  RequirementKind kind = RequirementKind::kProbability;
  std::string metric;
  Comparison op = Comparison::kLessEqual;  // P: the condition METRIC OP X; else: STATISTIC OP X
  double threshold = 0.0;                  // X
  Comparison prob_op = Comparison::kGreaterEqual;  // P only: P(...) PROB_OP PROB
  double probability = 0.0;                // P: PROB; pNN: NN / 100
  std::string key;                         // where written: "requirements[2]" (for errors)
  int line = 0;
};

// Parses one statement; throws std::invalid_argument saying what was expected and at which character
// (1-based), e.g. "at character 12: expected a comparison (<=, <, >= or >) after the metric".
Requirement parse_requirement(const std::string& text);

struct RequirementSet {
  std::vector<Requirement> statements;
  double confidence = 0.95;        // of every interval
  bool stop_when_decided = false;  // flexfarm run: stop a Monte Carlo study once every statement is decided
  int check_every = 100;           // variants between two early-stop checks
  std::uint64_t seed = 1;          // of the mean's bootstrap (the study's seed)
  std::string file;                // the study file, and the block's line and key, for errors
  int line = 0;
  std::string key = "requirements";
  int stop_line = 0;               // of `stop_when_decided` (the block's when not written)
};

// The keys of the map form of `requirements:` (docs/formats.md holds the docs to it).
std::vector<KeyDoc> requirements_keys();

// Reads `requirements:` of `top` (absent: an empty set): a list of statements, or a map of
// `statements` (that list), `confidence`, `stop_when_decided`, `check_every`. Errors name the file,
// line and key ("study.yaml:14: requirements[2]: ...").
RequirementSet read_requirements(YamlReader& top);

// Every metric a statement names is one of `columns`, else ConfigError naming the statement's file,
// line and key, and the columns there are.
void check_requirement_columns(const RequirementSet& set, const std::vector<std::string>& columns);

inline constexpr long long kCannotDecide = -1;  // Verdict::more when more rows at the same estimate cannot decide

struct Verdict {
  std::string requirement;          // the statement as written
  std::string verdict;              // "pass", "fail" or "undecided"
  // The quantity that decides: P and pNN: the probability of the condition (pNN: its equivalent
  // P(...)) with its Wilson interval; mean: the mean of the worst-case values with its percentile-
  // bootstrap interval; max / min: the sample's maximum / minimum (no interval: NaN).
  double estimate = kStatsNaN, lower = kStatsNaN, upper = kStatsNaN;
  double statistic = kStatsNaN;     // pNN: the Kaplan–Meier percentile (+inf: above the horizon); else = estimate
  int n = 0;                        // rows
  int misses = 0;                   // rows that do not meet the condition (P, pNN, max, min)
  int censored = 0, missing = 0;    // rows not settled (NaN with a horizon) and without a value
  long long more = 0;               // 0 when decided; rows still to run (max, min); else how many more
                                    // rows at the same estimate would decide it; kCannotDecide if none would
  std::string evidence;             // one line
};

// One verdict per statement, on the rows of `table`. `complete`: the table is the whole study (only
// then can max / min pass), `total` its size (0: unknown), for max / min's rows still to run.
// Throws std::invalid_argument for a metric the table does not have.
std::vector<Verdict> evaluate_requirements(const RequirementSet& set, const ResultTable& table, bool complete,
                                           int total = 0);

bool all_decided(const std::vector<Verdict>& verdicts);

// | requirement | verdict | estimate [interval] | n | evidence |
std::string format_requirements_md(const std::vector<Verdict>& verdicts);
// "PASS  P(m1_tip_settling_s <= 3) >= 0.95: <evidence>", one line per verdict.
std::string format_verdict_lines(const std::vector<Verdict>& verdicts);

// Where an early-stopping study stops (set.stop_when_decided), from its rows: the first checkpoint
// k = check_every, 2 check_every, ... below `total` at which every statement is decided on rows
// eval_id 0..k-1 (`decided(k)`, evaluated with complete = false); `total` when none is. A pure function
// of the rows, so any thread count, lane width or resume stops at the same k. `prefix`: rows 0..prefix-1
// are present; the walk checks only checkpoints k <= prefix and returns -1 when it reaches one beyond
// (not known yet). `next` (optional): the checkpoint to start from (0: the first), set to the first one
// not checked, so a caller with more rows later goes on from there. Without stop_when_decided: `total`.
int find_stop_point(const RequirementSet& set, int total, int prefix, const std::function<bool(int)>& decided,
                    int* next = nullptr);

}  // namespace ff
