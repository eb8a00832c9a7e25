// flexfarm table DIR: settling-time and overshoot tables of a finished study, grouped by any
// parameters (count, missing, mean, min, p5, p50, p95, max, and the probability of missing a spec);
// a parameter with more than --bins distinct values is grouped by its bins (results/statistics.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "apps/verbs.hpp"
#include "common/files.hpp"
#include "common/text.hpp"
#include "arm/arm_metrics.hpp"
#include "results/summaries.hpp"
#include "results/table.hpp"

namespace ff {

namespace {
std::vector<std::string> split_list(const std::vector<std::string>& items) {
  std::vector<std::string> out;
  for (const auto& item : items) {
    std::stringstream ss(item);
    std::string part;
    while (std::getline(ss, part, ','))
      if (!part.empty()) out.push_back(part);
  }
  return out;
}
}  // namespace

void add_table_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("table", "Summarise a study's results.csv grouped by parameters: count, mean, "
                                          "min, percentiles, max, and the probability of missing a spec");
  struct Args {
    std::string input, format = "md", binning = "quantile";
    std::vector<std::string> by, metrics, specs;
    int bins = Binning{}.bins;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("results", args->input, "a study's output directory or its results.csv")->required()->check(kPath)->check(CLI::ExistingPath);
  cmd->add_option("--by", args->by, "parameters to group by, comma separated (e.g. payload.mass,segments); none = all rows. "
                                    "One with more than --bins distinct values is grouped by bins, each an interval [a, b)");
  cmd->add_option("--metric", args->metrics, "metrics to summarise, comma separated")
      ->default_str("m1_tip_settling_s,m1_tip_overshoot_pct (an arm study's: each tool's, tool_settling_s,tool_overshoot_pct)");
  cmd->add_option("--spec", args->specs, "METRIC=LIMIT: report P(metric > limit or not settled), e.g. m1_tip_settling_s=3");
  cmd->add_option("--format", args->format, "md or csv (a binned parameter: its interval, then <param>_lo,<param>_hi)")
      ->check(CLI::IsMember({"md", "csv"}))
      ->capture_default_str();
  cmd->add_option("--bins", args->bins, "a --by parameter with more than N distinct values is grouped into N bins "
                                        "(fewer where ties merge them); 0 = one group per distinct value")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--binning", args->binning, "quantile (about equal numbers of rows per bin) or width (equal-width bins "
                                              "from the least to the largest value)")
      ->check(CLI::IsMember({"quantile", "width"}))
      ->capture_default_str();
  cmd->callback([args] {
    std::string path = args->input;
    if (std::filesystem::is_directory(path)) path += "/results.csv";
    const ResultTable t = parse_results_csv(read_file(path), path);
    auto metrics = split_list(args->metrics);
    if (metrics.empty()) {
      // An arm study's: each tool's (`tool:`'s is named "tool").
      for (const std::string& tool : arm_tool_names(t.columns))
        for (const char* s : {"_settling_s", "_overshoot_pct"}) metrics.push_back(tool + s);
      if (metrics.empty()) metrics = {"m1_tip_settling_s", "m1_tip_overshoot_pct"};
    }
    // Every name given is a column of this table (--by: a parameter too), else the closest and the list.
    auto check = [&](const char* option, const std::string& name, bool parameter) {
      const std::string why = parameter ? explain_unknown_name(t, name) : explain_unknown_column(name, t.columns);
      if (!why.empty()) throw CLI::ValidationError(option, why + " of " + path);
    };
    for (const std::string& m : split_list(args->metrics)) check("--metric", m, false);
    std::map<std::string, double> specs;
    for (const auto& s : split_list(args->specs)) {
      const auto eq = s.find('=');
      if (eq == std::string::npos) throw CLI::ValidationError("--spec", "expected METRIC=LIMIT, got '" + s + "'");
      check("--spec", s.substr(0, eq), false);
      const auto limit = parse_finite(s.substr(eq + 1));
      if (!limit) throw CLI::ValidationError("--spec", "limit of '" + s + "' is not a finite number");
      specs[s.substr(0, eq)] = *limit;
    }
    const auto by = split_list(args->by);
    for (const std::string& b : by) check("--by", b, true);
    try {
      const Binning binning{args->bins, args->binning == "width" ? Binning::kWidth : Binning::kQuantile};
      print_safe(stdout, "%s", (args->format == "csv" ? format_groupby_csv(t, by, metrics, specs, binning)
                                                      : format_groupby_md(t, by, metrics, specs, binning)).c_str());
    } catch (const std::invalid_argument& e) {
      throw CLI::ValidationError("--by/--metric", e.what());
    }
  });
}

}  // namespace ff
