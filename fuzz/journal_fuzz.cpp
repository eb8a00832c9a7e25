// libFuzzer harness of the journal readers behind --resume and merge: the input is a journal file of a
// study with a fixed hash and the paper study's header. read_journals (what merge and --resume read),
// JournalWriter (the --resume repair), read_journals again, which must find the same rows, and
// parse_results_csv of the rows found (the assembled table).
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <map>

#include "fuzz/fuzz_support.hpp"
#include "jobs/journal.hpp"
#include "results/table.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string hash = "0123456789abcdef";
  static const std::string header = [] {
    std::ifstream in(std::string(FLEXFARM_SOURCE_DIR) + "/tests/data/fbtb_paper_results.csv");
    std::string line;
    std::getline(in, line);
    return line + "\n";
  }();
  const auto dir = ff::fuzz::scratch().path() / "out";
  std::filesystem::remove_all(dir);
  ff::fuzz::scratch().write("out/journal-fuzz.csv", ff::fuzz::text_of(data, size));
  std::map<int, std::string> rows;
  try {
    rows = ff::read_journals(dir.string(), hash, header);
  } catch (const std::exception&) {
    return 0;  // another study's journal: --resume and merge stop here
  }
  try {
    { ff::JournalWriter repair(dir.string(), "fuzz", hash, header); }
    // The repair keeps every row the readers count.
    if (ff::read_journals(dir.string(), hash, header) != rows) std::abort();
    std::string text = header;
    for (const auto& [id, row] : rows) text += row;
    (void)ff::parse_results_csv(text, "journal-*.csv");
  } catch (const std::exception&) {
  }
  return 0;
}
