// libFuzzer harness of the results CSV reader behind `flexfarm table`: parse_results_csv, then the
// tables drawn from it (grouped by the first parameter, the first two metrics, a spec on the first),
// and a round trip: the table written again reads back the same.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <exception>

#include "fuzz/fuzz_support.hpp"
#include "results/summaries.hpp"
#include "results/table.hpp"

namespace {

// Equal values, NaN equal to NaN (an empty cell).
bool same(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!(std::isnan(a[i]) && std::isnan(b[i])) && std::memcmp(&a[i], &b[i], sizeof(double)) != 0) return false;
  return true;
}

bool same(const ff::ResultTable& a, const ff::ResultTable& b) {
  if (a.params != b.params || a.columns != b.columns || a.rows.size() != b.rows.size()) return false;
  for (std::size_t i = 0; i < a.rows.size(); ++i) {
    const auto &x = a.rows[i], &y = b.rows[i];
    if (x.eval_id != y.eval_id || x.seed != y.seed || x.label != y.label || x.status != y.status ||
        !same(x.params, y.params) || !same(x.values, y.values))
      return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ff::ResultTable t;
  try {
    t = ff::parse_results_csv(ff::fuzz::text_of(data, size), "results.csv");
  } catch (const std::exception&) {
    return 0;
  }
  // What is read is written back exactly.
  if (!same(t, ff::parse_results_csv(ff::format_results_csv(t), "again.csv"))) std::abort();
  std::vector<std::string> by;
  if (!t.params.empty()) by.push_back(t.params.front());
  std::vector<std::string> metrics(t.columns.begin(), t.columns.begin() + std::min<std::size_t>(2, t.columns.size()));
  std::map<std::string, double> specs;
  if (!metrics.empty()) specs[metrics.front()] = 3.0;
  try {
    (void)ff::format_groupby_md(t, by, metrics, specs);
    (void)ff::format_groupby_csv(t, by, metrics, specs);
  } catch (const std::exception&) {
  }
  (void)ff::format_settling_table_md(t, std::vector<std::vector<std::string>>(t.rows.size(), {"0 -> 0.5 rad"}));
  return 0;
}
