// libFuzzer harness of a finished run's results.sqlite (results/history.hpp read_run_dir, which
// `flexfarm view RUN_DIR` calls, and `flexfarm diff` on a run without run.yaml): the input is the bytes of
// results.sqlite beside a valid results.csv; its `study` table (read_results_study_info, any NULL cell)
// becomes the run's record.
#include <cstdint>
#include <exception>

#include "fuzz/fuzz_support.hpp"
#include "results/history.hpp"
#include "results/sqlite.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto dir = ff::fuzz::scratch().path() / "run";
  std::filesystem::remove_all(dir);  // with any -journal or -wal file SQLite left
  ff::ResultTable t;
  t.params = {"p"};
  t.columns = {"m1_tip_settling_s", "min_clearance_m"};
  t.rows.push_back({0, 1, "a", "ok", {1.0}, {2.0, 0.5}});
  ff::fuzz::scratch().write("run/results.csv", ff::format_results_csv(t));
  ff::fuzz::scratch().write("run/results.sqlite", ff::fuzz::text_of(data, size));
  try {
    const ff::RunDir d = ff::read_run_dir(dir.string());
    (void)d.record.describe();
  } catch (const std::exception&) {
  }
  return 0;
}
