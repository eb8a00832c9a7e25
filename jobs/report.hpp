// The outputs of a finished study, from its result table (and the traces on disk): results.csv,
// results.sqlite, table.md and plots. Each file is written whole.
#pragma once

#include <string>
#include <vector>

#include "arm/arm_simulate.hpp"
#include "kernel/simulate.hpp"
#include "results/history.hpp"
#include "results/table.hpp"
#include "sweep/study.hpp"

namespace ff {

// Plots of traces (tip angle, hub angle, tip deflection, torque) against time: DIR/<signal>.png.
void write_trace_plots(const std::string& dir, const std::vector<std::string>& labels,
                       const std::vector<const Trace*>& traces, const std::string& title);

// Plots of arm traces (arm/arm_simulate.hpp) of arms like `arm` (its joints' types) against time, one line per
// trace: DIR/joints.png (each actuated joint's angle, rad, or a prismatic joint's position, m, and
// dashed its reference), DIR/torques.png (N·m, or N), DIR/tool_error.png (|tool - where the rigid arm
// at the reference puts it|, mm), with flexible links DIR/deflection.png (each link tip's deflection
// along its y and z, signed, mm; a component that stays 0 left out) and with a world
// DIR/clearance.png (the arm's least clearance, mm; below 0: contact). Returns the file names written.
std::vector<std::string> write_arm_plots(const std::string& dir, const std::vector<std::string>& labels,
                                         const std::vector<const ArmTrace*>& traces, const std::string& title,
                                         const ArmModel& arm);

// How a run ran, beyond its study and results: when it started (UTC, "" when not known), its wall
// time so far and how it was spread.
struct RunContext {
  std::string started;
  double seconds = kStatsNaN;
  int processes = 1, threads = 0, lanes = 0;
};

// The record of a finished run in `dir` (results/history.hpp): its study, inputs, version, machine,
// times, counts by status and per-metric summaries; finished now.
RunRecord make_run_record(const Study& study, const ResultTable& table, const std::string& dir, const RunContext& ctx);

// table.md in its parts: the title and description, the results (tables of the variants, every metric,
// by case or parameter), the requirements' verdicts (report.html shows the first and last its own way).
struct StudyReport {
  std::string head, results, requirements;
  std::string md() const { return head + results + requirements; }
};

// Writes everything into `dir` (run.yaml holds `record`); returns the Markdown it also wrote to table.md.
StudyReport write_study_report(const Study& study, const ResultTable& table, const std::string& dir,
                               const RunRecord& record);

// table.md's "## Requirements" section: `verdicts` (calc_study_verdicts, jobs/farm.hpp, on `table`), and
// whether the study stopped early; "" without requirements.
std::string format_study_requirements_md(const Study& study, const ResultTable& table, const std::vector<Verdict>& verdicts);

}  // namespace ff
