// The `flexfarm` verbs. Each registers a CLI11 subcommand; its callback does the work.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "kernel/model.hpp"

namespace ff {

void add_modes_verb(CLI::App& app);
void add_simulate_verb(CLI::App& app);
void add_run_verb(CLI::App& app);

// Loads a model file and applies `--set PATH=VALUE` overrides (sweep/paths.hpp).
Model load_model_with(const std::string& path, const std::vector<std::string>& sets);

// Plots of recorded traces (tip angle, hub angle, tip deflection, torque) to DIR/<signal>.png.
void write_trace_plots(const std::string& dir, const std::vector<std::string>& labels,
                       const std::vector<const struct Trace*>& traces, const std::string& title);

}  // namespace ff
