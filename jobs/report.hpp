// The outputs of a finished study, from its result table (and the traces on disk): results.csv,
// results.sqlite, table.md and plots. Each file is written whole.
#pragma once

#include <string>
#include <vector>

#include "kernel/simulate.hpp"
#include "results/table.hpp"
#include "sweep/study.hpp"

namespace ff {

// Plots of traces (tip angle, hub angle, tip deflection, torque) against time: DIR/<signal>.png.
void write_trace_plots(const std::string& dir, const std::vector<std::string>& labels,
                       const std::vector<const Trace*>& traces, const std::string& title);

// Writes everything into `dir`; returns the Markdown table it also wrote to table.md.
std::string write_study_report(const Study& study, const ResultTable& table, const std::string& dir);

}  // namespace ff
