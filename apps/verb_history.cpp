// flexfarm history [STUDY | RUN_ID]: the runs recorded in the run history (results/history.hpp), or one
// run's record. flexfarm diff [RUN_A] RUN_B: what changed between two runs, exit 0 / 1 / 2.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "apps/verbs.hpp"
#include "common/files.hpp"
#include "common/text.hpp"
#include "common/version.hpp"
#include "results/diff.hpp"
#include "results/history.hpp"
#include "sweep/study.hpp"

namespace ff {

namespace {

std::string num(double x, const char* f = "%.4g") { return format_cell(x, f); }

// A run id as `flexfarm history` prints it: "12" or "#12"; 0 when `s` is not one.
long parse_run_id(const std::string& s) {
  const std::string digits = !s.empty() && s[0] == '#' ? s.substr(1) : s;
  if (digits.empty() || digits.size() > 15 || digits.find_first_not_of("0123456789") != std::string::npos) return 0;
  return std::stol(digits);
}

std::string counts_text(const RunRecord& r) {
  std::string s = std::to_string(r.variants);
  if (r.planned > r.variants) s += "/" + std::to_string(r.planned);
  const int not_ok = r.variants - (r.status.count("ok") ? r.status.at("ok") : 0);
  return s + (not_ok ? " (" + std::to_string(not_ok) + " not ok)" : "");
}

std::string verdicts_text(const RunRecord& r) {
  int pass = 0, fail = 0, undecided = 0;
  for (const Verdict& v : r.verdicts) (v.verdict == "pass" ? pass : v.verdict == "fail" ? fail : undecided)++;
  if (r.verdicts.empty()) return "-";
  return std::to_string(pass) + " pass, " + std::to_string(fail) + " fail" +
         (undecided ? ", " + std::to_string(undecided) + " undecided" : "");
}

// One run's record: provenance, summaries, verdicts.
std::string format_run_md(const RunRecord& r) {
  std::string md = "# " + r.describe() + "\n\n| | |\n|---|---|\n";  // every cell from the record through md_cell
  const std::pair<const char*, std::string> rows[] = {
      {"study", r.study_path},   {"model", r.model_path},   {"output", r.out},
      {"study hash", r.study_hash}, {"flexfarm", format_build(r.version, r.commit)},
      {"host", r.host},          {"started", r.started.empty() ? "-" : r.started}, {"finished", r.finished},
      {"wall time (s)", num(r.seconds, "%.1f")},
      {"processes x threads, lanes", std::to_string(r.processes) + " x " + std::to_string(r.threads) + ", " + std::to_string(r.lanes)},
      {"variants", counts_text(r)}};
  for (const auto& [k, v] : rows) md += std::string("| ") + k + " | " + md_cell(v) + " |\n";
  md += "\n| metric | count | not settled | missing | mean [95 %] | p5 | p50 | p95 | spec | P(miss) [95 %] |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n";
  // Not settled somewhere: the mean is the restricted mean (they count at their horizon), a lower bound.
  auto bounded = [](double x) { return std::isinf(x) ? std::string("> horizon") : num(x); };
  for (const MetricSummary& m : r.summaries)
    md += "| " + md_cell(m.metric) + " | " + std::to_string(m.count) + " | " + std::to_string(m.censored) + " | " +
          std::to_string(m.missing) + " | " + (m.censored > 0 ? "> " : "") + num(m.mean) + " [" + num(m.mean_lower) + ", " + num(m.mean_upper) + "] | " +
          bounded(m.p5) + " | " + bounded(m.p50) + " | " + bounded(m.p95) + " | " + num(m.spec) + " | " +
          (std::isnan(m.p_miss) ? "-" : num(m.p_miss, "%.3f") + " [" + num(m.p_miss_lower, "%.3f") + ", " + num(m.p_miss_upper, "%.3f") + "]") +
          " |\n";
  if (!r.verdicts.empty()) {
    md += "\n| requirement | verdict | estimate [interval] | n | evidence |\n|---|---|---|---|---|\n";
    for (const Verdict& v : r.verdicts)
      md += "| " + md_cell(v.requirement) + " | " + v.verdict + " | " + num(v.estimate) + " [" + num(v.lower) + ", " + num(v.upper) +
            "] | " + std::to_string(v.n) + " | " + md_cell(v.evidence) + " |\n";
  }
  return md;
}

// A run given on the command line: an output directory, or a history id.
RunDir resolve_run(const std::string& arg, const std::string& history) {
  if (std::filesystem::is_directory(arg)) {
    RunDir d = read_run_dir(arg);
    for (const RunRecord& r : list_runs(history, d.record.study_path))
      if (r.out == d.record.out) d.record.id = r.id;  // the history's latest record of this directory
    return d;
  }
  const long id = parse_run_id(arg);
  if (id == 0) throw std::runtime_error(arg + ": neither a run's output directory nor a run id of the history");
  return read_run_dir(read_history_run(history, id));
}

}  // namespace

void add_history_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("history", "List the runs recorded in the run history (every `flexfarm run` records "
                                            "itself), or show one run's record: inputs, version, machine, times, "
                                            "summaries and requirement verdicts");
  struct Args {
    std::string what, history;
    int limit = 20;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("what", args->what, "a study (its file or its name) to list only its runs, or a run id to show that run")
      ->check(kPath);
  cmd->add_option("--history", args->history, "run history directory (default: $FLEXFARM_HISTORY, else "
                                              "$XDG_DATA_HOME/flexfarm, else ~/.local/share/flexfarm)")
      ->check(kPath);
  cmd->add_option("--limit", args->limit, "list at most the latest N runs (0: all)")->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->callback([args] {
    const std::string hist = resolve_history_dir(args->history);
    if (hist.empty()) throw ExitError("no run history: give --history DIR or set FLEXFARM_HISTORY", 2);
    if (const long id = parse_run_id(args->what)) {
      print_safe(stdout, "%s", format_run_md(read_history_run(hist, id)).c_str());
      return;
    }
    std::string study = args->what;
    if (!study.empty() && std::filesystem::is_regular_file(study))
      study = std::filesystem::absolute(study).lexically_normal().string();
    std::vector<RunRecord> runs = list_runs(hist, study, true);
    if (runs.empty()) {
      print_safe(stdout, "no runs%s in %s/history.sqlite\n", study.empty() ? "" : (" of " + args->what).c_str(), hist.c_str());
      return;
    }
    if (args->limit > 0 && runs.size() > static_cast<std::size_t>(args->limit))
      runs.erase(runs.begin(), runs.end() - args->limit);
    std::string md = "| id | study | finished | host | flexfarm | variants | wall (s) | requirements | output |\n"
                     "|---|---|---|---|---|---|---|---|---|\n";
    for (const RunRecord& r : runs)
      md += "| " + std::to_string(r.id) + " | " + md_cell(r.study) + " | " + md_cell(r.finished) + " | " + md_cell(r.host) + " | " +
            md_cell(format_build(r.version, r.commit)) + " | " + counts_text(r) + " | " + num(r.seconds, "%.1f") +
            " | " + verdicts_text(r) + " | " + md_cell(r.out) + " |\n";
    print_safe(stdout, "%s", md.c_str());
  });
}

void add_diff_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "diff", "What changed between two runs: inputs (model and study keys, version), each metric's move with a "
              "bootstrap test against Monte Carlo noise, regressions against the study's tolerances, requirement "
              "verdicts. Exit 0: nothing worse; 1: a regression; 2: bad input");
  struct Args {
    std::vector<std::string> runs;
    std::string history, out;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("runs", args->runs, "RUN_A RUN_B, or RUN_B alone (compared with the study's previous run in the "
                                      "history); a run is an output directory of flexfarm run or a history id (12 or #12)")
      ->required()
      ->expected(1, 2)
      ->check(kPath);
  cmd->add_option("--history", args->history, "run history directory (default: $FLEXFARM_HISTORY, else "
                                              "$XDG_DATA_HOME/flexfarm, else ~/.local/share/flexfarm)")
      ->check(kPath);
  cmd->add_option("--out", args->out, "also write the diff (Markdown) to this file")->check(kPath);
  cmd->callback([args] {
    RunDiff d;
    std::string first;  // B is its study's first run: nothing to compare with, which is no error
    try {
      const std::string hist = resolve_history_dir(args->history);
      const RunDir b = resolve_run(args->runs.back(), hist);
      RunDir a;
      if (args->runs.size() == 2) {
        a = resolve_run(args->runs.front(), hist);
      } else if (const auto previous = find_previous_run(hist, b.record)) {  // the run recorded before b
        a = resolve_run(std::to_string(previous->id), hist);
      } else {
        first = "# Nothing to compare with\n\n" + b.record.describe() + " is the first run of " + b.record.study_path +
                " in the history " + (hist.empty() ? std::string("(none)") : hist) +
                ": there is no earlier run to compare it with. Nothing got worse.\n";
      }
      // The later run's specs, tolerances and requirements, read from its study as it ran.
      const StudyCriteria c =
          b.record.study_text.empty() ? StudyCriteria{} : read_study_criteria(b.record.study_text, b.record.study_path);
      check_criteria_columns(c, b.table.columns);  // a misspelled tolerance would guard nothing
      if (first.empty()) d = diff_runs(a, b, c.tolerances, c.requirements, c.specs);
    } catch (const std::exception& e) {
      throw ExitError(e.what(), 2);  // exit 1 means a regression
    }
    const std::string md = first.empty() ? format_diff_md(d) : first;
    if (!args->out.empty()) write_file_atomic(args->out, md);
    print_safe(stdout, "%s", md.c_str());
    if (!d.regressions.empty()) throw ExitError("", 1);  // the diff has said which
  });
}

}  // namespace ff
