// libFuzzer harness of a run's records (results/history.hpp): the input is read both as a run history
// database (the bytes of history.sqlite: every run listed with its inputs, summaries and verdicts, each
// one's previous run found) and as a run directory's run.yaml (beside a valid results.csv and
// results.sqlite), as `flexfarm history` and `flexfarm diff` read them.
#include <cstdint>
#include <exception>

#include "fuzz/fuzz_support.hpp"
#include "results/history.hpp"
#include "results/sqlite.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes = ff::fuzz::text_of(data, size);
  const auto dir = ff::fuzz::scratch().path() / "history";
  std::filesystem::remove_all(dir);  // with any -journal or -wal file SQLite left
  ff::fuzz::scratch().write("history/history.sqlite", bytes);
  try {
    for (const ff::RunRecord& r : ff::list_runs(dir.string(), "", true)) (void)ff::find_previous_run(dir.string(), r);
  } catch (const std::exception&) {
  }
  // The same bytes as a run directory's record.
  const auto run = ff::fuzz::scratch().path() / "run";
  if (!std::filesystem::exists(run / "results.sqlite")) {
    ff::ResultTable t;
    t.params = {"p"};
    t.columns = {"m1_tip_settling_s"};
    t.rows.push_back({0, 1, "a", "ok", {1.0}, {2.0}});
    ff::fuzz::scratch().write("run/results.csv", ff::format_results_csv(t));
    ff::write_results_sqlite(t, {{"name", "n"}}, (run / "results.sqlite").string());
  }
  ff::fuzz::scratch().write("run/run.yaml", bytes);
  try {
    (void)ff::read_run_dir(run.string());
  } catch (const std::exception&) {
  }
  return 0;
}
