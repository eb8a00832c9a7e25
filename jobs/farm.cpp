#include "jobs/farm.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "jobs/journal.hpp"
#include "common/files.hpp"
#include "common/text.hpp"

namespace ff {

namespace {
// Every requirement is decided on rows 0..k-1 (all in `rows`), the study not complete.
bool decided_at(const Study& study, const std::map<int, std::string>& rows, int k) {
  const ResultTable empty = make_result_table(study);
  std::string text = format_results_header(empty);
  for (int i = 0; i < k; ++i) text += rows.at(i);
  const ResultTable t = parse_results_csv(text, "journal rows");
  return all_decided(evaluate_requirements(study.requirements, t, false, static_cast<int>(study.variants.size())));
}

int leading_rows(const std::map<int, std::string>& rows, int from = 0) {
  while (rows.count(from)) ++from;
  return from;
}
}  // namespace

int find_study_stop_point(const Study& study, const std::map<int, std::string>& rows) {
  return find_stop_point(study.requirements, static_cast<int>(study.variants.size()), leading_rows(rows),
                         [&](int k) { return decided_at(study, rows, k); });
}

std::vector<Verdict> calc_study_verdicts(const Study& study, const ResultTable& table) {
  const int total = static_cast<int>(study.variants.size());
  return evaluate_requirements(study.requirements, table, static_cast<int>(table.rows.size()) == total, total);
}

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
  std::FILE* timings = ::fdopen(open_append_nofollow(timings_path), "ab");
  if (!timings) throw std::runtime_error(timings_path + ": cannot open for writing");
  if (new_timings) std::fputs("first_eval_id,variants,seconds\n", timings);

  // Early stop: the rows so far (journalled and new), how many lead without a gap, the next checkpoint.
  const bool track = study.requirements.stop_when_decided && opt.part.count == 1;
  std::map<int, std::string> rows = track ? done : std::map<int, std::string>{};
  int prefix = leading_rows(rows), next = 0;
  std::atomic<bool> stop{false};
  const int nvariants = static_cast<int>(study.variants.size());
  auto check_stop = [&] {
    prefix = leading_rows(rows, prefix);
    const int k = find_stop_point(study.requirements, nvariants, prefix, [&](int c) { return decided_at(study, rows, c); }, &next);
    if (k >= 0 && k < nvariants) {
      st.stop = k;
      stop = true;
    }
  };
  if (track) check_stop();
  EvalOptions eval = opt.eval;
  eval.stop = &stop;

  const auto t0 = std::chrono::steady_clock::now();
  int finished = st.already;
  if (opt.progress) opt.progress(finished, st.total, 0.0);
  try {
    if (!stop) evaluate_variants(study, pending, eval, [&](BatchResult&& res) {
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
      if (track && !stop) {
        for (const auto& r : res.rows) rows[r.eval_id] = format_results_row(r);
        check_stop();
      }
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

AttemptLog::AttemptLog(const std::string& out, const std::string& tag, const std::string& started, bool resume)
    : path_(out + "/attempts-" + tag + ".csv"), started_(started), first_started_(started) {
  std::map<int, std::pair<std::string, double>> earlier;  // attempt: its start and its latest seconds
  if (resume && std::filesystem::exists(path_)) {
    std::istringstream text(read_file(path_));
    std::string line;
    while (std::getline(text, line)) {
      const std::size_t c1 = line.find(','), c2 = line.find(',', c1 + 1);
      if (c1 == std::string::npos || c2 == std::string::npos) continue;  // the header, a torn line
      const auto attempt = parse_integer<int>(std::string_view(line).substr(0, c1));
      const auto at = parse_finite(std::string_view(line).substr(c2 + 1));
      if (!attempt || !at) continue;  // a line that is not whole numbers (a corrupted one): not an attempt
      auto& [start, seconds] = earlier[*attempt];
      start = line.substr(c1 + 1, c2 - c1 - 1);
      seconds = std::max(seconds, *at);
    }
  }
  for (const auto& [attempt, at] : earlier) earlier_ += at.second;
  if (!earlier.empty()) {
    attempt_ = earlier.rbegin()->first + 1;
    first_started_ = earlier.begin()->second.first;
  } else {
    try {
      write_file_atomic(path_, "attempt,started,seconds\n");
    } catch (const std::runtime_error&) {  // bookkeeping, as the timings: a full disk is the journal's error
    }
  }
}

void AttemptLog::note(double seconds) {
  char line[96];
  const int n = std::snprintf(line, sizeof line, "%d,%s,%.3f\n", attempt_, started_.c_str(), seconds);
  try {
    const int fd = open_append_nofollow(path_);  // never through a planted link
    if (n > 0 && ::write(fd, line, static_cast<std::size_t>(n)) != n) {}  // a torn line is skipped when read
    ::close(fd);
  } catch (const std::runtime_error&) {  // bookkeeping, as the timings: a full disk is the journal's error
  }
}

ResultTable assemble_results(const Study& study, const std::string& out) {
  ResultTable table = make_result_table(study);
  const std::string header = format_results_header(table);
  const auto rows = read_journals(out, study.hash, header);
  std::string text = header;
  int missing = 0, first_missing = -1;
  const int stop = find_study_stop_point(study, rows);  // -1: not known, so the study must be whole
  for (const auto& v : study.variants) {
    if (stop >= 0 && v.eval_id >= stop) break;
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
