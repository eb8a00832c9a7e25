// The `flexfarm` verbs. Each registers a CLI11 subcommand; its callback does the work.
#pragma once

#include <CLI/CLI.hpp>

#include <stdexcept>
#include <string>
#include <vector>

#include "common/files.hpp"
#include "common/text.hpp"  // print_safe: how the verbs print text that holds names from inputs
#include "kernel/model.hpp"
#include "sweep/paths.hpp"  // load_model_with: a model file with --set overrides

namespace ff {

// An error that ends the program with its own exit code (e.g. 3: some variants failed).
struct ExitError : std::runtime_error {
  ExitError(const std::string& what, int exit_code) : std::runtime_error(what), code(exit_code) {}
  int code;
};

// The one check of every option and argument that names a path (--out, --data, --history, a model
// file, ...): an empty or blank value, an unset $OUT in a script, is a usage error (exit 2) saying
// so, never "" + "/journal-main.csv" at the filesystem root. Put it before ExistingFile and kin.
inline const CLI::Validator kPath(
    [](std::string& value) {
      return is_blank_path(value) ? std::string("an empty or blank path (an unset variable?)") : std::string();
    },
    "PATH");

void add_modes_verb(CLI::App& app);
void add_simulate_verb(CLI::App& app);
void add_run_verb(CLI::App& app);
void add_merge_verb(CLI::App& app);
void add_table_verb(CLI::App& app);
void add_plot_verb(CLI::App& app);
void add_animate_verb(CLI::App& app);
void add_view_verb(CLI::App& app);
void add_diagnose_verb(CLI::App& app);
void add_calibrate_verb(CLI::App& app);
void add_record_verb(CLI::App& app);
void add_compare_verb(CLI::App& app);
void add_history_verb(CLI::App& app);
void add_diff_verb(CLI::App& app);

}  // namespace ff
