// The result table as an SQLite database: table `results` (eval_id, seed, label, status, one REAL
// column per parameter and metric, named as in the CSV) and table `study` (key, value).
#pragma once

#include <map>
#include <string>

#include "results/table.hpp"

namespace ff {

// Writes `path` whole (a temporary database renamed into place). Throws std::runtime_error naming
// the path on failure.
void write_results_sqlite(const ResultTable& table, const std::map<std::string, std::string>& study_info,
                          const std::string& path);

}  // namespace ff
