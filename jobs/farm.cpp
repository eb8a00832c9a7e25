#include "jobs/farm.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "jobs/journal.hpp"
#include "common/files.hpp"

namespace ff {

FarmStatus run_farm(const Study& study, const FarmOptions& opt) {
  const ResultTable empty = make_result_table(study);
  const std::string header = format_results_header(empty);
  const std::string own = opt.out + "/journal-" + opt.tag + ".csv";
  if (!opt.resume && std::filesystem::exists(own))
    throw std::runtime_error(opt.out + " already holds this run's journal; add --resume to continue it, or use another --out");

  // This share, less what the journals already hold.
  const auto done = opt.resume ? read_journals(opt.out, study.hash, header) : std::map<int, std::string>{};
  FarmStatus st;
  std::vector<int> pending;
  for (std::size_t i = 0; i < study.variants.size(); ++i) {
    const int id = study.variants[i].eval_id;
    if (id % opt.part.count != opt.part.index) continue;
    ++st.total;
    if (done.count(id)) ++st.already;
    else pending.push_back(static_cast<int>(i));
  }

  JournalWriter journal(opt.out, opt.tag, study.hash, header);
  if (!journal.repaired().empty() && opt.notice) opt.notice(journal.repaired());
  const std::string timings_path = opt.out + "/timings-" + opt.tag + ".csv";
  const bool new_timings = !std::filesystem::exists(timings_path);
  std::FILE* timings = std::fopen(timings_path.c_str(), "ab");
  if (!timings) throw std::runtime_error(timings_path + ": cannot open for writing");
  if (new_timings) std::fputs("first_eval_id,variants,seconds\n", timings);

  const auto t0 = std::chrono::steady_clock::now();
  int finished = st.already;
  if (opt.progress) opt.progress(finished, st.total, 0.0);
  try {
    evaluate_variants(study, pending, opt.eval, [&](BatchResult&& res) {
      // Traces first, then the rows: a journalled row always has its trace on disk.
      for (std::size_t k = 0; k < res.traces.size(); ++k) {
        char name[48];
        std::snprintf(name, sizeof name, "/traces/%06d.csv", res.rows[k].eval_id);
        write_trace_csv(res.traces[k], opt.out + name);
      }
      for (std::size_t k = 0; k < res.arm_traces.size(); ++k) {
        char name[48];
        std::snprintf(name, sizeof name, "/traces/%06d.csv", res.rows[k].eval_id);
        write_arm_trace_csv(res.arm_traces[k], opt.out + name);
      }
      std::string text;
      for (const auto& r : res.rows) text += format_results_row(r);
      journal.append(text);
      std::fprintf(timings, "%d,%zu,%.6f\n", res.rows.front().eval_id, res.rows.size(), res.seconds);
      std::fflush(timings);
      finished += static_cast<int>(res.rows.size());
      st.computed += static_cast<int>(res.rows.size());
      if (opt.progress)
        opt.progress(finished, st.total, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    });
  } catch (...) {
    std::fclose(timings);
    throw;
  }
  std::fclose(timings);
  return st;
}

ResultTable assemble_results(const Study& study, const std::string& out) {
  ResultTable table = make_result_table(study);
  const std::string header = format_results_header(table);
  const auto rows = read_journals(out, study.hash, header);
  std::string text = header;
  int missing = 0, first_missing = -1;
  for (const auto& v : study.variants) {
    auto it = rows.find(v.eval_id);
    if (it == rows.end()) {
      if (first_missing < 0) first_missing = v.eval_id;
      ++missing;
      continue;
    }
    text += it->second;
  }
  if (missing)
    throw std::runtime_error(out + ": " + std::to_string(missing) + " of " + std::to_string(study.variants.size()) +
                             " variants have no result yet (first: eval_id " + std::to_string(first_missing) +
                             "); run the missing shards or ranks, or flexfarm run --resume");
  return parse_results_csv(text, out + "/journal-*.csv");
}

}  // namespace ff
